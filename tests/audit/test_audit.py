"""
``mi-brdfs audit``: the triage table and report on synthetic records, the quick audit as a user
runs it, and every reproducer of a Mitsuba defect exiting 1 on the Mitsuba it was written for.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import mitsuba as mi
import pytest

from conftest import LLVM_OK
from mi_brdfs.audit import grid, report, switches, triage
from mi_brdfs.audit.triage import Finding

ROOT = Path(__file__).resolve().parents[2]
REPRODUCERS = sorted((ROOT / "validation" / "audit").glob("repro_*.py"))
#: The Mitsuba version the reproducers were written against (they exit 0 once it is fixed).
AUDITED = "3.9.1"
KEYS = {"bsdf", "config", "check", "verdict", "summary", "reproducer", "source", "issue",
        "fixed_upstream"}


def _record(bsdf="roughplastic", config="ggx α=0.5", check="chi2 θ=0°", passed=False, **kw):
    return {"bsdf": bsdf, "config": config, "check": check, "passed": passed,
            "skipped": False, "value": 0.0, "tolerance": 0.01, "message": "m", "details": kw}


def test01_verdicts():
    """A passed check is 'pass'; a failure takes the first finding that covers it (by BSDF,
    check and configuration patterns and an optional condition), else 'untriaged'."""
    table = [Finding("roughplastic", r"^chi2", "ggx", "defect", "s", "r.py", "src"),
             Finding("*", r"^mitsuba chi2", "", "check-limitation", "h",
                     when=lambda r: r["details"].get("ours_passed") is True)]
    assert triage.verdict(_record(passed=True), table)[0] == "pass"
    assert triage.verdict(_record(), table)[0] == "defect"
    assert triage.verdict(_record(config="beckmann"), table)[0] == "untriaged"
    harness = _record(bsdf="diffuse", check="mitsuba chi2 θ=0°", ours_passed=True)
    assert triage.verdict(harness, table)[0] == "check-limitation"
    harness["details"]["ours_passed"] = False
    assert triage.verdict(harness, table)[0] == "untriaged"
    for f in triage.findings():
        assert f.verdict in triage.VERDICTS[:-1] and f.summary
        if f.verdict == "defect":
            assert f.reproducer and (ROOT / f.reproducer).is_file() and f.source, f
            assert f.issue and (ROOT / f.issue).is_file(), f
            assert "## Prior art" in (ROOT / f.issue).read_text(), f.issue


def test02_report(tmp_path):
    records = [_record(passed=True, check="consistency"), _record(),
               _record(check="mitsuba chi2 θ=0°", skipped=True)]
    records[2]["skipped"] = True
    table = [Finding("roughplastic", r"^chi2", "", "defect", "why", "validation/x.py", "a.cpp")]
    md, js, counts = report.write(records, tmp_path, "mi-brdfs audit", 60.0, "llvm_ad_rgb",
                                  quick=False, table=table)
    items = json.loads(js.read_text())
    assert [i["verdict"] for i in items] == ["pass", "defect"]  # skipped checks left out
    assert all(set(i) == KEYS for i in items) and counts["defect"] == 1
    text = md.read_text()
    assert "**defect**" in text and "validation/x.py" in text and "a.cpp" in text
    assert "Fixed upstream: no" in text and "**defect** ⁺" not in text
    assert f"The `{report.GPU_VARIANT}` audit was not run for this report" in text
    fixed = [Finding("roughplastic", r"^chi2", "", "defect", "why", "validation/x.py", "a.cpp",
                     fixed_upstream="https://example.org/pull/1 (title)")]
    md, js, _ = report.write(records, tmp_path, "mi-brdfs audit", 60.0, "llvm_ad_rgb",
                             quick=False, table=fixed)
    text = md.read_text()
    assert "**defect** ⁺" in text and "Fixed upstream: https://example.org/pull/1" in text
    assert json.loads(js.read_text())[1]["fixed_upstream"].startswith("https://example.org")
    # a finding's heading names its checks in words, not as its regular expression
    words = [Finding("roughplastic", r"^(chi2 θ=0°|lobes)$", "", "defect", "why", "validation/x.py")]
    md, _, _ = report.write(records, tmp_path, "mi-brdfs audit", 60.0, "llvm_ad_rgb",
                            quick=False, table=words)
    assert "### `roughplastic`: chi2 θ=0° or lobes (1 records)" in md.read_text()


def test02b_variants_and_cuda():
    """The report names the variants it ran; a non-cuda report says the cuda audit was not run
    and how to run it, a cuda one does not; polarized BSDFs follow the audit's backend."""
    assert grid.polarized_variant("llvm_ad_rgb") == "llvm_ad_spectral_polarized"
    assert grid.polarized_variant("cuda_ad_rgb") == "cuda_ad_spectral_polarized"
    llvm = " ".join(report._variants("llvm_ad_rgb"))
    cuda = " ".join(report._variants("cuda_ad_rgb"))
    assert "not run for this report" in llvm and "--variant cuda_ad_rgb" in llvm
    assert "not run" not in cuda and "`cuda_ad_spectral_polarized`" in cuda


