"""
The validation library: checks that work on any Mitsuba BSDF (the package's, Mitsuba's built-ins
or a user's own plugin). Each check returns a :class:`CheckResult`; pytest, the command line and
the validation campaign all call the same functions.
"""

from .result import CheckResult
from .sampling import chi2_bsdf

__all__ = ["CheckResult", "chi2_bsdf"]
