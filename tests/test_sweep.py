"""
Sweeps of fits over measured materials (mi_brdfs.fit.sweep): one process per (material,
model), the same merged table from the local pool and from a two-worker Dask LocalCluster, the
cache that resumes a sweep (keyed by the file's content and the settings), one-line errors;
every file checked before any fit, a file given twice fitted once, a failed fit or a Ctrl-C
keeping every finished fit (those tests replace the fit by a fake task: the runner is what they
test, tests/test_runner.py the rest of it).
"""

import json
import os
import shutil
import signal
import socket
import sys
import time

import numpy as np
import pytest

from conftest import LLVM_OK
from helpers import cli_one_line_error, merl_file, run
from mi_brdfs import runner
from mi_brdfs.cli import main
from mi_brdfs.errors import MiBrdfsError, MiBrdfsWarning
from mi_brdfs.fit import sweep as sw
from mi_brdfs.measured import merl

SETTINGS = dict(pairs=1024, steps=40, seed=0)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Two materials: the tests' glossy file, and it at half the value."""
    folder = tmp_path_factory.mktemp("sweep")
    half = folder / "half.binary"
    merl.write(half, merl.read(merl_file()) * 0.5)
    return [str(merl_file()), str(half)]


def _rows(path):
    return [line for line in (path / "sweep.md").read_text().splitlines() if line.startswith("|")]


def test01_pool_and_dask_give_one_table(files, tmp_path):
    distributed = pytest.importorskip("distributed")
    pool = sw.sweep(files, ["ward"], "cuberoot", tmp_path / "pool", workers=2, **SETTINGS)
    assert pool["computed"] == 2
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        dask = sw.sweep(files, ["ward"], "cuberoot", tmp_path / "dask",
                        scheduler=cluster.scheduler_address, **SETTINGS)
    assert dask["computed"] == 2
    assert _rows(tmp_path / "pool") == _rows(tmp_path / "dask")
    doc = json.loads((tmp_path / "pool" / "sweep.json").read_text())
    assert [f["task"]["model"] for f in doc["fits"]] == ["ward", "ward"]
    # the same model on the same data at half the value: half the specular reflectance
    s = [np.mean(f["parameters"]["specular_reflectance"]) for f in doc["fits"]]
    assert s[1] == pytest.approx(s[0] / 2, rel=0.05)


def test02_the_cache_resumes(files, tmp_path):
    """A second run computes nothing; another setting, or changed data, recomputes."""
    first = sw.sweep(files[:1], ["ward"], "cuberoot", tmp_path, workers=1, **SETTINGS)
    again = sw.sweep(files[:1], ["ward"], "cuberoot", tmp_path, workers=1, **SETTINGS)
    assert first["computed"] == 1 and again["computed"] == 0
    assert _rows(tmp_path) and again["results"] == first["results"]
    task = dict(file=files[1], model="ward", metric="cuberoot", **SETTINGS)
    key = sw.task_key(task)
    assert sw.task_key(dict(task, steps=41)) != key
    assert sw.task_key(dict(task, model="phong")) != key


def test03_errors(files, tmp_path):
    with pytest.raises(MiBrdfsError, match=r"/nonexistent/x.binary: cannot read the MERL file "
                                           r"\(No such file or directory\)$"):
        sw.run_task(dict(file="/nonexistent/x.binary", model="ward", metric="cuberoot",
                         **SETTINGS))
    cli_one_line_error(["fit", files[0], "diffuse", "--models", "ward"],
                       "fit: a sweep (several TARGETs with --models) takes MERL .binary files "
                       "only, not diffuse")


