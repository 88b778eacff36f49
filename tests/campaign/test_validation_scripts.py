"""The validation scripts run (quick mode), so they cannot rot between campaigns."""

import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test01_bench_render_quick(tmp_path):
    """Two of its pairs (--pair; make bench runs them all): a scalar and an llvm row each."""
    out = tmp_path / "bench.json"
    p = subprocess.run([sys.executable, str(ROOT / "validation" / "bench_render.py"), "--quick",
                        "--pair", "lambert vs diffuse", "--pair", "(Smith)",
                        "--json", str(out)], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "| lambert vs diffuse | scalar_rgb (" in p.stdout
    assert "| cooktorrance (Smith) vs roughconductor | llvm_ad_rgb |" in p.stdout
    import json
    rows = json.loads(out.read_text())
    pairs = {r["pair"] for r in rows}
    assert pairs >= {"lambert vs diffuse", "cooktorrance (Smith) vs roughconductor"}
    ratios = [float(r["ratio"].rstrip("×")) for r in rows]
    assert all(math.isfinite(x) and x > 0 for x in ratios), ratios


def test02_phong_float32_quick():
    """float32 against float64 needs the float32 variant llvm_ad_rgb."""
    from conftest import LLVM_OK
    if not LLVM_OK:
        pytest.skip("llvm_ad_rgb: no working libLLVM")
    p = subprocess.run([sys.executable, str(ROOT / "validation" / "phong_float32.py"), "--quick"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "| 1e+06 |" in p.stdout and "no NaN, Inf or negative value" in p.stdout


def test03_profile_kernels_quick():
    """validation/profile_kernels.py --quick: a row per contender, with its kernel time and a
    division count read from the kernel's IR (every one of these kernels divides)."""
    p = subprocess.run([sys.executable, str(ROOT / "validation" / "profile_kernels.py"),
                        "--quick"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    rows = [line.rsplit("  ", 1)[0].split() for line in p.stdout.splitlines() if " ms " in line]
    assert len(rows) == 4, p.stdout
    for row in rows:
        kernels, fdiv = float(row[-6]), int(row[-1])
        assert kernels > 0 and fdiv > 0, p.stdout


def test04_merl_layout_quick():
    """validation/merl_layout.py --quick: a row per layout, each having evaluated the file's
    values before it was timed, with the row of bin (0, 1, 0) and the table's offset that
    the layout asks for."""
    from helpers import merl_file

    p = subprocess.run([sys.executable, str(ROOT / "validation" / "merl_layout.py"), "--quick",
                        "--file", str(merl_file())], capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stderr
    rows = {line.split(" | ")[0].lstrip("| "): line.rstrip(" |").split(" | ")[-2:]
            for line in p.stdout.splitlines() if " ns |" in line}
    assert rows == {"MERL's order, 16 bytes past a line": ["180", "16 bytes"],
                    "MERL's order on lines (the plugin's)": ["180", "0 bytes"],
                    "blocks of 2 × 2 × 2 on lines": ["2", "0 bytes"]}, p.stdout
