"""
The triage of the audit's failures, one module per family of BSDFs, each with a ``FINDINGS``
list of :class:`mi_brdfs.audit.triage.Finding`. Every entry states its proof: a reproducer in
``validation/audit/`` for a ``defect``, a finer check that passes for a ``check-limitation``, an
independent implementation or the BSDF's declared flags for a ``model-property``.
"""

from __future__ import annotations

import importlib
import pkgutil


def all_findings() -> list:
    """Every module's FINDINGS, in module order."""
    out = []
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        out += list(getattr(module, "FINDINGS", []))
    return out
