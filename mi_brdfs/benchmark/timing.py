"""
Timing that holds up on a shared, noisy machine: every contender is timed in the same process,
interleaved (A B B A A B ...), after untimed warm-up runs, and compared by medians.
"""

from __future__ import annotations

import statistics
import time
from typing import Callable


def sync() -> None:
    """Wait for queued JIT work (no-op in scalar variants)."""
    import drjit as dr
    import mitsuba as mi
    if dr.is_jit_v(mi.Float):
        dr.sync_thread()


def timed(fn: Callable) -> tuple[float, object]:
    """(seconds, result) of one call, JIT work included."""
    sync()
    t0 = time.perf_counter()
    result = fn()
    sync()
    return time.perf_counter() - t0, result


def interleaved(contenders: dict[str, Callable], repeats: int = 5,
                warmup: int = 1) -> dict[str, list[float]]:
    """
    Seconds per call of each contender, ``repeats`` times, in alternating order after
    ``warmup`` untimed rounds (which hold JIT tracing and compilation).
    """
    names = list(contenders)
    for _ in range(warmup):
        for name in names:
            timed(contenders[name])
    times: dict[str, list[float]] = {name: [] for name in names}
    for r in range(repeats):
        for name in (names if r % 2 == 0 else names[::-1]):
            times[name].append(timed(contenders[name])[0])
    return times


def median(values) -> float:
    return float(statistics.median(values))


def median_ratio(times: dict[str, list[float]], a: str, b: str) -> float:
    """Median of the per-repeat ratios a/b (robust to slow phases hitting both)."""
    return median([x / y for x, y in zip(times[a], times[b])])
