"""
Lafortune's generalized cosine lobe on its own (mi_brdfs.scattering.lafortune) against the
float64 reference written from the paper, the sampler about the principal direction against its
density (χ² with custom functions), the strategy choice, and the reference's lobe-aligned albedo
quadrature against brute force.
"""

import itertools
import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import assert_matches_reference, random_directions

from mi_brdfs.reference import Lafortune
from mi_brdfs.reference.lafortune import cosine_lobe_integral
from mi_brdfs.reference.quadrature import hemisphere_albedo
from mi_brdfs.scattering import lafortune as terms
from mi_brdfs.scattering import mixture

#: (Cx, Cy, Cz, n): Phong's mirror lobe, retro-reflection, off-specular towards grazing, an
#: anisotropic one with a negative Cz, one along the normal only, no lobe at all.
LOBES = [(-1.0, -1.0, 1.0, 30.0), (1.0, 1.0, 1.0, 8.0), (-1.0, -1.0, 0.4, 12.0),
         (0.9, -0.3, -0.5, 3.0), (0.0, 0.0, 0.7, 2.0), (0.0, 0.0, 0.0, 5.0)]


def _lobe_terms(wi, wo, cx, cy, cz, n, normalize):
    """(K·rⁿ·cosⁿβ, sampling density) of the terms, as NumPy arrays."""
    lobe = terms.Lobe(mi.Float(cx), mi.Float(cy), mi.Float(cz), mi.Float(n), normalize)
    if dr.is_jit_v(mi.Float):
        w_i, w_o = mi.Vector3f(wi.T.astype(np.float32)), mi.Vector3f(wo.T.astype(np.float32))
        d, scale = terms.axis(w_i, lobe)
        return tuple(np.array(x, dtype=np.float64) for x in terms.lobe_value(w_o, d, scale, lobe))
    out = [terms.lobe_value(mi.Vector3f(*b), *terms.axis(mi.Vector3f(*a), lobe), lobe)
           for a, b in zip(wi, wo)]  # scalar variants: Python floats, one pair at a time
    return tuple(np.array([o[k] for o in out]) for k in (0, 1))


