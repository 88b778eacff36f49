"""Side-by-side comparison: metrics, the noise-floor verdict, outputs, the command line."""

import numpy as np
import pytest

from mi_brdfs import compare as C
from mi_brdfs.imageio import read_exr
from helpers import run

WHITE = "lambert reflectance=0.885809,0.698859,0.666422"  # cbox's white, as lambert


def test01_metrics_closed_form():
    a = np.ones((4, 4, 3))
    b = a + 0.1
    assert C.rmse(a, b) == pytest.approx(0.1)
    assert C.rel_mse(a, b) == pytest.approx(0.01 / 1.01)
    m = C.metrics(a, a)
    assert m.rmse == 0 and m.rel_mse == 0 and m.mean_flip == pytest.approx(0, abs=1e-6)
    assert C.metrics(a * 0.2, a).mean_flip > 0.1  # FLIP sees a 5× brightness change


def test02_identical_material_is_within_noise(variant_llvm_ad_rgb):
    r = C.compare("cbox", swap={"white": WHITE}, spp=8, defines={"res": "32"})
    assert not r.different() and r.ab.rmse < 1e-6 < r.noise.rmse
    assert "within noise" in r.verdict()


def test03_other_material_is_different(variant_llvm_ad_rgb):
    r = C.compare("cbox", swap={"white": "roughconductor alpha=0.3"}, spp=8,
                  defines={"res": "32"})
    assert r.different() and "different" in r.verdict()
    assert r.flip.shape == (32, 32) and 0 <= r.flip.min() and r.flip.max() <= 1


def test04_cli_writes_figure_and_exrs(tmp_path, monkeypatch, capsys):
    """The command in this process (tests/cli runs the command line in subprocesses)."""
    from mi_brdfs.cli import main

    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    out = tmp_path / "cmp.png"
    code = main(["compare", "cbox", "--swap", f"white={WHITE}", "--spp", "4", "-D", "res=16",
                 "-o", str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert "noise floor" in printed.out and "within noise" in printed.out
    assert out.read_bytes()[:4] == b"\x89PNG"
    a, header = read_exr(tmp_path / "cmp-A.exr")
    d, _ = read_exr(tmp_path / "cmp-diff.exr")
    assert a.shape == (16, 16, 3) and header["compare.b"].startswith("white = lambert")
    assert np.abs(d).max() < 1e-6


@pytest.mark.parametrize("args,message", [
    (["compare", "cbox", "-D", "res=8"], "one scene with --swap ID=BSDF"),
    (["compare", "cbox", "--swap", "white"], "--swap expects ID=BSDF"),
    (["compare", "cbox", "--swap", "nosuchid=diffuse", "-D", "res=8"], 'no <bsdf id="nosuchid">'),
    (["compare", "cbox", "furnace"], "the renders differ in size"),  # 256² vs 64²
])
def test05_cli_bad_input(tmp_path, args, message):
    p = run(*args, "--spp", "1", "-o", str(tmp_path / "c.png"))
    assert p.returncode == 2, p.stderr
    assert message in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())