def test04_cli(files, tmp_path):
    p = run("fit", *files, "--models", "ward", "--pairs", "1024", "--steps", "40",
            "--workers", "2", "-q", "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert "| material | ward | best |" in p.stdout and "2 fits computed" in p.stdout


# -------------------------------------------------------------------------------------------------
# The runner's part: checks before any fit, failures, duplicates, Ctrl-C (a fake task each)
# -------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def flat(tmp_path_factory):
    """Four files of MERL's size and header, each a different constant (cheap to write)."""
    folder = tmp_path_factory.mktemp("flat")
    paths = []
    for i in range(4):
        path = folder / f"m{i}.binary"
        path.write_bytes(np.asarray(merl.RES, "<i4").tobytes()
                         + np.full(3 * int(np.prod(merl.RES)), 1.0 + i, "<f8").tobytes())
        paths.append(str(path))
    return paths


def _fake(calls, slow=()):
    """A task in place of the fit: its file's name as the result; a file named in ``slow``
    says what it does there ('fail', 'signal:N' after 0.3 s, 'long': a 30 s process)."""
    def task(t):
        calls.append(t)
        what = dict(slow).get(os.path.basename(t["file"]))
        if what == "fail":
            raise MiBrdfsError("46 values are NaN: not a MERL file")
        if what and what.startswith("signal:"):
            time.sleep(0.3)
            os.kill(os.getpid(), int(what.split(":")[1]))
        if what == "long":
            runner.run_command([sys.executable, "-c", "import time; time.sleep(30)"])
        return {"task": t, "scores": {t["metric"]: float(len(calls))}}
    return task


def _main(args, capsys) -> tuple[int, str, str]:
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test05_every_file_checked_before_any_fit(flat, tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    short, other = tmp_path / "short.binary", tmp_path / "other.binary"
    short.write_bytes(open(flat[0], "rb").read()[:1000])
    other.write_bytes(np.asarray((90, 90, 90), "<i4").tobytes() + bytes(merl.SIZE - 12))
    given = [flat[0], str(short), flat[1], str(tmp_path / "none.binary"), str(other)]
    with pytest.raises(MiBrdfsError) as e:
        sw.sweep(given, ["ward"], "cuberoot", tmp_path / "out", **SETTINGS)
    assert str(e.value) == (
        f"sweep: 3 of 5 files are not MERL files a fit can read: {short}: 1000 bytes where a "
        f"MERL file has {merl.SIZE}: truncated or padded; {tmp_path / 'none.binary'}: cannot "
        f"read the MERL file (No such file or directory); {other}: dimensions (90, 90, 90), "
        f"not MERL's (90, 90, 180) (θh, θd, φd): not a MERL .binary file (no fit started)")
    assert calls == [] and not (tmp_path / "out").exists()
    cli_one_line_error(["fit", flat[0], str(short), "--models", "ward", "--out",
                        str(tmp_path / "cli")], f"sweep: {short}: 1000 bytes where a MERL file")
    assert calls == [] and not (tmp_path / "cli").exists()


def test06_a_failed_fit_keeps_the_others(flat, tmp_path, monkeypatch, capsys):
    """One fit fails (at once, before the others finish): one line for it, the others run to
    the end and stay in the cache, and the same command computes only the failed one."""
    monkeypatch.setattr(sw, "run_task", _fake([], [("m1.binary", "fail")]))
    with pytest.raises(MiBrdfsError, match=r"^sweep: 1 of 3 fits failed \(each above\); the 2 "
                                           r"finished are kept in .*\.sweep-cache, and the same "
                                           r"command computes only the rest$"):
        sw.sweep(flat[:3], ["ward"], "cuberoot", tmp_path, workers=1, **SETTINGS)
    assert capsys.readouterr().err == (f"sweep: ward on {flat[1]} failed: 46 values are NaN: "
                                       f"not a MERL file\n")
    assert len(list((tmp_path / sw.CACHE).glob("*.json"))) == 2
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    done = sw.sweep(flat[:3], ["ward"], "cuberoot", tmp_path, workers=1, **SETTINGS)
    assert (done["computed"], done["cached"]) == (1, 2) and [c["file"] for c in calls] == [flat[1]]


def test07_a_file_given_twice_is_fitted_once(flat, tmp_path, monkeypatch, capsys):
    """By path (also written otherwise) or by content: one row, counts that add up."""
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    copy = tmp_path / "copy.binary"
    shutil.copy(flat[0], copy)
    relative = os.path.relpath(flat[0])
    with pytest.warns(MiBrdfsWarning) as caught:
        done = sw.sweep([flat[0], relative, str(copy), flat[1]], ["ward", "phong"], "cuberoot",
                        tmp_path / "lib", **SETTINGS)
    assert [str(w.message) for w in caught] == [
        f"sweep: {relative} is given twice: fitted and listed once",
        f"sweep: {copy} is the same content as {flat[0]}: fitted and listed once"]
    assert done["files"] == flat[:2] and len(calls) == 4
    assert (done["computed"], done["cached"], len(done["results"])) == (4, 0, 4)
    assert [r.split("|")[1].strip() for r in _rows(tmp_path / "lib")[2:4]] == ["m0", "m1"]
    if not LLVM_OK:
        return
    code, out, err = _main(["fit", flat[0], flat[0], flat[1], flat[2], "--models", "ward", "-q",
                            "--out", str(tmp_path / "cli")], capsys)
    assert code == 0 and "3 fits computed, 0 from the cache; wrote" in out, out + err
    assert err == f"mi-brdfs: warning: sweep: {flat[0]} is given twice: fitted and listed once\n"
    code, out, err = _main(["fit", flat[0], flat[1], "--models", "ward", "-q", "--force",
                            "--out", str(tmp_path / "cli")], capsys)
    assert code == 0 and "0 fits computed, 2 from the cache; wrote" in out, out + err


@pytest.mark.skipif(not LLVM_OK, reason="no working libLLVM (fit's variant)")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test08_a_signal_stops_the_sweep_and_keeps_what_finished(flat, tmp_path, monkeypatch, capsys,
                                                           sig):
    """Two fits finish, then Ctrl-C (or SIGTERM): the fits under way end, the queued ones never
    start, the command exits 130 in a second or so saying what it kept and where; the same
    command then computes only the rest."""
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls, [("m1.binary", f"signal:{int(sig)}"),
                                                      ("m2.binary", "long"),
                                                      ("m3.binary", "long")]))
    args = ["fit", *flat, "--models", "ward", "--workers", "2", "-q", "--out", str(tmp_path)]
    clock = time.perf_counter()
    code, out, err = _main(args, capsys)
    assert time.perf_counter() - clock < 10
    assert code == 130 and err == (f"mi-brdfs: interrupted: 2 of 4 fits finished, kept in "
                                   f"{tmp_path / sw.CACHE} (the same command resumes from "
                                   f"there)\n"), err
    assert len(list((tmp_path / sw.CACHE).glob("*.json"))) == 2 and runner._children == {}
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    code, out, err = _main(args, capsys)
    assert code == 0 and "2 fits computed, 2 from the cache" in out, out + err


