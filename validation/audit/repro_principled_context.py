"""
Reproducer: ``principled`` and ``principledthin`` ignore the lobe selection of the
``BSDFContext`` (Mitsuba 3.9.1, src/bsdfs/principled.cpp and principledthin.cpp: no
``ctx.is_enabled`` anywhere in ``sample()``, ``eval()``, ``pdf()`` or ``eval_pdf()``).

``BSDFContext::component`` (and ``type_mask``) select lobes: a BSDF that honours them returns,
with ``ctx.component = c``, only lobe c's samples and lobe c's value, so that the values of the
lobes selected one by one add up to the value of all lobes (``dielectric``, ``plastic``,
``roughplastic``, ``blendbsdf`` do; integrators and ``mi.chi2`` select lobes this way).

The reproducer shows, for the audit's configurations whose lobe check fails:

  A. ``eval()`` and ``sample()`` with ``ctx.component = c`` return exactly what they return in the
     default context, for every c (the selection is ignored);
  B. that alone predicts the lobe check's numbers: the sum over the components of the values
     selected one by one is ``component_count()`` times the value of all lobes, a relative gap
     of (count - 1) / count; and with ``ctx.component = c`` the samples reporting another
     component are those the default context reports with another component.

Unrelated to the numbering of ``sampled_component`` (repro_principled_component_slots.py):
principledthin numbers its samples right and still fails here.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
N = 20_000
CONFIGS = [("principled", {}), ("principled", {"clearcoat": 1.0, "sheen": 1.0}),
           ("principled", {"spec_trans": 0.7, "roughness": 0.3}),
           ("principledthin", {}), ("principledthin", {"roughness": 0.1, "diff_trans": 0.5}),
           ("principledthin", {"spec_trans": 0.6, "roughness": 0.3})]


def interaction(n, wi=(0.0, 0.0, 1.0)):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*wi)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def context(c=None):
    ctx = mi.BSDFContext()
    if c is not None:
        ctx.component = c
    return ctx


def sampled(bsdf, ctx):
    u = np.random.default_rng(0).random((N, 3), dtype=np.float32)
    bs, w = bsdf.sample(ctx, interaction(N), mi.Float(u[:, 0]),
                        mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    return (np.array(bs.wo), np.array(mi.unpolarized_spectrum(w)),
            np.broadcast_to(np.array(bs.sampled_component, dtype=np.int64), (N,)))


def main():
    bad = False
    rng = np.random.default_rng(1)
    v = rng.normal(size=(N, 3))
    wo = v / np.linalg.norm(v, axis=1, keepdims=True)
    wo_f = mi.Vector3f(*(mi.Float(wo[:, k].astype(np.float32)) for k in range(3)))
    for name, cfg in CONFIGS:
        bsdf = mi.load_dict(dict(type=name, **cfg))
        count = bsdf.component_count()
        whole = np.array(bsdf.eval(context(), interaction(N), wo_f))[0]
        parts = [np.array(bsdf.eval(context(c), interaction(N), wo_f))[0] for c in range(count)]
        same_eval = all(np.array_equal(p, whole) for p in parts)
        wo0, w0, comp0 = sampled(bsdf, context())
        same_sample = all(np.array_equal(sampled(bsdf, context(c))[0], wo0) and
                          np.array_equal(sampled(bsdf, context(c))[1], w0) for c in range(count))
        ignored = same_eval and same_sample
        bad |= ignored
        big = whole > 1e-3 * whole.max()
        gap = np.max(np.abs(whole[big] - sum(parts)[big]) / (count * whole[big]))
        ok0 = w0[0] > 0
        other = [int((ok0 & (comp0 != c)).sum()) for c in range(count)]
        print(f"{name} {cfg or 'default'}: {count} components; selection ignored by eval: "
              f"{same_eval}, by sample: {same_sample}{'   <-- defect' if ignored else ''}")
        print(f"   sum of the lobes one by one vs all lobes: max relative gap {gap:.4f} "
              f"(predicted by the ignored selection: {(count - 1) / count:.4f}); samples "
              f"reporting another component with ctx.component = 0..{count - 1}: {other}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
