"""
Where a direction pair falls in MERL's table (:mod:`.merl`), in drjit, for every variant: the
half and difference angles (Rusinkiewicz 1998) as MERL's reader defines them, and the bins and
weights of a lookup, trilinear between bin centres or MERL's nearest bin. Indices are rows of
the table as stored (:func:`position`): blocks of 2 × 2 × 2 bins, so that the eight corners of
a lookup fall in 1.5³ ≈ 3.4 blocks on average, where MERL's order (φd fastest) spreads them over
4.5 cache lines; a block of half-precision RGBA rows is one 64-byte line.

The angles come from ``atan2`` of sines and cosines rather than ``acos``: near the specular
peak (θh → 0) ``acos`` of a float32 cosine resolves no angle under about 3·10⁻⁴ rad, coarser
than MERL's first θh bin (2·10⁻⁴ rad).
"""

from __future__ import annotations

import functools

import drjit as dr
import mitsuba as mi
import numpy as np

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


#: Per axis (θh, θd, φd): the rows between neighbouring blocks, and between neighbouring
#: bins within a block (MERL's dimensions are even: every block is whole).
STRIDES = (((RES[1] // 2) * (RES[2] // 2) * 8, 4), ((RES[2] // 2) * 8, 2), (8, 1))


def offset(n, axis: int):
    """The part of :func:`position` that bin index ``n`` along ``axis`` contributes."""
    block, inner = STRIDES[axis]
    return (n >> 1) * block + (n & 1) * inner


def position(i, j, k):
    """The row of bin (θh i, θd j, φd k) in the table as stored: block ((i/2·45 + j/2)·90 +
    k/2) (integer halves), bin (i mod 2, j mod 2, k mod 2) in it, φd fastest; the sum of each
    axis's :func:`offset`. Integer NumPy arrays or drjit integers."""
    return offset(i, 0) + offset(j, 1) + offset(k, 2)


@functools.lru_cache(maxsize=1)
def stored_order() -> np.ndarray:
    """For each row of the table as stored, the bin in MERL's flat order ((i·90 + j)·180 + k,
    that of ``values[c].ravel()``) it holds."""
    i, j, k = np.meshgrid(*(np.arange(n) for n in RES), indexing="ij")
    order = np.empty(np.prod(RES), np.int64)
    order[position(i, j, k).ravel()] = np.arange(order.size)
    return order


def corners(wi, wo) -> list:
    """The eight (row, weight) pairs of trilinear interpolation between bin centres: clamped
    to the first and last bin in θh and θd, periodic in φd."""
    x, y, z = coordinates(wi, wo)
    x0, y0, z0 = dr.floor(x), dr.floor(y), dr.floor(z)
    fx, fy, fz = x - x0, y - y0, z - z0
    x0, y0, z0 = mi.Int32(x0), mi.Int32(y0), mi.Int32(z0)
    ks = [z0, z0 + 1]
    ks = [dr.select(k < 0, k + RES[2], dr.select(k >= RES[2], k - RES[2], k)) for k in ks]
    axes = [[dr.clip(x0, 0, RES[0] - 1), dr.clip(x0 + 1, 0, RES[0] - 1)],
            [dr.clip(y0, 0, RES[1] - 1), dr.clip(y0 + 1, 0, RES[1] - 1)], ks]
    # the rows' parts per axis (each computed once) and the weights
    parts = [[(offset(mi.UInt32(n), axis), w) for n, w in zip(axes[axis], (1.0 - f, f))]
             for axis, f in enumerate((fx, fy, fz))]
    return [(oi + oj + ok, wx * wy * wz) for oi, wx in parts[0] for oj, wy in parts[1]
            for ok, wz in parts[2]]


def nearest(wi, wo):
    """The row of MERL's own lookup: the bin the angles fall in (the floor of the coordinates
    shifted by ½), clamped."""
    x, y, z = coordinates(wi, wo)
    i, j, k = (dr.clip(mi.Int32(dr.floor(c + 0.5)), 0, n - 1) for c, n in zip((x, y, z), RES))
    return position(mi.UInt32(i), mi.UInt32(j), mi.UInt32(k))
