"""Turning an audit :class:`~mi_brdfs.audit.grid.Case` into a ``mi.BSDF`` in the current variant."""

from __future__ import annotations

import numpy as np


def _normal_map(n: int = 16) -> np.ndarray:
    """Normals tilted by up to ~30° in a smooth pattern, encoded as n·0.5 + 0.5."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, 2 * np.pi, n))
    nx, ny = 0.5 * np.sin(u), 0.5 * np.cos(v)
    nz = np.ones_like(nx)
    norm = np.sqrt(nx ** 2 + ny ** 2 + nz ** 2)
    normals = np.stack([nx, ny, nz], -1) / norm[..., None]
    return (normals * 0.5 + 0.5).astype(np.float32)


def _height_map(n: int = 16) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, 2 * np.pi, n))
    return (0.5 + 0.25 * np.sin(u) * np.cos(v))[..., None].astype(np.float32)


_DATA = {"__normal_map__": _normal_map, "__height_map__": _height_map}


def materialise(spec):
    """The spec with the grid's placeholders (bitmap data) replaced by arrays."""
    if isinstance(spec, dict):
        return {k: materialise(v) for k, v in spec.items()}
    if isinstance(spec, list):
        return [materialise(v) for v in spec]
    if isinstance(spec, str) and spec in _DATA:
        import mitsuba as mi
        return mi.Bitmap(_DATA[spec]())
    return spec


def load(case):
    """The case's BSDF in the current variant."""
    import mitsuba as mi
    return mi.load_dict(materialise(case.dict()))
