"""
Reproducer: ``principledthin``'s ``pdf()`` computes its mask of valid lanes but never applies
it to the result (Mitsuba 3.9.1, src/bsdfs/principledthin.cpp), so at ``cos θi = 0`` it returns
a nonzero pdf where ``eval()`` is 0, and NaN once its specular lobes exist (``spec_trans > 0``).

``PrincipledThin::pdf`` (lines 600-705) sets ``active &= cos_theta_i != 0`` (line 606) and
returns 0 early only if ``dr::none_or<false>(active)`` (lines 608-609), which for a JIT array is
``false`` without looking at it (scalar variants do take it); the result is returned unmasked
(line 704). With
``spec_trans > 0`` it adds the specular lobes' ``MicrofacetDistribution::pdf(wi, wh)`` (lines
688-692), the visible-normal density D(m) G1(wi, m) (wi·m) / cos θi, which is 0/0 at cos θi = 0.
``eval()`` masks its value with ``active`` and returns 0 there; the lobes without spec_trans
have no division by cos θi, so only configurations with spec_trans > 0 show it.
(roughplastic's pdf has the same missing final mask: repro_roughplastic_pdf_mask.py.)

The reproducer evaluates pdf() and eval() at wi = (1, 0, 0) (cos θi = 0 exactly) beside an
ordinary lane, for the audit's principledthin configurations; then it shows the NaN's origin
(the GGX visible-normal pdf at that wi and half vector) and that applying the mask
(``select(cos θi != 0, pdf, 0)``, as the early return intends) leaves 0: the missing mask alone
explains the audit's positivity and stability records (their NaN) and the nonzero pdf without
spec_trans, which no check flags (principledthin declares transmission lobes).

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
CONFIGS = [{}, {"roughness": 0.1, "diff_trans": 0.5}, {"spec_trans": 0.6, "roughness": 0.3},
           {"spec_trans": 0.4, "anisotropic": 0.5, "spec_tint": 0.5, "flatness": 0.5,
            "sheen": 1.0, "sheen_tint": 0.5}]


def lanes(wis):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wis))
    si.wi = mi.Vector3f(*(mi.Float([w[k] for w in wis]) for k in range(3)))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def main():
    bad = False
    wo = mi.Vector3f(0, 0, 1)
    print("pdf() and eval() at wi = (1, 0, 0) (cos θi = 0) beside wi = (0.6, 0, 0.8), "
          "wo = (0, 0, 1)")
    for cfg in CONFIGS:
        b = mi.load_dict(dict(type="principledthin", **cfg))
        si = lanes([(1.0, 0.0, 0.0), (0.6, 0.0, 0.8)])
        pdf = np.array(b.pdf(mi.BSDFContext(), si, wo))
        value = np.array(b.eval(mi.BSDFContext(), si, wo))[0]
        alone = float(np.array(b.pdf(mi.BSDFContext(), lanes([(1.0, 0.0, 0.0)]), wo))[0])
        masked = np.where(np.array([0.0, 0.8]) != 0, pdf, 0.0)
        nan = bool(np.isnan(pdf[0]) or pdf[0] != 0)
        bad |= nan
        print(f"   {cfg or 'default'}: pdf {pdf.tolist()}, eval {value.tolist()}; the cos θi = 0 "
              f"lane alone (no early return in JIT) {alone}; with the mask applied "
              f"{masked.tolist()}{'   <-- defect' if nan else ''}")
    wi, wh = mi.Vector3f(1, 0, 0), dr.normalize(mi.Vector3f(1, 0, 1))
    distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, 0.09, 0.09)
    print(f"origin of the NaN: GGX (α = 0.09) visible-normal pdf(wi = (1, 0, 0), wh = "
          f"{np.round(np.array(wh)[:, 0], 4).tolist()}) = {float(np.array(distr.pdf(wi, wh))[0])} "
          f"(it divides by cos θi)")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
