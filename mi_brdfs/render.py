"""
Progressive rendering: the samples per pixel in passes of independent seeds, accumulated.

Passes make a render interruptible (Ctrl-C keeps what is done), bounded in time
(``time_budget``) and, in scalar variants, parallel across processes. Why processes: in scalar
variants Mitsuba calls a Python BSDF once per ray from its C++ render threads, and those calls
serialise on the GIL; render threads fighting for it are slower than one thread alone, which is
itself far slower than a built-in BSDF. So a scalar scene that holds a Python plugin renders on
one thread per process, with the passes spread over one process per core: this one and helper
processes (:mod:`mi_brdfs.render_pool`), which it keeps rendering beside while they start. The
helpers stay for the next render in the same variant (they keep the last scene they loaded),
so a session that renders repeatedly pays their start once; :func:`close_helpers` ends them
(exit does too). With adaptive passes, the last passes shrink so that the processes finish
together. JIT variants trace the plugin once into a kernel and need none of this.
"""

from __future__ import annotations

import datetime
import math
import os
import platform
import signal
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from . import render_pool
from .errors import MiBrdfsError, counts
from .progress import Progress
from .render_pool import close_helpers, pass_seed  # noqa: F401 (public here too)

#: Lanes (pixels × spp) per JIT pass: bounds the memory of one pass, which grows with its lanes.
JIT_LANES_PER_PASS = 1 << 22

#: Seconds a scalar pass should take: short enough for Ctrl-C, the time budget and the
#: process pool to react, long enough that per-pass overhead does not matter.
SCALAR_PASS_S = 0.5


@dataclass
class RenderResult:
    """A finished (or interrupted) progressive render and how it was made."""

    image: np.ndarray
    spp: int
    passes: int
    seed: int
    variant: str
    wall_time: float
    arrangement: str
    scene: str = ""
    defines: dict = field(default_factory=dict)
    interrupted: bool = False
    channels: list | None = None

    def metadata(self) -> dict:
        """The header attributes written into the EXR."""
        import drjit as dr
        import mitsuba as mi

        from ._version import __version__
        return {
            "software": f"mi_brdfs {__version__} "
                        f"(Mitsuba {mi.__version__}, drjit {dr.__version__})",
            "mi_brdfs.version": __version__,
            "mitsuba.version": mi.__version__,
            "drjit.version": dr.__version__,
            "render.variant": self.variant,
            "render.spp": self.spp,
            "render.passes": self.passes,
            "render.seed": self.seed,
            "render.wall_time_s": f"{self.wall_time:.3f}",
            "render.arrangement": self.arrangement,
            "render.interrupted": str(self.interrupted).lower(),
            "render.scene": self.scene,
            "render.defines": " ".join(f"{k}={v}" for k, v in self.defines.items()),
            "render.date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
            "render.host": f"{platform.node()} ({platform.machine()}, {os.cpu_count()} cores)",
        }


def uses_python_plugins(scene) -> bool:
    """
    Whether an object the render uses is a plugin written in Python (ours or a user's): the
    integrator, sensors, emitters, shapes and their BSDFs, with everything nested in them. A
    BSDF the scene declares but no shape references does not count.
    """
    import mitsuba as mi

    def python(obj) -> bool:
        return obj is not None and not type(obj).__module__.startswith("mitsuba")

    roots = [scene.integrator(), *scene.sensors(), *scene.emitters()]
    for shape in scene.shapes():
        roots += [shape, shape.bsdf()]
    for root in roots:
        if root is None:
            continue
        if python(root) or any(python(obj) for obj in mi.traverse(root).hierarchy):
            return True
    return False


class _Accumulator:
    """Running spp-weighted mean of pass images, in float64."""

    def __init__(self):
        self.sum, self.spp, self.passes = None, 0, 0

    def add(self, image: np.ndarray, spp: int) -> None:
        image = np.asarray(image, dtype=np.float64) * spp
        self.sum = image if self.sum is None else self.sum + image
        self.spp += spp
        self.passes += 1

    def mean(self) -> np.ndarray | None:
        return None if self.sum is None else (self.sum / self.spp).astype(np.float32)


