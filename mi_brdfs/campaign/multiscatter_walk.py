"""
The energy compensation of ``cooktorrance`` (``multiscatter``; Kulla & Conty 2017, "Revisiting
Physically Based Shading at Imageworks", SIGGRAPH course "Physically Based Shading in Theory and
Practice") against the true multiple scattering: the random walk on the Smith microsurface of
Heitz, Hanika, d'Eon & Dachsbacher 2016 ("Multiple-Scattering Microfacet BSDFs with the Smith
Model", ACM TOG 35(4)), in float64.

Here, for :mod:`mi_brdfs.campaign.multiscatter` (the report's section): the compensated albedo
in closed form, where the compensation lobe puts its energy against where the walk's bounces
≥ 2 leave (in-plane slices, and the relative L1 difference binned over the whole hemisphere),
and a coloured conductor's total albedo against the walk's Fresnel-weighted bounces.

The walk's single scattering is weighted by the height-correlated Smith G2 = 1/(1 + Λi + Λo),
the plugin's (``shadowing="smith"``, as Mitsuba) by the separable G1·G1 ≤ G2: the plugin's
order 1 loses a little more energy than the walk's, and so its compensation carries a little
more than the walk's orders ≥ 2.
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import batch
from ..plots import pyplot, save_figure
from ..reference import multiscatter as ref_ms
from ..reference import randomwalk
from ..reference.cooktorrance import CookTorrance
from ..reference.quadrature import direction
from .core import Context, Row, Section, md_table

KINDS = ("ggx", "beckmann")
#: Gold's complex index (η, k) per RGB channel.
GOLD = ((0.143, 0.374, 1.442), (3.983, 2.385, 1.603))
#: The lobe comparison: roughnesses, incident angles (degrees), bins (degrees).
LOBE_ALPHAS, LOBE_THETAS = (0.5, 1.0), (0.0, 60.0, 80.0)
THETA_EDGES = tuple(range(0, 91, 5))
PHI_BINS = 12
#: Paths of the walk per lobe (full, quick).
LOBE_PATHS = (1_000_000, 50_000)
#: The coloured albedo: roughnesses and incident angles (degrees).
GOLD_ALPHAS, GOLD_THETAS = (0.5, 1.0), (0.0, 60.0, 80.0)


def spec(kind: str, alpha, multiscatter: bool = True, shadowing: str = "smith",
         **params) -> dict:
    """A ``cooktorrance`` reflection lobe with F ≡ 1 unless ``params`` say otherwise; ``alpha``
    a number or (αu, αv)."""
    out = {"type": "cooktorrance", "distribution": kind, "shadowing": shadowing,
           "fresnel": "none", "multiscatter": multiscatter}
    if isinstance(alpha, tuple):
        out.update(alpha_u=alpha[0], alpha_v=alpha[1])
    else:
        out["alpha"] = alpha
    out.update(params)
    return out


def gold_spec(kind: str, alpha, multiscatter: bool = True) -> dict:
    return spec(kind, alpha, multiscatter, fresnel="exact",
                eta={"type": "rgb", "value": list(GOLD[0])},
                k={"type": "rgb", "value": list(GOLD[1])})


def closed_form(kind: str, alpha, theta: float, phi: float = 0.0, shadowing: str = "smith",
                eta=None, k=None) -> tuple[np.ndarray, np.ndarray, float]:
    """
    (E_ss, E, E_table(μi)) at incidence ``theta``, azimuth ``phi`` (degrees), per channel:
    E_ss = ∫ f_ss cosθo dωo of the float64 reference (quadrature over the half vector), and the
    compensated E = E_ss + F_ms (1 − E_table(μi)) in closed form (Kulla & Conty: the lobe's
    albedo; :class:`~mi_brdfs.reference.multiscatter.Compensated`, the table read at
    sqrt(αu αv)). F ≡ 1 without ``eta`` (F_ms = 1), else the exact Fresnel term of η + ik.
    """
    fresnel = "none" if eta is None else "exact"
    base = CookTorrance(alpha, kind, shadowing, fresnel, eta=1.0 if eta is None else eta,
                        k=0.0 if k is None else k)
    model = ref_ms.Compensated(base)
    e_ss = base.albedo(math.radians(theta), phi=math.radians(phi))
    e_i = float(ref_ms.albedo(model.E, model.alpha_max, math.cos(math.radians(theta)),
                              model.alpha))
    return e_ss, e_ss + model.F_ms * (1.0 - e_i), e_i


def walk_albedo(kind: str, alpha, theta: float, n: int, seed, fresnel=None):
    """The random walk's albedo (every order up to 100, and each) at ``theta`` degrees."""
    return randomwalk.albedo(math.radians(theta), kind, alpha, n, np.random.default_rng(seed),
                             fresnel=fresnel)


def _phi_bins() -> list[tuple[float, float]]:
    """Azimuth bins relative to ωi's, centred on multiples of 2π/PHI_BINS: bin 0 on ωi's side
    of the plane of incidence, bin PHI_BINS/2 on the mirror side."""
    d = 2 * math.pi / PHI_BINS
    return [((j - 0.5) * d, (j + 0.5) * d) for j in range(PHI_BINS)]