def _lobes_match_the_reference(rng):
    """K·max(0, g/c)ⁿ at random pairs and pairs near the principal direction, both forms; the
    density (n+1)/(2π)·cosⁿβ about the reference's axis C∘ωi/|C∘ωi|."""
    n_pairs = 24 if mi.variant().startswith("scalar") else 2000
    wi = random_directions(rng, n_pairs, lower=False)
    for (cx, cy, cz, n), normalize in itertools.product(LOBES, (True, False)):
        ref = Lafortune([dict(cx=cx, cy=cy, cz=cz, exponent=n)], 0.0, normalize)
        axis = ref._axis(0, wi)[0]
        near = axis[: n_pairs // 2] + rng.normal(0, 0.1, (n_pairs // 2, 3))
        wo = np.concatenate([random_directions(rng, n_pairs - n_pairs // 2), near])
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        value, density = _lobe_terms(wi, wo, cx, cy, cz, n, normalize)
        if cx == cy == cz == 0:  # g = 0 everywhere: no lobe, for any n
            assert not value.any() and np.isfinite(density).all()
            continue
        assert_matches_reference(value, lambda a, b: ref.lobe(0, a, b), wi, wo, 1e-4,
                                 what=f"C = {(cx, cy, cz)}, n = {n}")
        cos = np.sum(ref._axis(0, wi)[0] * wo, axis=1)
        expected = (n + 1) / (2 * math.pi) * np.where(cos > 0, np.maximum(cos, 0) ** n, 0)
        np.testing.assert_allclose(density, expected, rtol=2e-4, atol=1e-6 * expected.max())


def test01_lobe_against_the_reference(variant_llvm_ad_rgb, np_rng):
    _lobes_match_the_reference(np_rng)


@pytest.mark.parametrize("wi", [[0.0, 0.0, 1.0], [0.98, 0.0, 0.2], [0.3, -0.99, 0.05]],
                         ids=["normal", "78deg", "87deg"])
def test02_sampler_matches_its_density(variant_llvm_ad_rgb, wi):
    """cosⁿβ about the principal direction of an anisotropic off-specular lobe, over the whole
    sphere (also where d lies below the horizon), with Mitsuba's χ²."""
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain
    lobe = terms.Lobe(mi.Float(-1.0), mi.Float(-0.6), mi.Float(-0.3), mi.Float(8.0), True)
    w = mi.Vector3f(*[float(c) for c in np.asarray(wi) / np.linalg.norm(wi)])
    d = terms.axis(w, lobe)[0]
    test = ChiSquareTest(domain=SphericalDomain(), sample_dim=2, res=101, ires=4,
                         sample_count=200_000,
                         sample_func=lambda u: terms.sample(d, u, lobe.inv_n1),
                         pdf_func=lambda wo: terms.lobe_value(wo, d, 1.0, lobe)[1])
    assert test.run(test_count=3, quiet=True), test.messages


def test03_strategy_choice(variant_llvm_ad_rgb):
    """mixture.choose() picks strategy k with probability pₖ = wₖ/Σw; one of weight 0 never;
    equal probabilities where every weight is 0; the rescaled number is uniform in [0, 1)
    within each strategy's interval."""
    u = mi.Float((np.arange(100_000) + 0.5) / 100_000)
    probs = mixture.probabilities([mi.Float(0.4), mi.Float(0.0), mi.Float(1.2), mi.Float(0.4)])
    k, rescaled = mixture.choose(probs, u)
    counts = np.bincount(np.array(k), minlength=4) / 100_000
    np.testing.assert_allclose(counts, [0.2, 0.0, 0.6, 0.2], atol=1e-4)
    for j in (0, 2, 3):
        within = np.sort(np.array(rescaled)[np.array(k) == j])
        assert 0.0 <= within[0] and within[-1] < 1.0 + 1e-6
        np.testing.assert_allclose(within, (np.arange(len(within)) + 0.5) / len(within),
                                   atol=2e-4)
    equal = mixture.probabilities([mi.Float(0.0), mi.Float(0.0)])
    assert [float(p[0]) for p in equal] == [0.5, 0.5]


def test04_reference_albedo_quadrature(variant_scalar_rgb):
    """The lobe-aligned quadrature against brute force (Gauss-Legendre × midpoint, 256²) for
    axes above and below the horizon (n ≥ 2: brute force resolves the clipped lobe's edge to
    1e-9); 2π/(n+2) about the normal, the largest of any axis."""
    for theta_axis in (0.3, 1.8, 2.6):
        axis = np.array([math.sin(theta_axis), 0.0, math.cos(theta_axis)])
        for n in (3.0, 20.0):
            def lobe(wi, wo):
                return np.maximum(wo @ axis, 0.0)[:, None] ** n
            brute = hemisphere_albedo(lobe, 0.0, 256, 256)[0]
            assert cosine_lobe_integral(theta_axis, n) == pytest.approx(brute, rel=1e-8)
    for n in (0.0, 1.0, 10.0, 1e4):
        top = cosine_lobe_integral(0.0, n)
        assert top == pytest.approx(2 * math.pi / (n + 2), rel=1e-9)
        assert all(cosine_lobe_integral(t, n) < top for t in np.linspace(0.05, math.pi, 12))
    # and the albedo of a three-lobe model against brute force of its brdf at 50°
    model = Lafortune([dict(cx=-1.0, cy=-1.0, cz=0.4, exponent=4.0),
                       dict(cx=1.0, cy=1.0, cz=1.0, exponent=3.0, specular_reflectance=0.3),
                       dict(cx=0.8, cy=-0.3, cz=0.5, exponent=2.0)], 0.1)
    theta = math.radians(50.0)
    brute = hemisphere_albedo(model.brdf, theta, 256, 256)
    np.testing.assert_allclose(model.albedo(theta), brute, rtol=1e-8)


def test05_lobe_against_the_reference_in_scalar_rgb(variant_scalar_rgb, np_rng):
    """test01 with Python floats, one pair at a time (last: each change to an LLVM variant
    costs a tenth of a second)."""
    _lobes_match_the_reference(np_rng)
