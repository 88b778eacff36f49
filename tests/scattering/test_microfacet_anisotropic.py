"""
The anisotropic microfacet terms (α a pair (αu, αv)): D and Mitsuba's G1 against
mi.MicrofacetDistribution with two roughnesses, all terms against the float64 reference, the
term-level integrals (∫ D cosθ = 1, Heitz's weak white furnace) in several azimuths, and the
samplers of microfacet normals by χ² for αu/αv up to 10:1 at normal, 45° and grazing incidence.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import random_directions
from test_microfacet_terms import chi2_normals, distribution, vec

from mi_brdfs import checks
from mi_brdfs.reference import cooktorrance as ref
from mi_brdfs.scattering import microfacet as mf

KINDS = ["beckmann", "ggx"]
PAIRS = [(0.05, 0.5), (0.5, 0.05), (1e-4, 0.3), (0.1, 1.0)]


def _normals(rng, n, au, av):
    """Microfacet normals over the hemisphere and concentrated within the lobe's ellipse."""
    near = random_directions(rng, n, lower=False) * [au, av, 1]
    near /= np.linalg.norm(near, axis=1, keepdims=True)
    return np.concatenate([random_directions(rng, n, lower=False), near])


def _alpha(pair):
    return tuple(mi.Float(a) for a in pair)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("pair", PAIRS)
def test01_d_and_g1_are_mitsubas(variant_llvm_ad_rgb, np_rng, kind, pair):
    """D and the rational G1 are bit-identical to mi.MicrofacetDistribution(αu, αv)'s."""
    distr = mi.MicrofacetDistribution(mf.mitsuba_type(kind), *pair, True)
    m = vec(_normals(np_rng, 20_000, *pair))
    v = vec(random_directions(np_rng, 40_000))
    ours = distribution(kind, _alpha(pair))
    np.testing.assert_array_equal(np.array(ours.ndf(m)), np.array(distr.eval(m)))
    np.testing.assert_array_equal(np.array(ours.smith_g1_mitsuba(v, m)),
                                  np.array(distr.smith_g1(v, m)))


@pytest.mark.parametrize("kind", KINDS)
def test02_terms_match_the_float64_reference(variant_llvm_ad_rgb, np_rng, kind):
    """D, Λ and both Smith G1 in float32 against the float64 reference, which writes them
    differently (the quadratic form of the slopes; Λ of the roughness in the azimuth)."""
    pair = (0.08, 0.6)
    m = _normals(np_rng, 20_000, *pair)
    wi, wo = random_directions(np_rng, 40_000, lower=False), random_directions(np_rng, 40_000)
    a = _alpha(pair)
    for ours, theirs in [
        (distribution(kind, a).ndf(vec(m)), ref.ndf(kind, pair, m)),
        (distribution(kind, a).smith_lambda(vec(wi)), ref.smith_lambda(kind, pair, wi)),
        (distribution(kind, a).smith_g1(vec(wo), vec(m)), ref.smith_g1(kind, pair, wo, m)),
        (distribution(kind, a).smith_g1_mitsuba(vec(wo), vec(m)),
         ref.smith_g1_rational(kind, pair, wo, m)),
    ]:
        ours = np.array(ours, dtype=np.float64)
        np.testing.assert_allclose(ours, theirs, rtol=2e-4, atol=1e-6 * np.max(theirs))


@pytest.mark.parametrize("kind", KINDS)
def test03_anisotropy_is_seen(variant_llvm_ad_rgb, kind):
    """The pair is not read as one α: D of (αu, αv) differs from D of (αv, αu) off the axes'
    diagonal and equals it after swapping x and y; the isotropic pair equals the plain α."""
    m = mi.Vector3f(0.3, 0.1, math.sqrt(1 - 0.1))
    swapped = mi.Vector3f(m.y, m.x, m.z)
    d_uv = distribution(kind, _alpha((0.1, 0.4))).ndf(m)
    d_vu = distribution(kind, _alpha((0.4, 0.1)))
    assert abs(d_uv[0] - d_vu.ndf(m)[0]) > 0.1 * d_uv[0]
    assert d_uv[0] == pytest.approx(d_vu.ndf(swapped)[0], rel=1e-6)
    isotropic = distribution(kind, mi.Float(0.2)).ndf(m)[0]
    assert distribution(kind, _alpha((0.2, 0.2))).ndf(m)[0] == isotropic


