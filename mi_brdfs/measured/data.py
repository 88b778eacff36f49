"""
A MERL file as the ``merl`` plugin uses it, read once per process and file (every instance and
every variant that names the file share it): the values per bin as RGB float32, unmeasured
bins as 0, and the density of its sampler (:mod:`.warp`), built from the interpolated values.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import MiBrdfsError
from . import merl, warp


class Unmeasured(NamedTuple):
    """How many bins are unmeasured in every channel, and how many in some channels only,
    with how many of those each channel misses."""

    every: int
    some: int
    red: int
    green: int
    blue: int


class Measured(NamedTuple):
    """One MERL file, ready for the plugin."""

    #: f per bin, (90·90·180, 3) float32 in flat bin order, unmeasured bins 0.
    rgb: np.ndarray
    #: The bins unmeasured although both directions at their centre lie above the surface
    #: (those below it are unmeasured in every file and never looked up alone).
    unmeasured: Unmeasured
    #: The sampler's density and its θi nodes (:func:`.warp.density`).
    density: np.ndarray
    thetas: list
    #: (path, modification time in ns, size): which version of which file this is.
    stamp: tuple


def load(path) -> Measured:
    """The file at ``path``, from the cache while the file is unchanged (same size and
    modification time)."""
    path = Path(path)
    try:
        stat = path.resolve().stat()
    except OSError as e:
        raise MiBrdfsError(f"{path}: cannot read the MERL file ({e.strerror or e})") from None
    return _load(str(path.resolve()), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=1)
def _above() -> np.ndarray:
    """The bins whose centre has both directions above the surface (1.46 million flags, built
    once: the directions of every bin take a few tenths of a second)."""
    wi, wo = merl.bin_directions()
    return ((wi[:, 2] > 0) & (wo[:, 2] > 0)).reshape(merl.RES)


@functools.lru_cache(maxsize=8)
def _load(path: str, mtime_ns: int, size: int) -> Measured:
    values = merl.read(path)
    missing = np.isnan(values) & _above()
    every = missing.all(axis=0)
    some = missing.any(axis=0) & ~every
    unmeasured = Unmeasured(int(every.sum()), int(some.sum()),
                            *(int((m & some).sum()) for m in missing))
    values = np.nan_to_num(values, nan=0.0)
    density, thetas, _ = warp.density(lambda wi, wo: merl.interpolate(values, wi, wo).mean(axis=-1))
    rgb = np.moveaxis(values, 0, -1).reshape(-1, 3).astype(np.float32)
    return Measured(rgb, unmeasured, density, thetas, (path, mtime_ns, size))
