"""
The ``mi-brdfs`` command line (also ``python -m mi_brdfs``): a thin layer over the library.

User errors (a missing scene, a bad parameter, an unwritable output) print one line
``mi-brdfs: error: ...`` and exit with status 2; no traceback. An interrupted render writes what
it has and exits with status 130.

The arguments of each subcommand are in :mod:`mi_brdfs.cli.parser`, the options each mode of a
command takes in :mod:`mi_brdfs.cli.modes`, what each does in :mod:`mi_brdfs.cli.commands`
(those that write a report folder in :mod:`mi_brdfs.cli.reports`).
"""

from __future__ import annotations

import sys
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
        with variant_kept():  # main called in-process leaves the caller's variant set
            return args.func(args)
    except MiBrdfsError as e:
        print(f"mi-brdfs: error: {e}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt as e:  # a long job's runner says what it kept (mi_brdfs.runner)
        print(f"mi-brdfs: {e.args[0] if e.args else 'interrupted; nothing written'}",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (| head): stop quietly, as cat does
        import os
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        return 0
