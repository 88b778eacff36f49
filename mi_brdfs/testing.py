"""
pytest helpers: the checks of :mod:`mi_brdfs.checks` as assertions, for your own test suite and
your own plugin. Each raises ``AssertionError`` with the check's one-line message (what failed,
by how much, where) and returns the :class:`~mi_brdfs.checks.CheckResult` when it passes::

    import mitsuba as mi, mi_brdfs
    from mi_brdfs.testing import assert_energy_conserving, assert_sampling_matches_pdf

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
                     check_furnace, check_ndf, check_positivity, check_reciprocity,
                     check_stability, check_weak_furnace, chi2_bsdf)


def _assert(result: CheckResult) -> CheckResult:
    if not result.passed:
        raise AssertionError(result.message)
    return result


def assert_sampling_matches_pdf(bsdf, wi=(0.0, 0.0, 1.0), **kwargs) -> CheckResult:
    """χ² test of ``sample()`` against ``pdf()`` at ``wi`` (JIT variants)."""
    return _assert(chi2_bsdf(bsdf, wi=wi, **kwargs))


def assert_consistent(bsdf, **kwargs) -> CheckResult:
    """weight = eval/pdf, bs.pdf = pdf(bs.wo), eval_pdf = (eval, pdf), valid sampled flags."""
    return _assert(check_consistency(bsdf, **kwargs))


def assert_energy_conserving(bsdf, **kwargs) -> CheckResult:
    """Directional albedo E(θ) ≤ 1 (within its Monte Carlo error) at every incident angle."""
    return _assert(check_energy(bsdf, **kwargs))


def assert_albedo_matches_eval(bsdf, **kwargs) -> CheckResult:
    """E(θ) from sample() weights = E(θ) from eval() (float64 reference or quadrature)."""
    return _assert(check_albedo_agreement(bsdf, **kwargs))


def assert_reciprocal(bsdf, **kwargs) -> CheckResult:
    """f(a, b) = f(b, a) at random pairs."""
    return _assert(check_reciprocity(bsdf, **kwargs))


def assert_positive(bsdf, **kwargs) -> CheckResult:
    """eval ≥ 0 and pdf ≥ 0, finite, over the whole sphere."""
    return _assert(check_positivity(bsdf, **kwargs))


def assert_stable(bsdfs, **kwargs) -> CheckResult:
    """No NaN/Inf/negative values at stress directions for one BSDF or a list (a grid)."""
    return _assert(check_stability(bsdfs, **kwargs))


def assert_furnace(bsdf, **kwargs) -> CheckResult:
    """The white furnace render is finite and matches the image its albedo curve predicts."""
    return _assert(check_furnace(bsdf, **kwargs))


def assert_ndf_normalized(D, alpha: float, label: str = "D", **kwargs) -> CheckResult:
    """∫ D cosθ dω = 1 for a microfacet distribution given as a callable."""
    return _assert(check_ndf(D, alpha, label, **kwargs))


def assert_weak_furnace(D, G1, alpha: float, label: str = "D, G1", **kwargs) -> CheckResult:
    """Heitz's weak white furnace = 1 for microfacet terms given as callables."""
    return _assert(check_weak_furnace(D, G1, alpha, label, **kwargs))
