"""
Reproducer: ``pplastic`` declares one component but samples, evaluates and selects two
(Mitsuba 3.9.1, src/bsdfs/pplastic.cpp).

The constructor pushes a single component that carries every flag (``m_components.push_back(
m_flags)``, lines 209-210), while ``sample()``, ``eval()`` and ``pdf()`` treat index 0 as the
specular lobe and index 1 as the diffuse one (``ctx.is_enabled(GlossyReflection, 0)`` and
``ctx.is_enabled(DiffuseReflection, 1)``, lines 251-252, 299-300, 443-444; ``sampled_component``
= 0 or 1, lines 278 and 284). The API numbers components 0 .. component_count() - 1, so every
diffuse sample reports an index out of range; and ``blendbsdf``, which routes ``ctx.component``
by its children's component_count(), cannot select pplastic's diffuse lobe.

The reproducer counts the successful samples whose component is out of range, then checks them
against the two components the plugin's methods use (GlossyReflection | FrontSide and
DiffuseReflection | FrontSide): with those declared, every sample is consistent, so the single
declared component alone explains the audit's count. It also shows the blendbsdf consequence.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_spectral_polarized")
N = 100_000
F = mi.BSDFFlags


def interaction(n, wi=(0.6, 0.0, 0.8)):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*wi)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.wavelengths = dr.zeros(mi.UnpolarizedSpectrum, n) + 550.0
    return si


def main():
    p = mi.load_dict({"type": "pplastic"})
    u = np.random.default_rng(0).random((N, 3), dtype=np.float32)
    bs, w = p.sample(mi.BSDFContext(), interaction(N), mi.Float(u[:, 0]),
                     mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    ok = np.array(mi.unpolarized_spectrum(w))[0] > 0
    comp = np.array(bs.sampled_component, dtype=np.int64)[ok]
    kind = np.array(bs.sampled_type, dtype=np.int64)[ok]
    count = p.component_count()
    out = int((comp >= count).sum())
    used = np.array([int(F.GlossyReflection | F.FrontSide), int(F.DiffuseReflection | F.FrontSide)])
    fixed = int(((kind & ~used[np.minimum(comp, 1)]) != 0).sum())
    print(f"component_count() = {count}; successful samples report components "
          f"{np.unique(comp).tolist()}: {out} of {len(comp)} out of range; against the two "
          f"components the methods use: {fixed} inconsistent")
    ctx = mi.BSDFContext()
    ctx.component = 1
    si, wo = interaction(1), mi.Vector3f(0.0, 0.6, 0.8)
    blend = mi.load_dict({"type": "blendbsdf", "weight": 0.5, "a": {"type": "pplastic"},
                          "b": {"type": "diffuse"}})
    own = float(np.array(mi.unpolarized_spectrum(p.eval(ctx, si, wo)))[0][0])
    routed = float(np.array(mi.unpolarized_spectrum(blend.eval(ctx, si, wo)))[0][0])
    print(f"ctx.component = 1: pplastic's own diffuse lobe {own:.5f}; blendbsdf(pplastic, "
          f"diffuse) gives {routed:.5f} (its diffuse child x 0.5)")
    bad = out > 0
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
