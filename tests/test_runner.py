"""
The runner of long work (mi_brdfs.runner): SIGINT and SIGTERM stop a run at once on each pool
(threads waiting on processes, worker processes, a Dask cluster) and keep what finished; a
failed task is one line and the others go on; a Dask scheduler's address is parsed without the
network, an unreachable one is one line in seconds, one without workers a bounded wait.
"""

import os
import signal
import socket
import sys
import threading
import time

import pytest

from mi_brdfs import runner
from mi_brdfs.errors import MiBrdfsError

#: Seconds a task "that runs long" takes: a stop must not wait for it.
LONG = 30


def _task(t):
    """A task: 'fast' returns at once; 'signal:N' sends signal N to this process (the runner's
    after 0.3 s) and returns; 'fail' raises; 'long' runs a process of LONG seconds."""
    if t == "fail":
        raise ValueError("this task fails")
    if t.startswith("signal:"):
        time.sleep(0.3)
        os.kill(os.getpid(), int(t.split(":")[1]))
    if t == "long":
        runner.run_command([sys.executable, "-c", f"import time; time.sleep({LONG})"])
    return t.upper()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test01_a_signal_stops_the_threads_and_keeps_what_finished(sig):
    """Two tasks finish, then the signal: the running processes are ended, the queued tasks
    never start, the finished ones reach on_done, in a second or so, not LONG."""
    kept = []
    tasks = ["fast", f"signal:{int(sig)}", "long", "long", "long", "long"]
    clock = time.perf_counter()
    with pytest.raises(runner.Interrupted, match=r"^interrupted: 2 of 6 tasks finished, kept "
                                                 r"in the cache$"):
        runner.run(tasks, _task, workers=2, on_done=lambda t, r: kept.append(r),
                   keep="the cache", progress=False)
    assert time.perf_counter() - clock < LONG / 3
    assert sorted(kept) == ["FAST", f"SIGNAL:{int(sig)}"]
    assert runner._children == {}  # no process of the run left
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handlers restored


def test02_a_signal_stops_worker_processes():
    """The same on worker processes (the audit's pool): the one under way is terminated."""
    kept = []
    clock = time.perf_counter()
    with pytest.raises(runner.Interrupted, match="1 of 3 tasks finished"):
        runner.run([0.0, LONG, LONG], time.sleep, workers=1, processes=True,
                   on_done=lambda t, r: (kept.append(t), os.kill(os.getpid(), signal.SIGINT)),
                   progress=False)
    assert kept == [0.0] and time.perf_counter() - clock < LONG / 2


def test03_a_failure_is_one_line_and_the_others_go_on(capsys):
    kept = []
    failures = runner.run(["fast", "fail", "fast"], _task, workers=1, label="job",
                          on_done=lambda t, r: kept.append(r), progress=False)
    assert kept == ["FAST", "FAST"]
    assert [(t, str(e)) for t, e in failures] == [("fail", "this task fails")]
    assert capsys.readouterr().err == "job: fail failed: this task fails\n"


@pytest.mark.parametrize("value, why", [
    ("tcp://127.0.0.1:99999", "the port 99999 is not a number in 1..65535"),
    ("tcp://127.0.0.1:0", "the port 0 is not a number in 1..65535"),
    ("tcp://127.0.0.1", "no HOST:PORT"),
    ("foo", "no HOST:PORT"),
    ("", "no HOST:PORT"),
    ("http://127.0.0.1:8786", "http:// is not the protocol of a Dask scheduler"),
    ("tcp://no such host!:8786", "no such host! is not a host name or an IP address"),
    ("tcp://[::zz]:8786", "[::zz] is not an IPv6 address"),
])
def test04_bad_addresses_without_the_network(value, why):
    clock = time.perf_counter()
    with pytest.raises(MiBrdfsError) as e:
        runner.scheduler_address(value, "--scheduler")
    assert str(e.value) == (f"--scheduler {value or repr(value)}: {why}; give tcp://HOST:PORT "
                            f"with PORT in 1..65535, e.g. tcp://127.0.0.1:8786")
    assert time.perf_counter() - clock < 0.1


