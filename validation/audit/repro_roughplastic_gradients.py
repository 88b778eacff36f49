#!/usr/bin/env python3
"""
Standalone reproducer: roughplastic's derivatives in ``alpha`` and ``eta`` (both marked
differentiable by ``traverse``) miss the diffuse term's dependence on them.

``parameters_changed`` (src/bsdfs/roughplastic.cpp, line 235 at v3.9.1) computes the Fresnel
transmittance tables of the diffuse term, ``m_external_transmittance`` and
``m_internal_reflectance``, from ``dr::slice(m_eta)`` and ``dr::slice(m_alpha)``: scalars,
which carry no derivative. So ∂eval/∂alpha and ∂eval/∂eta by automatic differentiation count
the specular lobe and the 1/η² factor only. Below: forward-mode AD against central
differences of eval at one pair of directions, where the diffuse term dominates. Exits 1
while the two disagree by more than 10 % (the defect is present), 0 once they agree.

    python validation/audit/repro_roughplastic_gradients.py
"""

import sys

import drjit as dr
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

bsdf = mi.load_dict({"type": "roughplastic", "distribution": "ggx", "alpha": 0.5})
params = mi.traverse(bsdf)
si = dr.zeros(mi.SurfaceInteraction3f)
si.wi = dr.normalize(mi.Vector3f(0.3, 0.1, 0.9))
wo = dr.normalize(mi.Vector3f(-0.6, 0.2, 0.5))
ctx = mi.BSDFContext()


def value(key, x):
    params[key] = x
    params.update()
    return bsdf.eval(ctx, si, wo)[0]


present = False
for key, x0 in (("alpha", 0.5), ("eta", 1.49)):
    t = mi.Float(0.0)
    dr.enable_grad(t)
    v = value(key, mi.Float(x0) + t)
    dr.forward(t)
    ad = dr.grad(v)[0]
    h = 1e-3
    fd = (value(key, mi.Float(x0 + h))[0] - value(key, mi.Float(x0 - h))[0]) / (2 * h)
    print(f"d eval / d {key}: AD {ad:.6g}, central differences {fd:.6g}")
    value(key, mi.Float(x0))
    present |= abs(ad - fd) > 0.1 * abs(fd)
sys.exit(1 if present else 0)
