r"""
The stochastic random walk on the Smith microsurface in float64, after Heitz, Hanika, d'Eon &
Dachsbacher, "Multiple-Scattering Microfacet BSDFs with the Smith Model", ACM Transactions on
Graphics 35(4), SIGGRAPH 2016: a ray enters the microsurface, meets it at a random height,
scatters on a facet whose normal is drawn from the distribution of visible normals, and goes on
until it leaves; the directions in which the rays leave, weighted, sample the BSDF with every
order of scattering times cosθo. Written from the paper, vectorised over paths (a loop over the
orders of scattering on the paths still inside), deterministic given a ``numpy.random.Generator``.
The independent reference for the energy compensation of Kulla & Conty (2017): the directional
albedo of each order and of all, and the lobe of the orders ≥ 2.

The microsurface is Smith's: heights uncorrelated with slopes, here uniform on [−1, 1]
(C1(h) = (h + 1)/2; the paper shows that the BSDF does not depend on the height distribution),
slopes Beckmann or GGX, α a number or (αu, αv) along x and y. With Λ Smith's function, extended
below the horizon by Λ(−ω) = −1 − Λ(ω) (so Λ ≤ −1 for a ray going down):

- a ray going up from height h leaves unoccluded with probability G1(ω, h) = C1(h)^Λ(ω); the
  probability that it travels from h to h' without meeting the surface is (C1(h)/C1(h'))^Λ(ω),
  for a ray going up or down, whose inversion gives the height of the next intersection (the
  paper's free-path distribution, written in heights);
- at an intersection the facet normal m is drawn from the visible normals of the direction ωi
  the ray comes from, D_ωi(m) = ⟨ωi, m⟩ D(m) / ∫⟨ωi, m'⟩ D(m') dm' (Heitz & d'Eon 2014), for
  ωi above or below the horizon: for GGX by Heitz's 2018 method ("Sampling the GGX Distribution
  of Visible Normals", JCGT 7(4)), for Beckmann by exact rejection sampling of the visible
  slopes (below);
- a conductor reflects and multiplies the path's weight by F(ωi·m) per channel; a dielectric
  reflects with probability F, else refracts and continues on the lower microsurface, the upper
  one seen from inside the medium (heights negated, the paper's dielectric walk); in radiance
  transport each refraction multiplies the weight by (η_i/η_t)² (Veach 1997, §5.2), where the
  walk runs from ωi (the camera's side, as a BSDF's ``sample``); in importance transport by 1.

Directions are (n, 3) unit vectors in the local frame (normal +z), both pointing away from the
surface: ``wi`` the side the walk enters from (Mitsuba's ``si.wi``, the camera's side in radiance
transport), the ray itself travelling along −ωi; ``wo`` the direction in which it leaves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cooktorrance import _pair, fresnel_exact, smith_lambda
from .quadrature import direction

KINDS = ("beckmann", "ggx")
TRANSPORTS = ("radiance", "importance")


def c1(h) -> np.ndarray:
    """The cumulative distribution of the uniform heights on [−1, 1]: C1(h) = (h + 1)/2."""
    return np.clip(0.5 * (np.asarray(h, dtype=np.float64) + 1), 0.0, 1.0)


def inv_c1(u) -> np.ndarray:
    """The height with C1(h) = u, u in [0, 1]."""
    return 2 * np.asarray(u, dtype=np.float64) - 1


def smith_lambda_signed(kind: str, alpha, w) -> np.ndarray:
    """Λ(ω) for any direction: Smith's Λ above the horizon, −1 − Λ(−ω) at or below it."""
    w = np.atleast_2d(w)
    lam = smith_lambda(kind, alpha, w)  # a function of |ωz|
    return np.where(w[:, 2] > 0, lam, -1 - lam)


def masking(kind: str, alpha, w, h) -> np.ndarray:
    """G1(ω, h) = C1(h)^Λ(ω): the probability that a ray leaving height h along ω (up) meets
    the microsurface no more; 0 for a ray going down."""
    w = np.atleast_2d(w)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        g = c1(h) ** smith_lambda_signed(kind, alpha, w)
    return np.where(w[:, 2] > 0, np.nan_to_num(g, nan=0.0), 0.0)


