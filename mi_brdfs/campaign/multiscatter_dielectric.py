"""
Campaign rows of the energy compensation of ``cooktorrance`` with ``transmission`` (Kulla &
Conty 2017's dielectric extension), part of the section of
:mod:`~mi_brdfs.campaign.multiscatter`: the white furnace in importance transport (reflection
plus refraction, from both sides) per α and θ for glass (η = 1.5, between the tables' nodes):
single scattering, compensated in closed form and from sample(), and the random walk of Heitz
et al. 2016 through a dielectric microsurface (total, order 1, and the share of its orders ≥ 2
that is reflected, against the compensation's share); the interpolation in η over a sweep of
indices; and a glass sphere in the furnace rendered with all its internal paths, beside
``roughdielectric``.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..reference import randomwalk
from ..reference.cooktorrance import RoughDielectric
from ..reference.multiscatter import CompensatedDielectric
from ..reference.quadrature import direction
from .core import Context, Row, Section, md_table

#: The relative index of the grid (glass; between two nodes of the tables' η axis).
ETA = 1.5
#: Roughnesses and incident angles (degrees; > 90: from inside the glass).
ALPHAS = (0.1, 0.3, 0.5, 1.0)
THETAS = (0.0, 30.0, 60.0, 80.0, 89.0, 100.0, 120.0, 150.0, 179.0)
#: The indices of the η sweep (α = 1, θ ∈ SWEEP_THETAS).
SWEEP_ETAS, SWEEP_THETAS = (1.05, 1.2, 1.33, 1.5, 1.8, 2.4, 2.9), (0.0, 60.0, 150.0)
#: The target of the compensated dielectric's white furnace: |E − 1| at most this.
TARGET = 0.01
#: Anisotropic roughness (αu, αv) through the equivalent α = sqrt(αu αv): incident angles and
#: azimuths (degrees); measured, flagged above TARGET.
ANISO_PAIRS, ANISO_THETAS, ANISO_PHIS = ((0.2, 1.0), (0.05, 0.8)), (0.0, 60.0, 150.0), (0.0, 90.0)
KINDS = ("ggx", "beckmann")


def glass(kind: str, alpha, multiscatter: bool = True, eta: float = ETA) -> dict:
    """The rough glass; ``alpha`` a number or (αu, αv)."""
    rough = {"alpha_u": alpha[0], "alpha_v": alpha[1]} if isinstance(alpha, tuple) else \
        {"alpha": alpha}
    return {"type": "cooktorrance", "transmission": True, "distribution": kind, **rough,
            "eta": eta, "multiscatter": multiscatter}


def walk_split(kind: str, alpha: float, theta: float, n: int, seed, eta: float = ETA) -> dict:
    """The walk in importance transport at ``theta`` degrees: its total, order 1, and the
    share of the orders ≥ 2 that leaves on ωi's side (reflected)."""
    w = randomwalk.walk(direction(math.radians(theta)), kind, alpha, n,
                        np.random.default_rng(seed), eta=eta, transport="importance")
    weight = w.weight[:, 0]
    multiple = w.order >= 2
    reflected = w.wo[:, 2] * math.cos(math.radians(theta)) > 0
    ms = float(weight[multiple].sum())
    return {"total": float(weight.mean()), "o1": float(weight[w.order == 1].sum() / n),
            "ms": ms / n, "ms_r": float(weight[multiple & reflected].sum()) / ms if ms else 0.0}


def furnace_grid(ctx: Context, sampled) -> dict:
    """Per (kind, α, θ): E of the single scattering (float64 quadrature, ``ss``), compensated
    (closed form ``e``; mean sample() weight ``e_s`` ± ``se``), the compensation's reflected
    share (``share_r``), and the walk's (:func:`walk_split`). ``sampled`` is the section's
    stratified sample() estimator."""
    importance = mi.BSDFContext(mi.TransportMode.Importance)
    out = {}
    for i, kind in enumerate(KINDS):
        for j, alpha in enumerate(ctx.n(ALPHAS, (1.0,))):
            model = CompensatedDielectric(RoughDielectric(alpha, kind, ETA))
            for t, theta in enumerate(ctx.n(THETAS, (0.0, 150.0))):
                side = 0 if theta < 90.0 else 1
                ss = float(model.base.albedo(math.radians(theta))[0])
                r = {"ss": ss, "e": ss + float(model.lobe_albedo(math.radians(theta))[0]),
                     "share_r": 1.0 - model.x[side]}
                r["e_s"], r["se"], _ = sampled(ctx, glass(kind, alpha), theta, seed=(5, i, j, t),
                                               precise=False, bsdf_ctx=importance)
                r.update(walk_split(kind, alpha, theta, ctx.n(200_000, 20_000), (6, i, j, t)))
                out[(kind, alpha, theta)] = r
    return out


