"""
docs/tutorial.py runs end to end: in a subprocess with the quick settings (``--quick`` and
``MI_BRDFS_TUTORIAL_QUICK=1``), into a temporary folder, and its outputs are what it says they
are, so that the tutorial cannot rot as the package changes.
"""

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import LLVM_OK

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial.py"


def _number(pattern: str, text: str) -> float:
    """The number a printed line gives after ``pattern`` (a regex), as a float."""
    m = re.search(pattern + r"\s*(-?[\d.]+(?:e[-+]?\d+)?)", text)
    assert m, f"the tutorial did not print {pattern!r}:\n{text[-3000:]}"
    return float(m.group(1))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """One quick run of the tutorial (from another working directory): (stdout, output folder)."""
    if not LLVM_OK:
        pytest.skip("the tutorial renders in llvm_ad_rgb, which needs a working libLLVM")
    work = tmp_path_factory.mktemp("tutorial")
    out = work / "out"
    env = dict(os.environ, MI_BRDFS_TUTORIAL_QUICK="1", MI_BRDFS_NO_PROGRESS="1")
    proc = subprocess.run([sys.executable, str(TUTORIAL), "--quick", "--out", str(out)],
                          capture_output=True, text=True, timeout=300, cwd=work, env=env)
    assert proc.returncode == 0, f"exit {proc.returncode}:\n{proc.stdout[-3000:]}\n" \
                                 f"{proc.stderr[-3000:]}"
    return proc.stdout, out


def test01_one_run_and_what_it_writes_and_prints(run):
    """One run of the tutorial (it takes seconds) checked three ways, below."""
    _the_render_is_written_and_finite(*run)
    _the_printed_numbers_parse_and_make_sense(*run)
    _every_announced_output_exists(*run)


def _the_render_is_written_and_finite(stdout, out):
    from mi_brdfs.imageio import read_exr

    image, _ = read_exr(out / "cooktorrance.exr")
    assert image.shape == (64, 64, 3)
    assert np.all(np.isfinite(image))
    assert 0.01 < float(image.mean()) < 1.0  # a lit sphere, neither black nor blown out
    assert abs(_number(r"mean =", stdout) - float(image.mean())) < 1e-4
    assert _number(r"non-finite pixels =", stdout) == 0
    assert (out / "cooktorrance.png").stat().st_size > 0


def _the_printed_numbers_parse_and_make_sense(stdout, out):
    # the furnace: Lambert with ρ = 1 vanishes; rough Cook-Torrance without Fresnel loses energy
    assert abs(_number(r"furnace lambert: mean =", stdout) - 1.0) < 0.01
    ct = _number(r"furnace cooktorrance: mean =", stdout)
    assert 0.5 < ct < 0.98
    assert abs(ct - _number(r"furnace cooktorrance: mean = [\d.]+, predicted =", stdout)) < 0.005
    p = _number(r"chi2 p-value =", stdout)
    assert 0.01 <= p <= 1.0
    assert _number(r"largest relative difference =", stdout) < 1e-4
    assert _number(r"compare: A vs B RMSE =", stdout) < \
        _number(r"noise floor RMSE =", stdout)
    n = _number(r"fitted exponent =", stdout)
    assert math.isfinite(n) and 10 < n < 1000
    assert "passed = False" not in stdout
    assert "tutorial done" in stdout


def _every_announced_output_exists(stdout, out):
    for name in ("cooktorrance.png", "furnace-lambert.png", "furnace-cooktorrance.png",
                 "fit-target.png", "fit-phong.png"):
        assert (out / name).is_file(), name
    for path in re.findall(r"^wrote (\S+)", stdout, re.M):
        assert Path(path).is_file(), path


def _code_cells() -> list[str]:
    """The tutorial's code cells, as a notebook (VS Code, Jupytext) splits it at ``# %%``."""
    parts = re.split(r"^(# %%.*)$", TUTORIAL.read_text(encoding="utf-8"), flags=re.M)
    return [body for marker, body in zip(parts[1::2], parts[2::2]) if "[markdown]" not in marker]


@pytest.mark.parametrize("argv, env, quick", [
    ([], {}, False),
    (["--quick"], {}, True),
    ([], {"MI_BRDFS_TUTORIAL_QUICK": "1"}, True),
    ([], {"MI_BRDFS_TUTORIAL_QUICK": "0"}, False),
    (["-f", "kernel.json"], {}, False),  # a Jupyter kernel's own arguments are ignored
])
def test04_the_settings_cell(tmp_path, monkeypatch, argv, env, quick):
    """--quick or MI_BRDFS_TUTORIAL_QUICK=1 select the quick settings; --out makes the folder."""
    monkeypatch.delenv("MI_BRDFS_TUTORIAL_QUICK", raising=False)
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    out = tmp_path / "a" / "b"
    monkeypatch.setattr(sys, "argv", ["tutorial.py", *argv, "--out", str(out)])
    settings = _code_cells()[0]
    assert "argparse" in settings, "the first code cell is no longer the settings cell"
    scope = {}
    exec(compile(settings, str(TUTORIAL), "exec"), scope)
    assert scope["QUICK"] is quick
    assert out.is_dir() and scope["OUT"] == out
    assert (scope["RES"] < 100) is quick
