"""
Sweeps of fits over measured materials (mi_brdfs.fit.sweep): one process per (material,
model), the same merged table from the local pool and from a two-worker Dask LocalCluster, the
cache that resumes a sweep (keyed by the file's content and the settings), one-line errors.
"""

import json

import numpy as np
import pytest

from helpers import cli_one_line_error, merl_file, run
from mi_brdfs.errors import MiBrdfsError
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
    with pytest.raises(MiBrdfsError, match=r"sweep: ward on /nonexistent/x.binary failed: "):
        sw.run_task(dict(file="/nonexistent/x.binary", model="ward", metric="cuberoot",
                         **SETTINGS))
    cli_one_line_error(["fit", files[0], "diffuse", "--models", "ward"],
                       "a sweep (several TARGETs, --workers or --scheduler) takes MERL .binary "
                       "files only")


def test04_cli(files, tmp_path):
    p = run("fit", *files, "--models", "ward", "--pairs", "1024", "--steps", "40",
            "--workers", "2", "-q", "--out", str(tmp_path))
    assert p.returncode == 0, p.stderr
    assert "| material | ward | best |" in p.stdout and "2 fits computed" in p.stdout
