#!/usr/bin/env python3
"""
Where float32 stops following float64 in the ``phong`` plugin, and what it does beyond: the
numbers quoted in the plugin's docstring and in README.md ("phong").

1. ``eval`` in llvm_ad_rgb (float32) against the float64 reference at the *same* float32
   directions, across the lobe (where cosⁿ = e^-0.5, e^-5, e^-30, at 8 azimuths), for the plugin
   and for the textbook float32 formula pow(R·V, n) (NumPy float32);
2. the sampler: the fraction of samples that collapse onto the lobe's axis (ωo = R exactly) and
   the Kolmogorov-Smirnov distance of cos^(n+1)α, which is uniform on [0, 1] for an exact
   sampler (α measured in float64 from the float32 ωo), for the plugin and for the textbook
   sampler sin α = sqrt(1 − cos²α) (NumPy float32);
3. the sampled albedo at normal incidence (mean weight) against the reference, and NaN/Inf/negative
   values anywhere (the stability sweep), up to the largest exponent.

    python validation/phong_float32.py           # the full table (about a minute)
    python validation/phong_float32.py --quick   # a smoke run (the test suite runs it)
"""

from __future__ import annotations

import argparse
import math
import sys

import mi_brdfs  # first: it chooses the libLLVM before drjit loads

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

from mi_brdfs.checks import batch, check_stability  # noqa: E402
from mi_brdfs.reference import Phong  # noqa: E402

#: Where on the lobe ``eval`` is compared: cosⁿ = e^−x.
LOBE_POINTS = (0.5, 5.0, 30.0)
THETA_I = math.radians(45.0)


def _rotate_about(axis: np.ndarray, angle: float, phis: np.ndarray) -> np.ndarray:
    """Unit vectors at ``angle`` from ``axis``, at azimuths ``phis`` (float64)."""
    t = np.cross(axis, [0.0, 1.0, 0.0])
    t /= np.linalg.norm(t)
    b = np.cross(axis, t)
    return (np.cos(angle) * axis[None, :] + np.sin(angle) * (np.cos(phis)[:, None] * t
                                                             + np.sin(phis)[:, None] * b))


def lobe_pairs(n: float, lobe: str):
    """(wi, wo) as float32-representable float64 arrays, on the lobe where cosⁿ = e^−x."""
    wi = np.array([math.sin(THETA_I), 0.0, math.cos(THETA_I)])
    phis = np.linspace(0, 2 * math.pi, 8, endpoint=False)
    wos = []
    for x in LOBE_POINTS:
        angle = math.acos(math.exp(-x / n))
        if lobe == "mirror":
            wos.append(_rotate_about(wi * [-1, -1, 1], angle, phis))
        else:
            h = _rotate_about(np.array([0.0, 0.0, 1.0]), angle, phis)
            wos.append(2 * (h @ wi)[:, None] * h - wi)
    wo = np.concatenate(wos).astype(np.float32).astype(np.float64)
    wi = np.broadcast_to(wi.astype(np.float32).astype(np.float64), wo.shape).copy()
    return wi, wo


def eval_errors(n: float, lobe: str) -> tuple[float, float]:
    """Max relative error of f's specular part: (plugin in float32, textbook pow in float32)."""
    spec = {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
            "exponent": n, "lobe": lobe}
    wi, wo = lobe_pairs(n, lobe)
    ref = Phong(0.0, 1.0, n, "normalized", lobe).brdf(wi, wo)[:, 0] * wo[:, 2]
    ours = batch.evaluate(mi.load_dict(spec), wi, wo).value[:, 0]
    a, b = wi.astype(np.float32), wo.astype(np.float32)
    if lobe == "mirror":
        cos = np.sum((a * np.float32([-1, -1, 1])) * b, axis=1, dtype=np.float32)
    else:
        h = a + b
        cos = h[:, 2] / np.linalg.norm(h, axis=1).astype(np.float32)
    textbook = np.power(np.maximum(cos, np.float32(0)), np.float32(n)).astype(np.float64) * \
        Phong(0.0, 1.0, n, "normalized", lobe).normalization * wo[:, 2]
    return (float(np.max(np.abs(ours / ref - 1))), float(np.max(np.abs(textbook / ref - 1))))


def _ks_uniform(x: np.ndarray) -> float:
    """Kolmogorov-Smirnov distance between the sample ``x`` and U(0, 1)."""
    x = np.sort(np.clip(x, 0, 1))
    i = np.arange(1, len(x) + 1) / len(x)
    return float(max(np.max(i - x), np.max(x - (i - 1 / len(x)))))


