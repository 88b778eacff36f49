"""
Campaign section: the energy compensation of ``cooktorrance`` (``multiscatter``; Kulla & Conty
2017, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH course "Physically Based
Shading in Theory and Practice"). The white furnace over α and θ, for GGX and Beckmann with
Smith's masking (and the V-cavity's at a few points, and anisotropic roughness through its
equivalent isotropic α), against the random walk on the Smith microsurface (Heitz, Hanika,
d'Eon & Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs with the Smith Model", ACM TOG
35(4)): its total and its single scattering; where the compensation puts the energy against
the walk's bounces ≥ 2 and a coloured conductor's albedo
(:mod:`~mi_brdfs.campaign.multiscatter_walk`); and a furnace render beside ``roughconductor``.
"""

from __future__ import annotations

import math

import numpy as np

from ..bsdfspec import load_bsdf
from ..checks import batch, furnace
from ..plots import pyplot, save_figure
from ..reference.quadrature import direction, sphere_grid
from .core import Context, Row, Section, image, md_table
from . import multiscatter_dielectric as dielectric
from .multiscatter_walk import (GOLD, KINDS, LOBE_PATHS, PHI_BINS, THETA_EDGES, closed_form,
                                gold, lobes, spec, walk_albedo)

#: The furnace grid: roughnesses and incident angles (degrees).
ALPHAS = (0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0)
THETAS = (0.0, 30.0, 60.0, 75.0, 85.0, 89.0)
#: The target of the compensated white furnace: |E − 1| at most this.
TARGET = 0.002
#: The V-cavity's points (α, θ).
VCAVITY_ALPHAS, VCAVITY_THETAS = (0.1, 0.5, 1.0), (0.0, 60.0, 85.0)
#: Anisotropic roughness (αu, αv), the incident angles and azimuths (degrees); flagged above.
ANISO_PAIRS = ((0.1, 0.5), (0.2, 1.0), (0.05, 0.8))
ANISO_THETAS, ANISO_PHIS, ANISO_FLAG = (0.0, 60.0, 85.0), (0.0, 45.0, 90.0), 0.01
#: The sampler whose mean weight is the BRDF's albedo: Beckmann with Smith's visible normals
#: is not (Mitsuba's sampler draws the exact visible normals, its pdf has Walter's rational
#: G1: the Cook-Torrance section), so there the furnace's sample() is D·cosθ's.
UNBIASED = {("beckmann", "smith"): {"sample_visible": False}}
#: sample(): the side of the jittered grid of a replicate, the replicates of a block (16: the
#: standard error from their spread has 15 degrees of freedom), and the most replicates (full,
#: quick).
STRATA, BLOCK, REPLICATES = (250, 100), 16, (256, 16)


