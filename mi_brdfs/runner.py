"""
Long work, run one way: :func:`run` hands tasks to a local pool or a Dask cluster and

* checks the scheduler before any task starts: the address parsed (:func:`scheduler_address`),
  a connection tried with a short timeout (:func:`reach`), then "waiting for workers at ..." and a bounded wait
  when the scheduler has none (:func:`connect`);
* shows a progress bar (:class:`~mi_brdfs.progress.Progress`) and hands each finished task's
  result to ``on_done`` (which keeps it: a cache file), in this thread, as it comes;
* reports each failed task in one line and runs the others to the end;
* on SIGINT (Ctrl-C) or SIGTERM (``timeout``, batch schedulers) starts nothing more: the queued
  tasks are cancelled, the running ones ended within seconds (their processes terminated),
  the tasks that finished meanwhile kept, and :class:`Interrupted` says how many and where.

Three pools, as :mod:`concurrent.futures` and `dask.distributed
<https://distributed.dask.org>`_ offer them: threads (``fn`` waits on a process of its own,
started with :func:`run_command`, which the stop terminates), worker processes
(``processes=True``: ``fn`` runs in them; the stop terminates them) and a Dask cluster
(``scheduler``: ``fn`` runs on its workers, each in a thread there; the stop cancels what is
queued and terminates the processes of :func:`run_command` on every worker).
"""

from __future__ import annotations

import functools
import ipaddress
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
import uuid

from .errors import MiBrdfsError
from .progress import Progress

#: Seconds to reach a Dask scheduler before it counts as unreachable.
CONNECT_TIMEOUT = 5.0
#: Seconds to wait for a Dask scheduler's first worker (a batch queue may take a while).
WORKER_WAIT = 120.0
#: Seconds a terminated process gets to end before it is killed.
GRACE = 5.0

_FORM = "tcp://HOST:PORT with PORT in 1..65535, e.g. tcp://127.0.0.1:8786"
_LABEL = re.compile(r"^[A-Za-z0-9_]([A-Za-z0-9_-]{0,61}[A-Za-z0-9_])?$")


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM stopped a run; the message says what finished and where it is kept."""


# -------------------------------------------------------------------------------------------------
# Processes that tasks start, ended with the run they belong to
# -------------------------------------------------------------------------------------------------

_lock = threading.Lock()
_children: dict = {}        # run id -> the processes of run_command under way
_stopped: set = set()       # run ids stopped: run_command starts nothing more for them
_current = threading.local()  # .run_id of the task this thread runs


def run_command(argv: list, env: dict | None = None) -> subprocess.CompletedProcess:
    """
    ``argv`` run to its end (stdout and stderr captured as text), as a task of :func:`run`
    starts a process: in a session of its own (a Ctrl-C at the terminal reaches the runner
    only, which ends the process), terminated with its process group when the run stops.
    """
    run_id = getattr(_current, "run_id", None)
    with _lock:
        if run_id in _stopped:
            raise MiBrdfsError("the run was stopped")
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=env, start_new_session=True)
        _children.setdefault(run_id, set()).add(proc)
    try:
        out, err = proc.communicate()
    except BaseException:
        _end([proc])
        raise
    finally:
        with _lock:
            mine = _children.get(run_id, set())
            mine.discard(proc)
            if not mine:
                _children.pop(run_id, None)
            if run_id in _stopped:  # ended by the stop: no result, whatever it printed
                raise MiBrdfsError("the run was stopped")
    return subprocess.CompletedProcess(argv, proc.returncode, out, err)


def end_children(run_id: str) -> int:
    """Stop the run ``run_id`` in this process: its processes of :func:`run_command` ended, no
    new one started; how many were ended. (On a Dask worker, through ``Client.run``.)"""
    with _lock:
        _stopped.add(run_id)
        procs = list(_children.pop(run_id, ()))
    _end(procs)
    return len(procs)


def _end(procs) -> None:
    """Terminate processes with their process groups; kill those still there after GRACE."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for p in procs:
            if p.poll() is None:
                try:
                    os.killpg(p.pid, sig)
                except (ProcessLookupError, PermissionError):
                    pass
        alive = []
        for p in procs:
            try:
                p.wait(GRACE if sig == signal.SIGTERM else None)
            except subprocess.TimeoutExpired:
                alive.append(p)
        procs = alive
        if not procs:
            return


