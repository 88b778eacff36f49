"""The plain data object every check returns."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class CheckResult:
    """
    The outcome of one check: what was measured, against what tolerance, and whether it passed.

    ``value`` is the measured statistic (a p-value, a relative error, a count, ...),
    ``tolerance`` what it was compared with, ``message`` one line for a human, ``details`` the
    numbers behind it (for reports and plots).
    """

    name: str
    passed: bool
    value: float
    tolerance: float | str
    message: str
    details: dict = field(default_factory=dict)
    #: The check did not apply (e.g. χ² in a scalar variant, or on Dirac lobes): passed, not run.
    skipped: bool = False

    def __bool__(self) -> bool:
        return self.passed
