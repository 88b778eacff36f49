"""mi-brdfs check / furnace / plot, in-process through cli.main (for the broken test plugin, and
where the process adds nothing to what is tested) and as a user runs them, in a subprocess (the
furnace, the first bad input)."""

import json

import pytest

from broken import register_broken
from helpers import cli_one_line_error
from mi_brdfs.cli import main
from mi_brdfs.imageio import read_exr
from helpers import run


def test01_check_passes_on_builtin_and_ours(capsys):
    """Two BSDFs, one table each, in the variant asked for (scalar_rgb: the battery's JIT
    variant runs in test02 and tests/checks/test_checks.py)."""
    assert main(["check", "diffuse", "lambert", "reflectance=0.3,0.4,0.5", "--quick", "-q",
                 "--variant", "scalar_rgb"]) == 0
    out = capsys.readouterr().out
    assert "diffuse (scalar_rgb)" in out
    assert "lambert(reflectance=[0.3, 0.4, 0.5])" in out and "all checks passed" in out


def test02_check_fails_with_status_1(variant_llvm_ad_rgb, capsys, tmp_path):
    """The battery flags the broken BSDF (energy) and only where it is broken (consistency
    passes): what run_battery returns, through the command's JSON."""
    register_broken()
    report = tmp_path / "check.json"
    assert main(["check", "broken", "defect=energy", "--quick", "-q", "--json",
                 str(report)]) == 1
    out = capsys.readouterr().out
    assert "energy" in out and "FAIL" in out and "check(s) failed" in out
    # strict JSON: no NaN or Infinity token (a check without a value reports NaN)
    text = report.read_text()
    results = {r["name"]: r["passed"] for r in json.loads(
        text, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))[0]["checks"]}
    assert not results["energy"] and results["consistency"]


def test02b_the_json_is_strict(tmp_path):
    """A check without a value (χ² skipped in a scalar variant: NaN) is written as "nan",
    so the file parses as strict JSON."""
    report = tmp_path / "check.json"
    assert main(["check", "lambert", "--quick", "-q", "--variant", "scalar_rgb", "--json",
                 str(report)]) == 0
    checks = json.loads(report.read_text(),
                        parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))[0]["checks"]
    assert {c["name"]: c["value"] for c in checks}["chi2"] == "nan"


BAD = {
    "unknown": (["check", "nosuch"], "unknown plugin 'nosuch'"),
    "orphan": (["check", "alpha=0.3"], "comes before any BSDF name"),
    "unknown-param": (["check", "roughconductor", "alpha=0.3", "colour=2"],
                      'unreferenced property'),
    "not-bsdf": (["check", "sphere"], "is a shape, not a BSDF"),
    "thetas": (["furnace", "diffuse", "--thetas", "100"], "angles must lie in [0, 90]"),
    "unwritable": (["plot", "lobe", "diffuse", "-o", "/proc/x.png"], "cannot write /proc/x.png"),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test03_bad_specs_one_line(case, monkeypatch):
    """Exit status 2 and one line, no traceback: each case through cli.main in this process,
    the first in a subprocess too, as a user runs it."""
    args, message = BAD[case]
    if case == next(iter(BAD)):
        p = run(*args)
        assert p.returncode == 2, p.stderr
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0] and "Traceback" not in p.stderr
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    cli_one_line_error(args, message)


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
def test05_plots(tmp_path, kind, monkeypatch):
    """Each kind of plot of two BSDFs, through cli.main (the furnace above runs the command
    line as a user does)."""
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    out = tmp_path / f"{kind}.png"
    extra = {"lobe": ["--thetas", "0,60"], "albedo": ["--thetas", "0,30,60,85", "-n", "20000"],
             "slice": ["--res", "32"]}[kind]
    assert main(["plot", kind, "roughconductor", "alpha=0.3", "lambert", "-o", str(out),
                 *extra]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 5000
