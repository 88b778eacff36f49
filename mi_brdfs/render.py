"""
Progressive rendering: the samples per pixel in passes of independent seeds, accumulated.

Passes make a render interruptible (Ctrl-C keeps what is done), bounded in time
(``time_budget``) and, in scalar variants, parallel across processes. Why processes: in scalar
variants Mitsuba calls a Python BSDF once per ray from its C++ render threads, and those calls
serialise on the GIL. Two render threads fighting for it made a Cornell box 150–200× slower than
with the built-in ``diffuse``; one thread made it about 20×. So a scalar scene that holds a Python
plugin renders on one thread per process, with the passes spread over one process per core: this
one and helper processes, which it keeps rendering beside while they start. The helpers stay for
the next render in the same variant (they keep the last scene they loaded), so a session that
renders repeatedly pays their start once; :func:`close_helpers` ends them (exit does too). With
adaptive passes, the last passes shrink so that the processes finish together.
JIT variants trace the plugin once into a kernel and need none of this.
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

from .errors import MiBrdfsError, counts
from .progress import Progress

#: Lanes (pixels × spp) per JIT pass: bounds the memory of one pass (about 100 B per lane).
JIT_LANES_PER_PASS = 1 << 22

#: Seconds a scalar pass should take: short enough for Ctrl-C, the time budget and the
#: process pool to react, long enough that per-pass overhead does not matter.
SCALAR_PASS_S = 0.5

#: Seconds a helper process needs to start (import Mitsuba, load the scene); the render path
#: only spreads a scalar render over processes when that start is repaid. An estimate of the
#: time from the pool's creation to one helper's first answer on a small machine.
WORKER_START_S = 0.5

#: Seconds helpers kept from an earlier render need to load another scene before their first
#: answer (an estimate, as WORKER_START_S): the showcase loads in about 0.1 s.
WORKER_LOAD_S = 0.25


def pass_seed(seed: int, index: int) -> int:
    """
    Seed of pass ``index`` of a render with base ``seed``: ``seed·2¹⁶ + index`` (mod 2³²).

    Distinct for every (seed, index) with both below 2¹⁶, so renders with different base seeds
    share no sample streams (which two-seed noise estimates rely on).
    """
    return (seed * 65536 + index) & 0xFFFFFFFF


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

        from . import __version__
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


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


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
    acc = _Accumulator()
    variant = mi.variant()

    slow_python = not jit and uses_python_plugins(scene)
    arrangement = "jit" if jit else "threads"
    bar = Progress(spp, label=f"render {path.name}", unit=" spp") if progress else None

    lock = threading.Lock()  # helpers' passes are recorded from the pool's result thread

    def record(image, k: int, seconds: float) -> None:
        with lock:
            schedule.pass_times.append(seconds)
            if image is not None:
                acc.add(image, k)
            if bar:
                bar.update(acc.spp)

    def run_pass(index: int, k: int) -> None:
        t0 = time.perf_counter()
        image = _render_pass(scene, pass_seed(seed, index), k)
        record(image, k, time.perf_counter() - t0)

    threads = dr.thread_count()
    try:
        stop.__enter__()
        if slow_python:
            dr.set_thread_count(1)
            arrangement = "1 thread"
        workers = _cores() if processes is None else processes
        spread = slow_python and workers > 1 and _is_main_process()

        def first_pass() -> float:
            """The first pass in this process, which times the scene (seconds per spp) for the
            adaptive pass size."""
            if (item := schedule.next()) is None:  # (helpers took every pass)
                return 0.0
            t0 = time.perf_counter()
            run_pass(*item)
            seconds_per_spp = (time.perf_counter() - t0) / item[1]
            if adaptive:
                schedule.pass_spp = _timed_pass_spp(seconds_per_spp, spp)
            return seconds_per_spp

        def spread_over(workers: int, first=None) -> str:
            if adaptive:
                schedule.guided_workers = workers
            _render_with_helpers(workers - 1, variant, path, defines, seed, schedule, run_pass,
                                 record, first)
            return f"{workers} processes × 1 thread"

        warm = spread and _helpers_ready(workers - 1, variant)
        if warm and _helpers_scene == _scene_key(path, defines):
            # helpers kept from a render of this scene: they start on the first pass at once
            arrangement = spread_over(workers, first_pass)
        else:
            seconds_per_spp = first_pass()
            remaining_s = math.inf
            if spp is not None:
                remaining_s = seconds_per_spp * (spp - schedule.issued)
            if time_budget is not None:
                remaining_s = min(remaining_s, time_budget - schedule.pass_times[0])
            # worth it when starting the helpers and splitting the rest beats going on alone;
            # never from a helper process itself (``spread``): a script without an ``if
            # __name__ == "__main__"`` guard runs again in each spawned helper, which would
            # spawn its own helpers without end
            start_s = WORKER_LOAD_S if warm else WORKER_START_S
            if spread and start_s + remaining_s / workers < 0.9 * remaining_s:
                arrangement = spread_over(workers)
        while (item := schedule.next()) is not None:
            run_pass(*item)
    finally:
        stop.__exit__()
        dr.set_thread_count(threads)
        if bar:
            bar.close()

    image = acc.mean()
    if image is None:
        raise KeyboardInterrupt  # interrupted before the first pass finished: nothing to keep
    return RenderResult(image=image, spp=acc.spp, passes=acc.passes, seed=seed, variant=variant,
                        wall_time=time.perf_counter() - schedule.start, arrangement=arrangement,
                        scene=str(path), defines=defines, interrupted=stop.requested)


class _GracefulInterrupt:
    """
    While active, the first Ctrl-C only sets :attr:`requested` (the render loop then stops
    after the passes under way); it also restores Python's handler, so a second one raises
    KeyboardInterrupt. Outside the main thread, where no handler can be set, it does nothing.
    """

    def __init__(self):
        self.requested = False
        self._previous = None

    def _handler(self, signum, frame):
        self.requested = True
        signal.signal(signal.SIGINT, signal.default_int_handler)

    def __enter__(self):
        try:
            self._previous = signal.signal(signal.SIGINT, self._handler)
        except ValueError:  # not the main thread
            self._previous = None
        return self

    def __exit__(self, *exc):
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None


def _render_pass(scene, seed: int, spp: int) -> np.ndarray | None:
    """
    One pass; None when Ctrl-C cancelled it. Mitsuba installs its own SIGINT handler while it
    renders: a keypress cancels the integrator (a scalar pass then returns with blocks missing)
    and is passed on to the previous handler (ours). A cancelled pass is discarded.
    """
    import mitsuba as mi

    image = np.array(mi.render(scene, seed=seed, spp=spp))
    return None if scene.integrator().should_stop() else image


# -------------------------------------------------------------------------------------------------
# Scalar renders spread over processes
# -------------------------------------------------------------------------------------------------

_worker_scene = None  # (key, scene): the last scene this helper loaded
_worker_error = None


def _worker_init(variant: str) -> None:
    # The parent handles Ctrl-C and ends us: leave the terminal's process group (Mitsuba would
    # otherwise catch the keypress itself during a render) and ignore SIGINT.
    if hasattr(os, "setpgrp"):
        os.setpgrp()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    global _worker_error
    try:
        import drjit as dr

        import mi_brdfs
        mi_brdfs.use_variant(variant, fallback=False)
        dr.set_thread_count(1)
    except Exception as e:  # an initializer that raises makes Pool respawn workers forever
        _worker_error = e


def _worker_render(key: tuple, path: str, defines: dict, seed: int, spp: int):
    """One pass of the scene ``key`` names (loaded unless it is the last one loaded here)."""
    global _worker_scene
    if _worker_error is not None:
        raise _worker_error
    if _worker_scene is None or _worker_scene[0] != key:
        from .scenes import load_scene
        _worker_scene = None  # the last scene goes before the next one is loaded
        _worker_scene = (key, load_scene(path, defines))
    t0 = time.perf_counter()
    image = _render_pass(_worker_scene[1], seed, spp)
    return image, time.perf_counter() - t0


#: The helper processes kept for the next render: ((variant, count), Pool), or None.
_helpers = None
#: The scene (:func:`_scene_key`) the kept helpers were last handed.
_helpers_scene = None


def _helpers_ready(count: int, variant: str) -> bool:
    """Whether ``count`` helpers of ``variant`` are there from an earlier render."""
    return count > 0 and _helpers is not None and _helpers[0] == (variant, count)


def _helper_pool(count: int, variant: str):
    """``count`` single-threaded helper processes of ``variant``: those kept from the last
    render when they match, else new ones (the others are ended)."""
    global _helpers
    import multiprocessing as mp
    if not _helpers_ready(count, variant):
        close_helpers()
        _helpers = ((variant, count), mp.get_context("spawn").Pool(count, _worker_init,
                                                                   (variant,)))
    return _helpers[1]


def close_helpers() -> None:
    """End the helper processes that scalar renders keep for the next render (if any);
    the interpreter's exit ends them too."""
    global _helpers, _helpers_scene
    _helpers_scene = None
    if _helpers is not None:
        pool, _helpers = _helpers[1], None
        pool.terminate()
        pool.join()


