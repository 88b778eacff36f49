"""Campaign section: Lafortune's generalized cosine lobes against the float64 reference, phong,
and what the paper says the lobes are for."""

from __future__ import annotations

import math

import numpy as np

from .. import checks
from ..bsdfspec import load_bsdf
from ..checks import batch
from ..plots import pyplot, save_figure
from ..reference import Lafortune
from ..reference.lafortune import cosine_lobe_integral
from .core import Context, Row, Section, image, md_table

#: The lobes the paper names (Lafortune et al. 1997), (Cx, Cy, Cz): Phong's mirror lobe,
#: retro-reflection, off-specular reflection towards grazing angles, and two more general ones
#: (anisotropic; a negative Cz, whose principal direction lies below the horizon).
SHAPES = {"phong mirror": (-1.0, -1.0, 1.0), "retro-reflective": (1.0, 1.0, 1.0),
          "off-specular": (-1.0, -1.0, 0.5), "anisotropic": (-1.0, -0.3, 0.8),
          "negative Cz": (0.7, -1.0, -0.2)}
#: Three lobes and a diffuse term, both normalisations (the tests' configuration).
THREE = {"cx_0": -1.0, "cy_0": -1.0, "cz_0": 0.6, "exponent_0": 20.0,
         "specular_reflectance_0": 0.3,
         "cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0, "exponent_1": 5.0, "specular_reflectance_1": 0.2,
         "cx_2": -0.5, "cy_2": -1.0, "cz_2": 1.0, "exponent_2": 200.0,
         "specular_reflectance_2": 0.25, "diffuse_reflectance": 0.1}
THETAS = (0.0, 30.0, 60.0, 80.0, 89.0)


def spec(shape: str, n: float, rho_d: float = 0.0, rho_s: float = 1.0, **extra) -> dict:
    cx, cy, cz = SHAPES[shape]
    return dict({"type": "lafortune", "cx_0": cx, "cy_0": cy, "cz_0": cz, "exponent_0": float(n),
                 "diffuse_reflectance": rho_d, "specular_reflectance_0": rho_s}, **extra)


def energy(ctx: Context, s: Section) -> str:
    """
    Each normalised lobe's albedo against its bound ρs (reference quadrature): E(θ) ≤ ρs, equal
    to it at normal incidence exactly where |Cz| = max|C|; the bound rests on the cosⁿ lobe's
    albedo being largest about the normal, measured over every axis direction.
    """
    rows, worst = [], 0.0
    for name in SHAPES:
        for n in ctx.n((1.0, 10.0, 100.0), (10.0,)):
            ref = Lafortune([dict(zip(("cx", "cy", "cz"), SHAPES[name]), exponent=n)], 0.0)
            e = [ref.lobe_albedo(0, math.radians(t)) for t in THETAS]
            worst = max(worst, max(e))
            rows.append((name, f"{n:g}", *(f"{v:.4f}" for v in e)))
    s.values["lafortune: max E normalised"] = f"{worst:.4f}"
    s.rows.append(Row("lafortune (normalize)", "reference E(θ) ≤ ρs, every lobe shape, θ ≤ 89°",
                      f"max {worst:.4f}", "≤ 1", worst <= 1.0 + 1e-12))
    ratio = max(cosine_lobe_integral(t, n) / (2 * math.pi / (n + 2))
                for n in (0.0, 1.0, 10.0, 1e3) for t in np.linspace(0.0, math.pi, 91))
    s.rows.append(Row("lafortune", "∫cosⁿβ cosθ⁺ dω largest for the axis at the normal",
                      f"max ratio {ratio:.12f}", "≤ 1", ratio <= 1.0 + 1e-12))
    for normalize in (True, False):
        r = checks.check_albedo_agreement(dict(type="lafortune", normalize=normalize, **THREE),
                                          n=ctx.n(400_000, 50_000))
        s.rows.append(Row.of(f"lafortune three lobes, normalize = {str(normalize).lower()}", r,
                             "E(θ) from sample() = reference"))
    return md_table(["lobe", "n", *(f"E({t:g}°)" for t in THETAS)], rows)


def _peak(bsdf, theta_i: float) -> float:
    """Signed θo (degrees) where f(ωi, ·) peaks in the plane of incidence (0.02° grid)."""
    theta_o = np.radians(np.arange(-89.99, 90.0, 0.02))
    wo = np.stack([np.sin(theta_o), 0 * theta_o, np.cos(theta_o)], axis=1)
    wi = np.tile([-math.sin(math.radians(theta_i)), 0.0, math.cos(math.radians(theta_i))],
                 (len(wo), 1))
    f = batch.evaluate(bsdf, wi, wo).value[:, 0] / wo[:, 2]
    return float(np.degrees(theta_o[int(np.argmax(f))]))


