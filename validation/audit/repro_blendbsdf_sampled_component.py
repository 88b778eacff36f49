"""
Reproducer: ``blendbsdf``'s ``sample()`` reports the *nested* component index of its second BSDF in
``bs.sampled_component``, not its own index (Mitsuba 3.9.1, ``src/bsdfs/blendbsdf.cpp``).

``BlendBSDF`` numbers its components as the first BSDF's, then the second's (constructor, lines
94-97), and it reads ``ctx.component`` that way: an index ``>= component_count(a)`` selects the
second BSDF, offset by ``component_count(a)`` (``sample``/``eval``/``pdf``/``eval_pdf``, lines
116-121, 167-172, 185-190, 205-209). But ``sample()`` copies the second BSDF's ``BSDFSample3f``
unchanged (lines 146-155), so a sample of ``b`` says ``sampled_component = 0``: the index of the
*first* BSDF's lobe. ``bs.sampled_type`` is then not among ``flags(bs.sampled_component)``, and
feeding the index back as ``ctx.component`` (to evaluate the lobe that was sampled) evaluates the
wrong lobe.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np


def main():
    mi.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict({"type": "blendbsdf", "weight": 0.3, "a": {"type": "diffuse"},
                         "b": {"type": "roughconductor", "alpha": 0.2}})
    print("components:", [str(bsdf.flags(i)) for i in range(bsdf.component_count())])

    n = 100_000
    rng = np.random.default_rng(0)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.3, 0.0, 0.9539392)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    ctx = mi.BSDFContext()
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n).astype(np.float32)),
                             mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32))
                                          for _ in range(2))))
    w = np.array(mi.unpolarized_spectrum(weight))[0]
    kind = np.array(bs.sampled_type, dtype=np.int64)
    comp = np.array(bs.sampled_component, dtype=np.int64)
    ok = w > 0
    glossy = ok & ((kind & int(mi.BSDFFlags.GlossyReflection)) != 0)
    flags_of = np.array([int(bsdf.flags(i)) for i in range(bsdf.component_count())])
    mismatch = ok & ((kind & ~flags_of[np.minimum(comp, len(flags_of) - 1)]) != 0)
    print(f"{int(ok.sum())} successful samples; {int(glossy.sum())} of them sampled the glossy "
          f"lobe of b, reported as component(s) {sorted(set(comp[glossy].tolist()))} "
          f"(blendbsdf's index of that lobe: 1)")
    print(f"samples whose sampled_type is not in flags(sampled_component): {int(mismatch.sum())}")

    # Re-evaluating "the lobe that was sampled" through ctx.component = bs.sampled_component
    i = int(np.flatnonzero(glossy)[0])
    one = dr.zeros(mi.SurfaceInteraction3f, 1)
    one.wi, one.n = mi.Vector3f(0.3, 0.0, 0.9539392), mi.Vector3f(0, 0, 1)
    one.sh_frame = mi.Frame3f(one.n)
    wo = mi.Vector3f(*(float(x) for x in np.array(bs.wo)[:, i]))
    lobe = mi.BSDFContext(mi.TransportMode.Radiance, 0x1FF, int(comp[i]))
    glossy_ctx = mi.BSDFContext(mi.TransportMode.Radiance, 0x1FF, 1)
    e_reported = float(mi.unpolarized_spectrum(bsdf.eval(lobe, one, wo))[0][0])
    e_glossy = float(mi.unpolarized_spectrum(bsdf.eval(glossy_ctx, one, wo))[0][0])
    print(f"glossy sample {i}: eval with ctx.component = bs.sampled_component ({comp[i]}) = "
          f"{e_reported:.6g} (the diffuse lobe); with ctx.component = 1 = {e_glossy:.6g}")

    bad = bool(mismatch.any())
    print("DEFECT PRESENT" if bad else "ok: sampled_component indexes blendbsdf's own components")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
