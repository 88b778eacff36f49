"""
MERL's measured-BRDF format (Matusik, Pfister, Brand & McMillan 2003, "A Data-Driven
Reflectance Model", the 100 materials of https://www.merl.com/brdf/), in float64 NumPy, after
the conventions of MERL's own reader (``BRDFRead.cpp``, distributed with the data):

* the file: three int32 dimensions (90, 90, 180), then 90·90·180 float64 values per channel,
  red, green, blue, each stored divided by its scale (:data:`SCALES`: 1/1500, 1.15/1500,
  1.66/1500); a negative value is an unmeasured bin;
* the coordinates: Rusinkiewicz's (1998) half and difference angles. θh is the angle of the
  half vector h to the normal; the difference vector is ωi rotated by −φh about the normal and
  by −θh about the binormal (0, 1, 0), which takes h to the normal; θd and φd are its angles;
* the bins: θh indexed by the square root, ⌊90·√(θh/(π/2))⌋ (finer about the specular peak);
  θd linearly, ⌊90·θd/(π/2)⌋; φd folded into [0, π) by reciprocity (φd + π for φd < 0),
  ⌊180·φd/π⌋; each clamped into its range. The table is isotropic: φh plays no part.

The values here are the BRDF f itself (the scales applied), as an array ``(3, 90, 90, 180)``
indexed [channel, θh, θd, φd], with NaN for an unmeasured bin.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import MiBrdfsError
from ..imageio import atomic_path

#: Bins of θh, θd and φd.
RES = (90, 90, 180)
#: The factor of each channel's stored values (red, green, blue).
SCALES = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
#: Bytes of a MERL file: the three int32 dimensions and three channels of float64.
SIZE = 3 * 4 + 3 * 8 * int(np.prod(RES))


def half_diff(wi: np.ndarray, wo: np.ndarray) -> tuple:
    """(θh, φh, θd, φd) of direction pairs (rows of unit vectors in the local frame, both
    pointing away from the surface), as MERL's reader computes them."""
    wi, wo = np.asarray(wi, np.float64), np.asarray(wo, np.float64)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    theta_h = np.arccos(np.clip(h[..., 2], -1.0, 1.0))
    phi_h = np.arctan2(h[..., 1], h[..., 0])
    # ωi rotated by −φh about the normal, then by −θh about the binormal (0, 1, 0)
    c, s = np.cos(-phi_h), np.sin(-phi_h)
    x, y, z = c * wi[..., 0] - s * wi[..., 1], s * wi[..., 0] + c * wi[..., 1], wi[..., 2]
    c, s = np.cos(-theta_h), np.sin(-theta_h)
    d = np.stack([c * x + s * z, y, -s * x + c * z], axis=-1)
    theta_d = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
    phi_d = np.arctan2(d[..., 1], d[..., 0])
    return theta_h, phi_h, theta_d, phi_d


def directions(theta_h, phi_h, theta_d, phi_d) -> tuple[np.ndarray, np.ndarray]:
    """(ωi, ωo) of half and difference angles, the inverse of :func:`half_diff`: the
    difference vector rotated by θh about the binormal and φh about the normal is ωi, and ωo
    is ωi reflected about h."""
    theta_h, phi_h, theta_d, phi_d = np.broadcast_arrays(
        *(np.asarray(a, np.float64) for a in (theta_h, phi_h, theta_d, phi_d)))
    x = np.sin(theta_d) * np.cos(phi_d)
    y = np.sin(theta_d) * np.sin(phi_d)
    z = np.cos(theta_d)
    c, s = np.cos(theta_h), np.sin(theta_h)
    x, z = c * x + s * z, -s * x + c * z
    c, s = np.cos(phi_h), np.sin(phi_h)
    wi = np.stack([c * x - s * y, s * x + c * y, z], axis=-1)
    h = np.stack([np.sin(theta_h) * c, np.sin(theta_h) * s, np.cos(theta_h)], axis=-1)
    wo = 2.0 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    return wi, wo


def indices(theta_h, theta_d, phi_d) -> tuple:
    """MERL's bins (θh, θd, φd indices) of half and difference angles."""
    half_pi = np.pi / 2.0
    i = np.sqrt(np.maximum(np.asarray(theta_h, np.float64), 0.0) / half_pi) * RES[0]
    j = np.asarray(theta_d, np.float64) / half_pi * RES[1]
    phi_d = np.asarray(phi_d, np.float64)
    k = np.where(phi_d < 0.0, phi_d + np.pi, phi_d) / np.pi * RES[2]
    return tuple(np.clip(np.floor(v), 0, n - 1).astype(np.int64)
                 for v, n in zip((i, j, k), RES))


def bin_centres() -> tuple:
    """(θh, θd, φd) at the centre of every bin, each an array of shape :data:`RES`: the middle
    of the bin in its index coordinate (√θh for θh), where the tabulated value is taken."""
    u = (np.arange(RES[0]) + 0.5) / RES[0]
    theta_h = u * u * (np.pi / 2.0)
    theta_d = (np.arange(RES[1]) + 0.5) / RES[1] * (np.pi / 2.0)
    phi_d = (np.arange(RES[2]) + 0.5) / RES[2] * np.pi
    return tuple(np.meshgrid(theta_h, theta_d, phi_d, indexing="ij"))


