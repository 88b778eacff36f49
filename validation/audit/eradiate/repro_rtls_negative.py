"""
rtls of eradiate-mitsuba 0.5.0: negative values and negative sample weights with its defaults
(f_iso 0.209741, f_vol 0.081384, f_geo 0.004140, h/b = 2, b/r = 1): the kernel-driven model
f = (f_iso + f_vol K_vol + f_geo K_geo)/π is a linear fit (Lucht, Schaaf & Strahler 2000,
https://doi.org/10.1109/36.841980, eqs. 37-41) and the Li-Sparse-Reciprocal kernel K_geo is
negative and grows like -sec θ towards grazing, so the sum goes below zero. The same formula
in float64 (below, written from the paper) is negative at the same pairs: a property of the
model, not of the implementation.

Run in the fork's environment:
.venv-eradiate/bin/python validation/audit/eradiate/repro_rtls_negative.py
Exits 1 while Eradiate's rtls returns a negative eval or sample weight.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
F_ISO, F_VOL, F_GEO = 0.209741, 0.081384, 0.004140


def interaction(wi):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = mi.Vector3f(*(np.ascontiguousarray(wi[:, k], dtype=np.float32) for k in range(3)))
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    return si


def model_f(wi, wo):
    """RTLS in float64: Ross-Thick (eq. 38) and Li-Sparse-Reciprocal (eqs. 39-41), h/b=2, b/r=1."""
    ti, to = np.arccos(wi[:, 2]), np.arccos(wo[:, 2])
    phi = np.arctan2(wi[:, 1], wi[:, 0]) - np.arctan2(wo[:, 1], wo[:, 0])
    cos_xi = np.sum(wi * wo, axis=1)
    xi = np.arccos(np.clip(cos_xi, -1, 1))
    k_vol = ((np.pi / 2 - xi) * cos_xi + np.sin(xi)) / (np.cos(ti) + np.cos(to)) - np.pi / 4
    tan_i, tan_o = np.tan(ti), np.tan(to)
    sec = 1 / np.cos(ti) + 1 / np.cos(to)
    d2 = np.maximum(tan_i ** 2 + tan_o ** 2 - 2 * tan_i * tan_o * np.cos(phi), 0)
    cos_t = np.clip(2.0 * np.sqrt(d2 + (tan_i * tan_o * np.sin(phi)) ** 2) / sec, -1, 1)
    t = np.arccos(cos_t)
    k_geo = (t - np.sin(t) * cos_t) * sec / np.pi - sec + \
        0.5 * (1 + cos_xi) / (np.cos(ti) * np.cos(to))
    return (F_ISO + F_VOL * k_vol + F_GEO * k_geo) / np.pi


bsdf = mi.load_dict({"type": "rtls"})
# normal incidence, viewed backwards at θo = 80°, 85°, 89°, 89.9°
theta = np.radians([80.0, 85.0, 89.0, 89.9])
wo = np.stack([-np.sin(theta), 0 * theta, np.cos(theta)], 1)
wi = np.tile([0.0, 0.0, 1.0], (len(theta), 1))
value = np.array(bsdf.eval(mi.BSDFContext(), interaction(wi),
                           mi.Vector3f(*wo.T.astype(np.float32))))
ours = value[0] / wo[:, 2]  # eval = f cosθo
ref = model_f(wi, wo)
for t, a, b in zip(np.degrees(theta), ours, ref):
    print(f"θi = 0°, θo = {t:5.1f}° backwards: Eradiate f = {a: .6g}, "
          f"float64 model f = {b: .6g}")

# sample(): the weight f cosθo / pdf at grazing incidence
rng = np.random.default_rng(0)
n = 100_000
wi = np.tile([np.sin(np.radians(89.5)), 0.0, np.cos(np.radians(89.5))], (n, 1))
bs, weight = bsdf.sample(mi.BSDFContext(), interaction(wi), mi.Float(rng.random(n)),
                         mi.Point2f(rng.random(n), rng.random(n)))
weight = np.array(weight)[0]
print(f"θi = 89.5°: {np.sum(weight < 0)} of {n} sample weights negative, min {weight.min():.5g}")
negative = bool(np.any(ours < 0) or np.any(weight < 0))
print("model agrees in sign:", bool(np.all(np.sign(ours) == np.sign(ref))))
sys.exit(1 if negative else 0)
