"""
The importance sampler of a measured isotropic BRDF: ωo is drawn through its half vector h, in
the square (u, v) of MERL's own warping of θh (Matusik et al. 2003: θh = (π/2)·u², finest about
the specular peak) and of φh measured from the plane of incidence (φh = φi + π·(2v − 1)), from
a density on (u, v) tabulated for a set of incident angles θi: f·cosθo times the Jacobian of
(u, v) ↦ ωo, at the nodes of a regular grid. :class:`Sampler` interpolates that density
bilinearly in (u, v) and linearly in θi, samples it exactly in constant time and returns its
density, so that pdf(ωo) = p(u, v | θi) / J with

    J = |∂ωo/∂(u, v)| = 4 (ωi·h) · sinθh · (π u) · 2π,

the reflection's Jacobian 4(ωi·h) (Walter et al. 2007, eq. 14), the sphere's sinθh and the
warping's dθh/du = πu and dφh/dv = 2π.

The density is a defensive mixture (Hesterberg 1995, "Weighted Average Importance Sampling and
Defensive Mixture Distributions"): :data:`DEFENSIVE_SHARE` of it is the cosine-weighted
hemisphere's density carried into the square, cosθo·J at the valid nodes and a little of
|cosθo·J| at the others (so that every cell touching the valid region has positive corners):
the pdf is positive wherever f is,
whatever the grid missed, and the weight f·cosθo/pdf stays bounded. Mixed inside the table,
the sampler's own density is the whole pdf: one draw, and no second density to evaluate at the
sample.

The density is built in float64 NumPy (:func:`density`); :func:`to_direction` and
:func:`to_square` are the map and its inverse in drjit for every variant, and :class:`Sampler`
samples a density and evaluates it in any variant: the sampler of measured data (``merl``)
and of models whose lobe has no sampler of its own (``he``'s directional diffuse term).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..arrays import floats
from .lookup import azimuth

#: Nodes of the density: incident angles θi in [0, π/2], and the (u, v) grid.
N_THETA, N_U, N_V = 16, 64, 32
#: The share of the density that is the cosine's (the defensive part).
DEFENSIVE_SHARE = 0.1
#: The cosine part's weight at nodes outside the valid region, relative to |cosθo·J| there:
#: enough to make every cell touching the valid region positive, little enough that few
#: samples land outside it (each is a failed sample, weight 0).
OUTSIDE = 1e-3


def forward(theta_i, u, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ωi, ωo, J) in float64 for ωi at θi in the xz-plane (φi = 0) and (u, v) in the square:
    the map :func:`to_direction` computes in drjit, and its Jacobian (0 where ωo is not valid:
    ωi·h ≤ 0 or ωo below the surface)."""
    wi, wo, jac = _forward(theta_i, u, v)
    return wi, wo, np.where((jac > 0) & (wo[..., 2] > 0), jac, 0.0)


