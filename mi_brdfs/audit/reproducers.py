"""
The audit's evidence, rerun: every standalone reproducer of a defect (``validation/audit/
repro_*.py`` in a checkout of the repository: Mitsuba, drjit and NumPy only) is run in its own
process, and the report says for each whether it still exits 1 (the defect is present in the
installed Mitsuba), 0 (fixed there) or otherwise (the reproducer itself is broken: the audit's
exit status is then 1).
"""

from __future__ import annotations

import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

#: Where a checkout keeps the reproducers (the wheel does not ship them).
FOLDER = Path(__file__).resolve().parents[2] / "validation" / "audit"

#: Seconds one reproducer may take before it counts as broken.
TIMEOUT = 600


def run_one(script: Path) -> int | None:
    """The exit status of ``python script`` run in the script's folder; None on a timeout."""
    try:
        return subprocess.run([sys.executable, str(script)], capture_output=True,
                              cwd=script.parent, timeout=TIMEOUT).returncode
    except subprocess.TimeoutExpired:
        return None


def run_all(folder: Path = FOLDER, processes: int = 2,
            prefix: str = "validation/audit") -> dict[str, int | None]:
    """Exit status of every ``repro_*.py`` in ``folder`` by its path relative to the checkout
    (``prefix/repro_x.py``, as the findings name them); {} without the folder."""
    scripts = sorted(Path(folder).glob("repro_*.py"))
    with ThreadPoolExecutor(max(1, processes)) as pool:
        codes = list(pool.map(run_one, scripts))
    return {f"{prefix}/{s.name}": code for s, code in zip(scripts, codes)}


def describe(code: int | None, fork: bool = False) -> str:
    """What an exit status says about the defect in the installed Mitsuba (``fork``: a fork of
    another version, where an exit 0 may also mean the defect was never there)."""
    if code == 1:
        return "exits 1 in this run: the defect is present"
    if code == 0:
        return ("exits 0 in this run: **not in this build** (absent from its Mitsuba, or fixed)"
                if fork else "exits 0 in this run: **fixed in this Mitsuba**")
    return ("**timed out**" if code is None else f"**exits {code}**") + \
        " in this run: the reproducer is broken"