def _lobe_statistic(wo: np.ndarray, axis: np.ndarray, n: float) -> np.ndarray:
    """cos^(n+1) of the angle between ``wo`` and ``axis``, in float64 without cancellation."""
    wo = wo / np.linalg.norm(wo, axis=1, keepdims=True)
    x = 0.5 * np.sum((wo - axis) ** 2, axis=1)
    return np.exp((n + 1) * np.log1p(-np.minimum(x, 1.0)))


def sampler_stats(n: float, count: int, seed: int = 0) -> tuple[float, float, float, float]:
    """(collapsed fraction, KS) of the plugin's mirror-lobe sampler, then of the textbook one."""
    rng = np.random.default_rng(seed)
    spec = {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
            "exponent": n}
    wi = np.array([math.sin(THETA_I), 0.0, math.cos(THETA_I)], dtype=np.float32)
    axis = (wi * np.float32([-1, -1, 1])).astype(np.float64)
    u = rng.random((count, 2))
    s = batch.sample(mi.load_dict(spec), wi.astype(np.float64), rng.random(count), u)
    ok = np.any(s.weight != 0, axis=1)
    wo = s.wo[ok]
    ours = (float(np.mean(np.all(wo.astype(np.float32) == axis.astype(np.float32), axis=1))),
            _ks_uniform(_lobe_statistic(wo, axis, n)))
    # the textbook sampler, in float32 about +z (the statistic is rotation invariant)
    u32 = u.astype(np.float32)
    cos = np.power(u32[:, 0], np.float32(1 / (n + 1)))
    sin = np.sqrt(np.maximum(np.float32(1) - cos * cos, np.float32(0)))
    phi = np.float32(2 * math.pi) * u32[:, 1]
    v = np.stack([sin * np.cos(phi), sin * np.sin(phi), cos], axis=1).astype(np.float64)
    z = np.array([0.0, 0.0, 1.0])
    textbook = (float(np.mean(sin == 0)), _ks_uniform(_lobe_statistic(v, z, n)))
    return ours + textbook


def sampled_albedo(n: float, count: int, lobe: str) -> tuple[float, float]:
    """(mean sample weight at normal incidence, the reference's albedo there)."""
    from mi_brdfs.checks import albedo_sampled
    spec = {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
            "exponent": n, "lobe": lobe}
    mean, _ = albedo_sampled(spec, 0.0, n=count)
    return float(mean[0]), float(Phong(0.0, 1.0, n, "normalized", lobe).albedo(0.0)[0])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="few exponents, few samples")
    args = parser.parse_args(argv)
    mi_brdfs.use_variant("llvm_ad_rgb", fallback=False)
    exponents = [1e3, 1e6, 1e8] if args.quick else \
        [1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e10, 1e12, 1e13, 1e14, 1e16, 1e20, 1e30]
    count = 20_000 if args.quick else 1_000_000
    print(f"phong in {mi.variant()} (float32) against the float64 reference "
          f"(Mitsuba {mi.__version__}, drjit {dr.__version__}); wi at 45°\n")
    print("| n | eval rel. error, mirror (textbook pow) | eval rel. error, halfway (textbook) "
          "| sampler: collapsed on R, KS (textbook: collapsed, KS) | albedo E(0): sampled vs "
          "reference (mirror / halfway) |")
    print("|---|---|---|---|---|")
    for n in exponents:
        em, tm = eval_errors(n, "mirror")
        eh, th = eval_errors(n, "halfway")
        c, ks, tc, tks = sampler_stats(n, count)
        am, rm = sampled_albedo(n, count, "mirror")
        ah, rh = sampled_albedo(n, count, "halfway")
        print(f"| {n:g} | {em:.1e} ({tm:.1e}) | {eh:.1e} ({th:.1e}) | {c:.1%}, {ks:.1e} "
              f"({tc:.1%}, {tks:.1e}) | {am:.5f} vs {rm:.5f} / {ah:.5f} vs {rh:.5f} |")
    grid = [{"type": "phong", "form": f, "lobe": lb, "exponent": n}
            for f in ("normalized", "lecture", "original") for lb in ("mirror", "halfway")
            for n in exponents]
    result = check_stability(grid, n_random=2_000 if args.quick else 20_000)
    print(f"\nKS critical value (α = 0.01) for {count} samples: "
          f"{1.63 / math.sqrt(count):.1e}\n{result.message}")
    return 0 if result.passed else 1


if __name__ == "__main__":
    sys.exit(main())