def features(ctx: Context, s: Section) -> str:
    """Where each lobe peaks in the plane of incidence, against where the paper puts it."""
    rows = []
    for theta in (20.0, 40.0, 60.0):
        t = math.radians(theta)
        # off-specular: the principal direction (−|Cx| sinθ, 0, Cz cosθ) normalised
        expected = {"phong mirror": theta, "retro-reflective": -theta,
                    "off-specular": math.degrees(math.atan(2 * math.tan(t)))}
        for name, angle in expected.items():
            got = _peak(load_bsdf(spec(name, 30.0)), theta)
            ok = abs(got - angle) <= 0.02
            rows.append((name, f"{theta:g}°", f"{got:.2f}°", f"{angle:.2f}°", "✓" if ok else "✗"))
            s.rows.append(Row(f"lafortune {name}", f"peak of f(ωi, ·) at θi = {theta:g}°",
                              f"{got:.2f}°", f"{angle:.2f}° ± 0.02°", ok))
        s.values[f"lafortune off-specular peak at {theta:g}°"] = f"{rows[-1][2]}"
    return md_table(["lobe (n = 30)", "θi", "peak θo (plugin's eval)", "expected", "agree"],
                    rows)


def phong_equivalence(ctx: Context, s: Section) -> str:
    """The mirror lobe against each phong form, pointwise (eval, pdf, samples)."""
    rows = []
    c = ((7.0 + 2) / (2 * math.pi)) ** (1 / 7.0)
    pairs = [("normalize, C = (−2.5, −2.5, 2.5)", dict(cx_0=-2.5, cy_0=-2.5, cz_0=2.5),
              "normalized", True),
             ("paper's form, C = (−1, −1, 1)", dict(normalize=False), "lecture", True),
             ("paper's form, C = ((n+2)/2π)^(1/n)·(−1, −1, 1)",
              dict(normalize=False, cx_0=-c, cy_0=-c, cz_0=c), "normalized", True),
             ("paper's form, C = (−1, −1, 1)", dict(normalize=False), "original", False)]
    for label, params, form, equal in pairs:
        samples = equal  # original's sampler weighs its lobe differently: eval only
        ours = dict(type="lafortune", exponent_0=7.0, **params)
        r = checks.check_equal(ours, {"type": "phong", "form": form, "exponent": 7.0},
                               n=ctx.n(100_000, 20_000), rtol=2e-5, sample=samples, upper=True,
                               pdf=samples)
        s.rows.append(Row.of(f"lafortune mirror lobe ({label})", r, f"= phong form={form}",
                             expected_fail=not equal))
        rows.append((label, f"`{form}`", f"{r.value:.2g}", "equal" if r.passed else "differs"))
    return md_table(["lafortune, n = 7", "phong form", "largest relative difference",
                     "verdict"], rows)


def sampling_and_stability(ctx: Context, s: Section) -> str:
    rows = []
    thetas = ctx.n((0.0, 30.0, 60.0, 80.0, 85.0, 89.0), (0.0, 85.0))
    for normalize in (True, False):
        sp = dict(type="lafortune", normalize=normalize, **THREE)
        label = f"lafortune three lobes, normalize = {str(normalize).lower()}"
        worst_p, fails, tests = 1.0, 0, len(thetas) * 5
        for t in thetas:
            wi = [0.6 * math.sin(math.radians(t)), 0.8 * math.sin(math.radians(t)),
                  math.cos(math.radians(t))]
            for component in (None, 0, 1, 2, 3):  # all, then each term alone
                one = None if component is None else _one(component)
                r = checks.chi2_bsdf(sp, wi=wi, ctx=one, res=None, ires=None, test_count=tests,
                                     sample_count=ctx.n(1_000_000, 200_000))
                worst_p, fails = min(worst_p, r.value), fails + (not r.passed)
        s.rows.append(Row(label, "χ², all terms and each alone, θ ∈ {"
                          + ", ".join(f"{t:g}°" for t in thetas) + "}",
                          f"min p = {worst_p:.3g}", f"Šidák over {tests}", fails == 0))
        cons = checks.check_consistency(sp, n=ctx.n(200_000, 20_000))
        recip = checks.check_reciprocity(sp, n=ctx.n(200_000, 20_000))
        s.rows += [Row.of(label, cons), Row.of(label, recip, "reciprocity")]
        rows.append((str(normalize).lower(), f"{worst_p:.3g}", f"{cons.value:.2g}",
                     f"{recip.value:.2g}"))
    grid = checks.parameter_grid({"type": "lafortune", "diffuse_reflectance": 0.0},
                                 cx_0=[0.0, -1.0, 1.0], cz_0=[0.0, 0.3, 1.0, -0.5],
                                 exponent_0=ctx.n([0.0, 1.0, 1e3, 1e6, 1e30], [0.0, 1e30]),
                                 normalize=[True, False])
    grid = [dict(g, cy_0=g["cx_0"]) for g in grid]
    stab = checks.check_stability(grid, n_random=ctx.n(5_000, 500))
    s.rows.append(Row.of("lafortune", stab, f"stability over {len(grid)} parameter sets"))
    table = md_table(["normalize", "smallest χ² p-value", "consistency (max rel. error)",
                      "max asymmetry (reciprocity)"], rows)
    return table + f"\n\nNaN/Inf/negative values over {len(grid)} parameter sets: " \
                   f"{int(stab.value)}."


