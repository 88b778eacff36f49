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
    issue: str | None = None       # the issue text with its prior art (validation/audit/upstream)
    #: where a fix landed upstream after the audited release (a pull request's URL and title,
    #: and what of the finding it fixes); None: not fixed in the newest upstream code searched
    fixed_upstream: str | None = None
    #: the Mitsuba build whose plugin it is about (``"eradiate-mitsuba"``: a plugin of that
    #: fork, which may share its name with one of ours); None: Mitsuba's code, in any build
    build: str | None = None

    def covers(self, record: dict) -> bool:
        return ((self.bsdf == "*" or record["bsdf"] == self.bsdf)
                and re.search(self.check, record["check"]) is not None
                and re.search(self.configs, record["config"]) is not None
                and (self.when is None or bool(self.when(record))))


def findings(build: str | None = None) -> list[Finding]:
    """The triage of the audit's failures under ``build`` (default: the installed Mitsuba's,
    :func:`mi_brdfs.registry.mitsuba_build`): :mod:`mi_brdfs.audit.findings`, less those
    about another build's plugins."""
    from .findings import all_findings
    if build is None:
        from ..registry import mitsuba_build
        build = mitsuba_build()[0]
    return [f for f in all_findings() if f.build in (None, build)]


def verdict(record: dict, table=None) -> tuple[str, Finding | None]:
    """(verdict, the finding that gives it) of one record: ``pass`` for a passed check,
    ``untriaged`` for a failure that no finding covers."""
    if record["passed"]:
        return "pass", None
    for f in findings() if table is None else table:
        if f.covers(record):
            return f.verdict, f
    return "untriaged", None


#: Limitations of our own checks that the audit exposed, and how each was fixed: (what the check
#: got wrong, the fix, (test file, test that the old check would fail)).
FIXED_LIMITATIONS = [
    ("bs.pdf vs pdf(bs.wo) judged with one relative tolerance: roughdielectric (α = 0.05) "
     "differs by 0.4 % at cosθi ≈ 0.002, where the generalised half vector of a float32 "
     "direction is that ill-conditioned",
     "the tolerance follows how far pdf and eval/pdf move when one coordinate of either "
     "direction moves by 8·2⁻²⁴, the rounding of a stored float32 direction "
     "(checks.consistency.conditioning)",
     ("tests/checks/test_checks.py",
     "test06b_consistency_tolerance_follows_float32_conditioning")),
    ("samples that failed (weight 0) were judged: roughconductor with sample_visible=false "
     "returns negative bs.pdf there, which the API leaves undefined; and a BSDF none of whose "
     "samples succeeded passed vacuously",
     "only successful samples are judged; no successful sample at all is a failure",
     ("tests/checks/test_checks.py",
     "test06c_consistency_ignores_failed_samples_and_rejects_vacuity")),
    ("reciprocity failed BSDFs that declare NonSymmetric (hair) and wrappers that replace the "
     "shading frame (normalmap, bumpmap; Veach 1997, §5.3)",
     "their asymmetry is measured and reported as expected",
     ("tests/checks/test_checks.py",
     "test13b_reciprocity_expected_where_declared_or_shading_frame")),
    ("reciprocity judged with one relative tolerance at grazing pairs: pplastic loses "
     "ε₃₂/cos² in one order of a pair (its exit transmittance from the refracted cosine)",
     "a per-pair tolerance 1e-4 + 4·ε₃₂/min(cosθa, cosθb)²",
     ("tests/checks/test_checks.py",
     "test13c_reciprocity_tolerance_follows_float32_conditioning_near_grazing")),
    ("the harness's surface had no tangents: bumpmap's perturbed frame degenerated (zero "
     "directions, 'samples outside the domain')",
     "checks.batch.interaction gives a flat surface with dp_du, dp_dv, p and t",
     ("tests/checks/test_checks.py",
     "test06d_bumpmap_needs_the_tangents_the_harness_gives")),
    ("χ² of a BSDF with a Dirac lobe restricted the context to the smooth lobes: mask could "
     "not be tested at all (expected frequency 0), and a wrong probability of choosing the "
     "smooth lobe went unseen",
     "every lobe enabled, Dirac samples counted as failed",
     ("tests/checks/test_lobes.py",
     "test06_chi2_tests_the_selection_of_a_smooth_lobe_beside_a_dirac_one")),
    ("no check saw lobe selection, lobe additivity or the normalisation of pdf(), nor a pdf "
     "that is not 0 across the surface of a BSDF that does not transmit",
     "checks.lobes (ctx.component, additivity, ∫ pdf = fraction of successful samples) and "
     "positivity's 'across the surface'",
     ("tests/checks/test_lobes.py",
     "test02_lobes_rejects")),
    ("Mitsuba's χ² harness raises in polarized variants (its BSDFAdapter masks a Mueller "
     "weight) and cannot judge a Dirac lobe (pdf 0 by convention)",
     "the audit marks it not applicable there; our χ² reduces Mueller weights and handles "
     "Dirac lobes",
     ("tests/checks/test_lobes.py",
     "test06_chi2_tests_the_selection_of_a_smooth_lobe_beside_a_dirac_one")),
]
