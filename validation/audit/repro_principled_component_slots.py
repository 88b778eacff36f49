"""
Reproducer: ``principled``'s ``sample()`` reports fixed slot numbers in
``bs.sampled_component`` where the API expects the index of the lobe in its own component list
(Mitsuba 3.9.1, src/bsdfs/principled.cpp).

``initialize_lobes()`` (lines 240-269) pushes only the lobes the material has, in this order:
diffuse, [clearcoat], [spec_trans], main specular. ``sample()`` writes main specular 3 (line 423),
spec_trans 2 (line 440), clearcoat 1 (line 463), diffuse 0 (line 480). The API numbers components
0 .. component_count() - 1 (``flags(i)`` asserts ``i < m_components.size()``,
include/mitsuba/render/bsdf.h:550-554; ``sampled_component`` is "the component index that was
sampled"), so a specular sample of the default material (2 lobes) reports 3, out of range, and a
transmission sample with spec_trans > 0 and no clearcoat reports 2, whose flags are the main
specular's GlossyReflection.

The reproducer counts, for each configuration of the audit that fails its consistency check,
the successful samples whose component is out of range or whose flags lack the sampled type;
then it maps each fixed slot to the index ``initialize_lobes()`` gives that lobe (the fix) and
counts again: every count drops to 0, so the slot numbers alone explain the audit's numbers.
principledthin, whose lobe list (diffuse, diffuse transmission, [spec_trans], main specular)
matches its slots 0-3 whenever the specular lobes are sampled (spec_trans > 0), is shown to be
consistent with and without spec_trans.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
N = 100_000
PRINCIPLED = [{}, {"roughness": 0.1}, {"metallic": 1.0, "roughness": 0.3}, {"anisotropic": 0.8},
              {"clearcoat": 1.0, "sheen": 1.0}, {"spec_trans": 0.7, "roughness": 0.3}]
THIN = [{}, {"spec_trans": 0.6, "roughness": 0.3}]


def samples(bsdf, wi=(0.6, 0.0, 0.8), seed=0):
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.wi = mi.Vector3f(*wi)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    u = np.random.default_rng(seed).random((N, 3), dtype=np.float32)
    bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[:, 0]),
                        mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    ok = np.array(mi.unpolarized_spectrum(w))[0] > 0
    comp = np.broadcast_to(np.array(bs.sampled_component, dtype=np.int64), ok.shape)[ok]
    kind = np.broadcast_to(np.array(bs.sampled_type, dtype=np.int64), ok.shape)[ok]
    return comp, kind


def inconsistent(bsdf, comp, kind):
    """(out of range, sampled type not in flags(component)) among successful samples."""
    count = bsdf.component_count()
    flags = np.array([int(bsdf.flags(i)) for i in range(count)] + [0], dtype=np.int64)
    out = comp >= count
    wrong = ~out & ((kind & ~flags[np.minimum(comp, count)]) != 0)
    return int(out.sum()), int(wrong.sum())


def list_index(cfg, slot):
    """The index initialize_lobes() gives the lobe that sample() calls ``slot``."""
    clearcoat, trans = bool(cfg.get("clearcoat")), bool(cfg.get("spec_trans"))
    order = [0] + ([1] if clearcoat else []) + ([2] if trans else []) + [3]
    return np.searchsorted(np.array(order), slot)


def main():
    bad = False
    print("principled: successful samples out of range | type not in flags(component), "
          "as shipped -> with the slots mapped to the lobe list")
    for cfg in PRINCIPLED:
        bsdf = mi.load_dict(dict(type="principled", **cfg))
        comp, kind = samples(bsdf)
        out, wrong = inconsistent(bsdf, comp, kind)
        fixed = inconsistent(bsdf, list_index(cfg, comp), kind)
        bad |= out + wrong > 0
        print(f"   {cfg or 'default'}: component_count() = {bsdf.component_count()}, slots "
              f"{np.unique(comp).tolist()}: {out} | {wrong} of {len(comp)} -> {fixed[0]} | "
              f"{fixed[1]}{'   <-- defect' if out + wrong else ''}")
    print("principledthin (its slots are its list's indices): as shipped")
    for cfg in THIN:
        bsdf = mi.load_dict(dict(type="principledthin", **cfg))
        comp, kind = samples(bsdf)
        out, wrong = inconsistent(bsdf, comp, kind)
        print(f"   {cfg or 'default'}: component_count() = {bsdf.component_count()}, slots "
              f"{np.unique(comp).tolist()}: {out} | {wrong} of {len(comp)}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
