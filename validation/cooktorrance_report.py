#!/usr/bin/env python3
"""
The measured numbers behind the cooktorrance section of README.md, in llvm_ad_rgb:

1. term level: ∫ D cosθ dω and Heitz's weak white furnace, worst |value − 1|;
2. equality with roughconductor (shadowing=smith) and roughdielectric's reflection (k = 0):
   the largest relative difference of eval and pdf at random direction pairs;
3. the white furnace (fresnel=none): directional albedo from sample() against the float64
   reference;
4. the smooth limit: albedo at α = 1e-4 against the Fresnel reflectance of dielectric/conductor;
5. stability: NaN/Inf/negative values over a parameter grid × stress directions.

    python validation/cooktorrance_report.py            # the README's figures (~3 minutes)
    python validation/cooktorrance_report.py --quick    # a smoke run (the test suite runs this)
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings

import mi_brdfs  # first: it chooses the libLLVM before drjit loads

import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

from mi_brdfs import checks  # noqa: E402
from mi_brdfs.checks import _batch  # noqa: E402
from mi_brdfs.reference import cooktorrance as ref  # noqa: E402
from mi_brdfs.reference import for_spec  # noqa: E402

CT = "cooktorrance"


KINDS, SHADOWINGS, VISIBLE = ("beckmann", "ggx"), ("vcavity", "smith"), (True, False)


def terms(alphas):
    print("| distribution | masking | worst \\|∫D cos − 1\\| | "
          "worst \\|weak furnace − 1\\| (θo ≤ 84°) |")
    print("|---|---|---|---|")
    for kind in KINDS:
        for masking in ("smith", "vcavity", "smith_mitsuba"):
            ndf, weak = 0.0, 0.0
            for alpha in alphas:
                D, G1 = checks.package_terms(kind, alpha, masking)
                ndf = max(ndf, abs(checks.ndf_normalization(D, alpha) - 1))
                weak = max(weak, abs(checks.check_weak_furnace(D, G1, alpha, "").value - 1))
            name = {"smith": "Smith, exact", "vcavity": "V-cavity",
                    "smith_mitsuba": "Smith, Mitsuba's"}[masking]
            print(f"| {kind} | {name} | {ndf:.1e} | {weak:.1e} |")


def _max_rel(a, b):
    scale = np.maximum(np.abs(a), np.abs(b))
    return float(np.max(np.where(scale > 1e-12, np.abs(a - b) / np.maximum(scale, 1e-12), 0)))


def builtins(n, kinds=KINDS, visibles=VISIBLE):
    rng = np.random.default_rng(0)
    wi, wo = _batch.random_directions(rng, n, sphere=False), _batch.random_directions(rng, n)
    reflection = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.GlossyReflection)
    print("| built-in | distribution | sampling | max rel. diff. eval | max rel. diff. pdf |")
    print("|---|---|---|---|---|")
    for kind in kinds:
        for visible in visibles:
            cases = [("roughconductor (η, k = 0.2, 3.9)", {"eta": 0.2, "k": 3.9}, None),
                     ("roughconductor (Au)", {"material": "Au"}, None),
                     ("roughdielectric, reflection (η = 1.5)", {"eta": 1.5}, reflection)]
            for label, ior, ctx in cases:
                common = dict(ior, alpha=0.25, distribution=kind, sample_visible=visible)
                if ctx is None:
                    theirs = dict(common, type="roughconductor")
                else:
                    theirs = {"type": "roughdielectric", "int_ior": 1.5, "ext_ior": 1.0,
                              "alpha": 0.25, "distribution": kind, "sample_visible": visible}
                a = _batch.evaluate(mi.load_dict(dict(common, type=CT, shadowing="smith")),
                                    wi, wo)
                b = _batch.evaluate(mi.load_dict(theirs), wi, wo, ctx)
                pdf = _max_rel(a.pdf, b.pdf) if visible or ctx is None else float("nan")
                print(f"| {label} | {kind} | {'visible' if visible else 'D·cosθ'} | "
                      f"{_max_rel(a.value, b.value):.1e} | {pdf:.1e} |")


def furnace(n, thetas, kinds=KINDS, shadowings=SHADOWINGS, visibles=VISIBLE,
            alphas=(0.1, 0.5, 1.0)):
    print("| distribution | shadowing | sampling | α | E(θ) reference, θ = "
          + ", ".join(f"{t:g}°" for t in thetas) + " | max \\|sample() − reference\\| | max σ |")
    print("|---|---|---|---|---|---|---|")
    for kind in kinds:
        for shadowing in shadowings:
            for visible in visibles:
                for alpha in alphas:
                    spec = {"type": CT, "distribution": kind, "shadowing": shadowing,
                            "sample_visible": visible, "alpha": alpha, "fresnel": "none"}
                    c = checks.albedo_curve(spec, thetas, n=n, estimators=("reference",))
                    dev = np.abs(c.sampled - c.reference).max()
                    print(f"| {kind} | {shadowing} | {'visible' if visible else 'D·cosθ'} | "
                          f"{alpha:g} | {', '.join(f'{e:.4f}' for e in c.reference[:, 0])} | "
                          f"{dev:.1e} | {c.sampled_err.max():.1e} |")


def smooth_limit(n, alphas=(1e-3, 1e-4)):
    reflection = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaReflection)
    thetas = np.radians([0, 45, 80, 87])
    for alpha in alphas:
        for ior, smooth, ctx in (({"eta": 1.5}, {"type": "dielectric", "int_ior": 1.5,
                                                  "ext_ior": 1.0}, reflection),
                                 ({"material": "Au"}, {"type": "conductor", "material": "Au"},
                                  None)):
            dev = max(float(np.abs(checks.albedo_sampled(dict(ior, type=CT, alpha=alpha), t,
                                                         n=n)[0]
                                   - checks.albedo_sampled(smooth, t, n=16, ctx=ctx)[0]).max())
                      for t in thetas)
            print(f"- α = {alpha:g}, {smooth['type']}: max |E − F| = {dev:.1e} "
                  f"(θ = 0°, 45°, 80°, 87°)")


def stability(quick):
    grid = []
    alphas = [0.0] if quick else [0.0, 1e-4, 1e-3, 0.02, 1.0, 10.0]
    iors = [(1.0 + 1e-6, 0.0)] if quick else \
        [(1.0 + 1e-6, 0.0), (1.5, 0.0), (0.5, 0.0), (1e3, 0.0), (0.2, 1e3), (1e3, 1e3), (0.0, 1.0)]
    for eta, k in iors:
        grid += checks.parameter_grid({"type": CT, "eta": eta, "k": k}, alpha=alphas,
                                      distribution=["beckmann", "ggx"],
                                      shadowing=["vcavity", "smith"],
                                      sample_visible=[True, False],
                                      fresnel=["exact"] if quick else ["exact", "schlick"])
    if not quick:
        grid += checks.parameter_grid({"type": CT, "diffuse_reflectance": 0.5, "material": "Au"},
                                      alpha=alphas, distribution=["beckmann", "ggx"],
                                      shadowing=["vcavity", "smith"], sample_visible=[True, False])
    result = checks.check_stability(grid, n_random=200 if quick else 2000)
    print(f"- {result.message}")
    return result.passed


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (smoke test)")
    args = parser.parse_args(argv)
    mi_brdfs.use_variant("llvm_ad_rgb", fallback=False)
    warnings.simplefilter("ignore", mi_brdfs.MiBrdfsWarning)  # α = 0 is clamped, on purpose
    q = args.quick
    print("## 1. Terms: NDF normalisation and weak white furnace (float32), α ∈ {0.1, 0.5, 1}\n")
    terms([0.5] if q else [0.1, 0.5, 1.0])
    print("\n## 2. cooktorrance (shadowing=smith, exact Fresnel) against the built-ins\n")
    if q:
        builtins(2_000, ("ggx",), (True,))
    else:
        builtins(200_000)
    print("\n## 3. White furnace (fresnel=none): sample() against the float64 reference\n")
    if q:
        furnace(20_000, (0.0, 60.0), ("beckmann",), ("vcavity",), (True,), (0.5,))
    else:
        furnace(1_000_000, (0.0, 45.0, 70.0, 84.26, 89.0))
    print("\n## 4. Smooth limit: albedo against the Fresnel reflectance\n")
    smooth_limit(10_000, (1e-4,)) if q else smooth_limit(200_000)
    print("\n## 5. Stability\n")
    ok = stability(q)
    textbook = ref.CookTorrance(0.5, fresnel="none").albedo(0.0)[0]
    builtin = for_spec({"type": "roughconductor", "alpha": 0.3}).albedo(math.radians(70))[0]
    print(f"\nV-cavity Beckmann α = 0.5, F ≡ 1, normal incidence: E = {textbook:.4f}; "
          f"roughconductor α = 0.3 at 70° (eval): E = {builtin:.5f}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
