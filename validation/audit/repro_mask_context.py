"""
Reproducer: ``mask``'s ``sample()`` inverts a context that selects only one of its two parts
(Mitsuba 3.9.1, ``src/bsdfs/mask.cpp``, ``MaskBSDF::sample``, lines 128-166).

``mask`` is the nested BSDF (weight = opacity) plus a Null pass-through component (the last
index). ``sample()`` computes ``sample_transmission = ctx.is_enabled(Null, null_index)`` and
``sample_nested``, and when only one of them is enabled overrides the opacity with

    if (sample_transmission != sample_nested)
        opacity = sample_transmission ? 1.f : 0.f;        // line 140

then picks the nested BSDF where ``sample1 < opacity``. This is inverted: with only the nested
BSDF enabled (``type_mask`` without ``Null``, or ``ctx.component`` = a nested component) the
opacity becomes 0 and *every* sample is the Null pass-through (``wo = -wi``, weight 1), a lobe
the context excluded; with only the Null component enabled the opacity becomes 1 and every
sample goes to the nested BSDF, which refuses it (weight 0). ``pdf()`` (lines 177-193) takes the
other reading: nested-only returns the nested pdf (sampling it with probability 1).

Expected, nested BSDF only (diffuse ρ = 0.5, opacity 0.4): no Null-typed sample, and a mean
weight equal to the integral of ``eval()`` in that context, 0.4 · 0.5 = 0.2. Null only: every
sample Null-typed, mean weight 1 - opacity = 0.6. The default context is right.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

OPACITY, RHO = 0.4, 0.5


def main():
    mi.set_variant("llvm_ad_rgb")
    mask = mi.load_dict({"type": "mask", "opacity": OPACITY, "bsdf": {"type": "diffuse"}})
    null, delta = int(mi.BSDFFlags.Null), int(mi.BSDFFlags.Delta)
    smooth = int(mask.flags()) & 0x1FF & ~delta
    n = 200_000
    rng = np.random.default_rng(0)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.3, 0.0, 0.9539392)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    u1 = mi.Float(rng.random(n).astype(np.float32))
    u2 = mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32)) for _ in range(2)))
    R = mi.TransportMode.Radiance
    cases = [  # label, context, expected Null-typed fraction, expected mean weight
        ("default context", mi.BSDFContext(), 1 - OPACITY, (1 - OPACITY) + OPACITY * RHO),
        ("type_mask without Null", mi.BSDFContext(R, smooth), 0.0, OPACITY * RHO),
        ("ctx.component = 0 (nested)", mi.BSDFContext(R, 0x1FF, 0), 0.0, OPACITY * RHO),
        ("ctx.component = 1 (Null)", mi.BSDFContext(R, 0x1FF, 1), 1.0, 1 - OPACITY),
    ]
    bad = False
    for label, ctx, want_null, want_mean in cases:
        bs, w = mask.sample(ctx, si, u1, u2)
        w = np.array(mi.unpolarized_spectrum(w), dtype=np.float64)[0]
        kind = np.array(bs.sampled_type, dtype=np.int64)
        kind = np.broadcast_to(kind, (n,)) if kind.size == 1 else kind
        is_null = ((kind & null) != 0) & (w > 0)
        err = w.std() / np.sqrt(n)
        wrong = (abs(is_null.mean() - want_null) > 0.01
                 or abs(w.mean() - want_mean) > 5 * err + 1e-3)
        print(f"{label:28s}: Null-typed samples {is_null.mean():.3f} (expected {want_null:.3f}), "
              f"mean weight {w.mean():.4f} (expected {want_mean:.4f})"
              + ("   <-- wrong" if wrong else ""))
        bad |= wrong
    print("DEFECT PRESENT" if bad else "ok: sample() honours the context")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
