"""Campaign section: Ashikhmin-Shirley against the float64 reference and the paper's claims."""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from .. import checks
from ..bsdfspec import load_bsdf
from ..checks.sampling import chi2_settings
from ..plots import pyplot, save_figure
from ..reference import Ashikhmin
from .core import Context, Row, Section, image, md_table

#: Incident angles of the energy table (degrees), dense towards grazing.
THETAS = (0.0, 30.0, 60.0, 80.0, 85.0, 89.0, 89.9)
#: Exponents of the energy table: isotropic from a uniform to a mirror-like lobe, and 1:100.
EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1e4, (10.0, 1000.0))
#: Specular reflectances of the energy table, with Rd = 1 (the most energy the model allows).
RS = (0.0, 0.05, 0.5, 1.0)


def spec(exponent, rho_d: float = 1.0, rho_s: float = 0.05) -> dict:
    out = {"type": "ashikhmin", "diffuse_reflectance": rho_d, "specular_reflectance": rho_s}
    if isinstance(exponent, tuple):
        out.update(nu=exponent[0], nv=exponent[1])
    else:
        out["exponent"] = exponent
    return out


def _label(exponent) -> str:
    return f"nu, nv = {exponent[0]:g}, {exponent[1]:g}" if isinstance(exponent, tuple) else \
        f"n = {exponent:g}"


def energy(ctx: Context, s: Section) -> str:
    """The reference's E(θ) with Rd = 1 at every Rs, against 1 and against the bounds the
    lobe choice uses; sample() agrees with the reference."""
    rows, worst, where = [], 0.0, None
    for exponent in ctx.n(EXPONENTS, (1.0, 1e4, (10.0, 1000.0))):
        ref = Ashikhmin(exponent, 1.0, np.array(RS))
        e = np.array([ref.albedo(math.radians(t), 0.4) for t in THETAS])  # (θ, Rs)
        i, j = np.unravel_index(int(np.argmax(e)), e.shape)
        if e[i, j] > worst:
            worst, where = e[i, j], f"{_label(exponent)}, Rs = {RS[j]:g}, θ = {THETAS[i]:g}°"
        for j, rs in enumerate(RS):
            rows.append((_label(exponent), f"{rs:g}", *(f"{v:.4f}" for v in e[:, j])))
    s.values["ashikhmin: max E"] = f"{worst:.4f}"
    s.values["ashikhmin: max E at"] = where
    s.rows.append(Row("ashikhmin", "reference E(θ) ≤ 1, Rd = 1, every Rs, θ ≤ 89.9° (the "
                      "paper's claim)", f"max {worst:.4f} ({where})", "≤ 1", worst <= 1.0))
    for exponent, rho_s in ((20.0, 0.05), ((10.0, 1000.0), 0.5)):
        agreement = checks.check_albedo_agreement(spec(exponent, 1.0, rho_s),
                                                  n=ctx.n(400_000, 50_000))
        s.rows.append(Row.of("ashikhmin", agreement, f"E(θ) from sample() = reference, "
                                                     f"{_label(exponent)}, Rs = {rho_s:g}"))
        conserved = checks.check_energy(spec(exponent, 1.0, rho_s), n=ctx.n(400_000, 50_000))
        s.rows.append(Row.of("ashikhmin", conserved, f"E(θ) ≤ 1 from sample() and eval(), "
                                                     f"{_label(exponent)}, Rs = {rho_s:g}"))
    return md_table(["exponents", "Rs", *(f"E({t:g}°)" for t in THETAS)], rows)


def albedo_figure(ctx: Context) -> str:
    """E(θ) for Rd = 1 and three Rs: lines the float64 reference, dots the sample() mean."""
    plt = pyplot()
    thetas = np.linspace(0.0, 89.5, ctx.n(36, 6))
    dots = thetas[:: max(1, len(thetas) // 6)]
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.6), sharey=True)
    for ax, exponent in zip(axes, (1.0, 100.0, (10.0, 1000.0))):
        for rs, color in zip((0.0, 0.5, 1.0), ("C0", "C1", "C3")):
            ref = Ashikhmin(exponent, 1.0, rs)
            ax.plot(thetas, [float(ref.albedo(math.radians(t))[0]) for t in thetas], "-",
                    color=color, lw=1.2, label=f"Rs = {rs:g}")
            means = [checks.albedo_sampled(spec(exponent, 1.0, rs), math.radians(t),
                                           n=ctx.n(100_000, 10_000))[0][0] for t in dots]
            ax.plot(dots, means, "o", color=color, ms=3)
        ax.axhline(1.0, color="0.5", lw=0.8, ls=":")
        ax.set_title(_label(exponent), fontsize=9)
        ax.set_xlabel("incident angle θ (degrees)")
        ax.set_xlim(0, 90)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("albedo E(θ), Rd = 1")
    axes[0].legend(fontsize=8)
    fig.suptitle("Ashikhmin-Shirley albedo (lines: float64 reference; dots: sample() mean)",
                 fontsize=9)
    return save_figure(fig, ctx.figure("ashikhmin_albedo.png"))


def _chi2(sp: dict, theta: float, tests: int, ctx: Context, lobe=None):
    """χ² at incidence ``theta`` (degrees), at least at res 201, ires 16: the automatic choice
    for a uniform half-vector lobe (n = 0) at grazing incidence, (101, 8), integrates its
    steep rise towards the forward horizon too coarsely for 10⁶ samples."""
    t = math.radians(theta)
    wi = np.array([0.6 * math.sin(t), 0.8 * math.sin(t), math.cos(t)])
    bsdf_ctx = None
    if lobe is not None:
        bsdf_ctx = mi.BSDFContext()
        bsdf_ctx.component = lobe
    res, ires, _, _ = chi2_settings(load_bsdf(sp), wi, bsdf_ctx)
    return checks.chi2_bsdf(sp, wi=wi, ctx=bsdf_ctx, res=max(res, 201), ires=max(ires, 16),
                            test_count=tests, sample_count=ctx.n(1_000_000, 200_000))