def _stratified_mean(bsdf, wi, m: int, rng, bsdf_ctx=None) -> float:
    """One mean ``sample()`` weight over a jittered m × m grid of the 2D sample and stratified,
    shuffled 1D samples (channel 0)."""
    n, i = m * m, np.arange(m * m)
    u2 = np.stack([(i // m + rng.random(n)) / m, (i % m + rng.random(n)) / m], axis=1)
    u1 = (rng.permutation(n) + rng.random(n)) / n
    return float(batch.sample(bsdf, wi, u1, u2, bsdf_ctx).weight[:, 0].mean())


def sampled(ctx: Context, sp: dict, theta: float, phi: float = 0.0, seed=0,
            precise: bool = True, bsdf_ctx=None) -> tuple[float, float, int]:
    """
    E(θ, φ) (degrees) as the mean ``sample()`` weight (in the ``mi.BSDFContext``
    ``bsdf_ctx``, default radiance): (mean, standard error, samples). Blocks of BLOCK
    independent stratified replicates, their spread the standard error; ``precise`` adds
    blocks until 4 SE ≤ TARGET/4 or REPLICATES replicates.
    """
    bsdf, rng = load_bsdf(sp), np.random.default_rng(seed)
    wi = direction(math.radians(theta), math.radians(phi))
    m, most = ctx.n(*STRATA), ctx.n(*REPLICATES) if precise else BLOCK
    means: list[float] = []
    while True:
        means += [_stratified_mean(bsdf, wi, m, rng, bsdf_ctx) for _ in range(BLOCK)]
        se = float(np.std(means, ddof=1) / math.sqrt(len(means)))
        if 4 * se <= TARGET / 4 or len(means) >= most:
            return float(np.mean(means)), se, len(means) * m * m


def plugin_energy(sp: dict, theta: float, alpha) -> float:
    """∫ f cosθo dωo of the plugin's eval (channel 0) at incidence ``theta`` degrees, on the
    float64 reference's nodes: over the half vector h (dωo = 4 (ωi·h) dωh), Gauss-Legendre in
    cosθh on two panels split at tanθh = 4α × the midpoint rule in φh."""
    wi = direction(math.radians(theta))
    split = 1 / math.sqrt(1 + (4 * float(np.max(alpha))) ** 2)
    total = 0.0
    for panel in ((0.0, split), (split, 1.0)):
        h, w = sphere_grid(192, 512, panel)
        c = h @ wi
        wo = 2 * c[:, None] * h - wi[None, :]
        keep = (c > 0) & (wo[:, 2] > 0)
        if keep.any():
            value = batch.evaluate(sp, wi, wo[keep]).value[:, 0]
            total += float(np.sum(w[keep] * 4 * c[keep] * value))
    return total


def furnace_grid(ctx: Context, kinds=KINDS, shadowing: str = "smith", alphas=None,
                 thetas=None, walk: bool = True) -> dict:
    """Per (kind, α, θ): the single scattering E_ss by quadrature (``ss``) and from sample()
    (``ss_s``), E_table, the compensated E in closed form (``e``), from the plugin's eval on
    the same nodes (``ie``) and from sample() (``e_s``, ``se``), and the walk's total, lost
    fraction and order 1 (``o1``, ``o1_se``)."""
    alphas, thetas = alphas or ctx.n(ALPHAS, (0.2, 1.0)), thetas or ctx.n(THETAS, (0.0, 85.0))
    out = {}
    for i, kind in enumerate(kinds):
        for j, alpha in enumerate(alphas):
            for t, theta in enumerate(thetas):
                ss, e, e_tab = closed_form(kind, alpha, theta, shadowing=shadowing)
                r = {"ss": float(ss[0]), "e": float(e[0]), "tab": e_tab,
                     "ie": plugin_energy(spec(kind, alpha, True, shadowing), theta, alpha)}
                unbiased = UNBIASED.get((kind, shadowing), {})
                r["ss_s"] = sampled(ctx, spec(kind, alpha, False, shadowing, **unbiased), theta,
                                    seed=(1, i, j, t), precise=False)[0]
                r["e_s"], r["se"], r["n"] = sampled(
                    ctx, spec(kind, alpha, True, shadowing, **unbiased), theta, seed=(2, i, j, t))
                if walk:
                    w = walk_albedo(kind, alpha, theta, ctx.n(200_000, 20_000), (3, i, j, t))
                    r.update(total=float(w.total[0]), lost=w.lost,
                             o1=float(w.orders[0][0]), o1_se=float(w.orders_se[0][0]))
                out[(kind, alpha, theta)] = r
    return out


def _worst(grid: dict, kind: str, key: str, alpha=None) -> tuple[float, str, dict]:
    """The largest |E − 1| of ``key`` over the grid's points of ``kind`` (and ``alpha``)."""
    best = (-1.0, "", {})
    for (k, a, t), r in grid.items():
        if k == kind and alpha in (None, a) and abs(r[key] - 1) > best[0]:
            best = (abs(r[key] - 1), f"α = {a:g}, θ = {t:g}°", r)
    return best


def furnace_rows(grid: dict, s: Section, label: str = "smith") -> None:
    """Per distribution and α: the compensated |E − 1| ≤ TARGET, in closed form (the BRDF's
    energy ∫ f cosθo) and from sample() (within 4 standard errors)."""
    for kind in sorted({k for k, _, _ in grid}, key=KINDS.index):
        alphas = sorted({a for k, a, _ in grid if k == kind})
        thetas = ", ".join(f"{t:g}°" for t in sorted({t for _, _, t in grid}))
        for alpha in alphas:
            dev, where, _ = _worst(grid, kind, "e", alpha)
            s.rows.append(Row(f"cooktorrance multiscatter {kind} {label}", f"α = {alpha:g}: "
                              f"white furnace, E = ∫ f cosθo (float64 closed form), θ ∈ "
                              f"{{{thetas}}}", f"max |E − 1| = {dev:.2e} ({where})",
                              f"≤ {TARGET:g}", dev <= TARGET))
            points = [r for (k, a, _), r in grid.items() if k == kind and a == alpha]
            ok = all(abs(r["e_s"] - 1) <= TARGET + 4 * r["se"] for r in points)
            dev, where, r = _worst(grid, kind, "e_s", alpha)
            s.rows.append(Row(f"cooktorrance multiscatter {kind} {label}", f"α = {alpha:g}: "
                              f"white furnace, E = mean sample() weight, θ ∈ {{{thetas}}}",
                              f"max |E − 1| = {dev:.2e} ± {r['se']:.1e} ({where}); largest "
                              f"4 SE {4 * max(p['se'] for p in points):.1e}",
                              f"≤ {TARGET:g} + 4 SE", ok))
        points = [r for (k, _, _), r in grid.items() if k == kind]
        dev = max(abs(r["ie"] - r["e"]) for r in points)
        s.values[f"multiscatter: eval vs closed form {kind} {label}"] = f"{dev:.1e}"
        s.rows.append(Row(f"cooktorrance multiscatter {kind} {label}", "white furnace: the "
                          "plugin's eval integrated on the reference's nodes = the closed form, "
                          "over the grid", f"max |Δ| = {dev:.1e}", "≤ 1e-4", dev <= 1e-4))
        for key, what in (("e", "closed form"), ("e_s", "sample()")):
            dev, where, _ = _worst(grid, kind, key)
            s.values[f"multiscatter: worst {kind} {label} {what}"] = f"{dev:.2e} ({where})"


def furnace_table(grid: dict) -> str:
    """E − 1 per (distribution, α) × θ: closed form / sample() ± SE."""
    thetas = sorted({t for _, _, t in grid})
    rows = []
    for kind, alpha in dict.fromkeys((k, a) for k, a, _ in grid):
        rs = [grid[(kind, alpha, t)] for t in thetas]
        cells = [f"{r['e'] - 1:+.1e} / {r['e_s'] - 1:+.1e} ± {r['se']:.0e}" for r in rs]
        rows.append((kind, f"{alpha:g}", *cells))
    return md_table(["distribution", "α", *(f"θ = {t:g}°" for t in thetas)], rows)


def single_table(grid: dict) -> str:
    """The single scattering: E_ss by quadrature / sample() / E_table / the walk's order 1;
    the walk's total (every order up to 100; F ≡ 1: 1 but for the paths cut)."""
    thetas = sorted({t for _, _, t in grid})
    rows = []
    for kind, alpha in dict.fromkeys((k, a) for k, a, _ in grid):
        rs = [grid[(kind, alpha, t)] for t in thetas]
        cells = [f"{r['ss']:.4f} / {r['ss_s']:.4f} / {r['tab']:.4f} / {r['o1']:.4f}"
                 for r in rs]
        rows.append((kind, f"{alpha:g}", *cells, f"{min(r['total'] for r in rs):.5f}"))
    return md_table(["distribution", "α", *(f"θ = {t:g}°" for t in thetas),
                     "walk total (min over θ)"], rows)


def walk_rows(grid: dict, s: Section) -> None:
    """Measured: the plugin's single scattering (G1·G1) against the walk's order 1 (G2)."""
    for kind in KINDS:
        diffs = [(r["ss"] - r["o1"], r["o1_se"], f"α = {a:g}, θ = {t:g}°")
                 for (k, a, t), r in grid.items() if k == kind]
        lo, hi = min(diffs), max(diffs)
        s.values[f"multiscatter: ss - order 1 {kind}"] = f"{lo[0]:+.4f} to {hi[0]:+.4f}"
        s.rows.append(Row(f"cooktorrance multiscatter {kind}", "single scattering E_ss "
                          "(separable G1·G1) − random walk order 1 (height-correlated G2)",
                          f"{lo[0]:+.4f} ({lo[2]}) to {hi[0]:+.4f} ({hi[2]}), SE ≤ "
                          f"{max(d[1] for d in diffs):.0e}", "measured (no target)", True))
        total = min(r["total"] for (k, _, _), r in grid.items() if k == kind)
        s.rows.append(Row(f"cooktorrance multiscatter {kind}", "random walk, F ≡ 1: every "
                          "order (≤ 100) sums to 1 but for the paths cut",
                          f"min total {total:.5f}, max cut "
                          f"{max(r['lost'] for r in grid.values()):.1e}",
                          "total = 1 − cut", all(abs(r["total"] + r["lost"] - 1) < 1e-9
                                                 for r in grid.values())))


def furnace_figure(ctx: Context, grid: dict) -> str:
    """Top: the single scattering (plugin by quadrature, lines; the walk's order 1, dots);
    bottom: the compensated E − 1 (closed form, lines; sample() ± 2 SE, dots)."""
    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    thetas = sorted({t for _, _, t in grid})
    alphas = sorted({a for _, a, _ in grid})
    colors = pyplot().cm.viridis(np.linspace(0, 0.9, len(alphas)))
    for col, kind in enumerate(KINDS):
        top, bottom = axes[0, col], axes[1, col]
        for alpha, color in zip(alphas, colors):
            rs = [grid[(kind, alpha, t)] for t in thetas]
            top.plot(thetas, [r["ss"] for r in rs], "-", color=color, lw=1.2,
                     label=f"α = {alpha:g}")
            top.plot(thetas, [r["o1"] for r in rs], "o", color=color, ms=3)
            bottom.plot(thetas, [r["e"] - 1 for r in rs], "-", color=color, lw=1.2)
            bottom.errorbar(thetas, [r["e_s"] - 1 for r in rs], [2 * r["se"] for r in rs],
                            fmt="o", color=color, ms=3, lw=0.8)
        bottom.axhspan(-TARGET, TARGET, color="0.9", zorder=0)
        top.set_title(f"{kind}, smith, F ≡ 1: single scattering (lines: plugin; dots: "
                      "walk order 1)", fontsize=8)
        bottom.set_title("compensated E − 1 (lines: closed form; dots: sample() ± 2 SE; "
                         f"grey: ±{TARGET:g})", fontsize=8)
        bottom.set_xlabel("incident angle θ (degrees)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("E_ss(θ)")
    axes[1, 0].set_ylabel("E(θ) − 1")
    axes[0, 0].legend(fontsize=7, ncol=2)
    return save_figure(fig, ctx.figure("multiscatter_furnace.png"))


def vcavity(ctx: Context, s: Section) -> str:
    """The V-cavity's tables at a few points: the same furnace, no walk (it is Smith's)."""
    grid = furnace_grid(ctx, shadowing="vcavity", alphas=ctx.n(VCAVITY_ALPHAS, (0.5,)),
                        thetas=ctx.n(VCAVITY_THETAS, (60.0,)), walk=False)
    furnace_rows(grid, s, "vcavity")
    return furnace_table(grid)


def anisotropic(ctx: Context, s: Section) -> str:
    """(αu, αv) through the tables' equivalent α = sqrt(αu αv): the furnace at several azimuths
    of ωi, in closed form and from sample(); measured, flagged above ANISO_FLAG."""
    rows = []
    phis = ctx.n(ANISO_PHIS, (0.0, 90.0))
    for i, kind in enumerate(KINDS):
        for j, pair in enumerate(ctx.n(ANISO_PAIRS, ANISO_PAIRS[-1:])):
            worst = (-1.0, "")
            for t, theta in enumerate(ctx.n(ANISO_THETAS, (85.0,))):
                cells = []
                for p, phi in enumerate(phis if theta > 0 else phis[:1]):
                    e = float(closed_form(kind, pair, theta, phi)[1][0])
                    e_s, se, _ = sampled(ctx, spec(kind, pair), theta, phi, (4, i, j, t, p),
                                         precise=False)
                    worst = max(worst, (abs(e - 1), f"θ = {theta:g}°, φ = {phi:g}°"))
                    cells.append(f"{e - 1:+.1e} / {e_s - 1:+.1e} ± {se:.0e}")
                rows.append((kind, f"{pair}", f"{theta:g}°",
                             *(cells + ["—"] * (len(phis) - len(cells)))))
            flag = f" — above {ANISO_FLAG:g}" if worst[0] > ANISO_FLAG else ""
            s.values[f"multiscatter: aniso {kind} {pair}"] = f"{worst[0]:.2e}"
            s.rows.append(Row(f"cooktorrance multiscatter {kind} anisotropic", f"(αu, αv) = "
                              f"{pair}, equivalent α = sqrt(αu αv): white furnace |E − 1| "
                              "(closed form), over θ and the azimuth φ of ωi",
                              f"max {worst[0]:.2e} ({worst[1]}){flag}",
                              f"measured (no target; flagged above {ANISO_FLAG:g})", True))
    return md_table(["distribution", "(αu, αv)", "θ", *(f"φ = {p:g}°" for p in phis)], rows)


def _regions(res: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centre, rim) pixel masks (θ < 14°; wholly on the sphere, θ > 70°), and each pixel's
    view cosines (res, res, 64)."""
    cos = furnace.view_cosines(res, sub=8)
    full = ~np.isnan(cos).any(axis=2)
    mean = np.where(full, np.nan_to_num(cos).mean(axis=2), 0.0)
    return full & (mean > 0.97), full & (mean < 0.34), cos


def _predicted(cos: np.ndarray, theta_deg, curve) -> np.ndarray:
    theta = np.degrees(np.arccos(np.clip(np.nan_to_num(cos, nan=-1.0), -1, 1)))
    return np.where(np.isnan(cos), 1.0, np.interp(theta, theta_deg, curve)).mean(axis=2)


def render(ctx: Context, s: Section) -> tuple[str, str]:
    """The white furnace (one bounce) of a GGX sphere, α = 1: cooktorrance without and with
    ``multiscatter``, and roughconductor (η = 0, k = 1: F ≡ 1); centre and rim measured
    against the image that E(θ) predicts (float64 closed form)."""
    res, spp = ctx.n(64, 48), ctx.n(4096, 256)
    centre, rim, cos = _regions(res)
    thetas = np.linspace(0.0, 89.9, ctx.n(46, 16))
    cases = {"cooktorrance": (spec("ggx", 1.0, False), 0),
             "cooktorrance multiscatter": (spec("ggx", 1.0, True), 1),
             "roughconductor": ({"type": "roughconductor", "distribution": "ggx",
                                 "alpha": 1.0}, 0)}
    out, rows = {}, []
    for name, (sp, which) in cases.items():
        img = furnace.furnace_render(sp, spp=spp, res=res, predict=False).image.mean(axis=2)
        curve = [float(closed_form("ggx", 1.0, t)[which][0]) for t in thetas]
        want = _predicted(cos, thetas, curve)
        stats = {}
        for region, mask in (("centre", centre), ("rim", rim)):
            v = img[mask]
            stats[region] = (float(v.mean()), float(v.std(ddof=1) / math.sqrt(v.size)),
                             float(want[mask].mean()))
        out[name] = (img, stats)
        rows.append((name, *(f"{m:.4f} ± {se:.4f} (E(θ): {w:.4f})"
                             for m, se, w in stats.values())))
    _render_rows(out, s)
    return md_table(["sphere", "centre (θ < 14°)", "rim (θ > 70°)"], rows), \
        _render_figure(ctx, out, res, spp)


def _render_rows(out: dict, s: Section) -> None:
    for name in ("cooktorrance multiscatter", "cooktorrance"):
        stats = out[name][1]
        dev = max(abs(m - w) - 4 * se for m, se, w in stats.values())
        s.values[f"multiscatter: render {name}"] = ", ".join(
            f"{region} {m:.4f}" for region, (m, _, _) in stats.items())
        s.rows.append(Row(f"{name} (ggx smith, α = 1)", "white furnace render, centre and "
                          "rim = the image E(θ) predicts", ", ".join(
                              f"{region} {m:.4f} ± {se:.4f} vs {w:.4f}"
                              for region, (m, se, w) in stats.items()),
                          f"|Δ| ≤ {TARGET:g} + 4 SE", dev <= TARGET))
    diff = max(abs(a[0] - b[0]) for a, b in zip(out["cooktorrance"][1].values(),
                                                 out["roughconductor"][1].values()))
    s.rows.append(Row("cooktorrance (ggx smith, α = 1)", "white furnace render, centre and "
                      "rim = roughconductor's", f"max |Δ| {diff:.1e}", "≤ 1e-3", diff <= 1e-3))


def _render_figure(ctx: Context, out: dict, res: int, spp: int) -> str:
    plt = pyplot()
    fig, axes = plt.subplots(1, 4, figsize=(14, 3.4),
                             gridspec_kw={"width_ratios": [1, 1, 1, 1.6]})
    for ax, (name, (img, stats)) in zip(axes, out.items()):
        ax.imshow(img, cmap="gray", vmin=0.0, vmax=1.1)
        ax.set_title(f"{name}\ncentre {stats['centre'][0]:.3f}, rim {stats['rim'][0]:.3f}",
                     fontsize=8)
        ax.axis("off")
    for (name, (img, _)), style in zip(out.items(), ("-", "-", ":")):
        axes[3].plot(np.arange(res), img[res // 2], style, lw=1.2, label=name)
    axes[3].set_title("middle row (background 1)", fontsize=8)
    axes[3].set_xlabel("pixel")
    axes[3].grid(alpha=0.3)
    axes[3].legend(fontsize=7)
    fig.suptitle(f"White furnace, one bounce, GGX α = 1, F ≡ 1 ({res}² px, {spp} spp)",
                 fontsize=9)
    return save_figure(fig, ctx.figure("multiscatter_furnace_render.png"))


def section(ctx: Context) -> Section:
    s = Section("Energy compensation: cooktorrance multiscatter")
    grid = furnace_grid(ctx)
    furnace_rows(grid, s)
    walk_rows(grid, s)
    t_furnace, t_single, f_furnace = furnace_table(grid), single_table(grid), \
        furnace_figure(ctx, grid)
    t_vcavity = vcavity(ctx, s)
    t_aniso = anisotropic(ctx, s)
    t_lobes, f_lobes = lobes(ctx, s)
    t_gold = gold(ctx, s)
    t_render, f_render = render(ctx, s)
    s.markdown = _markdown(ctx, s, t_furnace, t_single, f_furnace, t_vcavity, t_aniso,
                           t_lobes, f_lobes, t_gold, t_render, f_render)
    s.markdown += "\n\n" + "\n".join(_dielectric(ctx, s))
    return s


def _dielectric(ctx: Context, s: Section) -> list:
    """The dielectric's rows and markdown (:mod:`~mi_brdfs.campaign.multiscatter_dielectric`)."""
    grid = dielectric.furnace_grid(ctx, sampled)
    dielectric.furnace_rows(grid, s)
    t_furnace, t_share = dielectric.furnace_table(grid), dielectric.share_table(grid, s)
    t_sweep = dielectric.eta_sweep(ctx, s)
    t_aniso = dielectric.anisotropic(ctx, s, sampled)
    t_render, out = dielectric.render(ctx, s, _regions)
    return dielectric.markdown(ctx, s.values, t_furnace, t_share, t_sweep, t_aniso, t_render,
                               dielectric.render_figure(ctx, out), image)


def _markdown(ctx: Context, s: Section, t_furnace, t_single, f_furnace, t_vcavity, t_aniso,
              t_lobes, f_lobes, t_gold, t_render, f_render) -> str:
    v = s.values
    return "\n".join([
        "`cooktorrance` with `multiscatter=true`: Kulla & Conty's energy compensation (2017) "
        "adds to the single-scattering lobe f_ss the reciprocal lobe F_ms (1 − E(μi)) "
        "(1 − E(μo)) / (π (1 − E_avg)), E(μ, α) the albedo of f_ss with F ≡ 1 read from the "
        "shipped tables (`mi-brdfs tables`, built from the plugin's own single-scattering "
        "lobe: the mean sample() weight of its D·cosθ sampler, i.e. ∫ f cosθo), so "
        "that the albedo with F ≡ 1 is 1. The true multiple scattering is the random walk on "
        "the Smith microsurface (Heitz, Hanika, d'Eon & Dachsbacher 2016; "
        "`mi_brdfs/reference/randomwalk.py`, float64). The walk's single scattering carries "
        "the height-correlated G2 = 1/(1 + Λi + Λo), the plugin's (`shadowing=smith`, as "
        "Mitsuba) the separable G1·G1 ≤ G2: the plugin's order 1 loses more energy than the "
        "walk's (equal at normal incidence, most at grazing incidence on rough surfaces: the "
        "single-scattering table below), and its compensation carries correspondingly more.",
        "",
        f"**White furnace** (F ≡ 1, Smith's masking): E(θ) − 1 of the compensated BRDF, "
        "first in closed form (its energy ∫ f cosθo dωo: the float64 reference's quadrature of "
        "f_ss over the half vector plus the lobe's albedo 1 − E_table(μi)), then as the mean "
        "sample() weight (stratified replicates, ± 1 standard error; Beckmann with D·cosθ "
        "sampling, whose weights are unbiased; up to "
        f"{ctx.n(*REPLICATES) * ctx.n(*STRATA) ** 2:,} samples a point). Target: "
        f"|E − 1| ≤ {TARGET:g}. Worst in closed form: GGX "
        f"{v['multiscatter: worst ggx smith closed form']}, Beckmann "
        f"{v['multiscatter: worst beckmann smith closed form']}; from sample(): GGX "
        f"{v['multiscatter: worst ggx smith sample()']}, Beckmann "
        f"{v['multiscatter: worst beckmann smith sample()']}. The plugin's own eval, "
        "integrated on the reference's nodes, gives the closed form within "
        f"{v['multiscatter: eval vs closed form ggx smith']} (GGX) and "
        f"{v['multiscatter: eval vs closed form beckmann smith']} (Beckmann).", "",
        t_furnace, "",
        "**Single scattering against the walk**: per θ, E_ss by quadrature (∫ f_ss cosθo) / "
        "E_ss from sample() / the table's E / the walk's order 1. E_ss − walk order 1 spans GGX "
        f"{v['multiscatter: ss - order 1 ggx']}, Beckmann "
        f"{v['multiscatter: ss - order 1 beckmann']}.", "", t_single, "",
        image(ctx, f_furnace, "compensated white furnace"), "",
        "**V-cavity tables** (`shadowing=vcavity`, E − 1: closed form / sample()):", "",
        t_vcavity, "",
        "**Anisotropic roughness**: the tables are indexed by the equivalent isotropic "
        "α = sqrt(αu αv), so the furnace depends on the azimuth φ of ωi; E − 1 in closed form "
        "(quadrature of the anisotropic f_ss) / from sample(), GGX and Beckmann, Smith "
        f"(measured, no target; flagged above {ANISO_FLAG:g}):", "", t_aniso, "",
        *_markdown_walk(ctx, v, t_lobes, f_lobes, t_gold, t_render, f_render)])


def _markdown_walk(ctx: Context, v: dict, t_lobes, f_lobes, t_gold, t_render,
                   f_render) -> list:
    return [
        "**Where the energy goes**: the plugin's compensation lobe f_ms·cosθo (eval with "
        "`multiscatter` minus without) against the walk's orders ≥ 2, both as averages over "
        f"bins of {THETA_EDGES[1]}° in θo × {360 // PHI_BINS}° in φo over the whole "
        "hemisphere; relative L1 difference ∫|a − b| / ∫b, the same of the two scaled to unit "
        "integral (the shape alone), and the part of the L1 that the walk's noise alone makes "
        f"({ctx.n(*LOBE_PATHS):,} paths). Worst: GGX "
        f"{v['multiscatter: lobe L1 ggx']}, Beckmann {v['multiscatter: lobe L1 beckmann']}. "
        "The compensation has one shape, (1 − E(μo)) cosθo, in every azimuth and for every "
        "ωi; the walk's orders ≥ 2 do not: its lobe depends on ωi and on the azimuth (in the "
        "figure, θo > 0 is the mirror side). The figure's dots are the walk's bins in the "
        f"±{180 / PHI_BINS:g}° wedges of azimuth about the plane of incidence.", "", t_lobes,
        "",
        image(ctx, f_lobes, "compensation lobe against the random walk"), "",
        f"**A coloured conductor** (gold, η = {GOLD[0]}, k = {GOLD[1]} in R, G, B; exact "
        "Fresnel): the compensated albedo in closed form, E_ss + "
        "F_ms (1 − E(μi)) with F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)), against the "
        "walk's, whose every bounce is weighted by the Fresnel term at its own angle. Worst "
        f"relative difference of the totals: {v['multiscatter: gold worst relative']}.", "",
        t_gold, "",
        "**Furnace render** (`scenes/furnace.xml`, one bounce): a GGX sphere at α = 1 without "
        "and with `multiscatter`, beside `roughconductor` (η = 0, k = 1: F ≡ 1); the centre "
        "and the rim (pixels wholly on the sphere) ± 1 standard error, against the image that "
        "E(θ) in closed form predicts:", "", t_render, "",
        image(ctx, f_render, "furnace render")]
