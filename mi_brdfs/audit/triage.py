"""
The audit's verdicts: every failure of a check on a BSDF gets one, with the proof behind it.

=====================  ============================================================================
verdict                meaning
=====================  ============================================================================
``defect``             a defect of the BSDF: a standalone reproducer (``validation/audit/repro_*``)
                       exits 1 while it is present, and the cause is located in Mitsuba's source
``check-limitation``   a limitation of the check (ours or Mitsuba's harness), shown by a finer
                       check that passes; where it was ours, the check was fixed
``model-property``     declared by the BSDF (e.g. ``NonSymmetric``) or inherent to the published
                       model, shown against an independent implementation of that model
``statistical``        a false rejection that other seeds and a rotated domain do not repeat
``pass``               the check passed
=====================  ============================================================================

:data:`FINDINGS` holds the triage, one entry per (BSDF, check, configurations); a failure that no
entry covers is ``untriaged`` in the report, which is the audit's own open work.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

VERDICTS = ("defect", "check-limitation", "model-property", "statistical", "pass")


@dataclass(frozen=True)
class Finding:
    """One triaged failure: which records it covers, its verdict and its proof."""

    bsdf: str              # the plugin name as in XML ("*": every BSDF)
    check: str             # a regular expression on the check's name (e.g. "mitsuba chi2")
    configs: str           # a regular expression on the configuration label ("" = every one)
    verdict: str
    summary: str           # one paragraph: what fails, why, and the proof
    reproducer: str | None = None  # path relative to the repository root
    source: str | None = None      # where in Mitsuba's source (file, function, lines)
    when: object = None            # a further condition on the record (a function), or None

    def covers(self, record: dict) -> bool:
        return ((self.bsdf == "*" or record["bsdf"] == self.bsdf)
                and re.search(self.check, record["check"]) is not None
                and re.search(self.configs, record["config"]) is not None
                and (self.when is None or bool(self.when(record))))


def findings() -> list[Finding]:
    """The triage of the audit's failures: :mod:`mi_brdfs.audit.findings`."""
    from .findings import all_findings
    return all_findings()


def verdict(record: dict, table=None) -> tuple[str, Finding | None]:
    """(verdict, the finding that gives it) of one record: ``pass`` for a passed check,
    ``untriaged`` for a failure that no finding covers."""
    if record["passed"]:
        return "pass", None
    for f in findings() if table is None else table:
        if f.covers(record):
            return f.verdict, f
    return "untriaged", None