def sample_height(kind: str, alpha, w, h, u) -> np.ndarray:
    """
    The height of the next intersection of a ray at height h travelling along ω, by inverting
    P(no intersection between h and h') = (C1(h)/C1(h'))^Λ(ω) with the uniform number u, or +∞
    where it leaves the microsurface (u > 1 − G1(ω, h), upwards only).
    """
    w = np.atleast_2d(w)
    lam = smith_lambda_signed(kind, alpha, w)
    leaves = u > 1 - masking(kind, alpha, w, h)
    t = -np.log1p(-np.asarray(u, dtype=np.float64))  # −log(1 − u) ≥ 0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        log_c = np.log(np.maximum(c1(h), 1e-300)) + np.where(lam == 0, np.inf, t / lam)
    log_c = np.nan_to_num(log_c, nan=0.0, posinf=0.0)
    return np.where(leaves, np.inf, inv_c1(np.exp(np.minimum(log_c, 0.0))))


def _unit(v) -> np.ndarray:
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _ggx_visible_stretched(v, rng) -> np.ndarray:
    """
    Normals of the hemisphere visible from the unit v (Heitz 2018, the GGX VNDF for α = 1):
    a uniform point of the unit disc, its second coordinate remapped onto the projection of the
    visible half of the hemisphere, lifted onto the hemisphere. Valid for v below the horizon as
    well: the visible region is then the part of the disc between the projected equator (an
    ellipse with half-axis |vz|) and the circle, and the affine remapping keeps the density
    uniform over it.
    """
    lensq = v[:, 0] ** 2 + v[:, 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        t1_axis = np.where(lensq[:, None] > 0,
                           np.stack([-v[:, 1], v[:, 0], np.zeros(len(v))], axis=1)
                           / np.sqrt(lensq)[:, None], np.array([1.0, 0.0, 0.0]))
    t2_axis = np.cross(v, t1_axis)
    r, phi = np.sqrt(rng.random(len(v))), 2 * math.pi * rng.random(len(v))
    t1, t2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1 + v[:, 2])
    t2 = (1 - s) * np.sqrt(np.maximum(1 - t1 * t1, 0)) + s * t2
    t3 = np.sqrt(np.maximum(1 - t1 * t1 - t2 * t2, 0))
    return t1[:, None] * t1_axis + t2[:, None] * t2_axis + t3[:, None] * v


def _beckmann_visible_slope(mu, rng) -> np.ndarray:
    """
    Exact samples of p(x) ∝ (μ − x)⁺ e^(−x²), the slope along the view's azimuth of the Beckmann
    (α = 1) normals visible from a direction with cotθ = μ (Heitz & d'Eon 2014 sample it by
    inverting its CDF), here by rejection, without erf; the acceptance is ≥ 0.24 everywhere:

    - μ ≥ 0: proposal ∝ (μ + |x|) e^(−x²), a mixture of N(0, ½) (weight μ√π) and
      |x| e^(−x²) (weight 1; |x| = √E, E ~ Exp(1)); accept with (μ − x)⁺/(μ + |x|);
    - −1 < μ < 0, w = −x > −μ: proposal ∝ w e^(−w²) on w > −μ (w = √(μ² + E)); accept with
      (w + μ)/w;
    - μ ≤ −1, x = μ − s: the target ∝ s e^(−2|μ|s) e^(−s²); proposal Gamma(2, rate 2|μ|),
      accept with e^(−s²).
    """
    x, todo = np.empty(len(mu)), np.arange(len(mu))
    while todo.size:
        m, n = mu[todo], len(todo)
        e, accept_u = rng.standard_exponential(n), rng.random(n)
        # μ ≥ 0
        gauss = rng.random(n) < m * math.sqrt(math.pi) / (np.abs(m) * math.sqrt(math.pi) + 1)
        sign = np.where(rng.random(n) < 0.5, -1.0, 1.0)
        xa = np.where(gauss, rng.normal(0.0, math.sqrt(0.5), n), sign * np.sqrt(e))
        ok_a = accept_u * (m + np.abs(xa)) < m - xa
        # −1 < μ < 0
        wb = np.sqrt(m * m + e)
        ok_b = accept_u * wb < wb + m
        # μ ≤ −1
        with np.errstate(divide="ignore"):
            s = (e + rng.standard_exponential(n)) / (2 * np.abs(m))
        ok_c = accept_u < np.exp(-s * s)
        prop = np.select([m >= 0, m > -1], [xa, -wb], m - s)
        ok = np.select([m >= 0, m > -1], [ok_a, ok_b], ok_c)
        x[todo[ok]] = prop[ok]
        todo = todo[~ok]
    return x