def plugin_lobe(kind: str, alpha, theta_i: float, wo: np.ndarray) -> np.ndarray:
    """The plugin's compensation lobe f_ms·cosθo: eval with ``multiscatter`` minus without, at
    the (n, 3) directions ``wo``, ωi at ``theta_i`` degrees in the azimuth 0."""
    wi = direction(math.radians(theta_i))
    with_ms = batch.evaluate(spec(kind, alpha, True), wi, wo).value[:, 0]
    return with_ms - batch.evaluate(spec(kind, alpha, False), wi, wo).value[:, 0]


def plugin_bins(kind: str, alpha, theta_i: float, nodes: int = 6) -> np.ndarray:
    """The plugin's f_ms·cosθo averaged over each (θo, φo) bin's solid angle (Gauss-Legendre
    in cosθo, the midpoint rule in φo), (θ bins, φ bins)."""
    edges = np.radians(THETA_EDGES)
    x, w = np.polynomial.legendre.leggauss(nodes)
    lo, hi = np.cos(edges[1:]), np.cos(edges[:-1])
    mu = 0.5 * (hi - lo)[:, None] * (x[None, :] + 1) + lo[:, None]  # (θ bins, nodes)
    d = 2 * math.pi / PHI_BINS
    phi = np.array([[b + (i + 0.5) * d / 4 for i in range(4)] for b, _ in _phi_bins()])
    M = mu[:, None, :, None] + 0 * phi[None, :, None, :]
    P = phi[None, :, None, :] + 0 * M
    s = np.sqrt(np.maximum(1 - M * M, 0))
    wo = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    value = plugin_lobe(kind, alpha, theta_i, wo).reshape(M.shape)
    return np.einsum("tpnq,n->tp", value, w / 2) / 4


def lobe_comparison(kind: str, alpha, theta_i: float, n_paths: int, seed) -> dict:
    """
    The plugin's compensation lobe ``a`` against the walk's orders ≥ 2 ``b`` (with its standard
    error ``se``), both bin averages of f·cosθo, and the relative L1 difference over the
    hemisphere ∫|a − b| / ∫b (``l1``), of the shapes alone (each scaled to unit integral,
    ``l1_shape``), the part of ``l1`` the walk's noise alone makes (``floor``: Σ E|N(0, se)|Ω
    / ∫b) and the two integrals (``int_a``, ``int_b``).
    """
    edges = np.radians(THETA_EDGES)
    b, se = randomwalk.lobe_histogram(math.radians(theta_i), kind, alpha, n_paths,
                                      np.random.default_rng(seed), edges,
                                      phi_bins=_phi_bins())
    b, se = b[..., 0], se[..., 0]
    a = plugin_bins(kind, alpha, theta_i)
    omega = (np.cos(edges[:-1]) - np.cos(edges[1:]))[:, None] * (2 * math.pi / PHI_BINS)
    int_a, int_b = float((a * omega).sum()), float((b * omega).sum())
    shape = np.abs(a / int_a - b / int_b) * omega
    return {"a": a, "b": b, "se": se, "int_a": int_a, "int_b": int_b,
            "l1": float((np.abs(a - b) * omega).sum() / int_b),
            "l1_shape": float(shape.sum()),
            "floor": float((math.sqrt(2 / math.pi) * se * omega).sum() / int_b)}


def lobes(ctx: Context, s: Section) -> tuple[str, str]:
    """The lobe comparison's table and in-plane figure, over α, θi and both distributions."""
    alphas, thetas = ctx.n(LOBE_ALPHAS, LOBE_ALPHAS[-1:]), ctx.n(LOBE_THETAS, (60.0,))
    n_paths = ctx.n(*LOBE_PATHS)
    rows, results, worst = [], {}, {}
    for i, kind in enumerate(KINDS):
        for j, alpha in enumerate(alphas):
            for t, theta in enumerate(thetas):
                r = lobe_comparison(kind, alpha, theta, n_paths, (7, i, j, t))
                results[(kind, alpha, theta)] = r
                worst[kind] = max(worst.get(kind, (0.0, "")),
                                  (r["l1"], f"α = {alpha:g}, θi = {theta:g}°"))
                rows.append((kind, f"{alpha:g}", f"{theta:g}°", f"{r['int_a']:.4f}",
                             f"{r['int_b']:.4f}", f"{r['l1']:.3f}", f"{r['l1_shape']:.3f}",
                             f"{r['floor']:.3f}"))
    for kind, (l1, where) in worst.items():
        s.values[f"multiscatter: lobe L1 {kind}"] = f"{l1:.3f}"
        s.rows.append(Row(f"cooktorrance multiscatter {kind}", "compensation lobe vs random "
                          "walk orders ≥ 2: relative L1 over the hemisphere, worst over "
                          f"α ∈ {{{', '.join(f'{a:g}' for a in alphas)}}}, θi ∈ "
                          f"{{{', '.join(f'{t:g}°' for t in thetas)}}}",
                          f"{l1:.3f} ({where})", "measured (no target)", True))
    table = md_table(["distribution", "α", "θi", "∫ f_ms cosθo (plugin)",
                      "∫ orders ≥ 2 (walk)", "relative L1", "L1 of the shapes",
                      "walk noise alone"], rows)
    return table, lobe_figure(ctx, results, alphas, thetas)


