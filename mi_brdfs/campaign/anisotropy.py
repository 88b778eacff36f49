"""Campaign section: anisotropic roughness (alpha_u, alpha_v) in cooktorrance, against the
anisotropic roughconductor and the float64 reference."""

from __future__ import annotations

import math

import numpy as np

from .. import checks
from ..compare import compare, figure
from ..plots import pyplot, save_figure
from .core import Context, Row, Section, image, md_table
from .cooktorrance import KINDS, ct

#: The (αu, αv) pairs of the section: brushed both ways, and 10:1.
PAIRS = ((0.05, 0.5), (0.5, 0.05), (0.1, 1.0))
#: Azimuths of ωo for the weak furnace (the roughness seen depends on it).
PHIS = (0.0, 45.0, 90.0)


def _wi(theta_deg: float, phi: float = 0.6) -> list[float]:
    """An incident direction at ``theta_deg``, in an azimuth between the axes."""
    t = math.radians(theta_deg)
    return [math.sin(t) * math.cos(phi), math.sin(t) * math.sin(phi), math.cos(t)]


def terms(ctx: Context, s: Section) -> str:
    rows = []
    for kind in KINDS:
        for masking, label in (("smith", "Smith, exact"), ("vcavity", "V-cavity")):
            worst_ndf = worst_weak = 0.0
            for pair in ctx.n(PAIRS, PAIRS[:1]):
                D, G1 = checks.package_terms(kind, pair, masking)
                ndf = checks.check_ndf(D, pair, f"{kind} α = {pair}")
                worst_ndf = max(worst_ndf, abs(ndf.value - 1))
                s.rows.append(Row.of(f"cooktorrance terms {kind}", ndf,
                                     f"∫ D cos = 1, (αu, αv) = {pair}"))
                for phi in PHIS:
                    weak = checks.check_weak_furnace(D, G1, pair, f"{kind} {label} α = {pair}",
                                                     phi_deg=phi)
                    worst_weak = max(worst_weak, abs(weak.value - 1))
                    s.rows.append(Row.of(f"cooktorrance terms {kind}", weak,
                                         f"weak furnace, {label}, (αu, αv) = {pair}, "
                                         f"φo = {phi:g}°"))
            rows.append((kind, label, f"{worst_ndf:.1e}", f"{worst_weak:.1e}"))
    return md_table(["distribution", "masking", "worst |∫ D cos − 1|",
                     "worst |weak furnace − 1| (θo ≤ 84°, φo ∈ {0°, 45°, 90°})"], rows)


def equality(ctx: Context, s: Section) -> str:
    rows = []
    n = ctx.n(200_000, 20_000)
    for kind in KINDS:
        for visible in (True, False):
            for pair in ctx.n(PAIRS[:2], PAIRS[:1]):
                common = dict(material="Al", alpha_u=pair[0], alpha_v=pair[1],
                              distribution=kind, sample_visible=visible)
                r = checks.check_equal(ct(shadowing="smith", **common),
                                       dict(common, type="roughconductor"), n=n, rtol=1e-5,
                                       upper=True, sample=False)
                sampler = "VNDF" if visible else "D cos"
                s.rows.append(Row.of(f"cooktorrance smith {kind}", r,
                                     f"= anisotropic roughconductor ({pair}, {sampler})"))
                rows.append((kind, sampler, f"{pair}", f"{r.details['max']['eval']:.2g}",
                             f"{r.details['max']['pdf']:.2g}"))
    return md_table(["distribution", "sampling", "(αu, αv)", "max rel. Δ eval",
                     "max rel. Δ pdf"], rows)


def rendered(ctx: Context, s: Section) -> str:
    """The brushed-metal scene: roughconductor | cooktorrance (Smith), then (V-cavity)."""
    res, spp = ctx.n(192, 48), ctx.n(128, 16)
    parts = []
    for metal, label in (("cooktorrance-smith", "cooktorrance shadowing=smith"),
                         ("cooktorrance", "cooktorrance (textbook V-cavity)")):
        result = compare("brushed", defines={"res": str(res), "metal": "roughconductor"},
                         defines_b={"metal": metal}, spp=spp, labels=("roughconductor", label))
        fig = figure(result, ctx.figure(f"brushed_{metal}_vs_roughconductor.png"),
                     f"roughconductor | {label} (brushed aluminium, αu = 0.05, αv = 0.3)")
        if metal == "cooktorrance-smith":
            s.rows.append(Row("cooktorrance smith", "render vs anisotropic roughconductor "
                              "(brushed aluminium)", result.verdict().split(" (")[0],
                              "≤ 3 × noise floor", not result.different()))
        parts += ["```", result.summary(), "```", "", image(ctx, fig, label), ""]
    return "\n".join(parts)


def sampling(ctx: Context, s: Section) -> str:
    thetas = ctx.n((0.0, 45.0, 85.0), (85.0,))
    pairs = ctx.n(((0.04, 0.4), (0.4, 0.04)), ((0.04, 0.4),))
    configs = [(k, sh, v) for k in KINDS for sh, v in (("smith", True), ("vcavity", True),
                                                       ("vcavity", False))]
    tests = len(configs) * len(pairs) * len(thetas)
    rows = []
    for kind, shadowing, visible in configs:
        worst, fails = 1.0, 0
        for pair in pairs:
            for theta in thetas:
                r = checks.chi2_bsdf(ct(distribution=kind, shadowing=shadowing, alpha_u=pair[0],
                                        alpha_v=pair[1], sample_visible=visible, eta=1.5),
                                     wi=_wi(theta), res=None, ires=None, test_count=tests,
                                     sample_count=ctx.n(1_000_000, 200_000))
                worst, fails = min(worst, r.value), fails + (not r.passed)
        sampler = "VNDF" if visible else "D cos"
        s.rows.append(Row(f"cooktorrance {kind} {shadowing}", f"χ², {sampler}, anisotropic "
                          f"(αu, αv) ∈ {{{', '.join(map(str, pairs))}}}, θ ∈ "
                          f"{{{', '.join(f'{t:g}°' for t in thetas)}}}",
                          f"min p = {worst:.3g}", f"Šidák over {tests}", fails == 0))
        rows.append((kind, shadowing, sampler, f"{worst:.3g}"))
    return md_table(["distribution", "masking", "sampling", "smallest χ² p-value"], rows)


