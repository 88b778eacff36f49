"""
maignan of eradiate-mitsuba 0.5.0 leaves out the cosine foreshortening: eval() returns C·F
(maignan.cpp, v0.5.0, line 214), the BRDF f itself, where Mitsuba's BSDF::eval returns
f·cosθo, and sample() returns the same C·F as its weight (line 197) where the weight is
f·cosθo/pdf. So eval is symmetric in wi and wo (a reciprocal f·cosθo is not: eval(a→b)/
eval(b→a) = cosθb/cosθa), the reciprocity check's f = eval/cosθo is off by 1/cosθo, and every
sample weight equals eval, not eval/pdf (the model, Maignan et al. 2009,
https://doi.org/10.1016/j.rse.2009.07.022, eq. 21, is a reciprocal BRDF).

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_maignan_cosine.py
Exits 1 while eval(a→b)/eval(b→a) is 1 (no cosine) or the sample weight is not eval/pdf.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")


def direction(theta, phi):
    t, p = np.radians(theta), np.radians(phi)
    return [float(np.sin(t) * np.cos(p)), float(np.sin(t) * np.sin(p)), float(np.cos(t))]


def interaction(wi, n=2):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*wi)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    return si


bsdf = mi.load_dict({"type": "maignan", "C": 5.0, "ndvi": 0.6})
ctx = mi.BSDFContext()
a, b = direction(78.9, 48.8), direction(1.2, 46.0)
e_ab = float(np.array(bsdf.eval(ctx, interaction(a), mi.Vector3f(*b)))[0, 0])
e_ba = float(np.array(bsdf.eval(ctx, interaction(b), mi.Vector3f(*a)))[0, 0])
print(f"eval(a→b) = {e_ab:.6g}, eval(b→a) = {e_ba:.6g}: ratio {e_ab / e_ba:.4f} "
      f"(f·cosθo reciprocal: cosθb/cosθa = {b[2] / a[2]:.4f}; a BRDF without the cosine: 1)")

rng = np.random.default_rng(0)
n = 1000
si = interaction(direction(45.0, 10.0), n)
bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)), mi.Point2f(rng.random(n),
                                                                       rng.random(n)))
value = np.array(bsdf.eval(ctx, si, bs.wo))[0]
pdf = np.array(bs.pdf)
weight = np.array(weight)[0]
print(f"sample(): weight / eval = {np.median(weight / value):.4f}, weight / (eval/pdf) = "
      f"{np.median(weight / (value / pdf)):.4f} (1 for a consistent sampler)")
sys.exit(1 if abs(e_ab / e_ba - 1) < 1e-3 or abs(np.median(weight * pdf / value) - 1) > 1e-3
         else 0)
