"""
The float64 Hanrahan-Krueger layer (:mod:`mi_brdfs.reference.hk`) against closed forms: the
thin-slab limit (f = a p τ/(μi' μo') T_i T_o/η², the first order of τ), the semi-infinite limit
of reflection (Chandrasekhar's a p/(μi' + μo')), reciprocity; and against its own float64
random walk of the whole transport, tallied by order: the single-scattering albedos reflected
and transmitted, and the unscattered beam, within 4 standard errors. Slow tier: more layers,
and the walk's order-1 lobe in bins of ωo against the closed form integrated over each bin.
"""

import numpy as np
import pytest

from mi_brdfs.reference import hk as ref
from mi_brdfs.reference.quadrature import direction, sphere_grid

WI, WO, WT = direction(0.4), direction(1.1, 2.0), direction(2.3, 0.7)


def _inside(w, eta):
    mu = ref.refracted(abs(w[2]), eta)
    return mu, 1 - ref.fresnel(abs(w[2]), eta), np.array([w[0] / eta, w[1] / eta,
                                                         np.sign(w[2]) * mu])


@pytest.mark.parametrize("eta", [1.0, 1.5])
def test01_thin_slab_limit(eta):
    """τ → 0: both f_r and f_t → a p(cosΘ) τ T_i T_o/(η² μi' μo'), by hand from the paper's
    integrand (each path length in the slab is d/μ')."""
    model = ref.HK(sigma_s=0.6e-6, sigma_a=0.4e-6, thickness=1.0, g=0.4, eta=eta)
    mi_, ti, di = _inside(WI, eta)
    for wo in (WO, WT):
        mo, to, do = _inside(wo, eta)
        p = (1 - 0.16) / (4 * np.pi * (1 + 0.16 - 0.8 * -np.dot(di, do)) ** 1.5)
        expected = 0.6 * p * 1e-6 * ti * to / (eta ** 2 * mi_ * mo)
        assert model.brdf(WI, wo)[0, 0] == pytest.approx(expected, rel=1e-5)


def test02_semi_infinite_reflection_and_opaque_transmission():
    """τ → ∞: f_r → a p/(μi' + μo') T_i T_o/η² (Chandrasekhar 1960 §46), f_t → 0."""
    model = ref.HK(sigma_s=70.0, sigma_a=30.0, thickness=1.0, g=-0.2, eta=1.33)
    mi_, ti, di = _inside(WI, 1.33)
    mo, to, do = _inside(WO, 1.33)
    p = (1 - 0.04) / (4 * np.pi * (1 + 0.04 + 0.4 * -np.dot(di, do)) ** 1.5)
    expected = 0.7 * p * ti * to / (1.33 ** 2 * (mi_ + mo))
    assert model.brdf(WI, WO)[0, 0] == pytest.approx(expected, rel=1e-12)
    assert model.brdf(WI, WT)[0, 0] < 1e-40


@pytest.mark.parametrize("rho", [0.0, 0.5])
def test03_reciprocal(rho):
    """f(ωi, ωo) = f(ωo, ωi), reflection and transmission, at random pairs."""
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 64, 3))
    a, b = (x / np.linalg.norm(x, axis=1, keepdims=True) for x in (a, b))
    a[:, 2] = np.abs(a[:, 2])
    if rho:
        b[:, 2] = np.abs(b[:, 2])
    model = ref.HK(sigma_s=[0.3, 2.0], sigma_a=0.1, thickness=0.8, g=0.6, eta=1.4,
                   diffuse_reflectance=rho)
    fb = model.brdf(a, b)
    bb = np.where(b[:, 2:3] < 0, -b, b)  # from below: the slab is symmetric
    aa = np.where(b[:, 2:3] < 0, -a, a)
    np.testing.assert_allclose(fb, model.brdf(bb, aa), rtol=1e-12)
    assert np.all(fb > 0)


def _single_albedos(model, wi):
    """∫ f|cosθo| dωo of the closed form above and below (Gauss-Legendre)."""
    out = []
    for lo, hi in ((0.0, 1.0), (-1.0, 0.0)):
        dirs, w = sphere_grid(160, 160, (lo, hi))
        f = model.brdf(np.tile(wi, (len(dirs), 1)), dirs)[:, 0]
        out.append(float(np.sum(f * np.abs(dirs[:, 2]) * w)))
    return out


def _assert_walk_agrees(params, theta, n):
    model, wi = ref.HK(**params), direction(theta)
    walk = ref.walk(model, wi, n, np.random.default_rng(7))
    single = (walk.order == 1) & (walk.reflections == 0)
    for side, expected in zip((True, False), _single_albedos(model, wi)):
        mc, se = walk.mean(single & ((walk.wo[:, 2] > 0) == side))
        assert abs(mc - expected) <= 4 * se + 1e-4 * expected, (side, mc, expected, se)
    mc, se = walk.mean((walk.order == 0) & (walk.reflections == 0) & (walk.wo[:, 2] < 0))
    expected = model.unscattered(wi[2])[0, 0]
    assert abs(mc - expected) <= 4 * se + 1e-12, (mc, expected, se)


SETS = [
    ({"sigma_s": 1.5, "sigma_a": 0.5, "thickness": 0.7, "g": -0.3, "eta": 1.5}, 0.6),
    ({"sigma_s": 0.9, "sigma_a": 0.1, "thickness": 1.0, "g": 0.7}, 1.2),
    ({"sigma_s": 4.0, "sigma_a": 1.0, "thickness": 0.5, "g": 0.0, "eta": 1.33}, 0.1),
    ({"sigma_s": 0.6, "sigma_a": 0.2, "thickness": 1.0, "g": 0.3, "eta": 1.33,
      "diffuse_reflectance": 0.7}, 0.9),
]


@pytest.mark.parametrize("params,theta", SETS, ids=[str(i) for i in range(len(SETS))])
def test04_single_term_and_beam_equal_the_walk(params, theta):
    """The walk's paths of one event and no internal reflection carry the closed form's
    albedos, above and below; its unscattered paths the beam T² e^{−τ/μ'}."""
    _assert_walk_agrees(params, theta, 100_000)


def test05_single_lobe_in_bins_equals_the_walk():
    """The walk's order-1 exits in 4 × 6 bins of (μo, φo), each against the closed form
    integrated over the bin, within 4 standard errors (η = 1.5, forward-scattering g = 0.6)."""
    params = {"sigma_s": 1.2, "sigma_a": 0.3, "thickness": 0.8, "g": 0.6, "eta": 1.5}
    model, wi = ref.HK(**params), direction(0.7)
    walk = ref.walk(model, wi, 400_000, np.random.default_rng(11))
    single = (walk.order == 1) & (walk.reflections == 0)
    mu, phi = walk.wo[:, 2], np.arctan2(walk.wo[:, 1], walk.wo[:, 0])
    edges_mu, edges_phi = np.linspace(-1, 1, 5), np.linspace(-np.pi, np.pi, 7)
    for a, b in zip(edges_mu[:-1], edges_mu[1:]):
        dirs, w = sphere_grid(48, 240, (a, b))
        f = model.brdf(np.tile(wi, (len(dirs), 1)), dirs)[:, 0] * np.abs(dirs[:, 2]) * w
        p = np.arctan2(dirs[:, 1], dirs[:, 0])
        for c, d in zip(edges_phi[:-1], edges_phi[1:]):
            expected = f[(p >= c) & (p < d)].sum()
            mc, se = walk.mean(single & (mu >= a) & (mu < b) & (phi >= c) & (phi < d))
            assert abs(mc - expected) <= 4 * se + 2e-3 * expected, (a, c, mc, expected, se)
