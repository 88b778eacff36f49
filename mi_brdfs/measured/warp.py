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

The density is built in float64 NumPy (:func:`density`); :func:`to_direction` and
:func:`to_square` are the map and its inverse in drjit for every variant.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .lookup import azimuth

#: Nodes of the density: incident angles θi in [0, π/2], and the (u, v) grid.
N_THETA, N_U, N_V = 24, 128, 64


def forward(theta_i, u, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ωi, ωo, J) in float64 for ωi at θi in the xz-plane (φi = 0) and (u, v) in the square:
    the map :func:`to_direction` computes in drjit, and its Jacobian (0 where ωo is not valid:
    ωi·h ≤ 0 or ωo below the surface)."""
    theta_i, u, v = np.broadcast_arrays(*(np.asarray(a, np.float64) for a in (theta_i, u, v)))
    wi = np.stack([np.sin(theta_i), np.zeros_like(theta_i), np.cos(theta_i)], axis=-1)
    theta_h, phi_h = np.pi / 2 * u * u, np.pi * (2.0 * v - 1.0)
    h = np.stack([np.sin(theta_h) * np.cos(phi_h), np.sin(theta_h) * np.sin(phi_h),
                  np.cos(theta_h)], axis=-1)
    cos_d = np.sum(wi * h, axis=-1)
    wo = 2.0 * cos_d[..., None] * h - wi
    jac = 8.0 * np.pi ** 2 * cos_d * np.sin(theta_h) * u
    return wi, wo, np.where((cos_d > 0) & (wo[..., 2] > 0), jac, 0.0)


def density(f_mean) -> tuple[np.ndarray, list[float]]:
    """
    (data, θi nodes) for ``MarginalContinuous2D1``: data[t, b, a] = f·cosθo·J at θi node t and
    (u, v) = (a/(N_U − 1), b/(N_V − 1)), float32, where ``f_mean(wi, wo)`` is f (the mean over
    channels) at (n, 3) direction pairs. The last node sits just under the horizon's θi = π/2,
    where f·cosθo would be 0 everywhere; a node where f is 0 everywhere is uniform instead,
    so that every θi has a density.
    """
    thetas = np.linspace(0.0, np.pi / 2, N_THETA)
    t, v, u = np.meshgrid(np.minimum(thetas, np.pi / 2 - 1e-3), np.linspace(0, 1, N_V),
                          np.linspace(0, 1, N_U), indexing="ij")
    wi, wo, jac = forward(t, u, v)
    valid = jac > 0
    value = np.zeros(t.shape)
    value[valid] = np.maximum(f_mean(wi[valid], wo[valid]), 0.0) * wo[valid][:, 2] * jac[valid]
    empty = value.reshape(N_THETA, -1).sum(axis=1) <= 0
    value[empty] = 1.0
    return value.astype(np.float32), [float(x) for x in thetas]


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
