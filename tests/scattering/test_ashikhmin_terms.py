"""
The Ashikhmin-Shirley terms on their own (mi_brdfs.scattering.ashikhmin) against the float64
reference written from the paper: the specular and diffuse terms and the lobe's density, the
half-vector sampler against the paper's density (χ² with custom functions), the lobe at
exponents 0 and 10⁶ next to h = n, and the energy bounds the plugin's lobe choice relies on.
"""

import math

import mitsuba as mi
import numpy as np
import pytest
from helpers import assert_matches_reference, random_directions

from mi_brdfs.reference import Ashikhmin
from mi_brdfs.scattering import ashikhmin as terms


def _vectors(a):
    return mi.Vector3f(*[mi.Float(np.ascontiguousarray(a[:, i])) for i in range(3)])


def test01_terms_against_reference(variant_llvm_ad_rgb, np_rng):
    """
    p(ωo) = p_h/(4 k·h), ρs·cosθo and ρd/(Rd (1 − Rs)) against the reference, at
    random pairs and pairs near the mirror direction, isotropic and 1:100 anisotropic.
    """
    n = 4000
    wi = random_directions(np_rng, n, lower=False)
    near = wi[: n // 2] * [-1, -1, 1] + np_rng.normal(0, 0.05, (n // 2, 3))
    wo = np.concatenate([random_directions(np_rng, n - n // 2, lower=False), near])
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    rs = 0.3
    for nu, nv in ((100.0, 100.0), (10.0, 1000.0)):
        ref = Ashikhmin((nu, nv), 1.0, rs)
        pdf, k_dot_h = terms.lobe(_vectors(wi), _vectors(wo), mi.Float(nu), mi.Float(nv))
        cos_i, cos_o = mi.Float(wi[:, 2]), mi.Float(wo[:, 2])
        spec = terms.specular(pdf, terms.fresnel(k_dot_h, rs), cos_i, cos_o)
        assert_matches_reference(np.array(pdf), ref.sampling_pdf, wi, wo, 1e-4, what="pdf")
        assert_matches_reference(np.array(spec), lambda a, b: ref.specular_term(a, b)[:, 0]
                                 * b[:, 2], wi, wo, 1e-4, what=f"specular {nu}, {nv}")
    diffuse = np.array(terms.diffuse(cos_i, cos_o))
    assert_matches_reference(diffuse, lambda a, b: ref.diffuse_term(a, b)[:, 0] / (1 - rs),
                             wi, wo, 1e-4, what="diffuse")


def _sphere_chi2(nu, nv, wrong=False):
    """χ² of :func:`terms.sample_half` against the reference's p_h on the sphere."""
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain
    ref = Ashikhmin((nu, nv))

    def pdf_func(h):
        h = np.stack([np.array(h.x), np.array(h.y), np.array(h.z)], axis=1)
        p = ref.half_pdf(h)
        return mi.Float(p * h[:, 2] * 2.0 if wrong else p)

    test = ChiSquareTest(domain=SphericalDomain(), sample_dim=2, res=101, ires=8,
                         sample_count=200_000, pdf_func=pdf_func,
                         sample_func=lambda u: terms.sample_half(u, nu, nv))
    return test.run(test_count=3, quiet=True), test


@pytest.mark.parametrize("nu,nv", [(0.0, 0.0), (3.0, 60.0), (60.0, 3.0)])
def test02_half_vector_sampler_has_the_papers_density(variant_llvm_ad_rgb, nu, nv):
    """The paper's formulas for φh (extended to four quadrants) and cosθh draw h with its p_h."""
    passed, test = _sphere_chi2(nu, nv)
    assert passed, test.messages


def test03_a_wrong_density_is_rejected(variant_llvm_ad_rgb):
    """The check can fail: p_h with a stray factor 2 cosθh (a density per projected area)."""
    passed, _ = _sphere_chi2(3.0, 60.0, wrong=True)
    assert not passed


def test04_lobe_at_the_exponents_extremes(variant_llvm_ad_rgb):
    """
    At h = n exactly (nu ≠ nv: the exponent (nu hx² + nv hy²)/(1 − hz²) is 0/0) and close to it,
    exponents 0 and 10⁶: finite, and p(ωo) equal to the reference within 1e-4 (the textbook
    pow(n·h, e) rounds n·h to 1 at θh = 5·10⁻⁵ rad, where 1 − n·h = 1.25·10⁻⁹ is below
    float32's spacing there: 0.1 % off at e = 10⁶).
    """
    t = np.array([0.0, 1e-4, 1e-3, 0.3])
    wi = np.stack([np.sin(t), 0 * t, np.cos(t)], axis=1)
    wo = wi * [-1, -1, 1]  # h = n exactly, for every incidence
    tilt = np.stack([np.sin(t) * 0.6, np.sin(t) * 0.8, np.cos(t)], axis=1)  # h at θh = t/2
    wi, wo = np.concatenate([wi, tilt]), np.concatenate([wo, np.tile([0.0, 0.0, 1.0], (4, 1))])
    for nu, nv in ((0.0, 0.0), (1e6, 1e6), (0.0, 1e6), (1e6, 10.0)):
        pdf, k_dot_h = terms.lobe(_vectors(wi), _vectors(wo), mi.Float(nu), mi.Float(nv))
        pdf = np.array(pdf)
        assert np.isfinite(pdf).all() and np.isfinite(np.array(k_dot_h)).all()
        expected = Ashikhmin((nu, nv)).sampling_pdf(wi, wo)
        np.testing.assert_allclose(pdf, expected, rtol=1e-4, atol=1e-30 + 1e-6 * expected.max())


@pytest.mark.parametrize("exponent", [1.0, 100.0, (10.0, 1000.0)], ids=str)
def test05_albedo_within_the_energy_bounds(exponent):
    """
    The paper's claim, energy conservation, from the reference's quadrature: the specular
    albedo stays below Rs + (1 − Rs)(1 − cosθ/2)⁵ and the diffuse albedo equals Rd (1 −
    Rs)(1 − (1 − cosθ/2)⁵), so E(θ) ≤ 1 with Rd = 1 at every Rs, grazing incidence included.
    """
    rs = np.array([0.0, 0.05, 0.5, 1.0])
    ref = Ashikhmin(exponent, 1.0, rs)
    for theta in (0.0, 60.0, 85.0, 89.5):
        t = math.radians(theta)
        bound_s, diffuse = (np.array(b) for b in terms.albedo_bounds(rs, 1.0, math.cos(t)))
        e_s = ref.specular_albedo(t, 0.4, n_t=64, n_phi=128)
        np.testing.assert_allclose(ref.diffuse_albedo(t), diffuse, rtol=1e-12)
        assert (e_s <= bound_s).all(), (theta, e_s, bound_s)
        assert (e_s + diffuse <= 1.0).all()
