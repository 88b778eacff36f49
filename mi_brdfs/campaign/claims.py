"""Campaign section: the lecture notes' claims, each checked numerically, with its figure."""

from __future__ import annotations

import math

import numpy as np

from .. import checks
from ..checks import batch
from ..plots import pyplot, save_figure
from ..reference import Phong
from ..reference import cooktorrance as ref
from .core import Context, Row, Section, image, md_table


#: "Grazing": the reflectance tends to 1 as θ → 90° (1 − F ∝ cosθ near the horizon).
GRAZING = 89.99


def two_printed_forms(ctx: Context, s: Section) -> str:
    """(F/π)·D'·G/((N·L)(N·V)) with D' = e^(…)/(4m²cos⁴β)  =  F·D·G/(4(N·L)(N·V))."""
    rng = np.random.default_rng(7)
    n = ctx.n(200_000, 20_000)
    worst, factors, count = 0.0, [], 0
    for eta in (1.2, 1.5, 2.5):
        for m in (0.05, 0.2, 0.6, 1.0):
            wi = batch.random_directions(rng, n, sphere=False)
            wo = batch.random_directions(rng, n, sphere=False)
            h = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
            F = ref.fresnel_exact(np.sum(wi * h, axis=1), eta, 0.0)[:, 0]
            G = ref.vcavity_g(wi, wo, h)
            nl, nv = wo[:, 2], wi[:, 2]
            d_printed = ref.ndf_printed_1982(m, h)         # exp(−tan²β/m²) / (4 m² cos⁴β)
            d_normalised = ref.ndf("beckmann", m, h)       # the same over π m² cos⁴β
            paper = F / math.pi * d_printed * G / (nl * nv)
            walter = F * d_normalised * G / (4 * nl * nv)
            keep = walter > 1e-300
            worst = max(worst, float(np.max(np.abs(paper - walter)[keep] / walter[keep])))
            factors.append(np.median((F / math.pi * 4 * d_printed * G / (nl * nv))[keep]
                                     / walter[keep]))
            count += int(keep.sum())
    factor = float(np.median(factors))
    s.rows.append(Row("claim", "the two printed Cook-Torrance forms are one model",
                      f"max rel. Δ {worst:.1e}", "≤ 1e-12 (float64)", worst <= 1e-12))
    s.rows.append(Row("claim", "...but only with the 4 in D' (without it: a factor)",
                      f"× {factor:.6f}", "= 4", abs(factor - 4) < 1e-9))
    return (f"Over {count:,} random (L, V) at η ∈ {{1.2, 1.5, 2.5}}, m ∈ {{0.05, 0.2, 0.6, 1}} "
            f"in float64, the 1982 form (F/π)·D'·G/((N·L)(N·V)) with "
            f"D' = exp(−tan²β/m²)/(4m²cos⁴β) and Walter's F·D·G/(4(N·L)(N·V)) with the "
            f"normalised Beckmann D differ by at most {worst:.1e} (relative): the π has moved "
            f"from D into the prefactor. Printed without the 4 in D', the form is {factor:.6f}× "
            "larger: the 'missing factor of 4' of many implementations, which a white furnace "
            "exposes at once.")