def test05_good_addresses():
    assert runner.scheduler_address("127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert runner.scheduler_address(" tcp://node-01.cluster:08786 ") == \
        "tcp://node-01.cluster:8786"
    assert runner.scheduler_address("tcp://[::1]:8786") == "tcp://[::1]:8786"


def test06_no_scheduler_there_is_one_line_in_seconds():
    """Nothing listening: refused; a listener that says nothing: the connection timeout; one
    that says something else (a web server's reply): not Dask, not Dask's 30 s or its 3 EiB
    allocation."""
    pytest.importorskip("distributed")
    port = _free_port()
    with pytest.raises(MiBrdfsError, match=rf"^cannot reach the Dask scheduler at "
                                           rf"tcp://127.0.0.1:{port}: .*refused"):
        runner.connect(f"tcp://127.0.0.1:{port}", timeout=1)
    with socket.create_server(("127.0.0.1", 0)) as silent:
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        clock = time.perf_counter()
        with pytest.raises(MiBrdfsError, match=r"no answer in 1 s \(is a Dask scheduler"):
            runner.connect(address, timeout=1)
        assert time.perf_counter() - clock < 3
    with socket.create_server(("127.0.0.1", 0)) as web:
        threading.Thread(target=lambda: web.accept()[0].sendall(b"HTTP/1.1 400 Bad Request\r\n"
                                                                b"\r\n"), daemon=True).start()
        with pytest.raises(MiBrdfsError, match=r": what answers there is no Dask scheduler$"):
            runner.connect(f"tcp://127.0.0.1:{web.getsockname()[1]}", timeout=1)


@pytest.fixture(scope="module")
def no_workers():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp://",
                                  host="127.0.0.1", dashboard_address=":0") as cluster:
        yield cluster


def test07_a_scheduler_without_workers_is_a_bounded_wait(no_workers, capsys):
    address = no_workers.scheduler_address
    clock = time.perf_counter()
    with pytest.raises(MiBrdfsError, match=rf"^no worker joined the Dask scheduler at "
                                           rf"{address} in 1 s: start some there"):
        runner.run(["fast"], _task, scheduler=address, wait=1, label="job", progress=False)
    assert time.perf_counter() - clock < 5
    assert capsys.readouterr().err == f"job: waiting for workers at {address} (up to 1 s)\n"


def test08_a_signal_stops_a_dask_run():
    """On Dask: the queued tasks cancelled, the running processes ended on the workers."""
    distributed = pytest.importorskip("distributed")
    kept = []
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address=":0") as cluster:
        clock = time.perf_counter()
        with pytest.raises(runner.Interrupted, match="2 of 5 tasks finished"):
            runner.run(["fast", "signal:2", "long", "long", "long"], _task,
                       scheduler=cluster.scheduler_address,
                       on_done=lambda t, r: kept.append(r), progress=False)
        assert time.perf_counter() - clock < LONG / 3
    assert sorted(kept) == ["FAST", "SIGNAL:2"] and runner._children == {}


# -------------------------------------------------------------------------------------------------
# validate and bench run their sections one after the other in this process: a Ctrl-C stops them
# -------------------------------------------------------------------------------------------------


def test09_a_ctrl_c_inside_a_plugin_stops_a_report(tmp_path):
    """A Ctrl-C while Mitsuba runs a Python plugin's method reaches the report as drjit's
    RuntimeError (the KeyboardInterrupt its cause): the report stops as interrupted, not with
    a traceback; other errors pass as they are."""
    from mi_brdfs.campaign.core import Context, run

    def section(ctx):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as e:
            raise RuntimeError("drjit.custom(<mitsuba.python.util._RenderOp>): error while "
                               "performing a custom differentiable operation") from e

    def broken(ctx):
        raise RuntimeError("a bug")

    ctx = Context(out=tmp_path, quick=True, variant="scalar_rgb")
    with pytest.raises(KeyboardInterrupt):
        run([section], ctx, progress=False)
    with pytest.raises(RuntimeError, match="a bug"):
        run([broken], ctx, progress=False)


def test10_an_interrupted_render_stops_the_bench(monkeypatch):
    """mi_brdfs.render keeps a partial image on Ctrl-C (for `mi-brdfs render`); the bench's
    scalar timings stop instead of timing it."""
    from types import SimpleNamespace

    from mi_brdfs.benchmark import backends
    from mi_brdfs.campaign.core import Context, Section

    monkeypatch.setattr(backends, "render", lambda *a, **k: SimpleNamespace(interrupted=True))
    with pytest.raises(KeyboardInterrupt):
        backends.scalar_ratios(Context(out=None, quick=True, variant="scalar_rgb"),
                               Section("scalar"), pairs=backends.PAIRS[:1])
