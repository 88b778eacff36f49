"""
Where a test run's time goes into LLVM compilation: a pytest plugin that appends, for every
test, the drjit kernels it launched, those it compiled (not found in the in-memory cache) and
their compilation time (drjit's kernel history: codegen and backend time), as JSON lines to the
file ``$KERNEL_STATS``; run as a script on that file it sums them per test file.

    rm -f /tmp/k.jsonl
    KERNEL_STATS=/tmp/k.jsonl DRJIT_CACHE_DIR=$(mktemp -d) PYTHONPATH=tools \\
        .venv/bin/python -m pytest -p pytest_kernel_stats -n 2 -m "not slow"
    .venv/bin/python tools/pytest_kernel_stats.py /tmp/k.jsonl
"""

import collections
import json
import os
import sys

import pytest


def _history():
    """(kernels, compiled, seconds compiling) of the JIT kernels since the last call."""
    import drjit as dr

    if not dr.has_backend(dr.JitBackend.LLVM):
        return 0, 0, 0.0
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    runs = [k for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    compiled = [k for k in runs if not k.get("cache_hit")]
    seconds = sum(k.get("codegen_time", 0.0) + k.get("backend_time", 0.0) for k in compiled)
    return len(runs), len(compiled), seconds / 1000.0  # drjit reports milliseconds


def pytest_runtest_setup(item):
    _history()  # what ran before this test is not its own


@pytest.hookimpl(hookwrapper=True, tryfirst=True)
def pytest_runtest_teardown(item, nextitem):
    """Before the fixtures' teardown (the suite's clears the kernel history)."""
    kernels, compiled, seconds = _history()
    with open(os.environ["KERNEL_STATS"], "a", encoding="utf-8") as f:
        f.write(json.dumps([item.nodeid, kernels, compiled, round(seconds, 4)]) + "\n")
    yield


def summary(path: str, rows: int = 25) -> str:
    """The files whose tests compiled longest: seconds, kernels compiled, tests."""
    per_file = collections.defaultdict(lambda: [0.0, 0, 0])
    for line in open(path, encoding="utf-8"):
        nodeid, _, compiled, seconds = json.loads(line)
        entry = per_file[nodeid.partition("::")[0]]
        entry[0] += seconds
        entry[1] += compiled
        entry[2] += 1
    total = sum(e[0] for e in per_file.values())
    lines = [f"{total:.1f} s compiling in {sum(e[2] for e in per_file.values())} tests"]
    for name, (seconds, compiled, tests) in sorted(per_file.items(), key=lambda x: -x[1][0]):
        lines.append(f"{seconds:7.1f} s {compiled:5d} kernels {tests:4d} tests  {name}")
    return "\n".join(lines[:rows + 1])


if __name__ == "__main__":
    print(summary(sys.argv[1]))
