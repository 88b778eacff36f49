"""
``mi-brdfs audit`` under another Mitsuba build (Eradiate's fork, ``eradiate-mitsuba``): the
build detected, the fork's plugins never shadowed by the package's, its own cases, findings and
report files; and the committed report of that build (validation/audit/eradiate.md), which
``make audit-eradiate`` regenerates in the fork's virtual environment. Cheap: no process is
started, nothing imports the fork.
"""

import json
import warnings
from importlib import metadata
from pathlib import Path

import pytest

from mi_brdfs import registry
from mi_brdfs.audit import grid, report, triage
from mi_brdfs.errors import MiBrdfsWarning

ROOT = Path(__file__).resolve().parents[2]
FORK = ("eradiate-mitsuba", "0.5.0")
#: The BSDF plugins Eradiate adds in eradiate-mitsuba 0.5.0 (its src/eradiate_plugins/bsdfs/)
ERADIATE = {"rtls", "rpv", "hapke", "ocean_mishchenko", "ocean_legacy", "ocean_grasp",
            "bilambertian", "maignan", "selectbsdf", "mqdiffuse", "measured_mono"}


def test01_the_build_is_mitsuba_here():
    """The project's environment has Mitsuba itself, not a fork."""
    assert registry.mitsuba_build() == ("mitsuba", metadata.version("mitsuba"))


def test02_a_forks_plugin_of_the_same_name_is_not_shadowed():
    """Under a fork that ships a plugin named like one of ours, ours is left out (with one
    warning); under Mitsuba itself such a clash is a bug; without one, all of ours."""
    ours = list(registry.PLUGINS)
    fork_builtins = {"diffuse", "rtls"}
    with pytest.warns(MiBrdfsWarning, match="ships its own rtls"):
        kept = registry.own_plugins(fork_builtins, ("eradiate-mitsuba", "test-only"))
    assert "rtls" not in kept and kept == [p for p in ours if p != "rtls"]
    with pytest.raises(RuntimeError, match="'rtls' shadows a Mitsuba built-in"):
        registry.own_plugins(fork_builtins, ("mitsuba", "3.9.1"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert registry.own_plugins({"diffuse"}, ("mitsuba", "3.9.1")) == ours


def test03_the_forks_cases_findings_and_files():
    """The fork's grid: Mitsuba's built-ins and Eradiate's plugins (the issue's cases among
    them), not the package's; its findings apart from Mitsuba's; its report in
    audit/eradiate.md with links one folder deeper."""
    cases = grid.cases_for(FORK[0])
    names = {c.bsdf for c in cases}
    assert names >= ERADIATE - set(grid.skipped_for(FORK[0]))
    assert not names & {c.bsdf for c in grid.package_cases()} - ERADIATE
    assert len({c.key for c in cases}) == len(cases)
    assert grid.cases_for("mitsuba") == grid.all_cases()
    assert {"rtls | default (f_iso 0.21, f_vol 0.081, f_geo 0.0041)",
            "rpv | default (rho_0=0.1 k=0.1 g=0)",
            "hapke | default (w=0.5 b=0.2 c=0.5 θ=30° B_0=0 h=0)"} <= {c.key for c in cases}
    assert {c.dict()["wavelength"] for c in cases if c.bsdf.startswith("ocean_")
            and c.bsdf != "ocean_mishchenko"} == {550.0}
    fork_only = [f for f in triage.findings(FORK[0]) if f.build == FORK[0]]
    assert fork_only and not [f for f in triage.findings("mitsuba") if f.build]
    for f in fork_only:
        assert f.reproducer is None or (ROOT / f.reproducer).is_file(), f.reproducer
        if f.verdict == "defect":
            assert f.reproducer and f.source and (ROOT / f.issue).is_file(), f
            assert "## Prior art" in (ROOT / f.issue).read_text()
    out = Path("validation")
    assert report.paths(out, False, FORK) == (out / "audit" / "eradiate.md",
                                              out / "audit" / "eradiate" / "findings.json")
    assert report.paths(out, True, ("mitsuba", "3.9.1")) == (
        out / "MITSUBA_AUDIT-quick.md", out / "audit" / "findings-quick.json")


def test04_the_forks_report(tmp_path):
    """report.write for the fork: its title, its files, links relative to its folder."""
    records = [{"bsdf": "hapke", "config": "default", "check": "stability", "passed": False,
                "skipped": False, "value": 1.0, "tolerance": 0, "message": "NaN", "details": {}}]
    md, js, counts = report.write(records, tmp_path, "mi-brdfs audit", 60.0, "llvm_ad_rgb",
                                  False, exits={}, build=FORK)
    assert (md, js) == report.paths(tmp_path, False, FORK) and counts["defect"] == 1
    text = md.read_text()
    assert text.startswith("# Audit of eradiate-mitsuba 0.5.0's BSDFs (Mitsuba ")
    assert "](../../validation/audit/eradiate/repro_hapke_opposition_nan.py)" in text
    assert "](../mi_brdfs" not in text and json.loads(js.read_text())[0]["verdict"] == "defect"


REPORT = ROOT / "validation" / "audit" / "eradiate" / "findings.json"


@pytest.mark.skipif(not REPORT.is_file(), reason="no committed report of the fork's audit")
def test05_the_committed_report_triages_every_failure():
    """validation/audit/eradiate.md's findings (make audit-eradiate): every record judged, none
    untriaged (selectbsdf's crash and ocean_grasp's failures at 5 m/s included), every plugin
    Eradiate adds that can be built audited."""
    items = json.loads(REPORT.read_text())
    assert items and all(i["verdict"] in triage.VERDICTS for i in items)
    assert not [(i["bsdf"], i["config"], i["check"]) for i in items
                if i["verdict"] == "untriaged"]
    assert {i["bsdf"] for i in items} >= ERADIATE - set(grid.skipped_for(FORK[0]))
    assert (ROOT / "validation" / "audit" / "eradiate.md").is_file()
    judged = {(i["bsdf"], i["check"]): i["reproducer"] for i in items
              if i["bsdf"] in ("selectbsdf", "ocean_grasp") and i["verdict"] == "defect"}
    assert judged[("selectbsdf", "crash")].endswith("repro_selectbsdf_forward_ad.py")
    assert judged[("ocean_grasp", "lobes")].endswith("repro_ocean_grasp_component.py")