def glass(ctx: Context, s: Section) -> tuple[str, str]:
    """'Glass reflects about 4 % at normal incidence and 100 % at grazing.'"""
    plt = pyplot()
    cos = np.cos(np.radians(np.linspace(0, 90, 181)))
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    rows = []
    for eta, label in ((1.33, "water"), (1.5, "glass"), (2.42, "diamond")):
        exact = ref.fresnel_exact(cos, eta, 0.0)[:, 0]
        schlick = ref.fresnel_schlick(cos, eta, 0.0)[:, 0]
        line, = axes[0].plot(np.degrees(np.arccos(cos)), exact, label=f"{label} η = {eta}")
        axes[0].plot(np.degrees(np.arccos(cos)), schlick, "--", color=line.get_color(), lw=0.9)
        rows.append((label, eta, f"{exact[0]:.4f}", f"{schlick[0]:.4f}",
                     f"{ref.fresnel_exact([math.cos(math.radians(GRAZING))], eta, 0)[0, 0]:.4f}",
                     f"{np.abs(schlick - exact).max():.4f}",
                     f"{np.degrees(np.arccos(cos[np.argmax(np.abs(schlick - exact))])):.0f}°"))
    # the plugin itself, as α → 0: its albedo is what the renderer reflects
    f0, _ = checks.albedo_sampled({"type": "cooktorrance", "alpha": 1e-4, "eta": 1.5, "k": 0.0},
                                  0.0, n=ctx.n(100_000, 10_000))
    f85, _ = checks.albedo_sampled({"type": "cooktorrance", "alpha": 1e-4, "eta": 1.5, "k": 0.0},
                                   math.radians(85.0), n=ctx.n(100_000, 10_000))
    f0_exact = ref.fresnel_exact([1.0], 1.5, 0)[0, 0]
    f85_exact = ref.fresnel_exact([math.cos(math.radians(85.0))], 1.5, 0)[0, 0]
    f90_exact = ref.fresnel_exact([math.cos(math.radians(GRAZING))], 1.5, 0)[0, 0]
    s.rows.append(Row("claim", "glass (η 1.5) reflects about 4 % at normal incidence",
                      f"{f0_exact:.4f} (plugin, α = 1e-4: {f0.mean():.4f})", "≈ 0.04",
                      abs(f0_exact - 0.04) < 5e-3 and abs(f0.mean() - f0_exact) < 1e-3))
    s.rows.append(Row("claim", f"... and 100 % at grazing incidence (θ = {GRAZING}°)",
                      f"{f90_exact:.4f}", "≥ 0.995", f90_exact >= 0.995))
    s.rows.append(Row("cooktorrance", "renders that Fresnel curve: α = 1e-4 albedo at 85°",
                      f"{f85.mean():.4f} (exact F {f85_exact:.4f})", "± 1e-3",
                      abs(f85.mean() - f85_exact) < 1e-3))
    axes[0].set_title("exact Fresnel (solid) and Schlick (dashed), dielectrics", fontsize=9)
    axes[0].set_xlabel("θ (degrees)")
    axes[0].set_ylabel("F")
    axes[0].legend(fontsize=8)
    axes[0].grid(alpha=0.3)
    # Schlick's error over (θ, η)
    etas = np.linspace(1.01, 3.0, 200)
    err = np.stack([ref.fresnel_schlick(cos, e, 0.0)[:, 0] - ref.fresnel_exact(cos, e, 0.0)[:, 0]
                    for e in etas], axis=0)
    shown = axes[1].imshow(err, origin="lower", aspect="auto", cmap="RdBu_r",
                           extent=(0, 90, etas[0], etas[-1]), vmin=-0.06, vmax=0.06)
    axes[1].set_title("Schlick − exact over θ and η (k = 0)", fontsize=9)
    axes[1].set_xlabel("θ (degrees)")
    axes[1].set_ylabel("η")
    fig.colorbar(shown, ax=axes[1], label="ΔF")
    path = save_figure(fig, ctx.figure("claims_fresnel.png"))
    i, j = np.unravel_index(int(np.argmax(np.abs(err))), err.shape)
    s.rows.append(Row("claim", "Schlick's approximation error, dielectrics η ∈ [1.01, 3]",
                      f"max |ΔF| {np.abs(err).max():.3f} at η = {etas[i]:.2f}, "
                      f"θ = {np.degrees(np.arccos(cos[j])):.0f}°", "measured", True))
    table = md_table(["medium", "η", "F(0°) exact", "F(0°) Schlick", f"F({GRAZING}°) exact",
                      "max |Schlick − exact|", "at θ"], rows)
    return table, path


def conductors(ctx: Context, s: Section) -> str:
    """Schlick for metals: R0 from η, k, against the exact conductor Fresnel term."""
    from ..materials import conductor_ior

    cos = np.cos(np.radians(np.linspace(0, 90, 361)))
    rows = []
    for name in ("Au", "Ag", "Cu", "Al", "Cr"):
        eta, k = conductor_ior(name)
        exact = ref.fresnel_exact(cos, eta, k)
        schlick = ref.fresnel_schlick(cos, eta, k)
        err = np.abs(schlick - exact)
        i, c = np.unravel_index(int(np.argmax(err)), err.shape)
        rows.append((name, ", ".join(f"{x:.3f}" for x in eta), ", ".join(f"{x:.3f}" for x in k),
                     ", ".join(f"{x:.3f}" for x in exact[0]), f"{err.max():.4f}",
                     f"{np.degrees(np.arccos(cos[i])):.0f}° (channel {c})"))
        s.rows.append(Row("claim", f"Schlick's approximation error, conductor {name}",
                          f"max |ΔF| {err.max():.4f}", "measured", True))
    return md_table(["metal", "η (RGB)", "k (RGB)", "F(0°)", "max |Schlick − exact|", "at"],
                    rows)


def phong_claims(ctx: Context, s: Section) -> tuple[str, str]:
    """'Phong does not conserve energy, is not reciprocal, its maximum is always specular.'"""
    rows = []
    for form in ("normalized", "lecture", "original"):
        e1 = float(Phong(0.0, 1.0, 1.0, form).albedo(0.0)[0])
        sp = {"type": "phong", "form": form, "exponent": 1.0, "diffuse_reflectance": 0.0,
              "specular_reflectance": 1.0}
        recip = checks.check_reciprocity(sp, n=ctx.n(100_000, 10_000))
        rows.append((form, f"{e1:.4f}", "yes" if e1 <= 1 + 1e-9 else "no, E > 1",
                     f"{recip.value:.3g}", "yes" if recip.details["reciprocal"] else "no"))
        if form != "normalized":
            s.rows.append(Row("claim", f"Phong ({form}) does not conserve energy",
                              f"E(0°) = {e1:.4f} at n = 1, ks = 1", "> 1", e1 > 1))
    s.rows.append(Row("claim", "...but the normalized form does",
                      f"E(0°) = {float(Phong(0.0, 1.0, 1.0).albedo(0.0)[0]):.4f}", "≤ 1",
                      float(Phong(0.0, 1.0, 1.0).albedo(0.0)[0]) <= 1 + 1e-9))
    return md_table(["form", "E(0°), n = 1, ks = 1", "conserves energy",
                     "max reciprocity asymmetry", "reciprocal"], rows), ""


