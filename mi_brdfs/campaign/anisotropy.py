"""Campaign section: anisotropic roughness (alpha_u, alpha_v) in cooktorrance, against the
anisotropic roughconductor and the float64 reference."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .. import checks
from ..compare import compare, figure
from ..errors import MiBrdfsWarning
from ..plots import pyplot, save_figure
from .core import Context, Row, Section, image, md_table
from .cooktorrance import KINDS, ct

#: The (αu, αv) pairs of the section: brushed both ways, and 10:1.
PAIRS = ((0.05, 0.5), (0.5, 0.05), (0.1, 1.0))
#: The pairs of the terms' integrals: those, and 10:1 the rough way round.
TERM_PAIRS = PAIRS + ((1.0, 0.1),)
#: Azimuths of ωo for the weak furnace (the roughness seen depends on it).
PHIS = (0.0, 45.0, 90.0)
#: The cases of Mitsuba's roughconductor χ² tests (at ωi = (1, 1, 1)/√3, aluminium), which
#: the plugin runs with either masking function.
UPSTREAM_CHI2 = {
    "smooth": {"alpha": 0.05},
    "beckmann-all-normals": {"alpha_u": 0.2, "alpha_v": 0.05, "sample_visible": False},
    "beckmann-visible": {"alpha_u": 0.2, "alpha_v": 0.05},
    "ggx-all-normals": {"alpha_u": 0.2, "alpha_v": 0.05, "sample_visible": False,
                        "distribution": "ggx"},
    "ggx-visible": {"alpha_u": 0.2, "alpha_v": 0.05, "distribution": "ggx"},
}


def _wi(theta_deg: float, phi: float = 0.6) -> list[float]:
    """An incident direction at ``theta_deg``, in an azimuth between the axes."""
    t = math.radians(theta_deg)
    return [math.sin(t) * math.cos(phi), math.sin(t) * math.sin(phi), math.cos(t)]


def _reference_terms(kind: str, pair, masking: str):
    """(D, G1) of the float64 reference (:mod:`mi_brdfs.reference.cooktorrance`)."""
    from ..reference import cooktorrance as ref

    g1 = ref.vcavity_g1 if masking == "vcavity" else \
        (lambda v, m: ref.smith_g1(kind, pair, v, m))
    return (lambda m: ref.ndf(kind, pair, m)), g1


def terms(ctx: Context, s: Section) -> str:
    """∫ D cos = 1 and the weak furnace, of the package's float32 terms and of the float64
    reference, for each distribution, masking, pair and azimuth of ωo."""
    rows = []
    for kind in KINDS:
        for masking, label in (("smith", "Smith, exact"), ("vcavity", "V-cavity")):
            for what in ("float32", "float64"):
                worst_ndf = worst_weak = 0.0
                for pair in ctx.n(TERM_PAIRS, PAIRS[:1]):
                    D, G1 = checks.package_terms(kind, pair, masking) if what == "float32" \
                        else _reference_terms(kind, pair, masking)
                    ndf = checks.check_ndf(D, pair, f"{kind} α = {pair} {what}")
                    worst_ndf = max(worst_ndf, abs(ndf.value - 1))
                    s.rows.append(Row.of(f"cooktorrance terms {kind} ({what})", ndf,
                                         f"∫ D cos = 1, (αu, αv) = {pair}"))
                    for phi in PHIS:
                        weak = checks.check_weak_furnace(D, G1, pair,
                                                         f"{kind} {label} α = {pair} {what}",
                                                         phi_deg=phi)
                        worst_weak = max(worst_weak, abs(weak.value - 1))
                        s.rows.append(Row.of(f"cooktorrance terms {kind} ({what})", weak,
                                             f"weak furnace, {label}, (αu, αv) = {pair}, "
                                             f"φo = {phi:g}°"))
                rows.append((kind, label, what, f"{worst_ndf:.1e}", f"{worst_weak:.1e}"))
    return md_table(["distribution", "masking", "terms", "worst |∫ D cos − 1|",
                     "worst |weak furnace − 1| (θo ≤ 84°, φo ∈ {0°, 45°, 90°})"], rows)


def normal_samplers(ctx: Context, s: Section) -> str:
    """
    χ² of the package's microfacet-normal samplers against their densities on the sphere of m:
    sample_ndf ~ D cosθ, sample_visible ~ the visible normals with the exact Smith G1, and
    sample_vcavity_visible ~ those with the V-cavity G1, for αu/αv = 1:10 and 10:1 at normal,
    45° and grazing (83°) incidence, ωi in an azimuth between the axes.
    """
    import drjit as dr
    import mitsuba as mi
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    from ..scattering import microfacet as mf

    thetas = ctx.n((0.0, math.pi / 4, 1.45), (0.0, 1.45))
    pairs = ctx.n(PAIRS[:2], PAIRS[:1])
    # 1e6 samples see the trapezoid rule's error in the cells of a res-201, ires-16 grid at
    # α = 0.05 near grazing (p ~ 1e-4): the finer grid with them, as chi2_settings does
    count, res, ires = ctx.n((1_000_000, 301, 32), (200_000, 201, 16))
    tests = len(KINDS) * len(pairs) * (1 + 2 * len(thetas))
    rows = []
    for kind in KINDS:
        worst = {}
        for pair in pairs:
            def distr():
                return mf.Distribution(kind, *(mi.Float(a) for a in pair))

            for theta in thetas:
                wi = mi.Vector3f(math.sin(theta) * math.cos(0.6),
                                 math.sin(theta) * math.sin(0.6), math.cos(theta))
                dr.make_opaque(wi)
                cases = [] if theta else [("D cos (sample_ndf)", 2, lambda u: distr().sample(u),
                                           lambda m: mf.pdf_ndf(distr().ndf(m), m))]
                cases += [
                    ("visible, Smith (sample_visible)", 2,
                     lambda u: distr().sample_visible(wi, u),
                     lambda m: mf.pdf_visible(distr().ndf(m), distr().smith_g1(wi, m), wi, m)),
                    ("visible, V-cavity (sample_vcavity_visible)", 3,
                     lambda u: distr().sample_vcavity_visible(wi, mi.Point2f(u.x, u.y), u.z),
                     lambda m: mf.pdf_visible(distr().ndf(m), mf.vcavity_g1(wi, m), wi, m)),
                ]
                for name, dim, sample_m, pdf_m in cases:
                    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_m,
                                         pdf_func=pdf_m, sample_dim=dim, res=res, ires=ires,
                                         sample_count=count)
                    passed = bool(test.run(significance_level=0.01, test_count=tests,
                                           quiet=True))
                    p = float(test.p_value) if test.p_value is not None else float("nan")
                    p_worst, failed = worst.get(name, (1.0, 0))
                    worst[name] = (min(p_worst, p), failed + (not passed))
        for name, (p, failed) in worst.items():
            s.rows.append(Row(f"microfacet normals {kind}", f"χ², {name}, (αu, αv) ∈ "
                              f"{{{', '.join(map(str, pairs))}}}", f"min p = {p:.3g}",
                              f"Šidák over {tests}", failed == 0))
            rows.append((kind, name, f"{p:.3g}"))
    return md_table(["distribution", "sampler", f"smallest χ² p-value ({count:.0e} samples, "
                     f"res {res}, ires {ires})"], rows)


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
    # the configurations of Mitsuba's own roughconductor χ² tests, with either masking
    tests = 2 * len(UPSTREAM_CHI2)
    for shadowing in ("smith", "vcavity"):
        worst, fails = 1.0, 0
        for params in UPSTREAM_CHI2.values():
            r = checks.chi2_bsdf(ct(shadowing=shadowing, material="Al", **params),
                                 wi=[1.0, 1.0, 1.0], res=None, ires=None, test_count=tests,
                                 sample_count=ctx.n(1_000_000, 200_000))
            worst, fails = min(worst, r.value), fails + (not r.passed)
        s.rows.append(Row(f"cooktorrance {shadowing}", "χ², the cases of Mitsuba's "
                          "roughconductor tests (" + ", ".join(UPSTREAM_CHI2) + "), ωi = "
                          "(1, 1, 1)/√3", f"min p = {worst:.3g}", f"Šidák over {tests}",
                          fails == 0))
        rows.append(("Mitsuba's cases", shadowing, "both", f"{worst:.3g}"))
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
    pairs = ctx.n(((1e-4, 10.0), (10.0, 1e-4), (1e-4, 1e-3), (0.02, 1.0), (0.0, 0.5)),
                  ((1e-4, 10.0),))
    grid = []
    for au, av in pairs:
        grid += checks.parameter_grid(ct(alpha_u=au, alpha_v=av, eta=1.5),
                                      distribution=list(KINDS), shadowing=["vcavity", "smith"],
                                      sample_visible=[True, False])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)  # alpha_u = 0 is clamped
        r = checks.check_stability(grid, n_random=ctx.n(2_000, 200))
    s.rows.append(Row.of("cooktorrance anisotropic", r,
                         f"stability over {len(grid)} parameter sets"))
    return (f"{len(grid)} parameter sets: (αu, αv) ∈ "
            f"{{{', '.join(f'({a:g}, {b:g})' for a, b in pairs)}}} × both distributions × "
            "both masking functions × both samplers")


def section(ctx: Context) -> Section:
    s = Section("Anisotropic roughness")
    t_terms = terms(ctx, s)
    t_normals = normal_samplers(ctx, s)
    t_equal = equality(ctx, s)
    t_render = rendered(ctx, s)
    t_sampling = sampling(ctx, s)
    t_furnace, f_fig = furnace(ctx, s)
    grid = stability(ctx, s)
    s.markdown = "\n".join([
        "`cooktorrance` with `alpha_u` and `alpha_v`: the microfacet slopes stretched by αu "
        "along the surface's tangent and αv along its bitangent.", "",
        "**Terms** (the package's, in float32, and the float64 reference's): the NDF "
        "normalisation and Heitz's weak white furnace in three azimuths of ωo, worst over "
        f"(αu, αv) ∈ {{{', '.join(str(p) for p in ctx.n(TERM_PAIRS, PAIRS[:1]))}}} and θo:", "",
        t_terms, "",
        "**Microfacet-normal samplers** (χ² on the sphere of m, each against its density; "
        "ωi in the azimuth 0.6 rad):", "", t_normals, "",
        "**Equality with the anisotropic `roughconductor`** (aluminium; eval and pdf at "
        "random pairs over the upper hemisphere):", "", t_equal, "",
        "**Rendered** (`scenes/brushed.xml`, same seed; the noise floor is the built-in "
        "against itself with another seed):", "", t_render,
        "**Sampling** (χ², αu/αv = 1:10 and 10:1, ωi in the azimuth 0.6 rad; then the "
        "configurations of Mitsuba's own roughconductor χ² tests):", "",
        t_sampling, "",
        "**White furnace** (F ≡ 1, GGX): the albedo from `sample()` against the float64 "
        "reference:", "", t_furnace, "", image(ctx, f_fig, "anisotropic furnace albedo"), "",
        f"**Stability**: no NaN, Inf or negative value over {grid}, at the stress directions "
        "of `check_stability` and random ones."])
    return s