def _scene_key(path, defines: dict) -> tuple:
    """What identifies a scene for the helpers: its file (path, size and modification time:
    an edited file is loaded again) and the defines. Files it includes are not checked, nor
    the code of plugins the helpers imported: :func:`close_helpers` after editing those."""
    stat = os.stat(path)
    return (str(path), stat.st_size, stat.st_mtime_ns, tuple(sorted(defines.items())))


def _is_main_process() -> bool:
    """
    Whether this process is no multiprocessing child (a render helper, say). A spawned child
    gets its name before it re-runs the parent's script, and its parent only after.
    """
    import multiprocessing as mp
    return mp.current_process().name == "MainProcess" and mp.parent_process() is None


def _render_with_helpers(helpers, variant, path, defines, seed, schedule, run_pass,
                         record, first=None) -> None:
    """
    Run the schedule's remaining passes in this process (``run_pass``; ``first``, when given,
    runs here before them, once the helpers have their first pass) and, as they come up, on
    ``helpers`` single-threaded helper processes, each handed its next pass as soon as it
    returns one (``record`` takes their images). This process renders while the helpers
    import Mitsuba and load the scene, so no core waits for their start. The helpers are kept
    for the next render when this one completes; they are ended when it fails or is
    interrupted (a pass may still be under way in them).
    """
    state = threading.Condition()
    pending, failures = [0], []
    pool = _helper_pool(helpers, variant)
    global _helpers_scene
    key = _helpers_scene = _scene_key(path, defines)

    def submit() -> None:
        with state:  # not after the pool is closed (failures then holds a None)
            if failures or (item := schedule.next()) is None:
                return
            index, k = item
            args = (key, str(path), defines, pass_seed(seed, index), k)
            pool.apply_async(_worker_render, args, callback=lambda result, k=k: done(result, k),
                             error_callback=failed)
            pending[0] += 1

    def done(result, k: int) -> None:  # on the pool's result thread
        try:
            image, seconds = result
            record(image, k, seconds)
            submit()  # before this pass stops counting as pending: the wait below sees the next
        except BaseException as error:  # the thread must not die: the wait below would hang
            failed(error)
            return
        with state:
            pending[0] -= 1
            state.notify_all()

    def failed(error: BaseException) -> None:
        with state:
            failures.append(error)
            pending[0] -= 1
            state.notify_all()

    complete = False
    try:
        for _ in range(helpers):  # one pass each: a queued pass could overrun a time budget
            submit()
        if first is not None:
            first()
        while not failures and (item := schedule.next()) is not None:
            run_pass(*item)
        with state:
            while pending[0] and not failures and not schedule.stop.requested:
                state.wait(0.1)
            complete = not pending[0] and not failures
        if failures:
            raise failures[0]
    finally:
        with state:
            failures.append(None)  # no more submissions from a late result
        if not complete:
            close_helpers()
