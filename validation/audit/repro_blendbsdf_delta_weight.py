"""
Reproducer: ``blendbsdf``'s ``sample()`` weight is biased when one of the blended BSDFs has a Dirac
lobe (Mitsuba 3.9.1, ``src/bsdfs/blendbsdf.cpp``, ``BlendBSDF::sample``, lines 134-156).

Since "blendbsdf and blendphase: fix incorrect sampling weight" (2025), ``sample()`` returns the
one-sample-MIS weight (w·f_b + (1-w)·f_a) / (w·p_b + (1-w)·p_a) for a sample of either BSDF. For a
Dirac sample (``conductor``, ``dielectric``, ...) ``bs.pdf`` is not a density but the discrete
probability (1 for a perfect mirror) and the smooth BSDF's eval/pdf at the mirror direction are
finite densities, so the formula mixes a probability with densities: the mirror sample's weight
becomes (w·F + (1-w)·f_a cos) / (w + (1-w)·p_a) instead of F. The smooth BSDF can never produce
the mirror direction, so the correct weight of a Dirac sample chosen with probability w is F.

Expected directional albedo of blend(weight w, a = diffuse ρ, b = conductor with F = 1):
(1-w)·ρ + w. With w = 0.8, ρ = 0.5: 0.9 at every angle. ``sample()`` gives 0.870 at normal
incidence (-3.3 %).

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

W, RHO = 0.8, 0.5


def main():
    mi.set_variant("llvm_ad_rgb")
    bsdf = mi.load_dict({"type": "blendbsdf", "weight": W, "a": {"type": "diffuse"},
                         "b": {"type": "conductor"}})   # conductor: eta = 0, k = 1, so F = 1
    n = 2_000_000
    rng = np.random.default_rng(0)
    bad = False
    for theta in (0.0, 45.0, 80.0):
        t = np.radians(theta)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
        si.n = mi.Vector3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n).astype(np.float32)),
                            mi.Point2f(*(mi.Float(rng.random(n).astype(np.float32))
                                         for _ in range(2))))
        w = np.array(mi.unpolarized_spectrum(w), dtype=np.float64)[0]
        delta = (np.array(bs.sampled_type, dtype=np.int64) & int(mi.BSDFFlags.Delta)) != 0
        mean, err = w.mean(), w.std() / np.sqrt(n)
        expected = (1 - W) * RHO + W
        print(f"θi = {theta:4.1f}°: mean sample() weight = {mean:.5f} ± {err:.5f}, expected "
              f"(1-w)·ρ + w·F = {expected:.5f} ({mean / expected - 1:+.2%}); mirror samples: "
              f"{delta.mean():.3f} of them (expected w = {W}), mean weight {w[delta].mean():.5f} "
              f"(expected F = 1)")
        bad |= abs(mean - expected) > 5 * err + 1e-4
    print("DEFECT PRESENT" if bad else "ok: the Dirac lobe's samples are weighted F")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