def _call(fn, run_id: str, task):
    """``fn(task)`` as a task of the run ``run_id`` (what :func:`run_command` registers under)."""
    _current.run_id = run_id
    try:
        return fn(task)
    finally:
        _current.run_id = None


def _process_init(initializer, initargs) -> None:
    """A worker process: out of the terminal's process group (a Ctrl-C reaches the runner,
    which ends the workers, not a render under way in them), SIGINT ignored, then the pool's
    own initializer."""
    if hasattr(os, "setpgrp"):
        os.setpgrp()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if initializer is not None:
        initializer(*initargs)


# -------------------------------------------------------------------------------------------------
# The Dask scheduler, checked before any task
# -------------------------------------------------------------------------------------------------


def scheduler_address(value, option: str = "scheduler") -> str:
    """``value`` as a Dask scheduler's address ``tcp://HOST:PORT`` (a bare ``HOST:PORT`` is
    tcp, as Dask takes it); anything else is one error naming ``option``, the value and the
    form expected. No network access."""
    text = str(value).strip()

    def bad(why: str):
        raise MiBrdfsError(f"{option} {text or repr(value)}: {why}; give {_FORM}")

    scheme, sep, rest = text.rpartition("://")
    if sep and scheme != "tcp":
        bad(f"{scheme}:// is not the protocol of a Dask scheduler")
    host, colon, port = rest.rpartition(":")
    if not colon or not host:
        bad("no HOST:PORT")
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        bad(f"the port {port or '(none)'} is not a number in 1..65535")
    if host.startswith("[") and host.endswith("]"):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            bad(f"{host} is not an IPv6 address")
    elif not all(_LABEL.match(label) for label in host.split(".")):
        bad(f"{host} is not a host name or an IP address")
    return f"tcp://{host}:{int(port)}"


def connect(address: str, *, timeout: float = CONNECT_TIMEOUT, wait: float = WORKER_WAIT,
            stop: threading.Event | None = None, label: str = "run"):
    """
    A ``distributed.Client`` of the scheduler at ``address`` (:func:`scheduler_address`'s
    form) with one worker at least: a connection tried for ``timeout`` seconds, then, if the
    scheduler has no worker, "waiting for workers at ..." on stderr and a wait of ``wait``
    seconds at most (``stop`` set ends it). Each failure is one :class:`MiBrdfsError`.
    """
    try:
        from distributed import Client
    except ImportError:
        raise MiBrdfsError("a Dask scheduler needs dask.distributed: pip install "
                           "'mi-brdfs[sweep]'") from None
    reach(address, timeout)
    try:
        client = Client(address, timeout=timeout)
    except Exception as e:  # noqa: BLE001 - what answered there is no Dask scheduler
        raise MiBrdfsError(f"cannot reach the Dask scheduler at {address}: "
                           f"{_one_line(e)}") from None
    try:
        _wait_for_workers(client, address, wait, stop, label)
    except BaseException:
        client.close()
        raise
    return client