def furnace_rows(grid: dict, s: Section) -> None:
    """Per distribution and α: |E − 1| ≤ TARGET in closed form and from sample() (+ 4 SE)."""
    for kind in KINDS:
        for alpha in sorted({a for k, a, _ in grid if k == kind}):
            points = {t: r for (k, a, t), r in grid.items() if k == kind and a == alpha}
            thetas = ", ".join(f"{t:g}°" for t in points)
            for key, what in (("e", "E = ∫ f |cosθo| (float64 closed form)"),
                              ("e_s", "E = mean sample() weight")):
                t, r = max(points.items(), key=lambda p: abs(p[1][key] - 1))
                dev = abs(r[key] - 1)
                slack = 4 * r["se"] if key == "e_s" else 0.0
                ok = all(abs(p[key] - 1) <= TARGET + (4 * p["se"] if key == "e_s" else 0.0)
                         for p in points.values())
                s.rows.append(Row(f"cooktorrance transmission multiscatter {kind}",
                                  f"α = {alpha:g}, η = {ETA:g}: white furnace in importance "
                                  f"transport, {what}, θ ∈ {{{thetas}}}",
                                  f"max |E − 1| = {dev:.2e} (θ = {t:g}°)"
                                  + (f" ± {r['se']:.0e}" if slack else ""),
                                  f"≤ {TARGET:g}" + (" + 4 SE" if slack else ""), ok))
        worst = max((abs(r["e"] - 1), f"α = {a:g}, θ = {t:g}°")
                    for (k, a, t), r in grid.items() if k == kind)
        s.values[f"multiscatter dielectric: worst {kind}"] = f"{worst[0]:.2e} ({worst[1]})"
        total = min(r["total"] for (k, _, _), r in grid.items() if k == kind)
        s.rows.append(Row(f"cooktorrance transmission multiscatter {kind}", "random walk "
                          "(importance transport): reflection + refraction of every order sum "
                          "to 1", f"min total {total:.6f}", "≥ 0.9999", total >= 0.9999))


def _per_theta(grid: dict, cell) -> str:
    """A table of ``cell(r)`` per (kind, α) × θ of the grid."""
    thetas = sorted({t for _, _, t in grid})
    rows = [(kind, f"{alpha:g}", *(cell(grid[(kind, alpha, t)]) for t in thetas))
            for kind, alpha in dict.fromkeys((k, a) for k, a, _ in grid)]
    return md_table(["distribution", "α", *(f"θ = {t:g}°" for t in thetas)], rows)


def furnace_table(grid: dict) -> str:
    """Per (kind, α) × θ: single scattering / compensated − 1 (closed form, sample()) / walk
    order 1."""
    return _per_theta(grid, lambda r: f"{r['ss']:.3f} / {r['e'] - 1:+.1e}, "
                                      f"{r['e_s'] - 1:+.1e} / {r['o1']:.3f}")


def share_table(grid: dict, s: Section) -> str:
    """The reflected share of the multiple scattering: the compensation's 1 − x against the
    walk's orders ≥ 2, per (kind, α) × θ (measured, no target)."""
    for side, pick in (("outside", lambda t: t < 90.0), ("inside", lambda t: t > 90.0)):
        gaps = [(r["share_r"] - r["ms_r"], f"{k} α = {a:g}, θ = {t:g}°")
                for (k, a, t), r in grid.items() if pick(t) and r["ms"] > 0.01]
        if gaps:
            lo, hi = min(gaps), max(gaps)
            s.values[f"multiscatter dielectric: share gap {side}"] = \
                f"{lo[0]:+.2f} ({lo[1]}) to {hi[0]:+.2f} ({hi[1]})"
            s.rows.append(Row("cooktorrance transmission multiscatter", f"lit from {side}: "
                              "reflected share of the compensation − the walk's orders ≥ 2 "
                              "(where they carry > 1 %)", f"{lo[0]:+.2f} ({lo[1]}) to "
                              f"{hi[0]:+.2f} ({hi[1]})", "measured (no target)", True))
    return _per_theta(grid, lambda r: f"{r['share_r']:.2f} / {r['ms_r']:.2f} ({r['ms']:.2f})")


