"""
The lobe checks (mi_brdfs.checks.lobes): context selection, lobe additivity, pdf normalisation.
Each is shown to accept a correct two-lobe BSDF and built-ins, and to reject a deliberately broken
one: a sampler that ignores ctx.component, an eval that ignores it, a pdf that overstates.
The defects are deterministic (a wrong component, an eval off pointwise, ∫ pdf = 1.2 while
every sample succeeds), so 20 000 samples tell them apart as well as any number; the quick
battery runs both checks (tests/checks/test_checks.py, test23).
"""

import drjit as dr
import mitsuba as mi
import pytest

from mi_brdfs import checks
from mi_brdfs.checks.lobes import check_lobes, check_pdf_integral


def _register_two_lobes():
    """``twolobes``: two Lambertian lobes (ρ = 0.3 and 0.2, components 0 and 1), sampled with
    probability 0.6 and 0.4, with one defect chosen by ``defect``."""

    class TwoLobes(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.defect = props.get("defect", "none")
            flags = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [flags, flags]
            self.m_flags = flags

        def _on(self, ctx):
            if self.defect == "eval_ignores_component":
                return True, True
            return ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 0), \
                ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 1)

        def _pdf_factor(self):
            return 1.2 if self.defect == "pdf_overstated" else 1.0

        def eval(self, ctx, si, wo, active=True):
            a, b = self._on(ctx)
            rho = (0.3 if a else 0.0) + (0.2 if b else 0.0)
            ok = (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, mi.Spectrum(rho * dr.inv_pi) * wo.z, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            a, b = self._on(ctx)
            if self.defect == "pdf_below":  # the density mirrored below the surface
                return dr.select((si.wi.z > 0) & (a or b), dr.abs(wo.z) * dr.inv_pi, 0.0)
            ok = (si.wi.z > 0) & (wo.z > 0) & (a or b)
            return dr.select(ok, self._pdf_factor() * wo.z * dr.inv_pi, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            a, b = (True, True) if self.defect == "sample_ignores_component" else self._on(ctx)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.pdf = self._pdf_factor() * bs.wo.z * dr.inv_pi
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
            first = (sample1 < 0.6) if (a and b) else a
            bs.sampled_component = dr.select(first, mi.UInt32(0), mi.UInt32(1))
            rho = (0.3 if a else 0.0) + (0.2 if b else 0.0)
            ok = (si.wi.z > 0) & (a or b)
            return bs, dr.select(ok, mi.Spectrum(rho), 0.0)

    mi.register_bsdf("twolobes", TwoLobes)


#: Samples per check: see the module docstring.
N = 20_000


@pytest.fixture
def two_lobes(variant_llvm_ad_rgb):
    _register_two_lobes()
    return lambda defect="none": {"type": "twolobes", "defect": defect}


@pytest.mark.parametrize("spec", [None, "cooktorrance diffuse_reflectance=0.5",
                                  "roughdielectric alpha=0.3", "plastic"],
                         ids=["twolobes", "cooktorrance", "roughdielectric", "plastic"])
def test01_lobe_checks_accept(two_lobes, spec):
    for check in (check_lobes, check_pdf_integral):
        result = check(spec or two_lobes(), n=N)
        assert result.passed and not result.skipped, result.message


@pytest.mark.parametrize("defect,what", [("sample_ignores_component", "another sampled_component"),
                                         ("eval_ignores_component", "eval of all lobes")])
def test02_lobes_rejects(two_lobes, defect, what):
    result = check_lobes(two_lobes(defect), n=N)
    assert not result.passed and what in result.message, result.message


def test03_pdf_integral_rejects_an_overstated_pdf(two_lobes):
    """pdf 1.2× the density sample() draws: ∫ pdf = 1.2 while every sample succeeds."""
    result = check_pdf_integral(two_lobes("pdf_overstated"), n=N)
    assert not result.passed and "∫ pdf = 1.2" in result.message, result.message


def test04_one_lobe_and_unresolved_are_not_judged(variant_llvm_ad_rgb):
    assert check_lobes("diffuse").skipped
    result = check_pdf_integral("roughconductor alpha=0.001", n=20_000)
    assert result.skipped and "too sharp" in result.message


def _register_pass_through():
    """``passthrough``: a Dirac pass-through (null) lobe chosen with probability 0.6 and a
    Lambertian lobe with 0.4, as ``mask`` does; ``defect=selection`` makes pdf() report the
    Lambertian density without the factor 0.4 (a wrong lobe-selection weight)."""

    class PassThrough(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.defect = props.get("defect", "none")
            null = int(mi.BSDFFlags.Null | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide)
            diffuse = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [null, diffuse]
            self.m_flags = null | diffuse

        @staticmethod
        def _lobes(ctx):
            return ctx.is_enabled(mi.BSDFFlags.Null, 0), \
                ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 1)

        def _p(self, ctx):
            """The probability of the Lambertian lobe (as pdf() reports it)."""
            null, diffuse = self._lobes(ctx)
            if not diffuse:
                return 0.0
            return 1.0 if self.defect == "selection" or not null else 0.4

        def eval(self, ctx, si, wo, active=True):
            ok = (si.wi.z > 0) & (wo.z > 0) & self._lobes(ctx)[1]
            return dr.select(ok, mi.Spectrum(0.4 * 0.5 * dr.inv_pi) * wo.z, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            ok = (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, self._p(ctx) * wo.z * dr.inv_pi, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            has_null, has_diffuse = self._lobes(ctx)
            p_null = (0.6 if has_diffuse else 1.0) if has_null else 0.0
            bs = dr.zeros(mi.BSDFSample3f)
            null = sample1 < p_null
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
            bs.wo = dr.select(null, -si.wi, wo)
            bs.pdf = dr.select(null, p_null, (1.0 - p_null) * wo.z * dr.inv_pi)
            bs.eta = 1.0
            bs.sampled_type = dr.select(null, mi.UInt32(int(mi.BSDFFlags.Null)),
                                        mi.UInt32(int(mi.BSDFFlags.DiffuseReflection)))
            bs.sampled_component = dr.select(null, mi.UInt32(0), mi.UInt32(1))
            # f·cosθo/pdf: 0.6/0.6 for the pass-through, (0.2 cosθo/π)/(p cosθo/π) for diffuse
            weight = dr.select(null, mi.Spectrum(0.6 / max(p_null, 1e-9)),
                               mi.Spectrum(0.2 / max(1.0 - p_null, 1e-9)))
            return bs, dr.select((si.wi.z > 0) & (has_null | has_diffuse), weight, 0.0)

    mi.register_bsdf("passthrough", PassThrough)


def test06_chi2_tests_the_selection_of_a_smooth_lobe_beside_a_dirac_one(variant_llvm_ad_rgb):
    """χ² with every lobe enabled and Dirac samples counted as failed: mask (a null lobe beside
    diffuse) passes, where restricting the context to the smooth lobe made the test unable to
    run (every sample of the diffuse-only context left it empty); and a pdf that reports the
    smooth lobe without its selection probability is rejected, which the restricted context
    could not see."""
    _register_pass_through()
    wi = checks.batch.direction(0.5)
    mask = {"type": "mask", "opacity": 0.4, "bsdf": {"type": "diffuse"}}
    assert checks.chi2_bsdf(mask, wi=wi, res=None, ires=None).passed
    assert checks.chi2_bsdf({"type": "passthrough"}, wi=wi, res=None, ires=None).passed
    result = checks.chi2_bsdf({"type": "passthrough", "defect": "selection"}, wi=wi,
                              res=None, ires=None)
    assert not result.passed, result.message
    smooth = mi.BSDFContext(mi.TransportMode.Radiance, int(mi.BSDFFlags.DiffuseReflection))
    old = checks.chi2_bsdf({"type": "passthrough", "defect": "selection"}, wi=wi, ctx=smooth,
                           res=None, ires=None)
    assert old.passed  # the restricted context misses the wrong selection weight


def test07_positivity_rejects_a_pdf_across_the_surface(two_lobes):
    """A reflection-only BSDF whose pdf() is not 0 below the surface (as roughplastic's in
    llvm variants, Mitsuba 3.9.1) fails positivity; the correct one and a transmitting
    roughdielectric pass."""
    assert checks.check_positivity(two_lobes(), n=20_000).passed
    assert checks.check_positivity("roughdielectric alpha=0.3", n=20_000).passed
    result = checks.check_positivity(two_lobes("pdf_below"), n=20_000)
    assert not result.passed and result.details["across"] > 0, result.message


def test08_chi2_rejects_a_vacuous_pass(variant_llvm_ad_rgb):
    """A BSDF none of whose samples succeeds (a one-sided diffuse lit from below) fails χ²
    instead of passing on an empty histogram."""
    result = checks.chi2_bsdf("diffuse", wi=[0.0, 0.6, -0.8], res=101, ires=4, rotate=False)
    assert not result.passed and "no sample succeeded" in result.message, result.message


def test09_energy_rejects_a_vacuous_pass(variant_llvm_ad_rgb):
    """A BSDF that reflects nothing at all (a black diffuse: every weight and every eval is 0)
    fails the energy check instead of passing at E = 0; a dark but reflecting one passes."""
    dark = {"type": "diffuse", "reflectance": 0.01}
    assert checks.check_energy(dark, thetas_deg=(0.0, 60.0), n=20_000).passed
    black = {"type": "diffuse", "reflectance": 0.0}
    result = checks.check_energy(black, thetas_deg=(0.0, 60.0), n=20_000)
    assert not result.passed and "vacuously" in result.message, result.message