def _forward(theta_i, u, v):
    """(ωi, ωo, J) of :func:`forward`, J not masked (negative where ωi·h < 0)."""
    theta_i, u, v = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (theta_i, u, v)))
    wi = np.stack([np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=-1)
    theta_h, phi_h = np.pi / 2 * u * u, np.pi * (2.0 * v - 1.0)
    h = np.stack([np.sin(theta_h) * np.cos(phi_h), np.sin(theta_h) * np.sin(phi_h),
                  np.cos(theta_h)], axis=-1)
    cos_d = np.sum(wi * h, axis=-1)
    wo = 2.0 * cos_d[..., None] * h - wi
    return wi, wo, 8.0 * np.pi ** 2 * cos_d * np.sin(theta_h) * u


def _trapezoid(n: int) -> np.ndarray:
    """The trapezoidal rule's weights of ``n`` nodes spanning [0, 1]."""
    w = np.full(n, 1.0 / (n - 1))
    w[[0, -1]] *= 0.5
    return w


def _mean_one(value):
    """``value`` (θi, v, u) divided by its mean over each θi node's grid (NaN where that is
    0)."""
    mean = value.mean(axis=(1, 2), keepdims=True)
    return np.where(mean > 0, value / np.where(mean > 0, mean, 1.0), np.nan)


def density(f_mean) -> tuple[np.ndarray, list[float], np.ndarray]:
    """
    (data, θi nodes, albedo) for :class:`Sampler`: at θi node t and (u, v) = (a/(N_U − 1),
    b/(N_V − 1)), data[t, b, a] is f·cosθo·J and, its :data:`DEFENSIVE_SHARE`, cosθo·J
    (:data:`OUTSIDE` times |cosθo·J| at invalid nodes), each normalised to mean 1 over the
    nodes; float32. ``f_mean(wi, wo)`` is f (the mean over
    channels) at (n, 3) direction pairs. The last node sits just under the horizon's θi = π/2,
    where f·cosθo would be 0 everywhere; a node where f is 0 everywhere is the cosine's alone.
    albedo[t] = ∫ f cosθo dωo at node t, ∫∫ f·cosθo·J du dv by the trapezoidal rule over the
    nodes: the weight of a lobe sampled so, against the other lobes of a mixture.
    """
    thetas = np.linspace(0.0, np.pi / 2, N_THETA)
    t, v, u = np.meshgrid(np.minimum(thetas, np.pi / 2 - 1e-3), np.linspace(0, 1, N_V),
                          np.linspace(0, 1, N_U), indexing="ij")
    wi, wo, jac = forward(t, u, v)
    valid = jac > 0
    value = np.zeros(t.shape)
    value[valid] = np.maximum(f_mean(wi[valid], wo[valid]), 0.0) * wo[valid][:, 2] * jac[valid]
    _, wo_any, jac_any = _forward(t, u, v)
    cosine = np.abs(wo_any[..., 2] * jac_any)
    cosine = _mean_one(np.where(valid, cosine, OUTSIDE * cosine))
    albedo = np.einsum("tba,b,a->t", value, _trapezoid(N_V), _trapezoid(N_U))
    value = _mean_one(value)
    mixed = (1.0 - DEFENSIVE_SHARE) * value + DEFENSIVE_SHARE * cosine
    return np.where(np.isnan(value), cosine, mixed).astype(np.float32), \
        [float(x) for x in thetas], albedo


def theta(w):
    """The polar angle of w, from atan2 (accurate near the normal, unlike acos)."""
    return dr.atan2(dr.sqrt(w.x * w.x + w.y * w.y), w.z)


def _jacobian(u, sin_h, cos_d):
    return 8.0 * dr.pi * dr.pi * cos_d * sin_h * u


def to_direction(wi, uv) -> tuple:
    """(ωo, J, valid) of a point (u, v) of the square for the incident direction ωi."""
    cos_i, sin_i, _ = azimuth(wi.x, wi.y)
    theta_h = (0.5 * dr.pi) * uv.x * uv.x
    sin_h, cos_h = dr.sincos(theta_h)
    sin_p, cos_p = dr.sincos(dr.pi * (2.0 * uv.y - 1.0))
    hx, hy = sin_h * cos_p, sin_h * sin_p
    h = mi.Vector3f(cos_i * hx - sin_i * hy, sin_i * hx + cos_i * hy, cos_h)
    cos_d = dr.dot(wi, h)
    wo = 2.0 * cos_d * h - wi
    valid = (cos_d > 0) & (wo.z > 0)
    return wo, _jacobian(uv.x, sin_h, cos_d), valid


def to_square(wi, wo) -> tuple:
    """((u, v), J) of the direction ωo for ωi: the inverse of :func:`to_direction` (J = 0
    where ωi·h ≤ 0)."""
    h = dr.normalize(wi + wo)
    cos_i, sin_i, _ = azimuth(wi.x, wi.y)
    hx = cos_i * h.x + sin_i * h.y
    hy = cos_i * h.y - sin_i * h.x
    sin_h = dr.sqrt(hx * hx + hy * hy)
    theta_h = dr.atan2(sin_h, h.z)
    u = dr.sqrt(dr.maximum(theta_h, 0.0) * (2.0 / dr.pi))
    v = (dr.atan2(hy, hx) * dr.inv_pi + 1.0) * 0.5
    cos_d = dr.dot(wi, h)
    return mi.Point2f(dr.minimum(u, 1.0), dr.clip(v, 0.0, 1.0)), \
        dr.maximum(_jacobian(u, sin_h, cos_d), 0.0)


def alias_table(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(prob, alias) of Walker's alias method for the discrete distribution ``p`` (n ≥ 1
    probabilities, summing to 1), built by Vose's (1991, "A Linear Algorithm for Generating
    Random Numbers with a Given Distribution") algorithm: draw c uniformly from the n entries,
    keep it with probability prob[c], else take alias[c]."""
    n = len(p)
    scaled = np.asarray(p, np.float64) * n
    prob, alias = np.ones(n), np.arange(n)
    small = [i for i in range(n) if scaled[i] < 1.0]
    large = [i for i in range(n) if scaled[i] >= 1.0]
    while small and large:
        s, g = small.pop(), large.pop()
        prob[s], alias[s] = scaled[s], g
        scaled[g] -= 1.0 - scaled[s]
        (small if scaled[g] < 1.0 else large).append(g)
    return prob, alias  # what is left (rounding) keeps itself: prob 1


def gather_row(kind, buffer, index):
    """Row ``index`` of a table of rows of ``kind`` (NumPy rows with Python indices in scalar
    variants)."""
    if isinstance(buffer, np.ndarray):
        return kind(*(float(x) for x in buffer[int(index)]))
    return dr.gather(kind, buffer, index)


def _bilerp(c, x):
    """The bilinear interpolant of corners c = (v00, v10, v01, v11) at x in the unit square."""
    return dr.lerp(dr.lerp(c[0], c[1], x.x), dr.lerp(c[2], c[3], x.x), x.y)


class Sampler:
    """
    A density of :func:`density` in the current variant: p(u, v | θi) bilinear between the
    nodes of each θi node's grid (normalised to 1 over the square), linear in θi; sampled and
    evaluated at a direction in constant time.

    A draw picks the θi node below or above ωi's with the probability of its interpolation
    weight (``sample1``), a cell of that node's grid with Walker's alias method (Walker 1977,
    "An Efficient Method for Generating Discrete Random Variables with General
    Distributions") and the point within the cell by Mitsuba's ``square_to_bilinear``; so it
    draws exactly the mixture the density describes, and costs a few gathers, where inverting
    the marginal and conditional distributions costs a binary search in each.
    """

    def __init__(self, data: np.ndarray, thetas: list, albedo: np.ndarray | None = None):
        self.thetas = thetas
        corners = np.stack([data[:, :-1, :-1], data[:, :-1, 1:], data[:, 1:, :-1],
                            data[:, 1:, 1:]], axis=-1).astype(np.float64)
        mass = corners.mean(axis=-1).reshape(len(thetas), -1)  # per cell, × its area
        self.cells = mass.shape[1]
        total = mass.sum(axis=1)
        # p(u, v | θi) integrates to 1 over the square: the cells' area is 1/cells
        corners = corners.reshape(len(thetas), self.cells, 4) * (self.cells / total)[:, None,
                                                                                       None]
        aliases = [alias_table(m / t) for m, t in zip(mass, total)]
        pairs = np.stack([np.concatenate([a[0] for a in aliases]),
                          np.concatenate([a[1] for a in aliases])], axis=1)
        corners = corners.reshape(-1, 4).astype(np.float32)
        pairs = pairs.astype(np.float32)  # alias indices < 2**24: exact
        if dr.is_jit_v(mi.Float):  # scalar variants keep NumPy rows (:func:`gather_row`)
            corners, pairs = floats(corners), floats(pairs)
        self.corners, self.pairs = corners, pairs
        #: The largest albedo of the density's f at its nodes (0 without ``albedo``).
        self.albedo_max = 0.0 if albedo is None else float(np.max(albedo))
        if albedo is not None:
            self.albedo_nodes = albedo if not dr.is_jit_v(mi.Float) else floats(albedo)

    def _nodes(self, wi):
        """(i, w): ωi's θi lies between nodes i and i + 1, w the weight of i + 1."""
        x = theta(wi) * ((len(self.thetas) - 1) / (0.5 * dr.pi))
        i = dr.clip(mi.UInt32(dr.floor(x)), 0, len(self.thetas) - 2)
        return i, dr.clip(x - mi.Float(i), 0.0, 1.0)

    def albedo(self, wi):
        """The albedo of :func:`density` at θi of ωi, linear between the nodes."""
        if not dr.is_jit_v(mi.Float):  # scalar variants: one lane, NumPy
            return float(np.interp(theta(wi), self.thetas, self.albedo_nodes))
        i, w = self._nodes(wi)
        a0 = dr.gather(mi.Float, self.albedo_nodes, i)
        return dr.lerp(a0, dr.gather(mi.Float, self.albedo_nodes, i + 1), w)

    def _density(self, i, w, cell, x, active):
        """p(u, v | θi) at the point x of ``cell`` (its index in a node's grid)."""
        below = _bilerp(gather_row(mi.Vector4f, self.corners, i * self.cells + cell), x)
        above = _bilerp(gather_row(mi.Vector4f, self.corners, (i + 1) * self.cells + cell), x)
        return dr.select(active, dr.lerp(below, above, w), 0.0)

    def density(self, wi, uv, active=True):
        """p(u, v | θi of ωi) (per unit area of the square)."""
        i, w = self._nodes(wi)
        n_u, n_v = N_U - 1, N_V - 1
        a = dr.clip(mi.UInt32(dr.floor(uv.x * n_u)), 0, n_u - 1)
        b = dr.clip(mi.UInt32(dr.floor(uv.y * n_v)), 0, n_v - 1)
        x = mi.Point2f(uv.x * n_u - mi.Float(a), uv.y * n_v - mi.Float(b))
        return self._density(i, w, b * n_u + a, x, active)

    def pdf(self, wi, wo, active):
        """The density of :meth:`sample` at ωo (solid angle)."""
        uv, jac = to_square(wi, wo)
        ok = active & (jac > 0)
        p = self.density(wi, uv, ok)
        return dr.select(ok, p / dr.select(ok, jac, 1.0), 0.0)

    def sample(self, wi, sample1, sample2, active):
        """(ωo, its density, valid): one draw; the density comes with it, the same as
        :meth:`pdf` at ωo up to rounding."""
        i, w = self._nodes(wi)
        node = dr.select(sample1 < w, i + 1, i)
        x = sample2.x * self.cells
        c = dr.minimum(mi.UInt32(x), self.cells - 1)
        r = x - mi.Float(c)
        pair = gather_row(mi.Vector2f, self.pairs, node * self.cells + c)
        keep = r < pair.x
        cell = dr.select(keep, c, mi.UInt32(pair.y))
        r = dr.select(keep, r / dr.select(keep, pair.x, 1.0),
                      (r - pair.x) / dr.maximum(1.0 - pair.x, 1e-30))
        corners = gather_row(mi.Vector4f, self.corners, node * self.cells + cell)
        x, _ = mi.warp.square_to_bilinear(corners.x, corners.y, corners.z, corners.w,
                                          mi.Point2f(dr.clip(r, 0.0, 1.0), sample2.y))
        n_u = N_U - 1
        a, b = cell % n_u, cell // n_u
        uv = mi.Point2f((mi.Float(a) + x.x) / n_u, (mi.Float(b) + x.y) / (N_V - 1))
        wo, jac, valid = to_direction(wi, uv)
        ok = active & valid & (jac > 0)
        p = self._density(i, w, cell, x, ok)
        return wo, dr.select(ok, p / dr.select(ok, jac, 1.0), 0.0), ok
