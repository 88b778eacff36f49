"""Campaign section: rough transmission (cooktorrance with ``transmission``) against Mitsuba's
roughdielectric and, as α → 0, dielectric; energy in importance transport."""

from __future__ import annotations

import math

import mitsuba as mi

from .. import checks
from ..compare import compare, figure
from ..plots import pyplot, save_figure
from .core import Context, Row, Section, image, md_table
from .cooktorrance import KINDS, ct

#: The incident directions of the χ² grid: from outside, grazing, from inside, inside beyond
#: the critical angle (total internal reflection).
CHI2_WI = (("outside 45°", [0.5, 0.3, 0.81]), ("outside grazing", [0.8, 0.3, 0.05]),
           ("inside", [0.2, -0.6, -0.5]), ("inside, TIR", [0.8, 0.3, -0.05]))


#: The cases of Mitsuba's own roughdielectric χ² tests (and one of ours): params, ωi, the
#: component sampled alone (None: both lobes).
UPSTREAM_CHI2 = {
    "grazing": ({"alpha": 0.5}, [0.8, 0.3, 0.05], None),
    "beckmann-all-normals": ({"alpha": 0.5, "sample_visible": False}, [0.5, 0.0, 0.5], None),
    "beckmann-visible": ({"alpha": 0.5}, [0.5, 0.0, 0.5], None),
    "ggx-all-normals": ({"alpha": 0.5, "sample_visible": False, "distribution": "ggx"},
                        [0.5, 0.0, 0.5], None),
    "ggx-visible-grazing": ({"alpha": 0.5, "distribution": "ggx"}, [0.5, 0.5, 0.001], None),
    "from-inside": ({"alpha": 0.5}, [0.2, -0.6, -0.5], None),
    "from-inside-tir": ({"alpha": 0.5}, [0.8, 0.3, -0.05], None),
    # (not upstream) D·cos normals from inside: some face away from ωi and must be no sample
    "from-inside-all-normals": ({"alpha": 0.3, "sample_visible": False, "distribution": "ggx"},
                                [0.2, -0.6, -0.5], None),
    "from-the-denser-side": ({"alpha": 0.5, "int_ior": 1.0, "ext_ior": 1.5}, [0.2, -0.6, 0.5],
                             None),
    "reflection-lobe-aniso": ({"alpha_u": 0.5, "alpha_v": 0.2}, [-0.5, -0.5, 0.1], 0),
    "transmission-lobe-aniso": ({"alpha_u": 0.5, "alpha_v": 0.2}, [-0.5, -0.5, 0.1], 1),
}

#: The stability grid: α and η from index matching to far from it, on both sides of 1.
STABILITY_ALPHAS = (1e-4, 1e-3, 0.3, 1.0, 10.0)
STABILITY_ETAS = (1.0 + 1e-5, 1.0 - 1e-5, 1.5, 0.5, 1e3, 1e-3)


def glass(**params) -> dict:
    return ct(transmission=True, **params)


def equality(ctx: Context, s: Section) -> str:
    rows = []
    n = ctx.n(200_000, 20_000)
    for kind in KINDS:
        for visible in (True, False):
            for mode in (mi.TransportMode.Radiance, mi.TransportMode.Importance):
                common = dict(alpha=0.3, distribution=kind, sample_visible=visible)
                bctx = mi.BSDFContext(mode)
                r = checks.check_equal(glass(**common), dict(common, type="roughdielectric"),
                                       n=n, rtol=1e-5, sample=False, ctx=bctx)
                sampler = "VNDF" if visible else "D cos"
                mode_name = "radiance" if mode == mi.TransportMode.Radiance else "importance"
                s.rows.append(Row.of(f"cooktorrance transmission {kind}", r,
                                     f"= roughdielectric ({sampler}, {mode_name}): eval, pdf"))
                rows.append((kind, sampler, mode_name, f"{r.details['max']['eval']:.2g}",
                             f"{r.details['max']['pdf']:.2g}"))
    return md_table(["distribution", "sampling", "transport", "max rel. Δ eval",
                     "max rel. Δ pdf"], rows)