def _beckmann_visible_stretched(v, rng) -> np.ndarray:
    """Visible slopes of the α = 1 Beckmann surface seen from the unit v, as normals: along
    v's azimuth by :func:`_beckmann_visible_slope`, across it N(0, ½), rotated into place."""
    sin_v = np.sqrt(v[:, 0] ** 2 + v[:, 1] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.clip(np.where(sin_v > 0, v[:, 2] / sin_v, 1e12), -1e12, 1e12)
    x = _beckmann_visible_slope(mu, rng)
    y = rng.normal(0.0, math.sqrt(0.5), len(v))
    phi = np.arctan2(v[:, 1], v[:, 0])
    sx, sy = np.cos(phi) * x - np.sin(phi) * y, np.sin(phi) * x + np.cos(phi) * y
    return np.stack([-sx, -sy, np.ones(len(v))], axis=1)  # not normalised


def sample_visible_normal(kind: str, alpha, wi, rng) -> np.ndarray:
    """
    Microfacet normals m (upper hemisphere) drawn from D_ωi(m) ∝ ⟨ωi, m⟩ D(m), for ωi above or
    below the horizon (any but straight down, which sees no facet). Anisotropy by stretching:
    the α = 1 configuration seen from (αu ωx, αv ωy, ωz), slopes scaled back by (αu, αv)
    (Heitz & d'Eon 2014). Returns → (n, 3) unit vectors.
    """
    au, av = _pair(alpha)
    stretch = np.array([au, av, 1.0])
    v = _unit(np.atleast_2d(wi) * stretch)
    if kind == "ggx":
        n = _ggx_visible_stretched(v, rng)
        return _unit(np.column_stack([au * n[:, 0], av * n[:, 1], np.maximum(n[:, 2], 0)]))
    m = _beckmann_visible_stretched(v, rng)
    return _unit(np.column_stack([au * m[:, 0], av * m[:, 1], m[:, 2]]))


def _conductor_fresnel(fresnel):
    """F(cos) → (n, channels): None (F ≡ 1), a callable, or a complex IOR η + ik per channel
    (the exact Fresnel term of :func:`mi_brdfs.reference.cooktorrance.fresnel_exact`)."""
    if fresnel is None:
        return lambda c: np.ones((len(c), 1))
    if callable(fresnel):
        return lambda c: np.asarray(fresnel(c), dtype=np.float64).reshape(len(c), -1)
    n = np.atleast_1d(np.asarray(fresnel, dtype=np.complex128))
    return lambda c: fresnel_exact(c, n.real, n.imag)


@dataclass
class Walk:
    """The end of every path: ``wo`` (n, 3) the direction in which it left (on the other side
    of the surface from ωi: transmitted), ``weight`` (n, channels) its throughput, ``order`` (n,)
    its number of scattering events, 0 where it was still inside after ``max_order`` (then
    wo = 0, weight 0)."""

    wo: np.ndarray
    weight: np.ndarray
    order: np.ndarray

    @property
    def lost(self) -> float:
        """The fraction of the paths cut at the maximum order (counted as lost energy)."""
        return float(np.mean(self.order == 0))


def _scatter(kind, alpha, d, side, rng, fresnel, eta, radiance):
    """
    One scattering event of the paths travelling along d on the microsurface of ``side`` (+1
    the upper, −1 the lower one, where the walk runs in the mirror image z → −z): returns the new
    direction, the new side and the factor of the weight.
    """
    mirror = np.column_stack([np.ones(len(d)), np.ones(len(d)), side])
    m = sample_visible_normal(kind, alpha, -d * mirror, rng) * mirror  # facing the ray
    cos_i = np.maximum(-np.einsum("ij,ij->i", d, m), 0.0)
    reflected = d + 2 * cos_i[:, None] * m
    if eta is None:  # conductor
        return reflected, side, fresnel(cos_i)
    eta_rel = np.where(side > 0, eta, 1 / eta)  # η_t/η_i
    f = np.empty(len(d))
    for s in (1.0, -1.0):
        sel = side == s
        f[sel] = fresnel_exact(cos_i[sel], eta if s > 0 else 1 / eta, 0.0)[:, 0]
    refract = rng.random(len(d)) >= f  # total internal reflection: f = 1
    cos_t = np.sqrt(np.maximum(1 - (1 - cos_i**2) / eta_rel**2, 0.0))
    refracted = _unit(d / eta_rel[:, None] + (cos_i / eta_rel - cos_t)[:, None] * m)
    new_d = np.where(refract[:, None], refracted, reflected)
    factor = np.where(refract & radiance, 1 / eta_rel**2, 1.0)[:, None]
    return new_d, np.where(refract, -side, side), factor


def _check(wi, kind, fresnel, eta, transport, max_order):
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, not {kind!r}")
    if transport not in TRANSPORTS:
        raise ValueError(f"transport must be one of {TRANSPORTS}, not {transport!r}")
    if eta is not None and (fresnel is not None or eta <= 0):
        raise ValueError("a dielectric takes eta > 0 and no fresnel")
    if eta is None and np.any(wi[:, 2] <= 0):
        raise ValueError("a conductor is lit from above only (wi z > 0)")
    if np.any(wi[:, 2] == 0) or max_order < 1:
        raise ValueError("wi must not be horizontal, max_order ≥ 1")


def walk(wi, kind: str, alpha, n_paths: int, rng: np.random.Generator, fresnel=None,
         eta: float | None = None, transport: str = "radiance", max_order: int = 100) -> Walk:
    """
    ``n_paths`` random walks on the microsurface entering along −``wi`` ((3,) or (n_paths, 3),
    unit, pointing away from the surface; below the horizon for a dielectric from inside).

    ``kind`` 'beckmann' or 'ggx'; ``alpha`` a number or (αu, αv). A conductor by default, with
    ``fresnel``: None (F ≡ 1), a callable cos → (n, channels), or a complex IOR η + ik per
    channel. A dielectric when ``eta`` (η_int/η_ext, a number) is given, with ``transport``
    'radiance' (refraction scales by (η_i/η_t)²) or 'importance'. A path that scatters
    ``max_order`` times without leaving is cut and counted as lost (order 0, weight 0):
    E[weight] over all paths is then the albedo of the orders ≤ max_order.
    """
    wi = _unit(np.broadcast_to(np.asarray(wi, dtype=np.float64), (n_paths, 3)).copy())
    _check(wi, kind, fresnel, eta, transport, max_order)
    fresnel = None if eta is not None else _conductor_fresnel(fresnel)
    channels = 1 if fresnel is None else fresnel(np.ones(1)).shape[1]
    d = -wi  # the direction of travel
    side = np.where(wi[:, 2] > 0, 1.0, -1.0)  # +1 outside (above), −1 inside
    h = side * np.inf  # world heights: the ray comes from far away
    weight, order = np.ones((n_paths, channels)), np.zeros(n_paths, dtype=np.int64)
    wo = np.zeros((n_paths, 3))
    live = np.arange(n_paths)
    for k in range(1, max_order + 2):
        # the next height on the microsurface of the path's side, in its mirror frame
        s = side[live]
        dm = d[live] * np.column_stack([np.ones(len(s)), np.ones(len(s)), s])
        hm = sample_height(kind, alpha, dm, s * h[live], rng.random(len(live)))
        out = np.isinf(hm)
        wo[live[out]], order[live[out]] = d[live[out]], k - 1
        live, s = live[~out], s[~out]
        h[live] = s * hm[~out]
        if k > max_order or not live.size:
            break
        d[live], side[live], factor = _scatter(kind, alpha, d[live], s, rng, fresnel, eta,
                                               transport == "radiance")
        weight[live] *= factor
    weight[order == 0] = 0.0
    return Walk(wo, weight, order)


def _mean_se(total, squares, n) -> tuple[np.ndarray, np.ndarray]:
    """Mean and its standard error from the sums of n per-path values and of their squares."""
    mean = total / n
    return mean, np.sqrt(np.maximum(squares / n - mean**2, 0.0) / max(n - 1, 1))


@dataclass
class Albedo:
    """
    Directional albedo E(θi) = ∫ f |cosθo| dωo estimated by the walk, per channel, with standard
    errors (``*_se``): ``total`` of the orders 1…max_order, ``orders[k − 1]`` of order k,
    ``transmitted`` the part that left on the other side of the surface (0 for a conductor),
    ``lost`` the fraction of the paths cut at max_order (their energy is in no term),
    ``n_paths``.
    """

    total: np.ndarray
    total_se: np.ndarray
    orders: np.ndarray
    orders_se: np.ndarray
    transmitted: np.ndarray
    transmitted_se: np.ndarray
    lost: float
    n_paths: int


def albedo(theta_i: float, kind: str, alpha, n_paths: int, rng: np.random.Generator,
           phi_i: float = 0.0, max_order: int = 100, **options) -> Albedo:
    """
    The albedo of each order and of all, for light arriving from polar angle ``theta_i`` and
    azimuth ``phi_i`` (radians; θi > π/2: from inside a dielectric); ``options`` as
    :func:`walk` (``fresnel``, ``eta``, ``transport``).
    """
    w = walk(direction(theta_i, phi_i), kind, alpha, n_paths, rng, max_order=max_order,
             **options)
    n, channels = n_paths, w.weight.shape[1]
    orders = np.zeros((2, max_order + 1, channels))
    for c in range(channels):
        for i, power in enumerate((1, 2)):
            orders[i, :, c] = np.bincount(w.order, w.weight[:, c] ** power, max_order + 1)
    by_order, by_order_se = _mean_se(orders[0, 1:], orders[1, 1:], n)
    total, total_se = _mean_se(orders[0].sum(0), (w.weight**2).sum(0), n)
    below = (w.wo[:, 2] * math.cos(theta_i) < 0)[:, None]  # left on the other side
    transmitted, transmitted_se = _mean_se((w.weight * below).sum(0),
                                           (w.weight**2 * below).sum(0), n)
    return Albedo(total, total_se, by_order, by_order_se, transmitted, transmitted_se, w.lost, n)


def lobe_histogram(theta_i: float, kind: str, alpha, n_paths: int, rng: np.random.Generator,
                   theta_edges, phi_bins=((-math.pi, math.pi),), phi_i: float = 0.0,
                   min_order: int = 2, **options) -> tuple[np.ndarray, np.ndarray]:
    """
    The outgoing lobe of the orders ≥ ``min_order``, binned: for each bin B, the mean of
    f(ωi, ωo) |cosθo| over B per unit solid angle, ∫_B f |cosθo| dωo / Ω(B) — comparable with a
    BSDF's f·|cosθo| at the bin's centre —, and its standard error.

    Bins: polar angle between consecutive ``theta_edges`` (radians, up to π: below the surface,
    transmission) × azimuth relative to ``phi_i`` in each (lo, hi) of ``phi_bins``, taken modulo
    2π: an in-plane slice is e.g. phi_bins=((−δ, δ), (π − δ, π + δ)), the backward and the
    forward (specular) side of the plane of incidence. ``options`` as :func:`walk`.

    Returns → (density, standard error), each (len(theta_edges) − 1, len(phi_bins), channels).
    """
    w = walk(direction(theta_i, phi_i), kind, alpha, n_paths, rng, **options)
    keep = w.order >= min_order
    theta_o = np.arccos(np.clip(w.wo[keep, 2], -1, 1))
    dphi = np.arctan2(w.wo[keep, 1], w.wo[keep, 0]) - phi_i
    weight = w.weight[keep]
    edges = np.asarray(theta_edges, dtype=np.float64)
    t_bin = np.digitize(theta_o, edges) - 1  # bin i: edges[i] ≤ θo < edges[i + 1]
    shape = (len(edges) - 1, len(phi_bins), weight.shape[1])
    total, squares = np.zeros(shape), np.zeros(shape)
    for j, (lo, hi) in enumerate(phi_bins):
        inside = np.mod(dphi - lo, 2 * math.pi) < hi - lo
        for i in range(len(edges) - 1):
            sel = inside & (t_bin == i)
            solid_angle = (math.cos(edges[i]) - math.cos(edges[i + 1])) * (hi - lo)
            total[i, j] = weight[sel].sum(0) / solid_angle
            squares[i, j] = (weight[sel] ** 2).sum(0) / solid_angle**2
    return _mean_se(total, squares, n_paths)
