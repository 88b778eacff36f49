"""
ocean_legacy of eradiate-mitsuba 0.5.0 (λ = 550 nm, at 0.1 and 5 m/s) returns NaN at grazing
incidence with grazing exitance (wi at cosθ = 6.1e-17, wo = wi or near its mirror image). The
NaN is in the glint component (ctx.component = 1); the diffuse one is finite there, and at
cosθ = 1e-3 every value is finite. The glint's half vector m is then horizontal
(m.z ≈ 6e-17): eval_glint (ocean_legacy.cpp, v0.5.0, lines 424-427) multiplies Beckmann's D(m),
0 there, by cox_munk_gram_charlier_coef (include/mitsuba/eradiate/oceanprops.h from line 641),
whose slopes m.x/(σ m.z) reach 1e16 and whose quartic terms overflow float32: 0 · Inf is NaN.
This is the likely cause (the audit did not step through the function).

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_ocean_legacy_grazing_nan.py
Exits 1 while eval is NaN there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
MU = float(np.cos(np.pi / 2))  # 6.123e-17
bad = False
for wind in (0.1, 5.0):
    bsdf = mi.load_dict({"type": "ocean_legacy", "wavelength": 550.0, "wind_speed": wind})
    for component, name in ((None, "all"), (0, "diffuse"), (1, "glint")):
        ctx = mi.BSDFContext()
        if component is not None:
            ctx.component = component
        si = dr.zeros(mi.SurfaceInteraction3f, 3)
        si.wi = mi.Vector3f(1.0, 0.0, MU)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        wo = mi.Vector3f(np.array([1.0, -1.0, 1.0], dtype=np.float32),
                         np.array([0.0, 1e-3, 0.0], dtype=np.float32),
                         np.array([MU, MU, 1e-3], dtype=np.float32))
        value = np.array(bsdf.eval(ctx, si, wo))[0]
        print(f"wind {wind} m/s, {name}: wo = wi {value[0]}, near the mirror {value[1]}, "
              f"cosθo = 1e-3 {value[2]}")
        bad |= component is None and bool(np.isnan(value[:2]).any())
sys.exit(1 if bad else 0)