def reach(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """One :class:`MiBrdfsError` unless a Dask scheduler answers at ``address``
    (:func:`scheduler_address`'s form) within ``timeout`` seconds: a check a command makes
    before it creates its output folder."""
    host, port = address[len("tcp://"):].rsplit(":", 1)
    why = _probe(host.strip("[]"), int(port), timeout)
    if why:
        raise MiBrdfsError(f"cannot reach the Dask scheduler at {address}: {why}")


def _probe(host: str, port: int, timeout: float) -> str | None:
    """Why no Dask scheduler answers at ``host:port`` within ``timeout`` seconds (None: one
    does). A Dask server speaks first: on a connection it sends its handshake, a frame whose
    8-byte length leads (``distributed.comm.tcp``). Dask's own client gives up on a refused
    connection after 30 s and waits forever on a peer that says nothing."""
    import struct

    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            head = b""
            while len(head) < 8:
                more = sock.recv(8 - len(head))
                if not more:
                    break
                head += more
    except socket.timeout:
        return f"no answer in {timeout:g} s (is a Dask scheduler listening there?)"
    except OSError as e:
        return str(e.strerror or e)
    if len(head) < 8 or not 0 < struct.unpack("<Q", head)[0] < 1 << 20:
        return "what answers there is no Dask scheduler"
    return None


def _wait_for_workers(client, address: str, wait: float, stop, label: str) -> None:
    import time

    if client.scheduler_info(n_workers=1)["workers"]:
        return
    print(f"{label}: waiting for workers at {address} (up to {wait:g} s)", file=sys.stderr,
          flush=True)
    deadline = time.monotonic() + wait
    while not (stop is not None and stop.is_set()):
        left = deadline - time.monotonic()
        if left <= 0:
            raise MiBrdfsError(f"no worker joined the Dask scheduler at {address} in {wait:g} s: "
                               f"start some there (dask worker {address})")
        try:
            client.wait_for_workers(1, timeout=min(0.5, left))
            return
        except TimeoutError:
            pass
    raise Interrupted(f"interrupted while waiting for workers at {address}; nothing ran")


# -------------------------------------------------------------------------------------------------
# The run
# -------------------------------------------------------------------------------------------------


class _Stop:
    """While entered (in the main thread), SIGINT and SIGTERM set :attr:`event` instead of
    raising or ending the process; the handlers there were before come back on exit. A signal
    ignored (a shell starts background jobs with SIGINT ignored) stays ignored."""

    def __init__(self):
        self.event = threading.Event()
        self._previous = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for s in (signal.SIGINT, signal.SIGTERM):
                if signal.getsignal(s) is not signal.SIG_IGN:
                    self._previous[s] = signal.signal(s, lambda *_: self.event.set())
        return self

    def __exit__(self, *exc):
        for s, previous in self._previous.items():
            signal.signal(s, previous if previous is not None else signal.SIG_DFL)
        return False


def report_failure(label: str, what: str, error: BaseException) -> None:
    """One line on stderr for a failed task: ``LABEL: WHAT failed: the error's first line``."""
    print(f"{label}: {what} failed: {_one_line(error)}", file=sys.stderr, flush=True)


def _one_line(error: BaseException) -> str:
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def run(tasks: list, fn, *, workers: int | None = None, processes: bool = False,
        initializer=None, initargs: tuple = (), scheduler: str | None = None,
        on_done=None, on_failure=None, describe=str, label: str = "run",
        unit: str = " tasks", keep: str | None = None, progress: bool = True,
        wait: float = WORKER_WAIT) -> list:
    """
    ``fn(task)`` for every task of ``tasks`` (see the module's text); returns the failures,
    ``[(task, error)]``, each reported as it came by ``on_failure(task, error)`` (default: one
    line, :func:`report_failure`). ``on_done(task, result)`` gets each result, in this thread.

    Parameter ``workers`` (int | None): tasks at once on the local pool (default: one per core).
    Parameter ``processes`` (bool): run ``fn`` in worker processes (spawned; ``initializer``
    and ``initargs`` prepare each) instead of threads; ``fn`` and the tasks must pickle.
    Parameter ``scheduler`` (str | None): a Dask scheduler's address; ``fn`` runs on its workers.
    Parameter ``keep`` (str | None): where ``on_done`` keeps the results, for :class:`Interrupted`.
    Parameter ``wait`` (float): seconds to wait for a Dask scheduler's first worker.
    """
    if not tasks:
        return []
    on_failure = on_failure or (lambda t, e: report_failure(label, describe(t), e))
    with _Stop() as stop:
        pool = _Pool(workers or os.cpu_count() or 1, processes, initializer, initargs,
                     scheduler, stop.event, label, wait)
        bar = Progress(len(tasks), label=label, unit=unit) if progress else None
        finished, failures = [0], []

        def handle(future, task) -> None:
            error = None if future.cancelled() else future.exception()
            if future.cancelled() or (error is not None and stop.event.is_set()):
                return  # cancelled or ended by the stop: no failure of its own
            if error is not None:
                if bar is not None and bar.enabled:
                    bar.stream.write("\r\x1b[K")  # the failure's line, not the bar's
                failures.append((task, error))
                on_failure(task, error)
            else:
                if on_done is not None:
                    on_done(task, future.result())
                finished[0] += 1
            if bar is not None:
                bar.update(finished[0] + len(failures))

        try:
            pool.submit(fn, tasks)
            _collect(pool.futures, handle, stop.event)
            pool.stop()
            for future, task in list(pool.futures.items()):  # finished as the run stopped
                if future.done():
                    handle(future, task)
        finally:
            pool.close()
            if bar is not None:
                bar.close()
    if stop.event.is_set():
        failed = f" ({len(failures)} failed)" if failures else ""
        where = f", kept in {keep}" if keep else ""
        raise Interrupted(f"interrupted: {finished[0]} of {len(tasks)}{unit} finished{failed}"
                          f"{where}")
    return failures


def _collect(futures: dict, handle, stop: threading.Event) -> None:
    """Hand each future of ``futures`` ({future: task}) to ``handle`` as it finishes, and take
    it out, until none is left or ``stop`` is set (checked every 0.2 s: a stop takes effect at
    once, not after a running task)."""
    finished = queue.Queue()
    for future in list(futures):
        future.add_done_callback(finished.put)
    while futures and not stop.is_set():
        try:
            future = finished.get(timeout=0.2)
        except queue.Empty:
            continue
        handle(future, futures.pop(future))


class _Pool:
    """The futures of one run ({future: task}) on threads, worker processes or a Dask cluster,
    and their stop."""

    def __init__(self, workers, processes, initializer, initargs, scheduler, stop, label, wait):
        import concurrent.futures as cf
        import multiprocessing

        self.run_id, self.client, self.executor = uuid.uuid4().hex, None, None
        self.processes, self.futures, self.stopped = processes and not scheduler, {}, False
        if scheduler:
            self.client = connect(scheduler, stop=stop, label=label, wait=wait)
        elif processes:
            self.executor = cf.ProcessPoolExecutor(
                max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                initializer=_process_init, initargs=(initializer, initargs))
        else:
            self.executor = cf.ThreadPoolExecutor(max_workers=workers)

    def submit(self, fn, tasks) -> None:
        if self.client is not None:
            submit = functools.partial(self.client.submit, _call, fn, self.run_id, pure=False)
        elif self.processes:
            submit = functools.partial(self.executor.submit, fn)
        else:
            submit = functools.partial(self.executor.submit, _call, fn, self.run_id)
        for task in tasks:
            self.futures[submit(task)] = task

    def stop(self) -> None:
        """What has not started cancelled, what runs ended (its processes terminated); nothing
        when every task is done."""
        if self.stopped or all(f.done() for f in self.futures):
            return
        self.stopped = True
        if self.client is not None:
            self.client.cancel([f for f in self.futures if not f.done()])
            try:
                self.client.run(end_children, self.run_id)
            except Exception:  # noqa: BLE001 - a worker lost on the way has nothing to end
                pass
            return
        running = list((getattr(self.executor, "_processes", None) or {}).values())
        self.executor.shutdown(wait=False, cancel_futures=True)
        if self.processes:  # concurrent.futures has no way to end its workers before 3.14
            for p in running:
                if p.is_alive():
                    p.terminate()
            for p in running:
                p.join(GRACE)
        else:
            end_children(self.run_id)
        self.executor.shutdown(wait=True)

    def close(self) -> None:
        """The pool closed (stopped first, if a task is not done)."""
        self.stop()
        if self.client is not None:
            self.client.close()
        else:
            self.executor.shutdown(wait=True)