def lobe_figure(ctx: Context, results: dict, alphas, thetas) -> str:
    """In-plane slices: the plugin's f_ms·cosθo (line) and the walk's orders ≥ 2 (dots: the
    φ bins centred on the plane of incidence), θo < 0 on ωi's side."""
    plt = pyplot()
    keys = [(k, a) for k in KINDS for a in alphas]
    fig, axes = plt.subplots(len(keys), len(thetas), figsize=(3.6 * len(thetas),
                                                              2.6 * len(keys)),
                             squeeze=False, sharex=True)
    centres = 0.5 * (np.array(THETA_EDGES[:-1]) + np.array(THETA_EDGES[1:]))
    t = np.radians(np.linspace(0.0, 89.0, 90))
    for row, (kind, alpha) in enumerate(keys):
        for col, theta in enumerate(thetas):
            ax, r = axes[row, col], results[(kind, alpha, theta)]
            wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=1)
            line = plugin_lobe(kind, alpha, theta, wo)
            deg = np.degrees(t)
            ax.plot(np.concatenate([-deg[::-1], deg]), np.concatenate([line[::-1], line]),
                    "-", color="C0", lw=1.2, label="compensation (plugin)")
            back, forward = 0, PHI_BINS // 2
            ax.errorbar(np.concatenate([-centres[::-1], centres]),
                        np.concatenate([r["b"][::-1, back], r["b"][:, forward]]),
                        yerr=np.concatenate([r["se"][::-1, back], r["se"][:, forward]]),
                        fmt="o", ms=2.5, color="C3", lw=0.8, label="random walk, orders ≥ 2")
            ax.set_title(f"{kind}, α = {alpha:g}, θi = {theta:g}°: L1 {r['l1']:.2f}",
                         fontsize=8)
            ax.grid(alpha=0.3)
            ax.set_xlim(-90, 90)
    for ax in axes[-1]:
        ax.set_xlabel("θo (degrees; < 0: the side of ωi)")
    for ax in axes[:, 0]:
        ax.set_ylabel("f·cosθo")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("Where the energy goes: Kulla-Conty compensation lobe vs the random walk's "
                 "orders ≥ 2 (plane of incidence, F ≡ 1)", fontsize=9)
    return save_figure(fig, ctx.figure("multiscatter_lobes.png"))


def _triple(x) -> str:
    return ", ".join(f"{v:.4f}" for v in np.atleast_1d(x))


def gold(ctx: Context, s: Section) -> str:
    """Gold (exact Fresnel, RGB): the compensated albedo in closed form against the walk's
    Fresnel-weighted total, per channel; and their parts, single and multiple."""
    alphas, thetas = ctx.n(GOLD_ALPHAS, GOLD_ALPHAS[-1:]), ctx.n(GOLD_THETAS, (60.0,))
    ior = np.array(GOLD[0]) + 1j * np.array(GOLD[1])
    n_paths = ctx.n(400_000, 20_000)
    rows, worst = [], (0.0, "")
    for i, kind in enumerate(KINDS):
        for j, alpha in enumerate(alphas):
            for t, theta in enumerate(thetas):
                e_ss, e, _ = closed_form(kind, alpha, theta, eta=GOLD[0], k=GOLD[1])
                w = walk_albedo(kind, alpha, theta, n_paths, (11, i, j, t), fresnel=ior)
                rel = (e - w.total) / w.total
                c = int(np.argmax(np.abs(rel)))
                if abs(rel[c]) > abs(worst[0]):
                    worst = (float(rel[c]), f"{kind}, α = {alpha:g}, θ = {theta:g}°, "
                                            f"{'RGB'[c]}")
                rows.append((kind, f"{alpha:g}", f"{theta:g}°", _triple(e_ss),
                             _triple(w.orders[0]), _triple(e - e_ss),
                             _triple(w.total - w.orders[0]), _triple(e), _triple(w.total),
                             ", ".join(f"{v:+.2%}" for v in rel)))
    s.values["multiscatter: gold worst relative"] = f"{worst[0]:+.2%}"
    s.rows.append(Row("cooktorrance multiscatter gold", "compensated total albedo (closed "
                      "form, F_ms) vs random walk total (Fresnel per bounce), per channel",
                      f"worst {worst[0]:+.2%} ({worst[1]})", "measured (no target)", True))
    return md_table(["distribution", "α", "θ", "single: plugin E_ss (R, G, B)",
                     "walk order 1", "compensation F_ms(1 − E)", "walk orders ≥ 2",
                     "total: compensated", "walk total", "(compensated − walk)/walk"], rows)
