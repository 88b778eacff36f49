"""
Where a direction pair falls in MERL's table (:mod:`.merl`), in drjit, for every variant: the
half and difference angles (Rusinkiewicz 1998) as MERL's reader defines them, and the bins and
weights of a lookup, trilinear between bin centres or MERL's nearest bin. Indices are flat,
``(i·90 + j)·180 + k`` for bin (θh i, θd j, φd k), the order of ``values[c].ravel()``.

The angles come from ``atan2`` of sines and cosines rather than ``acos``: near the specular
peak (θh → 0) ``acos`` of a float32 cosine resolves no angle under about 3·10⁻⁴ rad, coarser
than MERL's first θh bin (2·10⁻⁴ rad).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .merl import RES


def azimuth(x, y):
    """(cos φ, sin φ) of the azimuth of (x, y), (1, 0) where it is undefined."""
    r = dr.sqrt(x * x + y * y)
    ok = r > 0
    inv = dr.select(ok, dr.rcp(dr.select(ok, r, 1.0)), 0.0)
    return dr.select(ok, x * inv, 1.0), y * inv, r


def half_diff(wi, wo) -> tuple:
    """(θh, θd, φd) of a direction pair in the local frame, φd in (−π, π]: h = (ωi + ωo)/‖·‖,
    and the difference vector, ωi rotated by −φh about the normal and by −θh about the
    binormal."""
    h = dr.normalize(wi + wo)
    cos_p, sin_p, sin_h = azimuth(h.x, h.y)
    cos_h = h.z
    x = cos_p * wi.x + sin_p * wi.y
    y = cos_p * wi.y - sin_p * wi.x
    dx = cos_h * x - sin_h * wi.z
    dz = sin_h * x + cos_h * wi.z
    theta_h = dr.atan2(sin_h, cos_h)
    theta_d = dr.atan2(dr.sqrt(dx * dx + y * y), dz)
    return theta_h, theta_d, dr.atan2(y, dx)


def coordinates(wi, wo) -> tuple:
    """The continuous bin coordinates (x, y, z) of :func:`.merl.coordinates`: bin (i, j, k)'s
    centre at (i, j, k), z periodic with period 180 (φd folded into [0, π))."""
    theta_h, theta_d, phi_d = half_diff(wi, wo)
    x = dr.sqrt(dr.maximum(theta_h, 0.0) * (2.0 / dr.pi)) * RES[0] - 0.5
    y = theta_d * (2.0 / dr.pi) * RES[1] - 0.5
    z = dr.select(phi_d < 0.0, phi_d + dr.pi, phi_d) * (1.0 / dr.pi) * RES[2] - 0.5
    return x, y, z


def _flat(i, j, k):
    return mi.UInt32((i * RES[1] + j) * RES[2] + k)


def corners(wi, wo) -> list:
    """The eight (flat index, weight) pairs of trilinear interpolation between bin centres:
    clamped to the first and last bin in θh and θd, periodic in φd."""
    x, y, z = coordinates(wi, wo)
    x0, y0, z0 = dr.floor(x), dr.floor(y), dr.floor(z)
    fx, fy, fz = x - x0, y - y0, z - z0
    x0, y0, z0 = mi.Int32(x0), mi.Int32(y0), mi.Int32(z0)
    xs = [(dr.clip(x0 + d, 0, RES[0] - 1), w) for d, w in ((0, 1.0 - fx), (1, fx))]
    ys = [(dr.clip(y0 + d, 0, RES[1] - 1), w) for d, w in ((0, 1.0 - fy), (1, fy))]
    zs = []
    for d, w in ((0, 1.0 - fz), (1, fz)):
        k = z0 + d
        zs.append((dr.select(k < 0, k + RES[2], dr.select(k >= RES[2], k - RES[2], k)), w))
    return [(_flat(i, j, k), wx * wy * wz) for i, wx in xs for j, wy in ys for k, wz in zs]


def nearest(wi, wo):
    """The flat index of MERL's own lookup: the bin the angles fall in (the floor of the
    coordinates shifted by ½), clamped."""
    x, y, z = coordinates(wi, wo)
    i, j, k = (dr.clip(mi.Int32(dr.floor(c + 0.5)), 0, n - 1) for c, n in zip((x, y, z), RES))
    return _flat(i, j, k)
