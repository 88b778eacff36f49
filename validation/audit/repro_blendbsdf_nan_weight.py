"""
Reproducer: ``blendbsdf``'s ``sample()`` returns a NaN weight (and a NaN ``bs.pdf``) where its
nested BSDF's sample *failed* (Mitsuba 3.9.1, ``src/bsdfs/blendbsdf.cpp``, ``BlendBSDF::sample``).

A BSDF whose sample fails returns weight 0 and leaves the other fields of ``BSDFSample3f``
undefined: ``roughconductor`` computes ``bs.wo`` and ``bs.pdf`` on every lane and only masks the
weight, so for a back-facing ``wi`` (cos θi < 0) or ``wi`` on the horizon they are NaN. That is
allowed. ``BlendBSDF::sample`` (lines 146-155, and 134-144 for the first BSDF) then *uses* those
undefined fields: ``pdf_weighted = weight * bs1.pdf + ...`` (NaN) and
``result_weighted = (weight * result1 * bs1.pdf + (1 - weight) * eval0) * select(pdf_weighted > 0,
rcp(pdf_weighted), 0)`` = (0 * NaN + ...) * 0 = NaN. The blend turns a failed sample (weight 0)
into a NaN weight. ``diffuse`` and ``roughconductor`` alone return weight 0 for the same inputs.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np


def main():
    mi.set_variant("llvm_ad_rgb")
    blend = mi.load_dict({"type": "blendbsdf", "weight": 0.3, "a": {"type": "diffuse"},
                          "b": {"type": "roughconductor", "alpha": 0.2}})
    rc = mi.load_dict({"type": "roughconductor", "alpha": 0.2})
    # One vectorised call, as a renderer makes it: lanes facing the surface and lanes behind it
    # (a one-sided surface seen from behind) together. (A call whose lanes all fail returns
    # early in roughconductor and hides the problem.)
    wis = {"front-facing (cos θi = 0.95)": (0.3, 0.0, 0.95),
           "tangent (cos θi = 0)": (1.0, 0.0, 0.0),
           "back-facing (cos θi = -0.94)": (0.3, 0.2, -0.9),
           "back-facing (cos θi = -1)": (0.0, 0.0, -1.0)}
    # sample1 = 0.1 <= weight 0.3 picks the roughconductor; 0.9 picks the diffuse BSDF
    rows = [(label, np.asarray(wi) / np.linalg.norm(wi), u1) for label, wi in wis.items()
            for u1 in (0.1, 0.9)]
    m = len(rows)
    si = dr.zeros(mi.SurfaceInteraction3f, m)
    si.wi = mi.Vector3f(*(mi.Float([float(r[1][k]) for r in rows]) for k in range(3)))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    ctx = mi.BSDFContext()
    u1 = mi.Float([r[2] for r in rows])
    u2 = mi.Point2f(dr.full(mi.Float, 0.3, m), dr.full(mi.Float, 0.6, m))
    bs, w = blend.sample(ctx, si, u1, u2)
    bs_rc, w_rc = rc.sample(ctx, si, u1, u2)
    w = np.array(mi.unpolarized_spectrum(w))[0]
    w_rc = np.array(mi.unpolarized_spectrum(w_rc))[0]
    pdf, pdf_rc = np.array(bs.pdf), np.array(bs_rc.pdf)
    bad = False
    for i, (label, _, s1) in enumerate(rows):
        print(f"wi {label:29s} sample1 = {s1}: blendbsdf weight = {w[i]:<9.6g} bs.pdf = "
              f"{pdf[i]:<9.6g} | roughconductor alone: weight = {w_rc[i]:<9.6g} bs.pdf = "
              f"{pdf_rc[i]:.6g}{'' if w_rc[i] else ' (failed sample: undefined)'}")
    bad |= bool(np.isnan(w).any())

    # How often, for random back-facing directions (a one-sided surface seen from behind)
    n = 100_000
    rng = np.random.default_rng(0)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[:, 2] = -np.abs(v[:, 2])
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*(mi.Float(v[:, k].astype(np.float32)) for k in range(3)))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    _, w = blend.sample(mi.BSDFContext(), si, mi.Float(rng.random(n).astype(np.float32)),
                        mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32)) for _ in range(2))))
    nan = np.isnan(np.array(mi.unpolarized_spectrum(w))[0])
    print(f"random back-facing wi: {nan.mean():.1%} of the blendbsdf's samples have a NaN weight "
          f"(expected 0: every one of them fails)")
    bad |= bool(nan.any())
    print("DEFECT PRESENT" if bad else "ok: failed samples have weight 0")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
