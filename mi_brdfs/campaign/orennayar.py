"""Campaign section: Oren-Nayar against the float64 reference, Lambert, and the lectures' claims."""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from .. import checks
from ..checks import batch
from ..compare import compare, figure
from ..plots import pyplot, save_figure
from ..reference import OrenNayar, hemisphere_albedo
from .core import Context, Row, Section, image, md_table

FORMS = ("qualitative", "full")
SIGMAS = (0.1, 0.2, 0.3, 0.5, 1.0, math.pi / 2)
THETAS = (0.0, 60.0, 80.0, 89.0)


def spec(form: str, sigma: float, rho: float = 1.0) -> dict:
    return {"type": "orennayar", "form": form, "sigma": sigma, "reflectance": rho}


def energy(ctx: Context, s: Section) -> str:
    """E(θ)/ρ of the reference (the qualitative form is linear in ρ; full at ρ = 1)."""
    rows = []
    for form in FORMS:
        worst, where = 0.0, None
        for sigma in ctx.n(SIGMAS, SIGMAS[1::2]):
            e = [float(OrenNayar(1.0, sigma, form).albedo(math.radians(t))[0]) for t in THETAS]
            if max(e) > worst:
                worst, where = max(e), (sigma, THETAS[int(np.argmax(e))])
            rows.append((form, f"{sigma:.3g}", *(f"{v:.4f}" for v in e)))
        s.values[f"orennayar {form}: max E"] = f"{worst:.4f}"
        s.values[f"orennayar {form}: max E at"] = f"σ = {where[0]:.3g}, θ = {where[1]:g}°"
        s.rows.append(Row(f"orennayar {form}", "reference E(θ) ≤ 1 with ρ = 1, θ ≤ 89°",
                          f"max {worst:.4f} ({s.values[f'orennayar {form}: max E at']})",
                          "≤ 1", worst <= 1.0, expected_fail=True))
        for sigma in (0.2, 1.0, math.pi / 2):
            curve = checks.albedo_curve(spec(form, sigma), n=ctx.n(400_000, 50_000),
                                        estimators=("eval", "reference"))
            r = checks.check_albedo_agreement(spec(form, sigma), curve=curve)
            s.rows.append(Row.of(f"orennayar {form}", r,
                                 f"E(θ) from sample() = reference, σ = {sigma:.3g}"))
            # the energy check (sample() and eval()) reaches the reference's verdict
            bounded = bool(curve.reference.max() <= 1.0)
            e = checks.check_energy(spec(form, sigma), curve=curve)
            s.rows.append(Row(f"orennayar {form}",
                              f"energy check = reference verdict, σ = {sigma:.3g}",
                              f"max E {e.value:.4f}: {'≤ 1' if e.passed else '> 1'}",
                              "≤ 1" if bounded else "> 1", e.passed == bounded))
    return md_table(["form", "σ", *(f"E({t:g}°)" for t in THETAS)], rows)


