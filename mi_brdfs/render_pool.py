"""
Scalar renders spread over processes: the helper processes of :func:`mi_brdfs.render.render`.

In scalar variants Mitsuba calls a Python BSDF once per ray from its C++ render threads, and
those calls serialise on the GIL: render threads fighting for it are slower than one thread
alone. So a scalar scene that holds a Python plugin renders on one thread per process, with the
passes spread over one process per core: the rendering process and helper processes, which it
keeps rendering beside while they start. The helpers stay for the next render in the same
variant (they keep the last scene they loaded), so a session that renders repeatedly pays their
start once; :func:`close_helpers` ends them (exit does too).

Here: one pass (:func:`_render_pass`) and its seed (:func:`pass_seed`), which this process and
the helpers render alike; the helpers' entry points (:func:`_worker_init`,
:func:`_worker_render`); the pool kept between renders; and the handing of a render's passes to
it (:func:`_render_with_helpers`).
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np

#: Seconds a helper process needs to start (import Mitsuba, load the scene); the render path
#: only spreads a scalar render over processes when that start is repaid. An estimate of the
#: time from the pool's creation to one helper's first answer on a small machine.
WORKER_START_S = 0.5

#: Seconds helpers kept from an earlier render need to load another scene before their first
#: answer (an estimate, as WORKER_START_S: loading a scene costs less than starting a process).
WORKER_LOAD_S = 0.25


def pass_seed(seed: int, index: int) -> int:
    """
    Seed of pass ``index`` of a render with base ``seed``: ``seed·2¹⁶ + index`` (mod 2³²).

    Distinct for every (seed, index) with both below 2¹⁶, so renders with different base seeds
    share no sample streams (which two-seed noise estimates rely on).
    """
    return (seed * 65536 + index) & 0xFFFFFFFF


def _render_pass(scene, seed: int, spp: int) -> np.ndarray | None:
    """
    One pass; None when Ctrl-C cancelled it. Mitsuba installs its own SIGINT handler while it
    renders: a keypress cancels the integrator (a scalar pass then returns with blocks missing)
    and is passed on to the previous handler (ours). A cancelled pass is discarded.
    """
    import mitsuba as mi

    image = np.array(mi.render(scene, seed=seed, spp=spp))
    return None if scene.integrator().should_stop() else image


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


# -------------------------------------------------------------------------------------------------
# The helpers' entry points
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

        from .registry import use_variant
        use_variant(variant, fallback=False)
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


# -------------------------------------------------------------------------------------------------
# The pool kept between renders
# -------------------------------------------------------------------------------------------------

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


# -------------------------------------------------------------------------------------------------
# A render's passes handed to the pool
# -------------------------------------------------------------------------------------------------


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
