r"""
The dielectric's energy compensation (:mod:`~mi_brdfs.scattering.multiscatter`) under a thin
film: the albedo E_R+T(μ) of the rough interface changes when a film replaces its Fresnel
term F by the film's reflectance R, because reflection and refraction lose different amounts
of light to masking. A film that absorbs nothing keeps R + T = 1 per facet, so that change is

.. math::

    E_\mathrm{film}(\mu) - E(\mu) = \int_0^1 K(\mu, c)\,\bigl(R(c) - F(c)\bigr)\,dc,

where K(μ, c) dc collects, over the microfacet normals m whose cosine with ωi is c (weighted by
their visible density, as in the table's own integral, :mod:`mi_brdfs.albedo_tables`), the
difference between what a reflection and a refraction through m keep after masking:
K = D_ωi(m) G1(ωi)(G1(ωo,r) − G1(ωo,t))/G1(ωi) per unit c. R − F is linear between N_NODES
cosines (uniform in the facet cosine *outside* the film; from below, the cosine outside is
that of the refracted ray, Snell's image: a lossless stack reflects the same from both sides),
so the integral is Σ_j K_j(μ) (R_j − F_j), K_j = ∫ K(μ, c) h_j(c) dc with the hat functions
h_j of the nodes. The kernel then reads R at the nodes once per shading point (the film's
thickness and the wavelengths vary), and E_film = E + Σ_j K_j ΔF_j keeps the compensation
white-furnace exact up to the tables' own error and the interpolation of ΔF between nodes.

K_j(μ, α) is computed at load for the material's η, in float64 NumPy, over the same μ and α
nodes as the tables and by the same integral they use (m from D·cosθm on a periodised
stratified grid); its averages 2∫K_j μ dμ as :func:`~mi_brdfs.scattering.multiscatter.average` makes
E_avg, so that E_avg,film = E_avg + Σ_j K̄_j ΔF_j is the exact average of the interpolated
E_film, which the compensation's normalisation needs.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from . import fresnel, multiscatter

#: Cosines (outside the film) at which the film's reflectance is read: uniform in [0, 1].
N_NODES = 12
NODES = np.linspace(0.0, 1.0, N_NODES)

#: The stratified grid of microfacet normals per (μ, α) node: GRID × GRID.
GRID = 64


def _g1(kind: str, alpha: float, v):
    """Smith's G1 as the plugin computes it (Walter's rational form for Beckmann), without the
    facing test, for unit vectors ``v`` (..., 3)."""
    z2 = v[..., 2] ** 2
    t2 = alpha * alpha * np.maximum(1.0 - z2, 0.0) / np.maximum(z2, 1e-300)  # α² tan²θ
    if kind == "beckmann":
        a = 1.0 / np.sqrt(np.maximum(t2, 1e-300))  # 1/(α tanθ)
        g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
        return np.where(a >= 1.6, 1.0, g)
    return 2.0 / (1.0 + np.sqrt(1.0 + t2))


def _normals(kind: str, alpha: float, grid: int):
    """Microfacet normals drawn from D·cosθm on a periodised grid (Sidi 1993, as the tables),
    (grid², 3), with their quadrature weights (sum 1)."""
    t = (np.arange(grid) + 0.5) / grid
    u = t - np.sin(2.0 * np.pi * t) / (2.0 * np.pi)
    w = (1.0 - np.cos(2.0 * np.pi * t)) / grid
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    weight = np.outer(w, w).ravel()
    u1, u2 = u1.ravel(), u2.ravel()
    if kind == "beckmann":
        tan2 = -alpha * alpha * np.log1p(-u1)
    else:
        tan2 = alpha * alpha * u1 / (1.0 - u1)
    cos_m = 1.0 / np.sqrt(1.0 + tan2)
    sin_m = np.sqrt(np.maximum(1.0 - cos_m * cos_m, 0.0))
    phi = 2.0 * np.pi * u2
    return np.stack((sin_m * np.cos(phi), sin_m * np.sin(phi), cos_m), axis=-1), weight


def kernel_row(kind: str, eta: float, alpha: float, mus, below: bool,
               grid: int = GRID) -> np.ndarray:
    """
    K_j(μ) at roughness ``alpha`` for each of ``mus`` of the interface of relative index
    ``eta`` lit from above (the film's side) or from ``below``, (len(mus), N_NODES): the hat
    weights of the cosine outside the film, over the normals whose reflection and refraction
    both exist (where ωi is totally reflected R = F = 1).
    """
    m, weight = _normals(kind, alpha, grid)
    eta = 1.0 / eta if below else eta  # the relative index in the direction of travel
    mus = np.asarray(mus, np.float64)
    wi = np.stack((np.sqrt(1.0 - mus ** 2), 0.0 * mus, mus), axis=-1)[:, None, :]
    c = np.einsum("nkd,kd->nk", np.broadcast_to(wi, (len(mus),) + m.shape), m)
    cos_t2 = 1.0 - (1.0 - c * c) / (eta * eta)
    keep = (c > 0.0) & (cos_t2 > 0.0)
    cos_t = np.sqrt(np.maximum(cos_t2, 0.0))
    wo_r = 2.0 * c[..., None] * m - wi
    wo_t = (c / eta - cos_t)[..., None] * m - wi / eta
    g_i = _g1(kind, alpha, np.broadcast_to(wi, wo_r.shape))
    g_r = np.where(wo_r[..., 2] > 0.0, _g1(kind, alpha, wo_r), 0.0)
    g_t = np.where(wo_t[..., 2] < 0.0, _g1(kind, alpha, wo_t), 0.0)
    # the weight of a D·cosθm sample: |ωi·m| G1(ωi) G1(ωo) / (μi cosθm)
    value = np.where(keep, weight * c * g_i * (g_r - g_t) / (mus[:, None] * m[:, 2]), 0.0)
    outside = cos_t if below else c
    return _hats(np.where(keep, outside, 0.0), value)


def _hats(cosines, values) -> np.ndarray:
    """Σ over the last axis of ``values`` times each node's hat function at ``cosines``."""
    s = np.clip(cosines, 0.0, 1.0) * (N_NODES - 1)
    j = np.minimum(s.astype(np.int64), N_NODES - 2)
    t = s - j
    n = values.shape[0]
    index = (np.arange(n)[:, None] * N_NODES + j).ravel()
    return (np.bincount(index, (values * (1.0 - t)).ravel(), n * N_NODES) +
            np.bincount(index + 1, (values * t).ravel(), n * N_NODES)).reshape(n, N_NODES)


def _rows(alpha_range, alphas) -> range:
    """The α nodes a lookup within ``alpha_range`` ((lo, hi), or None: any α) can read."""
    if alpha_range is None:
        return range(len(alphas))
    lo = max(int(np.searchsorted(alphas, alpha_range[0], side="right")) - 1, 0)
    hi = min(int(np.searchsorted(alphas, alpha_range[1], side="left")), len(alphas) - 1)
    return range(lo, max(hi, lo + 1) + 1)


def kernels(kind: str, eta: float, alpha_range=None) -> tuple[np.ndarray, np.ndarray]:
    """K_j on the dielectric tables' (α, μ) nodes, lit from above and from below, each
    (n_α, n_μ, N_NODES); only the α rows a roughness within ``alpha_range`` reads are
    computed (the others are 0 and never read)."""
    tables = multiscatter.load_tables()
    _, n_alpha, n_mu = next(iter(tables["ET"].values())).shape
    alphas = multiscatter.alpha_nodes(n_alpha, tables["alpha_max"])
    mus = multiscatter.mu_nodes(n_mu)
    out = []
    for below in (False, True):
        K = np.zeros((len(alphas), len(mus), N_NODES))
        for r in _rows(alpha_range, alphas):
            K[r] = kernel_row(kind, eta, float(alphas[r]), mus, below)
        out.append(K)
    return tuple(out)


def hat_averages() -> np.ndarray:
    """2∫₀¹ h_j(c) c dc of each node's hat function (exact: 3 Gauss-Legendre nodes per
    segment of a quadratic): F_avg of a reflectance linear between the nodes is Σ_j of these
    times its values."""
    x, w = np.polynomial.legendre.leggauss(3)
    step = 1.0 / (N_NODES - 1)
    out = np.zeros(N_NODES)
    for xk, wk in zip((x + 1.0) / 2.0, w / 2.0):
        c = (np.arange(N_NODES - 1) + xk) * step
        out[:-1] += 2.0 * step * wk * c * (1.0 - xk)
        out[1:] += 2.0 * step * wk * c * xk
    return out


class FilmShift:
    """
    What a film changes in the dielectric's albedo tables: Σ_j K_j ΔF_j on each side, with
    K_j as :class:`~mi_brdfs.scattering.multiscatter.AlbedoTable` s (the same interpolation
    as the tables they correct). ``alpha``: the uniform roughness, or None; ``alpha_range``:
    the roughness's (lo, hi) where known. ``eta``: the relative index (a number, or a Float
    whose derivative flows through the kernels' central difference in η).
    """

    def __init__(self, kind: str, eta, alpha=None, alpha_range=None):
        value = float(np.asarray(eta, np.float64).ravel()[0])
        if alpha is not None:
            a = float(np.asarray(alpha, np.float64).ravel()[0])
            alpha_range = (a, a)
        sides = kernels(kind, value, alpha_range)
        slopes = [None, None]
        if dr.is_diff_v(mi.Float) and dr.grad_enabled(eta):
            h = 1e-3 * value
            up, down = kernels(kind, value + h, alpha_range), kernels(kind, value - h, alpha_range)
            offset = eta - dr.detach(eta)
            slopes = [((u - d) / (2.0 * h), offset) for u, d in zip(up, down)]
        alpha_max = multiscatter.load_tables()["alpha_max"]
        average = multiscatter.average
        self.tables = []
        for K, slope in zip(sides, slopes):
            row = []
            for j in range(1, N_NODES):  # at c = 0, R = F = 1: no shift
                dk = None if slope is None else \
                    (slope[0][..., j], average(slope[0][..., j]), slope[1])
                row.append(multiscatter.AlbedoTable(K[..., j], average(K[..., j]), alpha_max,
                                                    alpha, dk))
            self.tables.append(row)
        self.hat_average = hat_averages()

    @staticmethod
    def deltas(reflectance, eta, constant: bool = False):
        """
        ΔF_j = R(c_j) − F(c_j) at the nodes (but the first), ``reflectance(c)`` the film's per
        channel from outside, F the bare interface's of relative index ``eta``. ``constant``:
        the film is the same everywhere (the values are then computed here once, in JIT
        variants as one array over the nodes: one evaluation of the film's code, not one per
        node, which keeps the kernel, and its derivative, small).
        """
        def at(c):
            return reflectance(c) - fresnel.dielectric(c, eta)[0]
        if not (constant and dr.is_jit_v(mi.Float)):
            return [at(mi.Float(c)) for c in NODES[1:]]
        values = at(mi.Float(NODES[1:]))
        dr.make_opaque(values)
        return [dr.gather(type(values), values, mi.UInt32(j)) for j in range(N_NODES - 1)]

    def __call__(self, deltas, mu, above, alpha):
        """(ΔE(μ), ΔE_avg) per channel of the side ``above`` (a mask), ``alpha`` as
        :meth:`~mi_brdfs.scattering.multiscatter.AlbedoTable.__call__` takes it."""
        (e0, a0), (e1, a1) = (self._sum(tables, deltas, lambda t: t(mu, alpha))
                              for tables in self.tables)
        return dr.select(above, e0, e1), dr.select(above, a0, a1)

    def averages(self, deltas, alpha):
        """(ΔE_avg from above, ΔE_avg from below) per channel."""
        return tuple(self._sum(tables, deltas, lambda t: (t.average(alpha),))[0]
                     for tables in self.tables)

    @staticmethod
    def _sum(tables, deltas, read):
        """Σ_j read(K_j) ΔF_j, each of the values ``read`` gives."""
        total = None
        for table, delta in zip(tables, deltas):
            terms = [k * delta for k in read(table)]
            total = terms if total is None else [a + b for a, b in zip(total, terms)]
        return total

    def transmittance_shift(self, deltas):
        """The change of the average transmittance from outside, −Σ_j (2∫h_j c dc) ΔF_j."""
        return -sum(float(w) * d for w, d in zip(self.hat_average[1:], deltas))