def _one(component: int):
    """A context that enables one component (lobe) only."""
    import mitsuba as mi
    one = mi.BSDFContext()
    one.component = component
    return one


def lobe_figure(ctx: Context) -> str:
    """f(ωi, ·) of each lobe in the plane of incidence at θi = 40°, and the normalised lobes'
    albedo curves (lines: reference; dots: sample())."""
    plt = pyplot()
    fig, (polar, curves) = plt.subplots(1, 2, figsize=(10, 3.8))
    theta_o = np.radians(np.linspace(-89.5, 89.5, 359))
    wo = np.stack([np.sin(theta_o), 0 * theta_o, np.cos(theta_o)], axis=1)
    wi = np.tile([-math.sin(math.radians(40.0)), 0.0, math.cos(math.radians(40.0))], (len(wo), 1))
    thetas = np.linspace(0.0, 89.0, ctx.n(30, 6))
    for (name, _), color in zip(SHAPES.items(), ("C0", "C1", "C3", "C2", "C4")):
        f = batch.evaluate(load_bsdf(spec(name, 10.0)), wi, wo).value[:, 0] / wo[:, 2]
        polar.plot(np.degrees(theta_o), f, color=color, lw=1.2, label=name)
        ref = Lafortune([dict(zip(("cx", "cy", "cz"), SHAPES[name]), exponent=10.0)], 0.0)
        curves.plot(thetas, [ref.lobe_albedo(0, math.radians(t)) for t in thetas], "-",
                    color=color, lw=1.2)
        dots = thetas[:: max(1, len(thetas) // 6)]
        curves.plot(dots, [checks.albedo_sampled(spec(name, 10.0), math.radians(t),
                                                 n=ctx.n(100_000, 10_000))[0][0] for t in dots],
                    "o", color=color, ms=3)
    polar.axvline(40.0, color="0.5", lw=0.8, ls=":")
    polar.axvline(-40.0, color="0.5", lw=0.8, ls=":")
    polar.set_title("f(ωi, ωo) in the plane of incidence, θi = 40° (ωi at −40°), n = 10",
                    fontsize=9)
    polar.set_xlabel("θo (degrees; negative: ωi's side)")
    polar.legend(fontsize=7)
    curves.axhline(1.0, color="0.5", lw=0.8, ls=":")
    curves.set_title("albedo, ρs = 1, normalize (lines: reference; dots: sample())", fontsize=9)
    curves.set_xlabel("incident angle θ (degrees)")
    for ax in (polar, curves):
        ax.grid(alpha=0.3)
    return save_figure(fig, ctx.figure("lafortune_lobes.png"))


def scalar_pass(ctx: Context, s: Section) -> None:
    with ctx.scalar():
        for normalize in (True, False):
            sp = dict(type="lafortune", normalize=normalize, **THREE)
            label = f"lafortune normalize = {str(normalize).lower()} ({ctx.scalar_variant})"
            s.rows.append(Row.of(label, checks.check_consistency(sp, n=ctx.n(1000, 200))))
            s.rows.append(Row.of(label, checks.check_stability(sp, n_random=ctx.n(300, 50))))


def section(ctx: Context) -> Section:
    s = Section("Lafortune: generalized cosine lobes")
    table = energy(ctx, s)
    peaks = features(ctx, s)
    phong = phong_equivalence(ctx, s)
    ss = sampling_and_stability(ctx, s)
    fig = lobe_figure(ctx)
    scalar_pass(ctx, s)
    s.markdown = "\n".join([
        "The `lafortune` plugin (Lafortune, Foo, Torrance & Greenberg 1997) against its float64 "
        "reference (`mi_brdfs/reference/lafortune.py`: the paper's sum of lobes, the albedo by "
        "a quadrature aligned with each lobe's principal direction), the `phong` plugin, and "
        "the paper's claims for its lobes.", "",
        "**Energy** of one normalised lobe (ρs = 1, ρd = 0), float64 reference: never above "
        "ρs, reached at normal incidence where |Cz| = max|C| (Phong's and the retro-reflective "
        "lobe):", "", table, "",
        "**What the lobes are for**: where f(ωi, ·) peaks in the plane of incidence:", "",
        peaks, "",
        "**The mirror lobe is Phong's**: pointwise against `phong` (eval; pdf and samples "
        "where the sampling agrees too). `original` divides by N·L and is not reciprocal: no "
        "normalisation makes a lobe equal to it.", "", phong, "",
        "**Sampling, consistency, reciprocity and stability** (three lobes and a diffuse term; "
        "stability over C, n ∈ {0 … 1e30} and both forms at stress directions):", "", ss, "",
        image(ctx, fig, "Lafortune lobes and albedo curves"), "",
        f"A smaller pass in `{ctx.scalar_variant}` (consistency and stability) is in the "
        "summary table."])
    return s