def rendered(ctx: Context, s: Section) -> str:
    res, spp = ctx.n(192, 48), ctx.n(128, 16)
    result = compare("glass", defines={"res": str(res), "glass": "roughdielectric"},
                     defines_b={"glass": "cooktorrance"}, spp=spp,
                     labels=("roughdielectric", "cooktorrance transmission=true"))
    fig = figure(result, ctx.figure("glass_cooktorrance_vs_roughdielectric.png"),
                 "roughdielectric | cooktorrance transmission=true (bk7, α = 0.1)")
    s.rows.append(Row("cooktorrance transmission", "render vs roughdielectric (glass sphere)",
                      result.verdict().split(" (")[0], "≤ 3 × noise floor",
                      not result.different()))
    return "\n".join(["```", result.summary(), "```", "", image(ctx, fig, "glass"), ""])


def smooth_limit(ctx: Context, s: Section) -> tuple[str, str]:
    """α → 0: reflected and transmitted fractions against the smooth dielectric's, both sides."""
    plt = pyplot()
    thetas = ctx.n((0.0, 30.0, 40.0, 60.0, 80.0, 100.0, 120.0, 136.0, 140.0, 150.0, 170.0),
                   (0.0, 80.0, 136.0, 170.0))
    smooth = {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}
    n = ctx.n(200_000, 20_000)
    rows, curves = [], {}
    for label, mask in (("reflected", +mi.BSDFFlags.Reflection),
                        ("transmitted", +mi.BSDFFlags.Transmission)):
        bctx = mi.BSDFContext(mi.TransportMode.Importance, mask)
        for alpha in (1e-2, 1e-4):
            curves[(label, alpha)] = [checks.albedo_sampled(glass(alpha=alpha, eta=1.5),
                                                            math.radians(t), n=n, ctx=bctx)[0][0]
                                      for t in thetas]
        curves[(label, 0)] = [checks.albedo_sampled(smooth, math.radians(t), n=n, ctx=bctx)[0][0]
                              for t in thetas]
        for i, t in enumerate(thetas):
            dev = abs(curves[(label, 1e-4)][i] - curves[(label, 0)][i])
            s.rows.append(Row("cooktorrance transmission", f"α = 1e-4 {label} fraction = "
                              f"dielectric's, θ = {t:g}°", f"|Δ| {dev:.1e}", "≤ 1e-3",
                              dev <= 1e-3))
    for i, t in enumerate(thetas):
        rows.append((f"{t:g}°", *(f"{curves[(lbl, a)][i]:.5f}" for lbl in ("reflected",
                                                                            "transmitted")
                                  for a in (0, 1e-2, 1e-4))))
    fig, ax = plt.subplots(figsize=(6.5, 3.8))
    for (label, alpha), values in curves.items():
        style = {0: "-", 1e-2: "o", 1e-4: "x"}[alpha]
        ax.plot(thetas, values, style, color="C0" if label == "reflected" else "C1", ms=4,
                label=f"{label}, " + ("dielectric" if alpha == 0 else f"α = {alpha:g}"))
    ax.axvline(180 - math.degrees(math.asin(1 / 1.5)), color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("incident angle θ (degrees; > 90°: from inside, dotted: critical angle)")
    ax.set_ylabel("fraction of the incident light")
    ax.set_title("The smooth limit: cooktorrance transmission=true against dielectric (η = 1.5)",
                 fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    path = save_figure(fig, ctx.figure("glass_smooth_limit.png"))
    table = md_table(["θ", "F (dielectric)", "α = 1e-2", "α = 1e-4", "1 − F (dielectric)",
                      "α = 1e-2", "α = 1e-4"], rows)
    return table, path


def energy(ctx: Context, s: Section) -> str:
    thetas = ctx.n((0.0, 45.0, 70.0, 80.0, 85.0, 95.0, 100.0, 110.0, 135.0, 160.0, 170.0),
                   (0.0, 85.0, 135.0))
    rows = []
    for kind in KINDS:
        for alpha in ctx.n((0.1, 0.3, 0.5), (0.5,)):
            sp = glass(alpha=alpha, eta=1.5, distribution=kind)
            curve = checks.albedo_curve(sp, thetas, n=ctx.n(400_000, 50_000),
                                        estimators=("reference",))
            e = checks.check_energy(sp, curve=curve)
            rtol = 1e-3 if kind == "ggx" else 3e-3
            agree = checks.check_albedo_agreement(sp, curve=curve, rtol=rtol)
            label = f"cooktorrance transmission {kind}"
            s.rows.append(Row.of(label, e, f"α = {alpha:g}: E(θ) ≤ 1 (importance transport)"))
            s.rows.append(Row.of(label, agree, f"α = {alpha:g}: E(θ) = reference"))
            rows.append((kind, f"{alpha:g}", ", ".join(f"{v:.4f}" for v in curve.reference[:, 0]),
                         ", ".join(f"{v:.4f}" for v in curve.sampled[:, 0])))
    return md_table(["distribution", "α", "E(θ) reference, θ = "
                     + ", ".join(f"{t:g}°" for t in thetas), "sample()"], rows)


def furnace(ctx: Context, s: Section) -> str:
    smooth = checks.furnace.furnace_render(glass(alpha=1e-4, eta=1.5), spp=ctx.n(512, 64),
                                           res=ctx.n(48, 16), max_depth=64, predict=False)
    dev = abs(smooth.mean - 1)
    s.rows.append(Row("cooktorrance transmission", "smooth glass sphere in the white furnace "
                      "(64 bounces) renders 1", f"{smooth.mean:.4f}", "|Δ| ≤ 5e-3", dev <= 5e-3))
    rough = checks.check_furnace(glass(alpha=0.3, eta=1.5), spp=ctx.n(128, 32), res=32)
    s.rows.append(Row.of("cooktorrance transmission", rough,
                         "one-bounce furnace = reflected fraction E_r(θ)"))
    return (f"A smooth glass sphere (α = 1e-4) in the white furnace with 64 bounces: image mean "
            f"{smooth.mean:.4f} (1 when no light is lost). With one bounce a rough sphere "
            f"(α = 0.3) shows its reflected fraction: {rough.message}")


def sampling(ctx: Context, s: Section) -> str:
    configs = [(k, v) for k in KINDS for v in (True, False)]
    tests = len(configs) * len(CHI2_WI)
    rows = []
    for kind, visible in configs:
        worst, fails = 1.0, 0
        for _, wi in CHI2_WI:
            r = checks.chi2_bsdf(glass(distribution=kind, alpha=0.3, sample_visible=visible),
                                 wi=wi, res=None, ires=None, test_count=tests,
                                 sample_count=ctx.n(1_000_000, 200_000))
            worst, fails = min(worst, r.value), fails + (not r.passed)
        sampler = "VNDF" if visible else "D cos"
        s.rows.append(Row(f"cooktorrance transmission {kind}", f"χ², {sampler}, ωi outside, "
                          "grazing, inside, inside beyond the critical angle", f"min p = "
                          f"{worst:.3g}", f"Šidák over {tests}", fails == 0))
        cons = checks.check_consistency(glass(distribution=kind, alpha=0.3,
                                              sample_visible=visible), n=ctx.n(100_000, 20_000))
        s.rows.append(Row.of(f"cooktorrance transmission {kind} {sampler}", cons))
        rows.append((kind, sampler, f"{worst:.3g}", f"{cons.value:.2g}"))
    # the configurations of Mitsuba's own roughdielectric χ² tests
    tests, worst, failed = len(UPSTREAM_CHI2), 1.0, []
    for name, (params, wi, component) in UPSTREAM_CHI2.items():
        bctx = None
        if component is not None:
            bctx = mi.BSDFContext()
            bctx.component = component
        r = checks.chi2_bsdf(glass(**params), wi=wi, ctx=bctx, res=None, ires=None,
                             test_count=tests, sample_count=ctx.n(1_000_000, 200_000))
        worst = min(worst, r.value)
        if not r.passed:
            failed.append(name)
    s.rows.append(Row("cooktorrance transmission", "χ², the cases of Mitsuba's roughdielectric "
                      "tests (" + ", ".join(UPSTREAM_CHI2) + ")", f"min p = {worst:.3g}"
                      + (f" (rejected: {', '.join(failed)})" if failed else ""),
                      f"Šidák over {tests}", not failed))
    rows.append(("Mitsuba's cases", "both", f"{worst:.3g}", "—"))
    return md_table(["distribution", "sampling", "smallest χ² p-value",
                     "consistency (max rel. error)"], rows)


def stability(ctx: Context, s: Section) -> str:
    """No NaN, Inf or negative value over α × η × both distributions × both samplers, at the
    stress directions of check_stability (both sides, grazing, total internal reflection)."""
    alphas = ctx.n(STABILITY_ALPHAS, (1e-4, 10.0))
    etas = ctx.n(STABILITY_ETAS, (1.0 + 1e-5, 1e3))
    grid = checks.parameter_grid(glass(), alpha=list(alphas), eta=list(etas),
                                 distribution=list(KINDS), sample_visible=[True, False])
    r = checks.check_stability(grid, n_random=ctx.n(2_000, 200))
    s.rows.append(Row.of("cooktorrance transmission", r,
                         f"stability over {len(grid)} parameter sets"))
    return (f"{len(grid)} parameter sets: α ∈ {{{', '.join(f'{a:g}' for a in alphas)}}} × η ∈ "
            f"{{{', '.join(f'{e:.6g}' for e in etas)}}} × both distributions × both samplers")


def section(ctx: Context) -> Section:
    s = Section("Rough transmission")
    t_equal = equality(ctx, s)
    t_render = rendered(ctx, s)
    t_limit, limit_fig = smooth_limit(ctx, s)
    t_energy = energy(ctx, s)
    t_furnace = furnace(ctx, s)
    t_sampling = sampling(ctx, s)
    grid = stability(ctx, s)
    s.markdown = "\n".join([
        "`cooktorrance` with `transmission=true`: the reflection and refraction lobes of Walter "
        "et al. 2007, lit from either side.", "",
        "**Equality with `roughdielectric`** (eval and pdf at random pairs over the whole "
        "sphere, both transport modes, α = 0.3):", "", t_equal, "",
        "**Rendered** (`scenes/glass.xml`, same seed; the noise floor is the built-in against "
        "itself with another seed):", "", t_render,
        "**The smooth limit**: the reflected and transmitted fractions (importance transport) "
        "tend to the smooth `dielectric`'s F and 1 − F from both sides, across the critical "
        "angle:", "", t_limit, "", image(ctx, limit_fig, "smooth limit"), "",
        "**Energy** (importance transport, where E(θ) ≤ 1 is energy conservation; θ > 90° lights "
        "the surface from inside): the float64 reference against `sample()`:", "", t_energy, "",
        "**White furnace**: " + t_furnace, "",
        "**Sampling and consistency** (χ² over the whole sphere, α = 0.3, η = bk7/air; then "
        "the configurations of Mitsuba's own roughdielectric χ² tests):", "",
        t_sampling, "",
        f"**Stability**: no NaN, Inf or negative value over {grid}, at the stress directions "
        "of `check_stability` (from both sides, grazing, beyond the critical angle) and random "
        "ones."])
    return s