def test09_a_bad_scheduler_is_one_line_before_any_fit(flat, tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    for value, why in (("http://127.0.0.1:8786", "http:// is not the protocol"),
                       ("tcp://127.0.0.1:99999", "the port 99999 is not a number in 1..65535")):
        cli_one_line_error(["fit", *flat[:2], "--models", "ward", "--scheduler", value,
                            "--out", str(tmp_path)], f"--scheduler {value}: {why}")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    clock = time.perf_counter()
    cli_one_line_error(["fit", *flat[:2], "--models", "ward", "--scheduler",
                        f"tcp://127.0.0.1:{port}", "--out", str(tmp_path)],
                       f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}: ")
    assert time.perf_counter() - clock < 10 and calls == []


def test10_an_empty_or_unreachable_scheduler_runs_nothing_and_makes_no_folder(flat, tmp_path,
                                                                              monkeypatch):
    """``--scheduler ''`` (an unset shell variable) is refused, not a run on the local pool; a
    scheduler that does not answer leaves no report folder behind."""
    calls = []
    monkeypatch.setattr(sw, "run_task", _fake(calls))
    monkeypatch.chdir(tmp_path)
    cli_one_line_error(["fit", *flat[:2], "--models", "ward", "--scheduler", ""],
                       "--scheduler '': no HOST:PORT; give tcp://HOST:PORT")
    with pytest.raises(MiBrdfsError, match="scheduler '': no HOST:PORT"):
        sw.sweep(flat[:2], ["ward"], "cuberoot", tmp_path / "api", scheduler="", **SETTINGS)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    cli_one_line_error(["fit", *flat[:2], "--models", "ward", "--scheduler",
                        f"tcp://127.0.0.1:{port}"], "cannot reach the Dask scheduler")
    with pytest.raises(MiBrdfsError, match="cannot reach the Dask scheduler"):
        sw.sweep(flat[:2], ["ward"], "cuberoot", tmp_path / "api",
                 scheduler=f"tcp://127.0.0.1:{port}", **SETTINGS)
    assert calls == [] and list(tmp_path.iterdir()) == []
