"""
hapke of eradiate-mitsuba 0.5.0 returns NaN at grazing incidence and grazing exitance in the
forward direction (wi at cosθ = 6.1e-17, the float64 cos 90° the checks use, wo its mirror
image, relative azimuth φ = π), for every parameter set tried. hapke.cpp (v0.5.0), eval_mu,
lines 181-185, divides opt_cos_phi * E2_e + sign * sin²(φ/2) * E2_i by
2 - E1_e - φ/π * E1_i; with e = i = 90° (tan e = 1.6e16), E1 = exp(-2/(π tanθ tan e)) and E2
round to 1 and, at φ = π, both the numerator (-E2_e + E2_i) and the denominator
(2 - E1_e - E1_i) are 0: 0/0 (the float32 terms are printed below). Slightly off the horizon
(cosθ = 1e-4) the same pair is finite.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_hapke_grazing_nan.py
Exits 1 while eval is NaN there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
SPEC = {"type": "hapke", "w": 0.5, "b": 0.3, "c": 0.5, "theta": 20.0, "B_0": 0.5, "h": 0.2}
bsdf = mi.load_dict(SPEC)
bad = False
for mu in (float(np.cos(np.pi / 2)), 1e-4):
    s = float(np.sqrt(1 - mu * mu))
    si = dr.zeros(mi.SurfaceInteraction3f, 2)
    si.wi = mi.Vector3f(s, 0.0, mu)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    value = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(-s, 0.0, mu)))[0, 0]
    print(f"cosθi = cosθo = {mu:.3g}, forward (φ = π): eval = {value}")
    bad |= mu < 1e-6 and bool(np.isnan(value))

# the terms of eval_mu in float32 at e = i = atan(tan θ) for cosθ = 6.1e-17, φ = π
f = np.float32
tan_theta = np.tan(f(np.radians(20.0)))
x = np.arctan(f(1.0) / f(np.cos(np.pi / 2)))
e1 = np.exp(f(-2.0) * f(1 / np.pi) / tan_theta / np.tan(x))
e2 = np.exp(f(-1 / np.pi) / tan_theta ** 2 / np.tan(x) ** 2)
print(f"float32: e = i = {x!r}, tan = {np.tan(x)!r}, E1 = {e1!r}, E2 = {e2!r}: numerator "
      f"-E2 + E2 = {-e2 + e2!r}, denominator 2 - E1 - E1 = {f(2) - e1 - e1!r}")
sys.exit(1 if bad else 0)