def maxima(ctx: Context, s: Section) -> tuple[str, str]:
    """Where f (and f·cosθo) peaks in the plane of incidence, against the mirror direction."""
    plt = pyplot()
    theta_o = np.radians(np.linspace(0, 89.95, 4000))
    wo = np.stack([-np.sin(theta_o), 0 * theta_o, np.cos(theta_o)], axis=1)  # mirror side
    models = {
        "Phong (mirror lobe), n = 30": Phong(0.0, 1.0, 30.0, "normalized", "mirror"),
        "Blinn-Phong (halfway), n = 30": Phong(0.0, 1.0, 30.0, "normalized", "halfway"),
        "Cook-Torrance, α = 0.3, glass": ref.CookTorrance(alpha=0.3, eta=1.5, k=0.0),
        "Cook-Torrance, α = 0.3, F ≡ 1": ref.CookTorrance(alpha=0.3, fresnel="none"),
    }
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    rows = []
    for ax, theta_i in zip(axes, (30.0, 60.0, 75.0)):
        t = math.radians(theta_i)
        wi = np.broadcast_to([math.sin(t), 0.0, math.cos(t)], wo.shape)
        for name, model in models.items():
            f = model.brdf(wi, wo)[:, 0]
            peak = float(np.degrees(theta_o[np.argmax(f)]))
            peak_cos = float(np.degrees(theta_o[np.argmax(f * wo[:, 2])]))
            ax.plot(np.degrees(theta_o), f / f.max(), label=name, lw=1.2)
            rows.append((name, f"{theta_i:g}°", f"{peak:.1f}°", f"{peak_cos:.1f}°"))
            if name.startswith("Phong") or name.startswith("Blinn"):
                s.rows.append(Row("claim", f"{name}: f peaks in the mirror direction, "
                                  f"θi = {theta_i:g}°", f"{peak:.2f}°",
                                  f"{theta_i:g}° ± 0.05°", abs(peak - theta_i) <= 0.05))
            elif name.endswith("F ≡ 1"):
                s.rows.append(Row("claim", f"{name}: f peaks off-specular, θi = {theta_i:g}°",
                                  f"{peak:.1f}°", f"≠ {theta_i:g}°", abs(peak - theta_i) > 0.5))
        ax.axvline(theta_i, color="0.5", ls=":", lw=0.8)
        ax.set_title(f"θi = {theta_i:g}° (dotted: mirror direction)", fontsize=9)
        ax.set_xlabel("θo, plane of incidence (degrees)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("f / max f")
    axes[-1].legend(fontsize=7)
    return md_table(["model", "θi", "peak of f at θo", "peak of f·cosθo at θo"], rows), \
        save_figure(fig, ctx.figure("claims_maxima.png"))


def section(ctx: Context) -> Section:
    s = Section("The lecture notes' claims")
    forms = two_printed_forms(ctx, s)
    glass_table, glass_fig = glass(ctx, s)
    metal_table = conductors(ctx, s)
    phong_table, _ = phong_claims(ctx, s)
    max_table, max_fig = maxima(ctx, s)
    s.markdown = "\n".join([
        "**\"The two printed forms of Cook-Torrance are the same model.\"** " + forms, "",
        "**\"Glass reflects about 4 % at normal incidence and 100 % at grazing incidence.\"** "
        "The exact Fresnel term (float64; the plugin with α = 1e-4 renders the same values, "
        "see the summary), and how far Schlick's approximation strays:", "", glass_table, "",
        image(ctx, glass_fig, "Fresnel and Schlick"), "",
        "Schlick's approximation for the conductors of Mitsuba's data (the RGB η, k that "
        "`roughconductor` uses in RGB variants):", "", metal_table, "",
        "**\"Phong does not conserve energy, is not reciprocal.\"** True of the lecture's "
        "forms, not of the normalized one (specular lobe alone, float64 albedo; reciprocity "
        "measured on the plugin):", "", phong_table, "",
        "**\"Its maximum is always in the specular direction.\"** True of Phong's f, mirror or "
        "halfway lobe (H = N exactly at the mirror direction); not of what the viewer sees, "
        "f·cosθo, which leans towards the normal; not of Cook-Torrance, whose "
        "1/(4 cosθi cosθo) and Fresnel term push the peak of f beyond the mirror direction, "
        "towards grazing (the off-specular peak that Torrance and Sparrow built their model to "
        "explain):", "", max_table, "", image(ctx, max_fig, "lobe maxima")])
    return s
