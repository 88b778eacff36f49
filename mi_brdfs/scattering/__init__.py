"""
Pure scattering terms, apart from any plugin: functions of DrJit values in the local shading
frame (normal +z), written with ``dr.*`` and ``mi.*`` only, so they work in every variant. The
plugins in :mod:`mi_brdfs.plugins` put them together; :mod:`mi_brdfs.reference` has their float64
NumPy counterparts.
"""
