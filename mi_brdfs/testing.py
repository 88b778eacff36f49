"""
pytest helpers: the checks of :mod:`mi_brdfs.checks` as assertions, for your own test suite and
your own plugin. Each raises ``AssertionError`` with the check's one-line message (what failed,
by how much, where) and returns the :class:`~mi_brdfs.checks.CheckResult` when it passes::

    import mitsuba as mi
    import mi_brdfs
    from mi_brdfs.testing import (assert_consistent, assert_energy_conserving,
                                  assert_sampling_matches_pdf)
    from my_package import MyBSDF  # your mi.BSDF subclass

    def test_my_bsdf():
        mi_brdfs.use_variant('llvm_ad_rgb')
        mi.register_bsdf('mybsdf', MyBSDF)
        spec = {'type': 'mybsdf', 'roughness': 0.2}
        assert_sampling_matches_pdf(spec, wi=[0.6, 0, 0.8])
        assert_consistent(spec)
        assert_energy_conserving(spec)

A BSDF is given as a ``load_dict`` dict, an XML fragment, ``'type key=value'`` or a loaded
``mi.BSDF``. χ² and the quadrature need a JIT variant (``llvm_*``); the others run everywhere.
"""

from __future__ import annotations

from .checks import (CheckResult, check_albedo_agreement, check_consistency, check_energy,
                     check_furnace, check_gradients, check_ndf, check_positivity,
                     check_reciprocity, check_stability, check_weak_furnace, chi2_bsdf)


def _assert(result: CheckResult) -> CheckResult:
    if not result.passed:
        raise AssertionError(result.message)
    return result


def _assertion(check, name: str, doc: str):
    """``check`` as an assertion: same arguments, raises AssertionError with its message."""

    def assertion(bsdf, **kwargs) -> CheckResult:
        return _assert(check(bsdf, **kwargs))

    assertion.__name__ = assertion.__qualname__ = name
    assertion.__doc__ = doc
    return assertion


def _chi2_as_the_battery(bsdf, res=None, ires=None, **kwargs):
    """χ² with the resolution the battery chooses from the lobe's sharpness unless given
    (Mitsuba's default of 4 integration points per cell rejects correct rough dielectrics)."""
    return chi2_bsdf(bsdf, res=res, ires=ires, **kwargs)


assert_sampling_matches_pdf = _assertion(
    _chi2_as_the_battery, "assert_sampling_matches_pdf",
    "χ² test of ``sample()`` against ``pdf()`` at ``wi`` (default: normal incidence; JIT "
    "variants), at the resolution the battery chooses from the lobe's sharpness unless "
    "``res`` and ``ires`` are given.")
assert_consistent = _assertion(
    check_consistency, "assert_consistent",
    "weight = eval/pdf, bs.pdf = pdf(bs.wo), eval_pdf = (eval, pdf), valid sampled flags.")
assert_energy_conserving = _assertion(
    check_energy, "assert_energy_conserving",
    "∫ f cosθo dωo ≤ 1 at every incident angle (within the Monte Carlo error), estimated from "
    "``sample()`` weights and from ``eval()``.")
assert_albedo_matches_eval = _assertion(
    check_albedo_agreement, "assert_albedo_matches_eval",
    "E(θ) from sample() weights = E(θ) from eval() (float64 reference or quadrature).")
assert_reciprocal = _assertion(
    check_reciprocity, "assert_reciprocal", "f(a, b) = f(b, a) at random pairs.")
assert_positive = _assertion(
    check_positivity, "assert_positive",
    "eval ≥ 0 and pdf ≥ 0, finite, over the whole sphere.")
assert_stable = _assertion(
    check_stability, "assert_stable",
    "No NaN/Inf/negative values at stress directions, for one BSDF or a list (a grid).")
assert_gradients = _assertion(
    check_gradients, "assert_gradients",
    "The derivatives by AD of eval, pdf and the sample weights equal finite differences for "
    "every differentiable parameter (AD variants); a detached pdf or weight is allowed.")
assert_furnace = _assertion(
    check_furnace, "assert_furnace",
    "The white furnace render is finite and matches the image its albedo curve predicts.")


def assert_ndf_normalized(D, alpha: float, label: str = "D", **kwargs) -> CheckResult:
    """∫ D cosθ dω = 1 for a microfacet distribution given as a callable."""
    return _assert(check_ndf(D, alpha, label, **kwargs))


def assert_weak_furnace(D, G1, alpha: float, label: str = "D, G1", **kwargs) -> CheckResult:
    """Heitz's weak white furnace = 1 for microfacet terms given as callables."""
    return _assert(check_weak_furnace(D, G1, alpha, label, **kwargs))