@pytest.mark.parametrize("kind,pair", [("beckmann", (0.1, 1.0)), ("ggx", (1.0, 0.1))])
def test04_ndf_normalised_and_weak_white_furnace(variant_llvm_ad_rgb, kind, pair):
    """∫ D cosθ dω = 1 and the weak white furnace = 1 within 1e-3, exact Smith and V-cavity
    masking, float32 terms and the float64 reference, αu/αv = 1:10 and 10:1, the azimuth of ωo
    taking 0°, 45° and 90° in turn. Each (distribution, pair, masking, terms) in every
    azimuth, for four pairs down to α = 0.05 (a finer quadrature: NumPy's Gauss-Legendre
    nodes for it cost seconds), runs in ``make validate``, section anisotropy."""
    D64 = lambda m: ref.ndf(kind, pair, m)
    masks = {"smith": lambda v, m: ref.smith_g1(kind, pair, v, m), "vcavity": ref.vcavity_g1}
    phis = iter((0.0, 45.0, 90.0, 45.0))
    for masking in ("smith", "vcavity"):
        D, G1 = checks.package_terms(kind, pair, masking)
        for d, g1, what in ((D, G1, "float32"), (D64, masks[masking], "float64")):
            label = f"{kind} α={pair} {masking} {what}"
            assert checks.check_ndf(d, pair, label).passed
            result = checks.check_weak_furnace(d, g1, pair, label, phi_deg=next(phis))
            assert result.passed, result.message


def test05_weak_furnace_rejects_a_mismatched_masking(variant_llvm_ad_rgb):
    """The furnace can fail here: Smith's G1 of the swapped pair (αv, αu) with D of (αu, αv)
    leaves the visible normals unnormalised at grazing angles."""
    pair = (0.1, 1.0)
    D = lambda m: ref.ndf("ggx", pair, m)
    G1 = lambda v, m: ref.smith_g1("ggx", pair[::-1], v, m)
    result = checks.check_weak_furnace(D, G1, pair, "mismatched", phi_deg=0.0)
    assert not result.passed, result.message


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("pair", [(0.05, 0.5), (0.5, 0.05)])
@pytest.mark.parametrize("theta", [0.0, math.pi / 4, 1.45])
def test06_normal_samplers_match_their_densities(variant_llvm_ad_rgb, kind, pair, theta):
    """sample_ndf ~ D cosθ, sample_visible ~ the visible normals with the exact G1, and the
    V-cavity's visible normals ~ their density, for αu/αv = 10:1 and 1:10, at normal, 45° and
    grazing incidence (wi in an azimuth between the axes)."""
    a = _alpha(pair)
    wi = mi.Vector3f(math.sin(theta) * math.cos(0.6), math.sin(theta) * math.sin(0.6),
                     math.cos(theta))
    dr.make_opaque(wi)
    if theta == 0.0:
        ok, p = chi2_normals(lambda u: distribution(kind, a).sample(u),
                             lambda m: mf.pdf_ndf(distribution(kind, a).ndf(m), m))
        assert ok, p
    ok, p = chi2_normals(lambda u: distribution(kind, a).sample_visible(wi, u),
                         lambda m: mf.pdf_visible(distribution(kind, a).ndf(m),
                                                  distribution(kind, a).smith_g1(wi, m), wi, m))
    assert ok, p

    def vcavity(u):
        return distribution(kind, a).sample_vcavity_visible(wi, mi.Point2f(u.x, u.y), u.z)

    ok, p = chi2_normals(vcavity, lambda m: mf.pdf_visible(distribution(kind, a).ndf(m),
                                                           mf.vcavity_g1(wi, m), wi, m), dim=3)
    assert ok, p


def test07_chi2_rejects_the_isotropic_sampler(variant_llvm_ad_rgb):
    """The χ² above can fail: normals drawn with the isotropic √(αu αv) do not follow the
    anisotropic D cosθ."""
    a = _alpha((0.05, 0.5))
    ok, p = chi2_normals(lambda u: distribution("beckmann", mi.Float(math.sqrt(0.025))).sample(u),
                         lambda m: mf.pdf_ndf(distribution("beckmann", a).ndf(m), m))
    assert not ok, p