def eta_sweep(ctx: Context, s: Section) -> str:
    """The closed-form furnace over indices between and at the tables' nodes (α = 1): the
    error of the interpolation in η."""
    rows, worst = [], (0.0, "")
    for kind in KINDS:
        for eta in ctx.n(SWEEP_ETAS, (1.33,)):
            model = CompensatedDielectric(RoughDielectric(1.0, kind, eta))
            devs = [float(model.albedo(math.radians(t))[0]) - 1 for t in SWEEP_THETAS]
            worst = max(worst, (max(abs(d) for d in devs), f"{kind} η = {eta:g}"))
            rows.append((kind, f"{eta:g}", *(f"{d:+.1e}" for d in devs)))
    s.rows.append(Row("cooktorrance transmission multiscatter", "α = 1: white furnace (closed "
                      "form) over η ∈ {" + ", ".join(f"{e:g}" for e in ctx.n(SWEEP_ETAS,
                                                                           (1.33,)))
                      + "}, θ ∈ {" + ", ".join(f"{t:g}°" for t in SWEEP_THETAS) + "}",
                      f"max |E − 1| = {worst[0]:.2e} ({worst[1]})", f"≤ {TARGET:g}",
                      worst[0] <= TARGET))
    s.values["multiscatter dielectric: eta sweep"] = f"{worst[0]:.2e} ({worst[1]})"
    return md_table(["distribution", "η", *(f"θ = {t:g}°" for t in SWEEP_THETAS)], rows)


def anisotropic(ctx: Context, s: Section, sampled) -> str:
    """(αu, αv) through the tables' equivalent α = sqrt(αu αv): the furnace from sample() in
    importance transport at several azimuths of ωi (measured, flagged above TARGET)."""
    importance = mi.BSDFContext(mi.TransportMode.Importance)
    phis, rows = ctx.n(ANISO_PHIS, (90.0,)), []
    for i, kind in enumerate(KINDS):
        for j, pair in enumerate(ctx.n(ANISO_PAIRS, ANISO_PAIRS[:1])):
            worst = (-1.0, "")
            for t, theta in enumerate(ctx.n(ANISO_THETAS, (60.0,))):
                cells = []
                for p, phi in enumerate(phis):
                    e, se, _ = sampled(ctx, glass(kind, pair), theta, phi, (7, i, j, t, p),
                                       precise=False, bsdf_ctx=importance)
                    worst = max(worst, (abs(e - 1), f"θ = {theta:g}°, φ = {phi:g}°"))
                    cells.append(f"{e - 1:+.1e} ± {se:.0e}")
                rows.append((kind, f"{pair}", f"{theta:g}°", *cells))
            flag = f" — above {TARGET:g}" if worst[0] > TARGET else ""
            s.rows.append(Row(f"cooktorrance transmission multiscatter {kind} anisotropic",
                              f"(αu, αv) = {pair}, η = {ETA:g}, equivalent α = sqrt(αu αv): "
                              "white furnace |E − 1| (sample(), importance), over θ and φ",
                              f"max {worst[0]:.2e} ({worst[1]}){flag}",
                              f"measured (no target; flagged above {TARGET:g})", True))
    return md_table(["distribution", "(αu, αv)", "θ", *(f"φ = {p:g}°" for p in phis)], rows)


def render(ctx: Context, s: Section, regions) -> tuple[str, dict]:
    """A GGX glass sphere (α = 1, η = 1.5) in the white furnace with paths of up to 64
    vertices, which a lossless interface keeps at radiance 1 everywhere: cooktorrance without
    and with ``multiscatter``, and roughdielectric; the centre and the rim measured.
    ``regions`` gives the (centre, rim) pixel masks of a resolution."""
    from ..checks import furnace

    res, spp = ctx.n(64, 32), ctx.n(1024, 32)
    centre, rim = regions(res)[:2]
    cases = {"cooktorrance transmission": glass("ggx", 1.0, False),
             "cooktorrance transmission multiscatter": glass("ggx", 1.0, True),
             "roughdielectric": {"type": "roughdielectric", "distribution": "ggx",
                                 "alpha": 1.0, "int_ior": ETA, "ext_ior": 1.0}}
    out, rows = {}, []
    for name, sp in cases.items():
        img = furnace.furnace_render(sp, spp=spp, res=res, max_depth=64,
                                     predict=False).image.mean(axis=2)
        stats = {region: (float(img[mask].mean()),
                          float(img[mask].std(ddof=1) / math.sqrt(mask.sum())))
                 for region, mask in (("centre", centre), ("rim", rim))}
        out[name] = (img, stats)
        rows.append((name, *(f"{m:.4f} ± {se:.4f}" for m, se in stats.values())))
    stats = out["cooktorrance transmission multiscatter"][1]
    dev = max(abs(m - 1) - 4 * se for m, se in stats.values())
    s.values["multiscatter dielectric: render"] = ", ".join(
        f"{region} {m:.4f}" for region, (m, _) in stats.items())
    s.rows.append(Row("cooktorrance transmission multiscatter (ggx, α = 1, η = 1.5)",
                      "white furnace render, every path (≤ 64 vertices): centre and rim = 1",
                      ", ".join(f"{region} {m:.4f} ± {se:.4f}"
                                for region, (m, se) in stats.items()),
                      f"|Δ| ≤ {TARGET:g} + 4 SE", dev <= TARGET))
    return md_table(["glass sphere", "centre (θ < 14°)", "rim (θ > 70°)"], rows), out