def furnace(ctx: Context, s: Section) -> tuple[str, str]:
    """F ≡ 1: the albedo at φ = 0.6 rad against the float64 reference, over θ."""
    plt = pyplot()
    thetas = np.degrees(np.arccos(np.linspace(1.0, 0.05, ctx.n(12, 4))))
    fig, ax = plt.subplots(figsize=(6, 3.8))
    rows = []
    for shadowing, style in (("vcavity", "-"), ("smith", "--")):
        for pair, color in zip(PAIRS, ("C0", "C1", "C3")):
            sp = ct(distribution="ggx", shadowing=shadowing, alpha_u=pair[0], alpha_v=pair[1],
                    fresnel="none")
            curve = checks.albedo_curve(sp, thetas, n=ctx.n(400_000, 50_000),
                                        estimators=("reference",))
            energy = checks.check_energy(sp, curve=curve)
            agree = checks.check_albedo_agreement(sp, curve=curve, rtol=1e-3)
            label = f"cooktorrance ggx {shadowing}"
            s.rows.append(Row.of(label, energy, f"F ≡ 1, (αu, αv) = {pair}: E(θ) ≤ 1"))
            s.rows.append(Row.of(label, agree, f"F ≡ 1, (αu, αv) = {pair}: E(θ) = reference"))
            ax.plot(curve.theta_deg, curve.reference[:, 0], style, color=color, lw=1.2,
                    label=f"{shadowing}, (αu, αv) = {pair}")
            ax.plot(curve.theta_deg, curve.sampled[:, 0], "o", color=color, ms=2)
            rows.append((shadowing, f"{pair}", f"{curve.reference[0, 0]:.4f}",
                         f"{curve.sampled[0, 0]:.4f}", f"{curve.reference[-1, 0]:.4f}",
                         f"{curve.sampled[-1, 0]:.4f}"))
    ax.set_title("anisotropic GGX, F ≡ 1 (lines: float64 reference; dots: sample())",
                 fontsize=9)
    ax.set_xlabel("incident angle θ (degrees), azimuth φ = 0")
    ax.set_ylabel("directional albedo")
    ax.axhline(1, color="0.5", lw=0.8, ls=":")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig_path = save_figure(fig, ctx.figure("aniso_furnace_albedo.png"))
    table = md_table(["masking", "(αu, αv)", "E(0°) reference", "E(0°) sample()",
                      f"E({thetas[-1]:.0f}°) reference", "sample()"], rows)
    return table, fig_path


def stability(ctx: Context, s: Section) -> str:
    pairs = ctx.n(((1e-4, 10.0), (10.0, 1e-4), (1e-4, 1e-3), (0.02, 1.0)), ((1e-4, 10.0),))
    grid = []
    for au, av in pairs:
        grid += checks.parameter_grid(ct(alpha_u=au, alpha_v=av, eta=1.5),
                                      distribution=list(KINDS), shadowing=["vcavity", "smith"],
                                      sample_visible=[True, False])
    r = checks.check_stability(grid, n_random=ctx.n(2_000, 200))
    s.rows.append(Row.of("cooktorrance anisotropic", r,
                         f"stability over {len(grid)} parameter sets"))
    return (f"{len(grid)} parameter sets: (αu, αv) ∈ "
            f"{{{', '.join(f'({a:g}, {b:g})' for a, b in pairs)}}} × both distributions × "
            "both masking functions × both samplers")


def section(ctx: Context) -> Section:
    s = Section("Anisotropic roughness")
    t_terms = terms(ctx, s)
    t_equal = equality(ctx, s)
    t_render = rendered(ctx, s)
    t_sampling = sampling(ctx, s)
    t_furnace, f_fig = furnace(ctx, s)
    grid = stability(ctx, s)
    s.markdown = "\n".join([
        "`cooktorrance` with `alpha_u` and `alpha_v`: the microfacet slopes stretched by αu "
        "along the surface's tangent and αv along its bitangent.", "",
        "**Terms** (float32): the NDF normalisation and Heitz's weak white furnace in three "
        "azimuths of ωo, worst over (αu, αv) ∈ "
        f"{{{', '.join(str(p) for p in ctx.n(PAIRS, PAIRS[:1]))}}} and θo:", "",
        t_terms, "",
        "**Equality with the anisotropic `roughconductor`** (aluminium; eval and pdf at "
        "random pairs over the upper hemisphere):", "", t_equal, "",
        "**Rendered** (`scenes/brushed.xml`, same seed; the noise floor is the built-in "
        "against itself with another seed):", "", t_render,
        "**Sampling** (χ², αu/αv = 1:10 and 10:1, ωi in the azimuth 0.6 rad):", "",
        t_sampling, "",
        "**White furnace** (F ≡ 1, GGX): the albedo from `sample()` against the float64 "
        "reference:", "", t_furnace, "", image(ctx, f_fig, "anisotropic furnace albedo"), "",
        f"**Stability**: no NaN, Inf or negative value over {grid}, at the stress directions "
        "of `check_stability` and random ones."])
    return s
