"""
The Phong terms on their own (mi_brdfs.scattering): the stable log1p/expm1, the lobe samplers
against their densities over the whole sphere (χ² with custom functions, as Mitsuba tests its
microfacet samplers), the cosⁿ evaluation at its edges, and the normalisations against the
float64 reference.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.reference import Phong
from mi_brdfs.scattering import phong as lobes
from mi_brdfs.scattering import stable


def test01_log1p_expm1_accuracy(variants_rgb):
    """
    Relative error ≤ 3e-7 (float32: a few ulp) over 12 decades in JIT variants, while the plain
    log(1 + x) and exp(x) − 1 that they replace are off by up to 100 % there; in scalar variants
    (Python floats, float64) within a few float64 ulp of Python's own.
    """
    x = -np.logspace(-12, math.log10(0.98), 2000)
    y = -np.logspace(-12, math.log10(32), 2000)
    if dr.is_jit_v(mi.Float):
        X, Y = mi.Float(x.astype(np.float32)), mi.Float(y.astype(np.float32))
        x, y = x.astype(np.float32).astype(np.float64), y.astype(np.float32).astype(np.float64)
        got = np.array(stable.log1p(X)), np.array(stable.expm1(Y))
        plain = np.array(dr.log(1.0 + X)), np.array(dr.exp(Y) - 1.0)
        for a, b, ref in zip(got, plain, (np.log1p(x), np.expm1(y))):
            assert np.max(np.abs(a / ref - 1)) < 3e-7
            assert np.max(np.abs(b / ref - 1)) > 0.5  # the check can fail
    else:
        for f, ref, values in ((stable.log1p, math.log1p, x), (stable.expm1, math.expm1, y)):
            err = max(abs(f(float(v)) / ref(float(v)) - 1.0) for v in values)
            assert err < 1e-15
            assert max(abs((1.0 + v - 1.0) / v - 1.0) for v in values) > 1e-6  # can fail
        assert stable.log1p(-1.0) == -math.inf and stable.expm1(-math.inf) == -1.0


def _chi2(sample, pdf, wi, n):
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain
    wi = mi.Vector3f(*[float(c) for c in np.asarray(wi) / np.linalg.norm(wi)])
    inv_n1 = 1.0 / (n + 1.0)
    mirror = sample is lobes.sample_mirror
    # The halfway density has an integrable 1/|ωi + ωo| singularity at ωo = −ωi, below the
    # surface, which χ²'s per-cell integration cannot resolve: that lobe is compared on the
    # upper hemisphere (the plugin's domain), samples below count as failed.

    def sample_func(u):
        wo = sample(wi, u, inv_n1)
        return wo if mirror else (wo, dr.select(wo.z > 0, 1.0, 0.0))

    def pdf_func(wo):
        density = pdf(wi, wo, n, lobes.pdf_normalization(n))[1]
        return density if mirror else dr.select(wo.z > 0, density, 0.0)

    test = ChiSquareTest(domain=SphericalDomain(), sample_dim=2, res=201, ires=16,
                         sample_count=500_000, sample_func=sample_func, pdf_func=pdf_func)
    return test.run(test_count=8, quiet=True), test


@pytest.mark.parametrize("n", [1.0, 50.0])
@pytest.mark.parametrize("wi", [[0, 0, 1], [0.99, 0, 0.1]], ids=["normal", "grazing"])
@pytest.mark.parametrize("lobe", ["mirror", "halfway"])
def test02_samplers_match_their_densities(variant_llvm_ad_rgb, lobe, wi, n):
    """The mirror lobe over the whole sphere (below the surface too), the halfway lobe above it."""
    sample = lobes.sample_mirror if lobe == "mirror" else lobes.sample_halfway
    pdf = lobes.mirror_lobe if lobe == "mirror" else lobes.halfway_lobe
    passed, test = _chi2(sample, pdf, wi, n)
    assert passed, test.messages


def test03_sampler_with_a_wrong_density_is_rejected(variant_llvm_ad_rgb):
    """The check can fail: the halfway sampler judged by the density without its Jacobian."""
    def no_jacobian(wi, wo, n, pdf_norm):
        value, _ = lobes.halfway_lobe(wi, wo, n, pdf_norm)
        return value, pdf_norm * value
    passed, _ = _chi2(lobes.sample_halfway, no_jacobian, [0.6, 0, 0.8], 50.0)
    assert not passed


def test04_cos_power_edges(variant_llvm_ad_rgb):
    """n = 0 is the hemisphere about the axis; no NaN at the edge, in values nor gradients."""
    x = mi.Float([0.0, 0.5, 1.0 - 2 ** -24, 1.0, 1.5, 2.0])
    for n, expected in ((0.0, [1, 1, 1, 0, 0, 0]), (1.0, [1, 0.5, 2 ** -24, 0, 0, 0])):
        np.testing.assert_allclose(np.array(lobes.cos_power(x, n)), expected, rtol=1e-6)
    n = mi.Float(0.0)
    dr.enable_grad(x, n)
    value = lobes.cos_power(x, n)
    dr.backward(dr.sum(value))
    assert np.isfinite(np.array(dr.grad(x))).all() and np.isfinite(np.array(dr.grad(n))).all()
    big = lobes.cos_power(mi.Float([0.0, 1e-31, 1e-8, 0.5]), 1e30)
    np.testing.assert_allclose(np.array(big), [1.0, math.exp(-0.1), 0.0, 0.0], rtol=1e-6)


@pytest.mark.parametrize("lobe", ["mirror", "halfway"])
@pytest.mark.parametrize("form", ["normalized", "lecture", "original"])
def test05_normalizations_match_the_reference(variant_llvm_ad_rgb, form, lobe):
    """Float32 constants against the float64 reference, and finite up to n = 1e30."""
    for n in (0.0, 1.0, 30.0, 1e4, 1e8, 1e30):
        model = Phong(0.0, 1.0, n, form, lobe)
        norm = float(lobes.specular_normalization(form, lobe, mi.Float(n))[0])
        albedo = float(lobes.specular_albedo(form, lobe, mi.Float(n))[0])
        assert norm == pytest.approx(model.normalization, rel=1e-6)
        if n <= 1e8:  # the reference's quadrature needs float64 to stay above underflow
            assert albedo == pytest.approx(model.specular_albedo(0.0), rel=1e-6)
        assert math.isfinite(norm) and math.isfinite(albedo) and albedo > 0
