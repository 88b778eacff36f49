"""
Any command stops on SIGTERM (what ``timeout`` and batch schedulers send) as on Ctrl-C: one
line and exit status 130, not a silent end (status 143) that leaves temporary files; a Ctrl-C
while Mitsuba builds a Python plugin, which Mitsuba reports as its own error, is an
interruption too, not a user error.
"""

import subprocess
import sys
import time

import mitsuba as mi

from mi_brdfs.cli import main

_SELF_TERMINATED = """
import os, signal, sys, time
from mi_brdfs.cli import parser

def presets(args):
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(30)
    return 0

parser.cmd_presets = presets
from mi_brdfs.cli import main
sys.exit(main(["presets"]))
"""


def test01_sigterm_stops_a_command_in_one_line():
    clock = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _SELF_TERMINATED], capture_output=True, text=True,
                       timeout=60)
    assert time.perf_counter() - clock < 30
    assert p.returncode == 130, (p.returncode, p.stderr)
    assert p.stderr == "mi-brdfs: interrupted; presets did not finish\n"


def test02_ctrl_c_while_a_plugin_is_built_is_an_interruption(variant_scalar_rgb, capsys,
                                                             tmp_path, monkeypatch):
    def interrupted(props):  # a Ctrl-C while the plugin reads its data
        raise KeyboardInterrupt

    monkeypatch.chdir(tmp_path)
    mi.register_bsdf("interrupted_while_built", interrupted)
    code = main(["check", "interrupted_while_built", "--variant", "scalar_rgb", "--quick"])
    err = capsys.readouterr().err
    assert (code, err) == (130, "mi-brdfs: interrupted; check did not finish\n")
    assert list(tmp_path.iterdir()) == []


_SWALLOWED = """
import os, signal, sys, time
import mi_brdfs.cli
from mi_brdfs.cli import parser

def presets(args):
    try:  # as Mitsuba turns an interrupt inside a Python plugin into an error a caller handles
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(1)
    except KeyboardInterrupt:
        pass
    time.sleep(30)
    return 0

parser.cmd_presets = presets
mi_brdfs.cli._TermAsInterrupt.GRACE = 0.5
sys.exit(mi_brdfs.cli.main(["presets"]))
"""


def test03_a_sigterm_whose_interrupt_is_swallowed_still_ends_the_command():
    clock = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _SWALLOWED], capture_output=True, text=True,
                       timeout=60)
    assert time.perf_counter() - clock < 20
    assert p.returncode == -15, (p.returncode, p.stderr)