def test02c_coverage_table_from_the_grid(tmp_path):
    """The report's coverage tables come from the grid's configurations: each state of a switch
    lists the configurations in it, and a state none exercises is flagged."""
    cases = [c for c in grid.mitsuba_cases() if c.bsdf == "roughconductor" and not c.polarized]
    records = [_record(bsdf=c.bsdf, config=c.config, check="consistency", passed=True)
               for c in cases]
    lines = "\n".join(report._coverage(records))
    assert "### `roughconductor`" in lines and "| `sample_visible` |" in lines
    assert "false: beckmann α=0.3 sample_visible=false, ggx α=0.3 sample_visible=false" in lines
    lines = "\n".join(report._coverage(records[:2]))  # only beckmann α=0.05/0.3 Au
    assert "**not exercised here: ggx**" in lines


def test03b_every_switch_is_exercised_in_every_state():
    """Every switch of a built-in BSDF in the grid without a reason to stay at its default is
    exercised in each of its states; taking one configuration away is seen."""
    cases = grid.all_cases()
    assert {c.bsdf for c in grid.mitsuba_cases()} <= set(switches.SWITCHES)
    assert switches.unexercised(cases) == []
    fewer = [c for c in cases if c.key != "roughconductor | ggx α=0.3 specular_reflectance=0.5"]
    assert switches.unexercised(fewer) == ["roughconductor: specular_reflectance (given)"]
    for rows in switches.coverage(cases).values():
        for row in rows:
            assert row.switch.states[0] in row.configs or row.switch.default_only is None


def test03_grid_names_every_case_once():
    keys = [c.key for c in grid.all_cases()]
    assert len(keys) == len(set(keys)) and any(c.quick for c in grid.all_cases())
    builtins = {c.bsdf for c in grid.mitsuba_cases()}
    assert {"diffuse", "roughconductor", "roughdielectric", "roughplastic", "principled",
            "hair", "blendbsdf", "normalmap", "bumpmap", "pplastic"} <= builtins


