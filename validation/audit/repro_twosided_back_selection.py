"""
Reproducer: ``twosided`` maps ``ctx.component`` wrongly on the back side (Mitsuba 3.9.1,
src/bsdfs/twosided.cpp), so selecting a lobe of one side samples and evaluates the other.

Its component list is the front BSDF's n0 lobes (FrontSide) followed by the back BSDF's
(BackSide; the front BSDF again when only one is nested). For a back-facing wi, a correct
``twosided`` enables back lobe c of the nested BSDF for ``ctx.component = n0 + c`` and nothing for
``ctx.component < n0``. Instead:

* one nested BSDF (lines 124-127, 159-162, 194-197, 232-235): ``ctx.component`` is passed on
  unchanged, so ``ctx.component = c < n0`` (a front lobe) samples and evaluates the back side and
  the back lobes ``n0 + c`` sample and evaluate nothing;
* two nested BSDFs (lines 136-139, 170-172, 205-207, 243-245): ``ctx.component -= n0`` in
  unsigned arithmetic, so the last front lobe, ``ctx.component = n0 - 1``, becomes
  ``(uint32_t) -1``, which means "every component": the whole back BSDF.

The reproducer evaluates and samples twosided at back-facing wi with each ``ctx.component`` and
compares with the nested BSDF called as the code above calls it (with the flipped wi and the
component it passes on) and as a correct mapping would (nothing for a front lobe, back lobe
c - n0 otherwise): twosided matches the former exactly, so this mapping alone explains the
audit's numbers.

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
N = 20_000
NONE = 0xFFFFFFFE    # a component index no nested BSDF has
CONFIGS = [({"type": "diffuse"}, {"type": "roughconductor", "alpha": 0.3}),
           ({"type": "diffuse"}, None)]


def interaction(flip):
    rng = np.random.default_rng(0)
    theta, phi = np.radians(np.resize([20.0, 60.0], N)), rng.random(N) * 2 * np.pi
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.wi = mi.Vector3f(mi.Float(np.sin(theta) * np.cos(phi)),
                        mi.Float(np.sin(theta) * np.sin(phi)),
                        mi.Float(np.cos(theta) * (1 if flip else -1)))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def run(bsdf, component, flip):
    """(fraction of successful samples, mean eval at mirrored directions) with ctx.component."""
    ctx = mi.BSDFContext()
    ctx.component = component
    si = interaction(flip)
    u = np.random.default_rng(1).random((N, 3), dtype=np.float32)
    _, w = bsdf.sample(ctx, si, mi.Float(u[:, 0]), mi.Point2f(mi.Float(u[:, 1]),
                                                             mi.Float(u[:, 2])))
    wo = mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z)
    value = np.array(bsdf.eval(ctx, si, wo))[0]
    return float(np.mean(np.array(w)[0] > 0)), float(value.mean())


def main():
    bad = False
    for front, back in CONFIGS:
        ts = mi.load_dict({"type": "twosided", "a": front, "b": back} if back else
                          {"type": "twosided", "bsdf": front})
        nested = mi.load_dict(back or front)
        n0 = mi.load_dict(front).component_count()
        name = f"twosided({front['type']}{', ' + back['type'] if back else ''})"
        print(f"{name}, back-facing wi: (successful samples, mean eval) per ctx.component")
        for c in range(ts.component_count()):
            passed_on = (c - n0) % 2 ** 32 if back else c          # what the code passes on
            correct = c - n0 if c >= n0 else NONE
            got = run(ts, c, flip=False)
            as_coded = run(nested, passed_on, flip=True)
            fixed = run(nested, correct, flip=True)
            wrong = not np.allclose(got, fixed)
            bad |= wrong
            print(f"   ctx.component = {c} ({'front' if c < n0 else 'back'} lobe): twosided "
                  f"{got[0]:.3f}, {got[1]:.4f}; nested BSDF with the component the code passes "
                  f"on ({passed_on}) {as_coded[0]:.3f}, {as_coded[1]:.4f}; with the correct one "
                  f"{fixed[0]:.3f}, {fixed[1]:.4f}{'   <-- defect' if wrong else ''}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