class _Schedule:
    """Which passes to run: their spp, and when to stop (spp reached or time budget spent)."""

    def __init__(self, spp: int | None, pass_spp: int, time_budget: float | None, stop=None):
        self.spp, self.pass_spp, self.budget, self.stop = spp, pass_spp, time_budget, stop
        #: Processes sharing the passes, when the last passes should shrink so that they
        #: finish together (guided self-scheduling: each pass at most 1/(2·workers) of what
        #: remains); 0 keeps every pass at pass_spp (an explicit pass_spp: reproducible images).
        self.guided_workers = 0
        self.start = time.perf_counter()
        self.issued = 0        # spp handed out so far
        self.index = 0         # passes handed out so far
        self.pass_times: list[float] = []
        self._lock = threading.Lock()  # passes are handed out to this process and to helpers

    def next(self) -> tuple[int, int] | None:
        """(pass index, pass spp) of the next pass, or None when the render is complete."""
        with self._lock:
            return self._next()

    def _next(self) -> tuple[int, int] | None:
        if self.spp is not None and self.issued >= self.spp:
            return None
        if self.stop is not None and self.stop.requested:
            return None
        if self.budget is not None and self.index > 0:
            elapsed = time.perf_counter() - self.start
            typical = float(np.median(self.pass_times)) if self.pass_times else 0.0
            if elapsed + typical > self.budget:
                return None
        k = self.pass_spp if self.spp is None else min(self.pass_spp, self.spp - self.issued)
        if self.spp is not None and self.guided_workers > 1:
            k = min(k, max(1, math.ceil((self.spp - self.issued) / (2 * self.guided_workers))))
        item = (self.index, k)
        self.issued += k
        self.index += 1
        return item


