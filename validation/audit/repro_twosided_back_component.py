"""
Reproducer: ``twosided`` reports, for a sample on the back side, the component index of its
nested BSDF, not the index of that lobe in its own component list (Mitsuba 3.9.1,
src/bsdfs/twosided.cpp).

The constructor (lines 89-100) lists the front BSDF's lobes (flags with FrontSide) followed by
the back BSDF's (flags with BackSide; the front BSDF again when only one is nested), so the back
lobe c of the nested BSDF is twosided's component n0 + c, n0 = component_count() of the front
BSDF. ``sample()`` hands back the nested sample unchanged on the back side: in the one-BSDF branch
(lines 124-127) and in the two-BSDF branch (lines 136-144, which shifts ``ctx.component`` down by
n0 on the way in but not ``bs.sampled_component`` up on the way out). A back-side sample therefore
reports a front lobe, whose flags lack BackSide and, for two different BSDFs, its type
(``blendbsdf`` has the same missing offset:
https://github.com/mitsuba-renderer/mitsuba2/issues/151).

The reproducer draws samples at front- and back-facing wi, counts the successful ones whose
component lacks the side of wi or the sampled type, then adds n0 to the component of every
back-side sample (the fix) and counts again: every count drops to 0, so the missing offset alone
explains the audit's numbers.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
N = 20_000
RC = {"type": "roughconductor", "alpha": 0.3}
CONFIGS = [({"type": "diffuse"}, RC), ({"type": "diffuse"}, None), (RC, None)]


def twosided(front, back):
    return mi.load_dict({"type": "twosided", "a": front, "b": back} if back else
                        {"type": "twosided", "bsdf": front})


def samples(bsdf, back, seed=0):
    rng = np.random.default_rng(seed)
    theta, phi = np.radians(np.resize([20.0, 60.0], N)), rng.random(N) * 2 * np.pi
    z = np.cos(theta) * (-1 if back else 1)
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.wi = mi.Vector3f(mi.Float(np.sin(theta) * np.cos(phi)), mi.Float(np.sin(theta) *
                                                                          np.sin(phi)), mi.Float(z))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    u = rng.random((N, 3), dtype=np.float32)
    bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(u[:, 0]),
                        mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
    ok = np.array(w)[0] > 0
    comp = np.broadcast_to(np.array(bs.sampled_component, dtype=np.int64), (N,))[ok]
    kind = np.broadcast_to(np.array(bs.sampled_type, dtype=np.int64), (N,))[ok]
    return comp, kind


def wrong(bsdf, comp, kind, back):
    """(component without the side of wi, component whose flags lack the sampled type)."""
    flags = np.array([int(bsdf.flags(c)) for c in range(bsdf.component_count())] + [0])
    f = flags[np.minimum(comp, len(flags) - 1)]
    side = int(mi.BSDFFlags.BackSide if back else mi.BSDFFlags.FrontSide)
    return int(((f & side) == 0).sum()), int(((kind & ~f) != 0).sum())


def main():
    bad = False
    for front, back in CONFIGS:
        bsdf = twosided(front, back)
        n0 = mi.load_dict(front).component_count()
        name = f"twosided({front['type']}{', ' + back['type'] if back else ''})"
        print(f"{name}: flags {[hex(int(bsdf.flags(c))) for c in range(bsdf.component_count())]}")
        for is_back in (False, True):
            comp, kind = samples(bsdf, is_back)
            side, kinds = wrong(bsdf, comp, kind, is_back)
            fixed = wrong(bsdf, comp + (n0 if is_back else 0), kind, is_back)
            bad |= side + kinds > 0
            print(f"   {'back' if is_back else 'front'}-facing wi: {len(comp)} samples report "
                  f"{np.unique(comp).tolist()}: {side} without the side's flag, {kinds} without "
                  f"the sampled type; with + {n0} on the back side: {fixed[0]}, {fixed[1]}"
                  f"{'   <-- defect' if side + kinds else ''}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