@pytest.mark.skipif(not LLVM_OK, reason="no working libLLVM")
def test04_quick_audit_as_a_user_runs_it(tmp_path):
    """`mi-brdfs audit --quick` on two of its plugins (``make audit`` runs them all): every
    record gets a verdict (none untriaged), roughplastic's defect among them; a second run
    resumes from the cache."""
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    only = {"roughplastic", "twosided"}
    cmd = [sys.executable, "-m", "mi_brdfs", "audit", "--quick", "--out", str(tmp_path),
           "--processes", "2"]
    p = subprocess.run(cmd + ["--only", ",".join(sorted(only))], capture_output=True, text=True,
                       env=env, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    items = json.loads((tmp_path / "audit" / "findings-quick.json").read_text())
    assert all(set(i) == KEYS and i["verdict"] in triage.VERDICTS for i in items)
    assert any(i["bsdf"] == "roughplastic" and i["verdict"] == "defect" for i in items)
    assert (tmp_path / "MITSUBA_AUDIT-quick.md").is_file()
    cached = len(list((tmp_path / "audit" / ".cache").glob("*.json")))
    assert cached == sum(c.quick and c.bsdf in only for c in grid.all_cases()) == 2
    p = subprocess.run(cmd + ["--only", "roughplastic", "--force"], capture_output=True, text=True,
                       env=env, timeout=120)
    assert p.returncode == 0 and "defect" in p.stdout, p.stdout + p.stderr


def test05_bad_input_is_one_line(tmp_path):
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    for args in (["--only", "nosuchbsdf"], ["--variant", "scalar_rgb"]):
        p = subprocess.run([sys.executable, "-m", "mi_brdfs", "audit", "--out", str(tmp_path),
                            *args], capture_output=True, text=True, env=env, timeout=60)
        assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
        assert p.stderr.startswith("mi-brdfs: error: ")


#: Reproducers that integrate or histogram with many samples: ``make audit`` reruns them (with
#: all the others, :mod:`mi_brdfs.audit.reproducers`); the suite runs the quick ones.
HEAVY = {"repro_hair_fiber_pdf", "repro_hair_pmax_sampling", "repro_roughdielectric_widened_weight",
         "repro_blendbsdf_delta_weight"}


def test06a_every_reproducer_is_standalone():
    """Mitsuba, drjit and NumPy only, and valid Python; the heavy ones named exist."""
    import ast

    for script in REPRODUCERS:
        source = script.read_text()
        assert "mi_brdfs" not in source, script
        imported = {a.name.split(".")[0] for node in ast.walk(ast.parse(source))
                    if isinstance(node, (ast.Import, ast.ImportFrom))
                    for a in (node.names if isinstance(node, ast.Import)
                              else [ast.alias(node.module or "")])}
        assert imported <= {"sys", "drjit", "mitsuba", "numpy"}, (script.name, imported)
    assert HEAVY <= {p.stem for p in REPRODUCERS}


def test06b_the_audit_reruns_reproducers_and_reports_each(tmp_path):
    """reproducers.run_all: exit 1 (present), 0 (fixed) and anything else (broken) each said
    so in the report next to the finding that names the script."""
    from mi_brdfs.audit import reproducers

    for name, code in (("repro_a", 1), ("repro_b", 0), ("repro_c", 3), ("other", 1)):
        (tmp_path / f"{name}.py").write_text(f"import sys\nsys.exit({code})\n")
    exits = reproducers.run_all(tmp_path, processes=2)
    assert exits == {"validation/audit/repro_a.py": 1, "validation/audit/repro_b.py": 0,
                     "validation/audit/repro_c.py": 3}
    table = [Finding("roughplastic", r"^chi2", "", "defect", "s", f"validation/audit/{n}.py",
                     "src") for n in ("repro_a", "repro_b", "repro_c")]
    texts = []
    for finding in table:
        report.write([_record()], tmp_path / finding.reproducer[-6:], "c", 1.0, "llvm_ad_rgb",
                     False, table=[finding], exits=exits)
        texts.append((tmp_path / finding.reproducer[-6:] / "MITSUBA_AUDIT.md").read_text())
    assert "the defect is present" in texts[0] and "fixed in this Mitsuba" in texts[1]
    assert "**exits 3** in this run: the reproducer is broken" in texts[2]
    report.write([_record()], tmp_path / "none", "c", 1.0, "llvm_ad_rgb", False,
                 table=table[:1])
    assert "not rerun in this run" in (tmp_path / "none" / "MITSUBA_AUDIT.md").read_text()


@pytest.mark.skipif(not LLVM_OK, reason="no working libLLVM")
@pytest.mark.skipif(mi.__version__ != AUDITED, reason=f"reproducers target Mitsuba {AUDITED}")
@pytest.mark.parametrize("script", [p for p in REPRODUCERS if p.stem not in HEAVY],
                         ids=lambda p: p.stem)
def test06_each_reproducer_exits_1_while_the_defect_is_present(script):
    """Failing on the audited Mitsuba (the heavy ones: by make audit)."""
    p = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                       timeout=300, cwd=script.parent)
    assert p.returncode == 1, p.stdout[-2000:] + p.stderr[-2000:]
