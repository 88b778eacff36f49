"""
Measured BRDFs: MERL's format (:mod:`.merl`) and a virtual gonioreflectometer that tabulates
any BSDF in it (:mod:`.tabulate`).
"""
