"""
hapke of eradiate-mitsuba 0.5.0 returns NaN at normal incidence looking straight back
(wo = wi = +z, the opposition peak itself) with its defaults: hapke.cpp (v0.5.0) line 78 sets
h = 0 by default, and line 261, eval_B, returns B_0 / (1.f + 1.f / h * dr::tan(g / 2)): at
the phase angle g = 0, 1/h = Inf times tan(0) = 0 is NaN (B_0 = 0 by default, so the
opposition term should vanish). Any h = 0 does it at g = 0; h > 0 gives a finite value.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_hapke_opposition_nan.py
Exits 1 while eval is NaN there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
# a batch of directions (a single literal lane is folded into a constant by LLVM, which
# happens to give a finite value; scalar_rgb gives NaN too)
wi = np.array([[0, 0, 1], [0.1, 0, 0.995], [0, 0, 1]], dtype=np.float32)
wo = np.array([[0, 0, 1], [0, 0, 1], [0.1, 0, 0.995]], dtype=np.float32)
wi /= np.linalg.norm(wi, axis=1)[:, None]
wo /= np.linalg.norm(wo, axis=1)[:, None]
bad = False
for h in (0.0, 0.05):
    bsdf = mi.load_dict({"type": "hapke", "h": h})
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*(np.ascontiguousarray(wi[:, k]) for k in range(3)))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    value = np.array(bsdf.eval(mi.BSDFContext(), si,
                               mi.Vector3f(*(np.ascontiguousarray(wo[:, k]) for k in range(3)))))
    print(f"h = {h}: eval at wo = wi = +z: {value[0, 0]}; at 5.7° from it: {value[0, 1:]}")
    bad |= h == 0.0 and bool(np.isnan(value[0, 0]))
sys.exit(1 if bad else 0)
