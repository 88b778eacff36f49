"""The package's BSDF plugins, one module each; :mod:`mi_brdfs.registry` registers them."""