def coordinates(theta_h, theta_d, phi_d) -> tuple:
    """Continuous bin coordinates (x, y, z) of half and difference angles, in which bin (i, j,
    k)'s centre sits at (i, j, k): x = 90·√(θh/(π/2)) − ½, y = 90·θd/(π/2) − ½, z = 180·φd/π − ½
    with φd folded into [0, π) (z is periodic with period 180: f(φd) = f(φd + π))."""
    half_pi = np.pi / 2.0
    x = np.sqrt(np.maximum(np.asarray(theta_h, np.float64), 0.0) / half_pi) * RES[0] - 0.5
    y = np.asarray(theta_d, np.float64) / half_pi * RES[1] - 0.5
    phi_d = np.asarray(phi_d, np.float64)
    z = np.where(phi_d < 0.0, phi_d + np.pi, phi_d) / np.pi * RES[2] - 0.5
    return x, y, z


def interpolate(values: np.ndarray, wi, wo) -> np.ndarray:
    """
    f at direction pairs by trilinear interpolation between bin centres in the coordinates of
    :func:`coordinates`: clamped to the first and last bin in θh and θd, periodic in φd (so
    f(ωi, ωo) = f(ωo, ωi): swapping the directions turns φd by π). Unmeasured bins (NaN) count
    as 0. (n, 3) float64.
    """
    theta_h, _, theta_d, phi_d = half_diff(wi, wo)
    values = np.nan_to_num(values, nan=0.0)
    out = 0.0
    x, y, z = coordinates(theta_h, theta_d, phi_d)
    x0, y0, z0 = np.floor(x), np.floor(y), np.floor(z)
    for di in (0, 1):
        i = np.clip(x0 + di, 0, RES[0] - 1).astype(np.int64)
        wx = np.where(di, x - x0, 1.0 - (x - x0))
        for dj in (0, 1):
            j = np.clip(y0 + dj, 0, RES[1] - 1).astype(np.int64)
            wy = np.where(dj, y - y0, 1.0 - (y - y0))
            for dk in (0, 1):
                k = np.mod(z0 + dk, RES[2]).astype(np.int64)
                wz = np.where(dk, z - z0, 1.0 - (z - z0))
                out = out + (wx * wy * wz)[:, None] * np.moveaxis(values[:, i, j, k], 0, -1)
    return out


def bin_directions() -> tuple[np.ndarray, np.ndarray]:
    """(ωi, ωo), each ``(90·90·180, 3)``: the pair at the centre of every MERL bin, with φh = 0
    (the format is isotropic), in the bins' order."""
    theta_h, theta_d, phi_d = (a.ravel() for a in bin_centres())
    return directions(theta_h, 0.0, theta_d, phi_d)


def lookup(values: np.ndarray, wi, wo) -> np.ndarray:
    """f at direction pairs by MERL's nearest-bin lookup: (n, 3), NaN where unmeasured."""
    theta_h, _, theta_d, phi_d = half_diff(wi, wo)
    i, j, k = indices(theta_h, theta_d, phi_d)
    return np.moveaxis(values[:, i, j, k], 0, -1)


def read(path) -> np.ndarray:
    """
    The BRDF of a MERL ``.binary`` file: f as ``(3, 90, 90, 180)`` float64, NaN where a bin is
    unmeasured (stored negative). A missing file, a short or truncated one and one whose
    dimensions are not MERL's are one :class:`MiBrdfsError` naming the file and what is wrong.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as e:
        raise MiBrdfsError(f"{path}: cannot read the MERL file ({e.strerror or e})") from None
    if len(data) < 12:
        raise MiBrdfsError(f"{path}: {len(data)} bytes, too short for a MERL file (three int32 "
                           f"dimensions, then the values)")
    dims = tuple(int(v) for v in np.frombuffer(data[:12], dtype="<i4"))
    if dims != RES:
        raise MiBrdfsError(f"{path}: dimensions {dims}, not MERL's {RES} (θh, θd, φd): not a "
                           f"MERL .binary file")
    if len(data) != SIZE:
        raise MiBrdfsError(f"{path}: {len(data)} bytes where a MERL file has {SIZE} (three "
                           f"channels of {int(np.prod(RES))} float64): truncated or padded")
    raw = np.frombuffer(data[12:], dtype="<f8").reshape((3,) + RES)
    values = raw * np.asarray(SCALES).reshape(3, 1, 1, 1)
    bad = np.count_nonzero(~(raw < 0.0) & ~(np.abs(values) <= np.finfo(np.float32).max))
    if bad:
        raise MiBrdfsError(f"{path}: {bad} values are NaN or beyond float32's range (a "
                           f"measured value is finite, an unmeasured one negative): not a "
                           f"MERL file")
    return np.where(raw < 0.0, np.nan, values)


def write(path, values: np.ndarray) -> None:
    """Write f (``(3, 90, 90, 180)``, NaN for unmeasured bins) as a MERL ``.binary`` file,
    atomically: the file is complete or absent."""
    values = np.asarray(values, dtype=np.float64)
    if values.shape != (3,) + RES:
        raise MiBrdfsError(f"MERL values must have the shape {(3,) + RES}, not {values.shape}")
    raw = values / np.asarray(SCALES).reshape(3, 1, 1, 1)
    raw = np.where(np.isnan(raw), -1.0, raw)
    with atomic_path(path, ".binary") as tmp:
        with open(tmp, "wb") as f:
            f.write(np.asarray(RES, dtype="<i4").tobytes())
            f.write(raw.astype("<f8").tobytes())