def _default_pass_spp(spp: int | None, pixels: int) -> int:
    """JIT passes: about 1/16 of the render, at most :data:`JIT_LANES_PER_PASS` lanes."""
    cap = max(1, JIT_LANES_PER_PASS // max(pixels, 1))
    target = 16 if spp is None else max(1, math.ceil(spp / 16))
    return max(1, min(cap, target))


def _timed_pass_spp(seconds_per_spp: float, spp: int | None) -> int:
    """Scalar passes: sized from the first (1 spp) pass to last about :data:`SCALAR_PASS_S`."""
    k = max(1, int(SCALAR_PASS_S / max(seconds_per_spp, 1e-6)))
    return k if spp is None else min(k, max(1, math.ceil(spp / 8)))


class _Passes:
    """
    The passes of one render: run in this process or handed to the helpers, and recorded (the
    helpers' ones from the pool's result thread) into the accumulated image and the progress bar.
    """

    def __init__(self, scene, path, defines: dict, variant: str, seed: int, adaptive: bool,
                 schedule: _Schedule, bar):
        self.scene, self.path, self.defines, self.variant = scene, path, defines, variant
        self.seed, self.adaptive, self.schedule, self.bar = seed, adaptive, schedule, bar
        self.acc = _Accumulator()
        self.lock = threading.Lock()  # helpers' passes are recorded from the pool's result thread

    def record(self, image, k: int, seconds: float) -> None:
        with self.lock:
            self.schedule.pass_times.append(seconds)
            if image is not None:
                self.acc.add(image, k)
            if self.bar:
                self.bar.update(self.acc.spp)

    def run(self, index: int, k: int) -> None:
        t0 = time.perf_counter()
        image = render_pool._render_pass(self.scene, pass_seed(self.seed, index), k)
        self.record(image, k, time.perf_counter() - t0)

    def first(self) -> float:
        """The first pass in this process, which times the scene (seconds per spp) for the
        adaptive pass size."""
        if (item := self.schedule.next()) is None:  # (helpers took every pass)
            return 0.0
        t0 = time.perf_counter()
        self.run(*item)
        seconds_per_spp = (time.perf_counter() - t0) / item[1]
        if self.adaptive:
            self.schedule.pass_spp = _timed_pass_spp(seconds_per_spp, self.schedule.spp)
        return seconds_per_spp

    def spread_over(self, workers: int, first=None) -> str:
        """The remaining passes on this process and ``workers`` − 1 helpers; the arrangement."""
        if self.adaptive:
            self.schedule.guided_workers = workers
        render_pool._render_with_helpers(workers - 1, self.variant, self.path, self.defines,
                                         self.seed, self.schedule, self.run, self.record, first)
        return f"{workers} processes × 1 thread"


def _spread(passes: _Passes, spread: bool, workers: int) -> str | None:
    """
    The first passes of a render, spread over ``workers`` processes where that pays (``spread``:
    a scalar scene with Python plugins, outside a helper): the arrangement, or None when this
    process renders alone. Helpers kept from a render of this scene start on the first pass at
    once; else this process times a first pass, which decides.
    """
    schedule = passes.schedule
    warm = spread and render_pool._helpers_ready(workers - 1, passes.variant)
    if warm and render_pool._helpers_scene == render_pool._scene_key(passes.path, passes.defines):
        # helpers kept from a render of this scene: they start on the first pass at once
        return passes.spread_over(workers, passes.first)
    seconds_per_spp = passes.first()
    if not schedule.pass_times:  # interrupted during the first pass: nothing was timed
        return None
    remaining_s = math.inf
    if schedule.spp is not None:
        remaining_s = seconds_per_spp * (schedule.spp - schedule.issued)
    if schedule.budget is not None:
        remaining_s = min(remaining_s, schedule.budget - schedule.pass_times[0])
    # worth it when starting the helpers and splitting the rest beats going on alone;
    # never from a helper process itself (``spread``): a script without an ``if
    # __name__ == "__main__"`` guard runs again in each spawned helper, which would
    # spawn its own helpers without end
    start_s = render_pool.WORKER_LOAD_S if warm else render_pool.WORKER_START_S
    if spread and start_s + remaining_s / workers < 0.9 * remaining_s:
        return passes.spread_over(workers)
    return None


@counts("spp", "pass_spp", "processes")
def render(scene_path: str | os.PathLike, spp: int | None = None, seed: int = 0,
           time_budget: float | None = None, defines: dict | None = None,
           pass_spp: int | None = None, processes: int | None = None,
           progress: bool = True) -> RenderResult:
    """
    Render a scene file progressively in the current variant.

    Parameter ``spp`` (int | None): samples per pixel; default the scene's sampler count, or
    unlimited when a ``time_budget`` is given.

    Parameter ``seed`` (int): base seed; pass ``i`` uses :func:`pass_seed` (seed, i).

    Parameter ``time_budget`` (float | None): seconds; no pass starts that would end after it.

    Parameter ``pass_spp`` (int | None): spp per pass; default about 1/16 of the total (JIT,
    bounded by :data:`JIT_LANES_PER_PASS`), or in scalar variants a first pass of 1 spp that
    times the scene, then passes of about :data:`SCALAR_PASS_S` seconds.

    Parameter ``processes`` (int | None): render processes for scalar scenes with Python plugins,
    this one included (it renders passes beside ``processes`` − 1 helpers); default: one per
    core when the render is long enough to repay the helpers' start, else this one alone.

    The first Ctrl-C stops the render after the passes under way and returns what was
    accumulated (``interrupted=True``); a second one raises KeyboardInterrupt at once.
    """
    import drjit as dr
    import mitsuba as mi

    from .scenes import load_scene
    from .scenes import scene_path as find_scene

    path = find_scene(scene_path)
    defines = dict(defines or {})
    scene = load_scene(path, defines)
    sensor = scene.sensors()[0]
    if spp is None and time_budget is None:
        spp = sensor.sampler().sample_count()
    if spp is not None and spp < 1:
        raise MiBrdfsError(f"spp must be at least 1, got {spp}")
    if time_budget is not None and not time_budget > 0:
        raise MiBrdfsError(f"time budget must be a positive number of seconds, got {time_budget}")
    size = sensor.film().crop_size()
    jit = dr.is_jit_v(mi.Float)
    adaptive = pass_spp is None and not jit
    if pass_spp is None:
        pass_spp = 1 if adaptive else _default_pass_spp(spp, int(size[0]) * int(size[1]))
    stop = _GracefulInterrupt()
    schedule = _Schedule(spp, pass_spp, time_budget, stop)
    variant = mi.variant()

    slow_python = not jit and uses_python_plugins(scene)
    arrangement = "jit" if jit else "threads"
    bar = Progress(spp, label=f"render {path.name}", unit=" spp") if progress else None
    passes = _Passes(scene, path, defines, variant, seed, adaptive, schedule, bar)

    threads = dr.thread_count()
    try:
        stop.__enter__()
        if slow_python:
            dr.set_thread_count(1)
            arrangement = "1 thread"
        workers = render_pool._cores() if processes is None else processes
        spread = slow_python and workers > 1 and render_pool._is_main_process()
        arrangement = _spread(passes, spread, workers) or arrangement
        while (item := schedule.next()) is not None:
            passes.run(*item)
    finally:
        stop.__exit__()
        dr.set_thread_count(threads)
        if bar:
            bar.close()

    image = passes.acc.mean()
    if image is None:
        raise KeyboardInterrupt  # interrupted before the first pass finished: nothing to keep
    return RenderResult(image=image, spp=passes.acc.spp, passes=passes.acc.passes, seed=seed,
                        variant=variant, wall_time=time.perf_counter() - schedule.start,
                        arrangement=arrangement, scene=str(path), defines=defines,
                        interrupted=stop.requested)


class _GracefulInterrupt:
    """
    While active, the first Ctrl-C (SIGINT) or SIGTERM (what ``timeout`` and batch schedulers
    send) only sets :attr:`requested` (the render loop then stops after the passes under way);
    it also restores Python's handlers, so a second one raises KeyboardInterrupt (SIGINT) or
    ends the process (SIGTERM). Outside the main thread, where no handler can be set, it does
    nothing.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self):
        self.requested = False
        self._previous = {}

    def _handler(self, signum, frame):
        self.requested = True
        self.__exit__()

    def __enter__(self):
        try:
            self._previous = {s: signal.signal(s, self._handler) for s in self.SIGNALS}
        except ValueError:  # not the main thread
            self._previous = {}
        return self

    def __exit__(self, *exc):
        for s, previous in self._previous.items():
            signal.signal(s, previous if previous is not None else signal.SIG_DFL)
        self._previous = {}
