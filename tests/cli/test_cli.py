"""The mi-brdfs command line, run as a user runs it: in a subprocess, judged by exit code,
output files and what it prints."""

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import LLVM_OK
from mi_brdfs.imageio import read_exr

from helpers import CLI, run


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test01_render_smoke(tmp_path, variant):
    if variant.startswith("llvm") and not LLVM_OK:
        pytest.skip("no working libLLVM")
    out = tmp_path / "f.exr"
    p = run("render", "furnace", "-o", str(out), "--spp", "8", "-D", "res=8", "--variant", variant)
    assert p.returncode == 0, p.stderr
    assert "rendered 8 spp of 8×8" in p.stdout
    image, header = read_exr(out)
    assert image.shape == (8, 8, 3) and np.isfinite(image).all()
    assert abs(image.mean() - 1.0) < 0.05  # furnace with ρ = 1
    for key, value in {"render.variant": variant, "render.spp": "8", "render.seed": "0",
                       "mitsuba.version": "3.9.1"}.items():
        assert header[key] == value
    for key in ("mi_brdfs.version", "drjit.version", "render.wall_time_s", "render.scene"):
        assert header[key]
    assert (tmp_path / "f.png").stat().st_size > 0
    assert sorted(f.name for f in tmp_path.iterdir()) == ["f.exr", "f.png"]  # no temporaries


def test02_default_scene_is_the_showcase(tmp_path):
    p = run("render", "--spp", "1", "-D", "res=8", "--no-png", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "showcase.exr").exists() and not (tmp_path / "showcase.png").exists()


BAD = {
    "missing scene": (["render", "nosuch.xml"], "scene file nosuch.xml does not exist"),
    "parse error": (["render", "{bad}"], "Parsing of XML file"),
    "unknown variant": (["render", "furnace", "--variant", "llvm_rgb"],
                        "unknown variant 'llvm_rgb'"),
    "unwritable output": (["render", "furnace", "-o", "/proc/out.exr"],
                          "cannot write /proc/out.exr"),
    "missing folder": (["render", "furnace", "-o", "{tmp}/no/dir/x.exr"], "does not exist"),
    "bad reflectance": (["render", "furnace", "-D", "reflectance=1.5"],
                        'lambert: parameter "reflectance" = [1.5, 1.5, 1.5] is invalid'),
    "nan reflectance": (["render", "furnace", "-D", "reflectance=nan"], '"reflectance" ='),
    "unknown define": (["render", "furnace", "-D", "colour=1"], "no <default> for colour"),
    "malformed define": (["render", "furnace", "-D", "spp"], "-D expects name=value"),
    "zero spp": (["render", "furnace", "--spp", "0"], "--spp: must be at least 1"),
    "not exr": (["render", "furnace", "-o", "{tmp}/x.png"], "'{tmp}/x.png' must end in .exr"),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test03_bad_input_one_line_no_output(tmp_path, case, capsys, monkeypatch):
    """Each case through the command's entry point in this process; one of them (the first) in
    a subprocess too, as a user runs it: the same exit code, the same one line."""
    from mi_brdfs.cli import main

    args, message = BAD[case]
    bad = tmp_path / "bad.xml"
    bad.write_text('<scene version="3.0.0"><shape type="sphere">')
    args = [a.format(bad=bad, tmp=tmp_path) for a in args]
    if "-o" not in args:
        args += ["-o", str(tmp_path / "out.exr")]
    if case == next(iter(BAD)):
        p = run(*args)
    else:
        monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
        try:
            code = main(args)
        except SystemExit as e:  # argparse's own errors exit as they do from the shell
            code = e.code
        p = subprocess.CompletedProcess(args, code, *capsys.readouterr())
    assert p.returncode == 2, (p.stdout, p.stderr)
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("mi-brdfs: error: "), p.stderr
    assert message.format(tmp=tmp_path) in lines[0] and "Traceback" not in p.stderr
    assert [f.name for f in tmp_path.iterdir()] == ["bad.xml"]  # nothing written, not even partly


RENDER = ["render", "cbox", "-D", "res=16", "--pass-spp", "64"]


@pytest.fixture(scope="module")
def one_pass_seconds(tmp_path_factory):
    """The wall time of a whole one-pass render of test04's scene, its kernels then cached:
    how long that test waits before its signal, so that the signal reaches the render loop
    (a signal during start-up ends the command with nothing written, rightly) on any machine."""
    out = tmp_path_factory.mktemp("warm") / "w.exr"
    start = time.perf_counter()
    subprocess.run(CLI + RENDER + ["--spp", "64", "-o", str(out), "-q"], check=True,
                   capture_output=True, env=dict(os.environ, MI_BRDFS_NO_PROGRESS="1"))
    return time.perf_counter() - start


@pytest.mark.skipif(not LLVM_OK, reason="no working libLLVM")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test04_ctrl_c_keeps_what_is_done(tmp_path, signum, one_pass_seconds):
    """Ctrl-C, and SIGTERM (what timeout and batch schedulers send: it kept nothing), stop
    after the passes under way and write what is done, complete passes only."""
    out = tmp_path / "i.exr"
    proc = subprocess.Popen(CLI + RENDER + ["--spp", "10000000", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, MI_BRDFS_NO_PROGRESS="1"))
    time.sleep(1.5 * one_pass_seconds + 1)
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted after" in stdout
    image, header = read_exr(out)
    assert header["render.interrupted"] == "true" and int(header["render.spp"]) % 64 == 0
    assert np.isfinite(image).all() and image.mean() > 0.05  # complete passes only


def test05_no_working_llvm_falls_back_to_scalar(tmp_path):
    """A DRJIT_LIBLLVM_PATH that does not work: one warning line, then a scalar render."""
    out = tmp_path / "f.exr"
    p = run("render", "furnace", "--spp", "2", "-D", "res=4", "-o", str(out),
            env={"DRJIT_LIBLLVM_PATH": str(tmp_path / "libLLVM-nope.so"),
                 "XDG_CACHE_HOME": str(tmp_path / "cache")})
    assert p.returncode == 0, p.stderr
    warnings = [ln for ln in p.stderr.splitlines() if ln.startswith("mi-brdfs: warning:")]
    assert len(warnings) == 1 and "using scalar_rgb" in warnings[0] and "libllvm19" in warnings[0]
    assert "scalar_rgb" in p.stdout and read_exr(out)[1]["render.variant"] == "scalar_rgb"


def test06_entry_points():
    p = run("--version")
    assert p.returncode == 0 and p.stdout.startswith("mi-brdfs ")
    exe = shutil.which("mi-brdfs", path=str(Path(sys.executable).parent))
    assert exe, "console script mi-brdfs is not installed beside the interpreter"
    p = subprocess.run([exe, "info"], capture_output=True, text=True, timeout=60)
    assert p.returncode == 0 and "lambert" in p.stdout and "libLLVM" in p.stdout