def sampling_and_stability(ctx: Context, s: Section) -> str:
    exponents = ctx.n((0.0, 10.0, 1000.0, (10.0, 1000.0), (1000.0, 10.0)), (0.0, (10.0, 1000.0)))
    thetas = ctx.n((0.0, 45.0, 85.0, 89.0), (0.0, 85.0))
    tests = len(exponents) * len(thetas) + 2 * len(exponents)
    rows = []
    for exponent in exponents:
        worst_p, fails = 1.0, 0
        for theta in thetas:
            r = _chi2(spec(exponent, 0.5, 0.1), theta, tests, ctx)
            worst_p, fails = min(worst_p, r.value), fails + (not r.passed)
        for lobe in (0, 1):  # each lobe alone, at 60°
            r = _chi2(spec(exponent, 0.5, 0.1), 60.0, tests, ctx, lobe)
            worst_p, fails = min(worst_p, r.value), fails + (not r.passed)
        s.rows.append(Row(f"ashikhmin {_label(exponent)}", "χ², θ ∈ {" + ", ".join(
            f"{t:g}°" for t in thetas) + "} and each lobe alone", f"min p = {worst_p:.3g}",
            f"Šidák over {tests}", fails == 0))
        cons = checks.check_consistency(spec(exponent, 0.5, 0.2), n=ctx.n(100_000, 20_000))
        recip = checks.check_reciprocity(spec(exponent, 0.5, 0.2), n=ctx.n(200_000, 20_000))
        lobes = checks.check_lobes(spec(exponent, 0.5, 0.2), n=ctx.n(200_000, 20_000))
        for r in (cons, recip, lobes):
            s.rows.append(Row.of(f"ashikhmin {_label(exponent)}", r))
        rows.append((_label(exponent), f"{worst_p:.3g}", f"{cons.value:.2g}",
                     f"{recip.value:.2g}"))
    grid = [spec(e, d, r) for e in ctx.n([0.0, 1.0, 1e3, 1e6, 1e10, 1e30, (0.0, 1e6),
                                          (1e6, 0.0), (1.0, 1e30)], [0.0, 1e6, (0.0, 1e6)])
            for d in (0.0, 1.0) for r in (0.0, 1.0)]
    stab = checks.check_stability(grid, n_random=ctx.n(5_000, 500))
    s.rows.append(Row.of("ashikhmin", stab, f"stability over {len(grid)} parameter sets"))
    return md_table(["exponents", "smallest χ² p-value", "consistency (max rel. error)",
                     "max asymmetry (reciprocity)"], rows)


def furnace_and_scalar(ctx: Context, s: Section) -> None:
    """A white furnace render against the albedo curve, and the scalar variant's pass."""
    r = checks.check_furnace(spec(100.0, 0.9, 0.1), spp=ctx.n(128, 16), res=ctx.n(64, 24),
                             n=ctx.n(200_000, 20_000))
    s.rows.append(Row.of("ashikhmin (n = 100, Rd = 0.9, Rs = 0.1)", r,
                         "furnace render = E(θ) prediction"))
    with ctx.scalar():
        sp = spec((10.0, 300.0), 0.5, 0.2)
        s.rows.append(Row.of(f"ashikhmin ({ctx.scalar_variant})",
                             checks.check_consistency(sp, n=ctx.n(1000, 200))))
        s.rows.append(Row.of(f"ashikhmin ({ctx.scalar_variant})",
                             checks.check_stability([spec(e) for e in (0.0, 1e6, (0.0, 1e6))],
                                                    n_random=ctx.n(300, 30))))


def section(ctx: Context) -> Section:
    s = Section("Ashikhmin-Shirley: anisotropic Phong")
    table = energy(ctx, s)
    fig = albedo_figure(ctx)
    ss = sampling_and_stability(ctx, s)
    furnace_and_scalar(ctx, s)
    s.markdown = "\n".join([
        "The `ashikhmin` plugin (Ashikhmin & Shirley 2000, \"An Anisotropic Phong BRDF "
        "Model\") against its float64 reference (`mi_brdfs/reference/ashikhmin.py`: the "
        "paper's formulas as written, the albedo by a quadrature over the half vector "
        "in the lobe's own variable). The paper claims the model conserves energy. It does, "
        "at every Rs and Rd in [0, 1], grazing incidence included: for ωo above the surface "
        "k·h > cosθi/2, so the specular albedo is at most Rs + (1 − Rs)(1 − cosθi/2)⁵, and "
        "the diffuse albedo is exactly Rd (1 − Rs)(1 − (1 − cosθi/2)⁵) "
        "(`mi_brdfs/scattering/ashikhmin.py`).", "",
        f"**Albedo** E(θ) with Rd = 1 (the most the model allows), float64 reference, at most "
        f"{s.values['ashikhmin: max E']} ({s.values['ashikhmin: max E at']}):", "", table, "",
        image(ctx, fig, "Ashikhmin-Shirley albedo curves"), "",
        "**Sampling, consistency and reciprocity** (ρd = 0.5, Rs = 0.1 for χ², at least "
        "res 201, ires 16), and stability over exponents from 0 to 10³⁰ × Rs, Rd ∈ {0, 1} at "
        "stress directions (summary table):", "", ss, "",
        "A white furnace render and a smaller pass in the scalar variant are in the summary "
        "table."])
    return s
