"""
The Mitsuba variant kept across a call: an entry point that sets a variant of its own (``fit``
needs an AD variant, ``simplify`` measures in the one it is given, a command takes
``--variant``) hands the caller's variant back when it returns, and when it raises.

    with variant_kept():
        mi.set_variant("llvm_ad_rgb")
        ...                      # the caller's variant is set again on the way out

Where no variant was set on the way in, the one set inside stays (Mitsuba cannot unset one).
"""

from __future__ import annotations

import contextlib
import functools


@contextlib.contextmanager
def variant_kept():
    """Restore the variant current on entry (if any) on the way out, also after an exception;
    yields that variant (None where none was set)."""
    import mitsuba as mi

    before = mi.variant()
    try:
        yield before
    finally:
        if before is not None and mi.variant() != before:
            mi.set_variant(before)


def keeps_variant(fn):
    """Decorator: ``fn`` runs inside :func:`variant_kept`."""
    @functools.wraps(fn)
    def kept(*args, **kwargs):
        with variant_kept():
            return fn(*args, **kwargs)
    return kept