def markdown(ctx: Context, v: dict, t_furnace: str, t_share: str, t_sweep: str,
             t_aniso: str, t_render: str, f_render: str, image) -> list:
    return [
        "### The dielectric (`transmission=true`)", "",
        "Kulla & Conty's dielectric extension: E is the albedo of reflection plus refraction "
        "in importance transport (the fraction of the light arriving along ωi that leaves), "
        "tabulated over μ, α and η from the plugin's rough dielectric, read at η from above "
        "and at 1/η from below; the lost light 1 − E(μi) leaves through a lobe on either "
        "side, the refracted share x from the interface's average transmittance, balanced so "
        "that the pair stays reciprocal across the interface (docs/models.md).", "",
        f"**White furnace** (importance transport, η = {ETA:g}, between two nodes of the "
        "tables; θ > 90°: lit from inside the glass): per θ, the single scattering (float64 "
        "quadrature) / the compensated E − 1 in closed form, and as the mean sample() weight / "
        f"the random walk's order 1. Target |E − 1| ≤ {TARGET:g}. Worst in closed form: GGX "
        f"{v['multiscatter dielectric: worst ggx']}, Beckmann "
        f"{v['multiscatter dielectric: worst beckmann']}.", "", t_furnace, "",
        "**Where the energy goes**: the reflected share of the multiple scattering, the "
        "compensation's 1 − x / the walk's orders ≥ 2 (in brackets, the walk's orders ≥ 2 as a "
        "fraction of all the light). Lit from outside: "
        f"{v.get('multiscatter dielectric: share gap outside', '—')}; from inside: "
        f"{v.get('multiscatter dielectric: share gap inside', '—')}.", "", t_share, "",
        "**The interpolation in η** (α = 1, closed form, E − 1; the tables' nodes lie "
        f"{_node_spacing():.1%} apart in η): worst {v['multiscatter dielectric: eta sweep']}.",
        "", t_sweep, "",
        "**Anisotropic roughness** through the equivalent α = sqrt(αu αv) (E − 1 from "
        "sample() in importance transport ± 1 standard error; measured, flagged above "
        f"{TARGET:g}):", "", t_aniso, "",
        "**Furnace render** (`scenes/furnace.xml` with paths of up to 64 vertices: a closed "
        "furnace around a lossless interface is 1 everywhere, inside the glass η² times "
        "that): a GGX glass sphere, α = 1, η = 1.5, ± 1 standard error:", "", t_render, "",
        image(ctx, f_render, "dielectric furnace render")]


def _node_spacing() -> float:
    """The relative step between neighbouring η nodes of the shipped tables."""
    from ..scattering.multiscatter import load_tables

    tables = load_tables()
    n_eta = len(next(iter(tables["ET"].values())))
    return math.exp(2.0 * math.log(tables["eta_max"]) / (n_eta - 1)) - 1.0


def render_figure(ctx: Context, out: dict) -> str:
    from ..plots import pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(1, len(out), figsize=(3.4 * len(out), 3.4))
    for ax, (name, (img, stats)) in zip(axes, out.items()):
        ax.imshow(img, cmap="gray", vmin=0.0, vmax=1.1)
        ax.set_title(f"{name}\ncentre {stats['centre'][0]:.3f}, rim {stats['rim'][0]:.3f}",
                     fontsize=8)
        ax.axis("off")
    fig.suptitle("White furnace, every path, GGX glass α = 1, η = 1.5", fontsize=9)
    return save_figure(fig, ctx.figure("multiscatter_dielectric_render.png"))
