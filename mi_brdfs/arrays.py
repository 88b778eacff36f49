"""
NumPy arrays handed to drjit in drjit's own alignment. drjit 1.5's CPU backend uses the memory
of a contiguous NumPy array in place (NumPy aligns it to 16 bytes, drjit its own arrays to 64),
and the kernels it compiles for a gather from it depend on where that memory starts: data at an
arbitrary address compiles a kernel that the on-disk kernel cache has not seen (a new LLVM
compilation in every process, and for every table made anew, e.g. after a parameter set through
``mi.traverse``), and a large table 16 bytes past a cache line renders slower
(``validation/merl_layout.py`` times both).
"""

from __future__ import annotations

import numpy as np


def aligned(rows: np.ndarray, alignment: int = 64, offset: int = 0) -> np.ndarray:
    """``rows`` copied to memory that starts on a multiple of ``alignment`` bytes (``offset``
    bytes past one, for comparisons)."""
    raw = np.empty(rows.nbytes + alignment, np.uint8)
    start = (offset - raw.ctypes.data) % alignment
    out = raw[start:start + rows.nbytes].view(rows.dtype).reshape(rows.shape)
    out[...] = rows
    return out


def floats(a):
    """A NumPy array as ``mi.Float`` (the current variant's) from a 64-byte aligned copy."""
    import mitsuba as mi

    return mi.Float(aligned(np.asarray(a, dtype=np.float32).ravel()))
