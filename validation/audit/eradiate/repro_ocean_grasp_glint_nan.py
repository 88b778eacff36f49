"""
ocean_grasp of eradiate-mitsuba 0.5.0 returns NaN for a direction at the surface normal whose
float32 length rounds above 1 (z = 1.0000001, the float after 1): its Smith term
lambda(v, sigma) (ocean_grasp.cpp v0.5.0 lines 241-249) takes sqrt(1 - v.z * v.z) unclamped,
which is sqrt of a negative number there, so G (line 226) and the glint (line 230) are NaN.
At z = 1 exactly the same pair is finite. sample() produces such directions itself: its
reflect(wi, H) (line 322) of a facet normal is rounded to a length just above 1, and with
wind 5 m/s, wi at 15° and the random numbers below the sample weight is NaN (1 of 10⁶
samples in the audit's albedo estimate, which is then NaN; its energy check fails on it).

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_ocean_grasp_glint_nan.py
Exits 1 while eval or the sample weight is NaN there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "ocean_grasp", "wavelength": 550.0, "wind_speed": 5.0})
t = np.radians(15.0)
wi = [float(np.sin(t)), 0.0, float(np.cos(t))]
above_one = float(np.nextafter(np.float32(1), np.float32(2)))
wo = np.array([[0, 0, 1.0], [0, 0, above_one]], dtype=np.float32)
si = dr.zeros(mi.SurfaceInteraction3f, len(wo))
si.wi = mi.Vector3f(*wi)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
value = np.array(bsdf.eval(mi.BSDFContext(), si,
                           mi.Vector3f(*(np.ascontiguousarray(wo[:, k]) for k in range(3)))))
print(f"eval at wi = 15°, wo = (0, 0, 1): {value[0, 0]}; wo = (0, 0, {above_one!r}): "
      f"{value[0, 1]}")
one = dr.zeros(mi.SurfaceInteraction3f, 1)
one.wi = mi.Vector3f(*wi)
one.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
bs, weight = bsdf.sample(mi.BSDFContext(), one, mi.Float(0.46289155),
                         mi.Point2f(0.14240177, 0.50013208))
bs_wo, weight = np.array(bs.wo, dtype=np.float64).ravel(), np.array(weight).ravel()
print(f"sample(): wo = {bs_wo.tolist()} (length - 1 = {np.linalg.norm(bs_wo) - 1:.2g}), "
      f"component {bs.sampled_component[0]}, pdf {bs.pdf[0]:.6g}, weight {weight[0]}")
sys.exit(1 if np.isnan(value[0, 1]) or np.isnan(weight[0]) else 0)
