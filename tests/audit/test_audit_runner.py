"""
The audit on the runner of long work (mi_brdfs.runner): its worker processes stop at once on
SIGINT or SIGTERM with every finished case in the cache, and a case whose run raises is one line
while the others finish and stay cached. A fake check in place of the battery (the worker
processes import it from here): the quick audit itself is tests/audit/test_audit.py's.
"""

import os
import signal
import time

import pytest

from mi_brdfs import runner
from mi_brdfs.audit import grid
from mi_brdfs.audit import run as audit
from mi_brdfs.errors import MiBrdfsError


def _check(case, variant, quick):
    """A case's records at once ('fast'), an exception ('raise'), or none in the next 30 s:
    'signal:N' sends signal N to the audit's process after 0.5 s, then runs on, as 'long'."""
    if case.config == "raise":
        raise ValueError("the battery raised")
    if case.config.startswith("signal:"):
        time.sleep(0.5)  # the case before it has come back
        os.kill(os.getppid(), int(case.config.split(":")[1]))
    if case.config != "fast":
        time.sleep(30)
    return [{"bsdf": case.bsdf, "config": case.config, "check": "fake", "passed": True}]


def test01_a_signal_stops_the_workers_and_keeps_what_finished(tmp_path):
    """SIGTERM, as a batch scheduler sends it (SIGINT: tests/test_runner.py)."""
    sig = signal.SIGTERM
    cases = [grid.case("diffuse", "fast", {"type": "diffuse"}),
             grid.case("diffuse", f"signal:{int(sig)}", {"type": "diffuse"}),
             grid.case("diffuse", "long", {"type": "diffuse"})]
    clock = time.perf_counter()
    with pytest.raises(runner.Interrupted, match=rf"^interrupted: 1 of 3 cases finished, kept "
                                                 rf"in {tmp_path} \(the same command resumes "
                                                 rf"there\)$"):
        audit.run(cases, "llvm_ad_rgb", True, tmp_path, processes=2, progress=False,
                  check=_check)
    assert time.perf_counter() - clock < 20  # the worker's spawn included, not its 30 s
    assert len(list(tmp_path.glob("*.json"))) == 1


def test02_a_case_that_raises_is_one_line_and_the_others_are_kept(tmp_path, capsys):
    cases = [grid.case("diffuse", "fast", {"type": "diffuse"}),
             grid.case("diffuse", "raise", {"type": "diffuse"}),
             grid.case("conductor", "fast", {"type": "conductor"})]
    with pytest.raises(MiBrdfsError, match=rf"^audit: 1 of 3 cases failed \(each above\); the "
                                           rf"others are kept in {tmp_path}, and the same "
                                           rf"command runs only those$"):
        audit.run(cases, "llvm_ad_rgb", True, tmp_path, processes=1, progress=False,
                  check=_check)
    assert capsys.readouterr().err == "audit: diffuse | raise failed: the battery raised\n"
    assert len(list(tmp_path.glob("*.json"))) == 2
