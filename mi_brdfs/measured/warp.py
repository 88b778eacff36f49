"""
The importance sampler of a measured isotropic BRDF: ωo is drawn through its half vector h, in
the square (u, v) of MERL's own warping of θh (Matusik et al. 2003: θh = (π/2)·u², finest about
the specular peak) and of φh measured from the plane of incidence (φh = φi + π·(2v − 1)), from
a density on (u, v) tabulated for a set of incident angles θi: f·cosθo times the Jacobian of
(u, v) ↦ ωo, at the nodes of a regular grid. Mitsuba's ``MarginalContinuous2D1``, the sampler
of its ``measured`` plugin (Dupuy & Jakob 2018, "An Adaptive Parameterization for Efficient
Material Acquisition and Rendering", §5), interpolates that density bilinearly in (u, v) and
linearly in θi, samples it by inversion and returns its exact density, so that
pdf(ωo) = p(u, v | θi) / J with

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
    (data, θi nodes, albedo) for ``MarginalContinuous2D1``: at θi node t and (u, v) = (a/(N_U − 1),
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


class Sampler:
    """A density of :func:`density` sampled in the current variant (Mitsuba's
    ``MarginalContinuous2D1``): :meth:`pdf` at a direction, :meth:`sample` one with its
    density."""

    def __init__(self, data: np.ndarray, thetas: list, albedo: np.ndarray | None = None):
        self.table = mi.MarginalContinuous2D1(data, [thetas])
        self.thetas = thetas
        #: The largest albedo of the density's f at its nodes (0 without ``albedo``).
        self.albedo_max = 0.0 if albedo is None else float(np.max(albedo))
        if albedo is not None:
            self.albedo_nodes = albedo if not dr.is_jit_v(mi.Float) else mi.Float(albedo)

    def albedo(self, wi):
        """The albedo of :func:`density` at θi of ωi, linear between the nodes."""
        t = theta(wi)
        if not dr.is_jit_v(mi.Float):  # scalar variants: one lane, NumPy
            return float(np.interp(t, self.thetas, self.albedo_nodes))
        x = t * ((len(self.thetas) - 1) / (0.5 * dr.pi))
        i = dr.clip(mi.UInt32(dr.floor(x)), 0, len(self.thetas) - 2)
        w = dr.clip(x - mi.Float(i), 0.0, 1.0)
        a0 = dr.gather(mi.Float, self.albedo_nodes, i)
        return dr.lerp(a0, dr.gather(mi.Float, self.albedo_nodes, i + 1), w)

    def pdf(self, wi, wo, active):
        """The density of :meth:`sample` at ωo (solid angle)."""
        uv, jac = to_square(wi, wo)
        p = self.table.eval(uv, [theta(wi)], active)
        ok = active & (jac > 0)
        return dr.select(ok, p / dr.select(ok, jac, 1.0), 0.0)

    def sample(self, wi, sample2, active):
        """(ωo, its density, valid): one draw; the density comes with it, the same as
        :meth:`pdf` at ωo up to rounding."""
        uv, p = self.table.sample(sample2, [theta(wi)], active)
        wo, jac, valid = to_direction(wi, uv)
        ok = valid & (jac > 0)
        return wo, dr.select(ok, p / dr.select(ok, jac, 1.0), 0.0), ok
