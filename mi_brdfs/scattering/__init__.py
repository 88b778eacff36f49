"""
Pure scattering terms of the package's models: functions of DrJit values in the local shading
frame (normal = +z, ``wi`` and ``wo`` pointing away from the surface) and of the model's
parameters, written with ``dr.*`` and ``mi.*`` only and looked up at call time, so that one module
serves every Mitsuba variant (scalar, JIT, spectral) without being rebuilt. Nothing here knows
``mi.BSDF``: the plugins in :mod:`mi_brdfs.plugins` put these terms together, and
:mod:`mi_brdfs.reference` has their float64 NumPy counterparts.
"""
