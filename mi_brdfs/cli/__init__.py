"""
The ``mi-brdfs`` command line (also ``python -m mi_brdfs``): a thin layer over the library.

User errors (a missing scene, a bad parameter, an unwritable output) print one line
``mi-brdfs: error: ...`` and exit with status 2; no traceback. Ctrl-C (SIGINT) or SIGTERM (what
``timeout`` and batch schedulers send) stops any command with one line and exit status 130: an
interrupted render writes what it has, a long job's runner says what it kept.

The arguments of each subcommand are in :mod:`mi_brdfs.cli.parser`, the options each mode of a
command takes in :mod:`mi_brdfs.cli.modes`, what each does in :mod:`mi_brdfs.cli.commands`
(those that write a report folder in :mod:`mi_brdfs.cli.reports`).
"""

from __future__ import annotations

import signal
import sys
import threading
import warnings

from .commands import EXIT_INTERRUPTED, EXIT_USER_ERROR
from .parser import _parser


def _one_line_warnings():
    """
    A ``warnings.showwarning`` that prints each warning as one line, each distinct one once per
    command: a command loads the same BSDF many times (a fit at every start, for its scores,
    its figures), each load warns again, and Python's record of the warnings shown is reset
    whenever the filters change (matplotlib's style contexts change them).
    """
    shown = set()

    def show(message, category, filename, lineno, file=None, line=None):
        if str(message) not in shown:
            shown.add(str(message))
            print(f"mi-brdfs: warning: {message}", file=sys.stderr if file is None else file)
    return show


def _interrupted(error: BaseException) -> bool:
    """Whether a Ctrl-C caused ``error``: a KeyboardInterrupt in its chain, or Mitsuba's error
    for a Python plugin whose constructor was interrupted, which carries only its text
    ("failed to instantiate ... plugin ...: KeyboardInterrupt: ")."""
    while error is not None:
        if isinstance(error, KeyboardInterrupt) or "KeyboardInterrupt:" in str(error):
            return True
        error = error.__cause__ or error.__context__
    return False


class _TermAsInterrupt:
    """
    While entered in the main thread of a process left with SIGTERM's default (which ends it at
    once, silently, leaving temporary files behind), the first SIGTERM raises KeyboardInterrupt,
    as Ctrl-C does, so that the command stops with one line; should the command not be gone
    :data:`GRACE` seconds later (the interrupt raised inside a Python plugin that Mitsuba was
    running, which reaches the caller as an error it may handle), the default ends the process,
    as does a second SIGTERM. A handler the caller set is left alone.
    """

    GRACE = 10.0

    def __enter__(self):
        self.timer = None
        self.active = (threading.current_thread() is threading.main_thread()
                       and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL)
        if self.active:
            signal.signal(signal.SIGTERM, self._raise)
        return self

    def _raise(self, *_):
        import os

        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        self.timer = threading.Timer(self.GRACE, os.kill, (os.getpid(), signal.SIGTERM))
        self.timer.daemon = True
        self.timer.start()
        raise KeyboardInterrupt

    def __exit__(self, *exc):
        if self.timer is not None:
            self.timer.cancel()
        if self.active:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
        return False


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    warnings.showwarning = _one_line_warnings()
    try:
        import mi_brdfs  # noqa: F401  (preflight: libatomic, libLLVM)
        from ..errors import MiBrdfsError
    except ImportError as e:
        print(f"mi-brdfs: error: {e}", file=sys.stderr)
        return EXIT_USER_ERROR
    from ..registry import quiet_drjit_syntax
    quiet_drjit_syntax()
    from ..variants import variant_kept

    from .modes import check as check_modes

    try:
        check_modes(args)  # an option the mode chosen does not take: before any work
        with variant_kept(), _TermAsInterrupt():  # main called in-process leaves the caller's
            return args.func(args)                # variant set
    except MiBrdfsError as e:
        if not _interrupted(e):
            print(f"mi-brdfs: error: {e}", file=sys.stderr)
            return EXIT_USER_ERROR
        print(f"mi-brdfs: interrupted; {args.command} did not finish", file=sys.stderr)
        return EXIT_INTERRUPTED
    except KeyboardInterrupt as e:  # a long job's runner says what it kept (mi_brdfs.runner)
        said = e.args[0] if e.args else f"interrupted; {args.command} did not finish"
        print(f"mi-brdfs: {said}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (| head): stop quietly, as cat does
        import os
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        return 0
