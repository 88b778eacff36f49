"""
Reproducer: ``principled`` and ``pplastic`` report component indices that do not match their
component lists (Mitsuba 3.9.1).

The BSDF API numbers components 0 .. component_count() - 1: ``flags(i)`` returns component i's
flags (``Assert(i < m_components.size())``, include/mitsuba/render/bsdf.h:550-554),
``BSDFSample3f::sampled_component`` is "the component index that was sampled", and
``BSDFContext::component`` selects one component by that index (``BSDFContext::is_enabled``).
``dielectric``, ``roughdielectric``, ``blendbsdf`` and ``mask`` follow that numbering.

  A. ``principled`` (src/bsdfs/principled.cpp) pushes only the lobes it has into m_components
     (``initialize_lobes``, lines 240-269: diffuse, [clearcoat], [spec_trans], main specular),
     but ``sample()`` writes fixed slot numbers (lines 423, 440, 463, 480: main specular 3,
     spec_trans 2, clearcoat 1, diffuse 0). Default: 2 components, the specular samples say 3;
     with spec_trans: the transmission samples say 2, whose flags are GlossyReflection.
  B. ``principled`` never consults ``ctx.component`` (nor ``ctx.type_mask``): selecting one
     component changes nothing in sample() or eval().
  C. ``principled``/``principledthin``: ``parameters_changed()`` calls ``initialize_lobes()``
     again without clearing m_components: component_count() grows by its size at every update.
  D. ``pplastic`` (src/bsdfs/pplastic.cpp, lines 209-210) declares ONE component (all flags), but
     its sample()/eval()/pdf() use two: index 0 specular, 1 diffuse (``ctx.is_enabled(...,
     0/1)``, lines 251-252, 278-285): sampled_component = 1 is out of range, and ``blendbsdf``,
     which routes ``ctx.component`` by its children's component_count(), cannot reach the diffuse
     lobe of a pplastic child.

Uses only mitsuba, drjit and numpy. Exits 1 while any of A-D is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
N = 100_000


def interaction(wi, n):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f([float(x) for x in wi])
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def sample(bsdf, ctx, seed=0, wi=(0.6, 0.0, 0.8)):
    rng = np.random.default_rng(seed)
    u = rng.random((N, 3), dtype=np.float32)
    bs, w = bsdf.sample(ctx, interaction(wi, N), mi.Float(u[:, 0]),
                        mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    ok = np.array(mi.unpolarized_spectrum(w))[0] > 0
    return (np.array(bs.sampled_component)[ok].astype(np.int64),
            np.array(bs.sampled_type)[ok].astype(np.int64), np.array(bs.wo.z)[ok])


def consistency(bsdf):
    """(out of range, type not in flags(component)) counts of successful samples."""
    comp, typ, _ = sample(bsdf, mi.BSDFContext())
    count = bsdf.component_count()
    out = comp >= count
    flags = np.array([int(bsdf.flags(i)) for i in range(count)], dtype=np.int64)
    wrong = np.where(out, True, (typ & ~flags[np.minimum(comp, count - 1)]) != 0)
    return int(out.sum()), int(wrong.sum()), count, np.unique(comp).tolist()


def main():
    bad = False
    print("A/D. sampled_component against component_count() and flags(sampled_component)")
    for cfg in ({"type": "principled"}, {"type": "principled", "clearcoat": 1.0},
                {"type": "principled", "spec_trans": 0.7, "roughness": 0.3},
                {"type": "principledthin"}, {"type": "pplastic"}):
        out, wrong, count, comps = consistency(mi.load_dict(cfg))
        bad |= out > 0 or wrong > 0
        print(f"   {cfg}: component_count() = {count}, sampled_component in {comps}: "
              f"{out} out of range, {wrong} whose sampled_type is not in flags(component) "
              f"(of {N} samples)")

    print("B. principled with ctx.component = 0 (its diffuse component)")
    b = mi.load_dict({"type": "principled"})
    ctx = mi.BSDFContext()
    ctx.component = 0
    comp, typ, _ = sample(b, ctx)
    not_diffuse = int((typ & int(mi.BSDFFlags.DiffuseReflection) == 0).sum())
    si = interaction((0.6, 0.0, 0.8), 1)
    e_all = float(np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(-0.6, 0, 0.8)))[0][0])
    e_0 = float(np.array(b.eval(ctx, si, mi.Vector3f(-0.6, 0, 0.8)))[0][0])
    bad |= not_diffuse > 0 or e_all == e_0
    print(f"   {not_diffuse} of {len(typ)} samples are not DiffuseReflection; eval at the mirror "
          f"direction: all components {e_all:.5f}, component 0 only {e_0:.5f}")

    print("C. component_count() after parameter updates (same parameters)")
    for t in ("principled", "principledthin"):
        b = mi.load_dict({"type": t})
        params = mi.traverse(b)
        counts = [b.component_count()]
        for _ in range(2):
            params["roughness.value"] = 0.5
            params.update()
            counts.append(b.component_count())
        bad |= counts[-1] != counts[0]
        print(f"   {t}: {counts}")

    print("D. blendbsdf(pplastic, diffuse): ctx.component = 1 (pplastic's own diffuse index)")
    blend = mi.load_dict({"type": "blendbsdf", "weight": 0.5,
                          "a": {"type": "pplastic"}, "b": {"type": "diffuse"}})
    p = mi.load_dict({"type": "pplastic"})
    ctx = mi.BSDFContext()
    ctx.component = 1
    si = interaction((0.6, 0.0, 0.8), 1)
    wo = mi.Vector3f(0.0, 0.6, 0.8)
    print(f"   blend component count {blend.component_count()} (pplastic contributes "
          f"{p.component_count()}); pplastic.eval(ctx.component=1) = "
          f"{float(np.array(p.eval(ctx, si, wo))[0][0]):.5f} (its diffuse lobe), "
          f"blend.eval(ctx.component=1) = {float(np.array(blend.eval(ctx, si, wo))[0][0]):.5f} "
          f"(the diffuse child x 0.5)")
    bad |= p.component_count() < 2
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