def albedo_figure(ctx: Context) -> str:
    """E(θ) of both forms for several σ against Lambert's (ρ = 1): lines the float64
    reference, dots the plugin's sample() mean."""
    plt = pyplot()
    thetas = np.linspace(0.0, 89.0, ctx.n(30, 6))
    dots = thetas[:: max(1, len(thetas) // 6)]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, form in zip(axes, FORMS):
        ax.axhline(1.0, color="0.3", lw=1.2, label="lambert (ρ = 1)")
        for sigma, color in zip((0.2, 0.5, 1.0, math.pi / 2), ("C0", "C1", "C2", "C3")):
            ref = OrenNayar(1.0, sigma, form)
            ax.plot(thetas, [float(ref.albedo(math.radians(t), 96, 192)[0]) for t in thetas],
                    "-", color=color, lw=1.2, label=f"σ = {sigma:.3g}")
            means = [checks.albedo_sampled(spec(form, sigma), math.radians(t),
                                           n=ctx.n(100_000, 10_000))[0][0] for t in dots]
            ax.plot(dots, means, "o", color=color, ms=3)
        ax.set_title(f"{form} (lines: float64 reference; dots: sample() mean)", fontsize=9)
        ax.set_xlabel("incident angle θ (degrees)")
        ax.set_xlim(0, 90)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("albedo E(θ), ρ = 1")
    axes[0].legend(fontsize=8)
    return save_figure(fig, ctx.figure("orennayar_albedo.png"))


def backscatter(ctx: Context, s: Section) -> tuple[str, str]:
    """
    The lectures' observation: a rough diffuse surface retro-reflects and looks flatter.
    Backscatter ratio f(ωi, ωi)/f(ωi, mirror of ωi) at θ = 60°, from the plugin's eval; and
    the radiance profile across a sphere lit from the camera (a full moon looks flat).
    """
    theta = math.radians(60.0)
    wi = np.array([[math.sin(theta), 0.0, math.cos(theta)]])
    mirror = wi * [-1, -1, 1]
    sigmas = np.linspace(0.0, math.pi / 2, ctx.n(25, 7))
    ratios = {}
    for form in FORMS:
        values = []
        for sigma in sigmas:
            bsdf = batch.load_bsdf(spec(form, float(sigma), 0.8))
            back = batch.evaluate(bsdf, wi, wi).value[0, 0]
            fore = batch.evaluate(bsdf, wi, mirror).value[0, 0]
            values.append(back / fore)
        ratios[form] = values
        s.values[f"orennayar {form}: backscatter ratio at σ = π/2"] = f"{values[-1]:.2f}"
    monotone = all(np.all(np.diff(v) > 0) for v in ratios.values())
    s.rows.append(Row("orennayar", "backscatter ratio at 60° grows with σ (from 1 at σ = 0)",
                      ", ".join(f"{f} → {ratios[f][-1]:.2f}" for f in FORMS), "increasing",
                      monotone and abs(ratios["qualitative"][0] - 1) < 1e-6))

    # the profile across a sphere lit from the viewer's direction
    res, spp = ctx.n(128, 48), ctx.n(64, 16)
    profiles = {}
    for label, bsdf in (("lambert", {"type": "lambert", "reflectance": 0.8}),
                        ("orennayar σ = 0.5", spec("full", 0.5, 0.8)),
                        ("orennayar σ = 1.0", spec("full", 1.0, 0.8))):
        scene = mi.load_dict({
            "type": "scene", "integrator": {"type": "direct"},
            "light": {"type": "directional", "direction": [0, 0, -1], "irradiance": 3.0},
            "shape": {"type": "sphere", "bsdf": bsdf},
            "sensor": {"type": "orthographic",
                       "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5],
                                                                  target=[0, 0, 0],
                                                                  up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": res, "height": res,
                                "rfilter": {"type": "box"}}}})
        img = np.array(mi.render(scene, spp=spp), dtype=np.float64)
        profiles[label] = img[res // 2, :, 0]
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for form, style in zip(FORMS, ("-", "--")):
        axes[0].plot(np.degrees(sigmas), ratios[form], style, label=form)
    axes[0].axhline(1.0, color="0.5", lw=0.8, ls=":")
    axes[0].set_xlabel("σ (degrees)")
    axes[0].set_ylabel("f(ωi, ωi) / f(ωi, mirror of ωi), θi = 60°")
    axes[0].set_title("Backscatter: light returned towards the light", fontsize=9)
    axes[0].legend(fontsize=8)
    x = np.linspace(-1, 1, res)
    for label, profile in profiles.items():
        axes[1].plot(x, profile, label=label)
    axes[1].set_xlabel("position across the sphere (lit and seen from the front)")
    axes[1].set_ylabel("radiance")
    axes[1].set_title("A rough sphere lit from the viewer looks flatter (full moon)", fontsize=9)
    axes[1].legend(fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    # flatness: radiance at 80 % of the radius over the centre's
    edge = int(res * 0.9)
    for label, profile in profiles.items():
        s.values[f"flatness {label}"] = f"{profile[edge] / profile[res // 2]:.3f}"
    flatter = profiles["orennayar σ = 1.0"][edge] / profiles["orennayar σ = 1.0"][res // 2] > \
        profiles["lambert"][edge] / profiles["lambert"][res // 2]
    s.rows.append(Row("orennayar", "rim/centre radiance of a sphere lit from the viewer "
                      "(0.8 of the radius)", f"σ = 1: {s.values['flatness orennayar σ = 1.0']}, "
                      f"lambert: {s.values['flatness lambert']}", "> lambert's", flatter))
    table = md_table(["surface", "rim/centre radiance (0.8 of the radius)"],
                     [(k.removeprefix("flatness "), v) for k, v in s.values.items()
                      if k.startswith("flatness ")])
    return save_figure(fig, ctx.figure("orennayar_backscatter.png")), table


def checks_table(ctx: Context, s: Section) -> str:
    rows = []
    for form in FORMS:
        worst_p, fails = 1.0, 0
        for sigma in (0.3, math.pi / 2):
            for t in (0.0, 45.0, 85.0):
                r = checks.chi2_bsdf(spec(form, sigma, 0.8), wi=batch.direction(math.radians(t)),
                                     test_count=12, sample_count=ctx.n(1_000_000, 100_000))
                worst_p, fails = min(worst_p, r.value), fails + (not r.passed)
        s.rows.append(Row(f"orennayar {form}", "χ², σ ∈ {0.3, π/2}, θ ∈ {0°, 45°, 85°}",
                          f"min p = {worst_p:.3g}", "Šidák over 12", fails == 0))
        recip = checks.check_reciprocity(spec(form, 0.8, 0.6), n=ctx.n(200_000, 20_000))
        cons = checks.check_consistency(spec(form, 0.8, 0.6), n=ctx.n(100_000, 20_000))
        grid = checks.parameter_grid({"type": "orennayar", "form": form},
                                     sigma=[0.0, 1e-4, 0.5, math.pi / 2], reflectance=[0.0, 1.0])
        stab = checks.check_stability(grid, n_random=ctx.n(5_000, 500))
        for r, label in ((recip, "reciprocity"), (cons, None),
                         (stab, f"stability over {len(grid)} parameter sets")):
            s.rows.append(Row.of(f"orennayar {form}", r, label))
        rows.append((form, f"{worst_p:.3g}", f"{recip.value:.2g}", f"{cons.value:.2g}",
                     int(stab.value)))
    return md_table(["form", "smallest χ² p-value", "max asymmetry (reciprocity)",
                     "consistency (max rel. error)", "NaN/Inf/negative values"], rows)


def reference_brute_force(ctx: Context, s: Section) -> None:
    """The reference's split albedo quadrature against a plain 1024² hemisphere quadrature of
    its brdf(), within 1e-5, at oblique and grazing incidence (ρ = 0.8, σ = 0.7)."""
    for form in FORMS:
        model, worst = OrenNayar(0.8, 0.7, form), 0.0
        for theta in (30.0, 75.0):
            plain = hemisphere_albedo(model.brdf, math.radians(theta), 1024, 1024)
            worst = max(worst, float(np.max(np.abs(model.albedo(math.radians(theta)) / plain
                                                   - 1))))
        s.rows.append(Row(f"orennayar {form} reference", "E(θ) = 1024² grid of brdf(), "
                          "θ ∈ {30°, 75°}", f"{worst:.2g}", "1e-5 relative", worst <= 1e-5))


def lambert_limit(ctx: Context, s: Section) -> str:
    """σ = 0 computes what lambert computes: eval, pdf and samples to the bit."""
    rows = []
    for form in FORMS:
        r = checks.check_equal(spec(form, 0.0, 0.7), {"type": "lambert", "reflectance": 0.7},
                               n=ctx.n(1_000_000, 100_000), rtol=0.0, atol=0.0)
        s.rows.append(Row.of(f"orennayar {form}", r, "σ = 0: = lambert pointwise, to the bit"))
        rows.append((form, f"{r.value:.3g}"))
    return md_table(["form (σ = 0, ρ = 0.7)", "largest relative difference to lambert"], rows)


def rendered(ctx: Context, s: Section) -> str:
    res, spp = ctx.n(192, 48), ctx.n(64, 16)
    result = compare("cbox", defines={"res": str(res), "material": "lambert"},
                     defines_b={"material": "orennayar"}, spp=spp,
                     labels=("lambert", "orennayar σ = 0.2"))
    fig = figure(result, ctx.figure("orennayar_vs_lambert.png"),
                 "Cornell box: lambert | orennayar (qualitative, σ = 0.2)")
    return image(ctx, fig, "Cornell box: lambert vs orennayar")


def section(ctx: Context) -> Section:
    s = Section("Oren-Nayar: rough diffuse")
    table = energy(ctx, s)
    reference_brute_force(ctx, s)
    fig_albedo = albedo_figure(ctx)
    fig, flat = backscatter(ctx, s)
    ct = checks_table(ctx, s)
    limit = lambert_limit(ctx, s)
    render = rendered(ctx, s)
    s.markdown = "\n".join([
        "The `orennayar` plugin (Oren & Nayar 1994; a model Mitsuba 3 lacks, Mitsuba 0.6's "
        "`roughdiffuse`) against its float64 reference (`mi_brdfs/reference/orennayar.py`: the "
        "paper's formulas with angles, the albedo by quadrature; σ = 0 is Lambert, and the "
        "albedo at normal incidence has the closed form ρA, + ρ²C4 for `full`).", "",
        "**Albedo** with ρ = 1 (the reference): the model is not energy-conserving at grazing "
        f"incidence for small σ — the largest value is {s.values['orennayar qualitative: max E']} "
        f"for `qualitative` ({s.values['orennayar qualitative: max E at']}) and "
        f"{s.values['orennayar full: max E']} for `full` ({s.values['orennayar full: max E at']})"
        ". The qualitative form's albedo scales with ρ, so it stays ≤ 1 for ρ ≤ 1/max; "
        "the full form's interreflection term scales with ρ². Rough surfaces (σ ≳ 0.5) lose "
        "energy, as the single-scattering model of V-grooves does:", "", table, "",
        image(ctx, fig_albedo, "Oren-Nayar albedo curves against Lambert"), "",
        "**Backscatter and flatness**, the lectures' observation measured: the light returned "
        "towards the light grows with σ, and a rough sphere lit from the viewer's direction "
        "is flatter than a Lambertian one (its rim stays bright):", "",
        image(ctx, fig, "Oren-Nayar backscatter and flatness"), "", flat, "",
        "**Sampling, reciprocity, consistency and stability** (cosine-weighted hemisphere "
        "sampling, as Mitsuba 0.6):", "", ct, "",
        "**σ = 0 is Lambert**, computed in lambert's order of operations (eval, pdf, eval_pdf "
        "and sample() with the same random numbers at random direction pairs; "
        "`tests/plugins/test_orennayar.py` also renders both, bit-identical on one thread):",
        "", limit, "",
        "**Rendered** beside `lambert` (Cornell box, every surface one material, the default "
        "σ = 0.2): the difference is the model's — rough walls are flatter and brighter "
        "towards the light's direction:", "", render])
    return s
