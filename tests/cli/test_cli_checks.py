"""mi-brdfs check / furnace / plot, in-process through cli.main (for the broken test plugin)
and as a user runs them."""

import pytest

from broken import register_broken
from mi_brdfs.cli import main
from mi_brdfs.imageio import read_exr
from test_cli import run


def test01_check_passes_on_builtin_and_ours(capsys):
    assert main(["check", "diffuse", "lambert", "reflectance=0.3,0.4,0.5", "--quick", "-q"]) == 0
    out = capsys.readouterr().out
    assert "diffuse (llvm_ad_rgb)" in out or "diffuse (scalar_rgb)" in out
    assert "lambert(reflectance=[0.3, 0.4, 0.5])" in out and "all checks passed" in out


def test02_check_fails_with_status_1(variant_llvm_ad_rgb, capsys):
    register_broken()
    assert main(["check", "broken", "defect=energy", "--quick", "-q"]) == 1
    out = capsys.readouterr().out
    assert "energy" in out and "FAIL" in out and "check(s) failed" in out


@pytest.mark.parametrize("args,message", [
    (["check", "nosuch"], "unknown plugin 'nosuch'"),
    (["check", "alpha=0.3"], "comes before any BSDF name"),
    (["check", "roughconductor", "alpha=0.3", "colour=2"], 'unreferenced property'),
    (["check", "sphere"], "is a shape, not a BSDF"),
    (["furnace", "diffuse", "--thetas", "100"], "angles must lie in [0, 90]"),
    (["plot", "lobe", "diffuse", "-o", "/proc/x.png"], "cannot write /proc/x.png"),
], ids=["unknown", "orphan", "unknown-param", "not-bsdf", "thetas", "unwritable"])
def test03_bad_specs_one_line(args, message):
    p = run(*args)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in p.stderr


def test04_furnace_table_and_render(tmp_path):
    out = tmp_path / "f.exr"
    p = run("furnace", "lambert", "reflectance=1", "--thetas", "0,60,85", "-n", "2000",
            "--render", "--spp", "16", "--res", "16", "-o", str(out), "--variant", "scalar_rgb")
    assert p.returncode == 0, p.stderr
    assert "sample() mean ± err" in p.stdout and "85.00" in p.stdout and "furnace:" in p.stdout
    image, header = read_exr(out)
    assert header["furnace.bsdf"] == "lambert(reflectance=1)" and image.shape == (16, 16, 3)
    assert abs(image.mean() - 1) < 0.02 and (tmp_path / "f.png").exists()


@pytest.mark.parametrize("kind", ["lobe", "albedo", "slice"])
def test05_plots(tmp_path, kind):
    out = tmp_path / f"{kind}.png"
    extra = {"lobe": ["--thetas", "0,60"], "albedo": ["--thetas", "0,30,60,85", "-n", "20000"],
             "slice": ["--res", "32"]}[kind]
    p = run("plot", kind, "roughconductor", "alpha=0.3", "lambert", "-o", str(out), *extra)
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 5000
