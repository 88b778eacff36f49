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


def traced_kernels(fn: Callable) -> tuple[float, list]:
    """
    (tracing, kernels): the seconds ``fn`` takes to build its JIT arrays (Python tracing the
    computation: a fixed cost per launch), and DrJit's kernel-history records of the kernels
    that then evaluate its result (execution time in ms, IR, operation count). JIT variants
    only; ``fn`` returns its arrays unevaluated.
    """
    import drjit as dr
    flag = dr.JitFlag.KernelHistory
    was = dr.flag(flag)
    dr.set_flag(flag, True)
    try:
        sync()
        dr.kernel_history()  # drops what earlier calls recorded
        t0 = time.perf_counter()
        result = fn()
        tracing = time.perf_counter() - t0
        dr.eval(result)
        sync()
        kernels = dr.kernel_history()
    finally:
        dr.set_flag(flag, was)
    return tracing, kernels


def kernel_ir(record: dict) -> str:
    """The LLVM IR of a kernel-history record of :func:`traced_kernels` ('' when it has none;
    DrJit keeps it as a StringIO)."""
    ir = record.get("ir", "")
    return ir.getvalue() if hasattr(ir, "getvalue") else str(ir)


def kernel_timed(fn: Callable) -> tuple[float, float]:
    """(tracing, kernels) seconds of :func:`traced_kernels`: the kernels' execution time, the
    cost that grows with the number of lanes."""
    tracing, kernels = traced_kernels(fn)
    return tracing, sum(k.get("execution_time", 0.0) for k in kernels) * 1e-3


def interleaved(contenders: dict[str, Callable], repeats: int = 5, warmup: int = 1,
                timer: Callable | None = None) -> dict[str, list]:
    """
    Seconds per call of each contender, ``repeats`` times, in alternating order after
    ``warmup`` untimed rounds (which hold JIT tracing and compilation). ``timer`` (default:
    wall seconds of :func:`timed`) measures one call; :func:`kernel_timed` splits it.
    """
    timer = timer or (lambda fn: timed(fn)[0])
    names = list(contenders)
    for _ in range(warmup):
        for name in names:
            timer(contenders[name])
    times: dict[str, list] = {name: [] for name in names}
    for r in range(repeats):
        for name in (names if r % 2 == 0 else names[::-1]):
            times[name].append(timer(contenders[name]))
    return times


def median(values) -> float:
    return float(statistics.median(values))


def median_ratio(times: dict[str, list[float]], a: str, b: str) -> float:
    """Median of the per-repeat ratios a/b (robust to slow phases hitting both)."""
    return median([x / y for x, y in zip(times[a], times[b])])
