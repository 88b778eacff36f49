"""
What the MODIS BRDF/albedo algorithm does with the Ross-Thick Li-Sparse-Reciprocal kernels
(Lucht, Schaaf & Strahler 2000, IEEE TGRS 38(2)), against the ``rtls`` plugin and its float64
reference: the black-sky albedo polynomials of Table 1 against the float64 quadrature of the
kernels (their error measured); the plugin's white furnace (black-sky and white-sky albedo)
against the kernels' integrals where the clamp does not act; the linear inversion of the
kernels (reference) and the AD fit (``mi-brdfs fit TARGET --model rtls``), which coincide under
the ``ngan`` metric.
"""

import math

import numpy as np
import pytest

from mi_brdfs import earth
from mi_brdfs.checks import batch
from mi_brdfs.checks.albedo import albedo_sampled
from mi_brdfs.fit import fit
from mi_brdfs.fit.optimise import direction_pairs, metric_weights
from mi_brdfs.reference import rtls as ref

#: The defaults (f_geo > 0: the clamp acts near the horizon) and a surface where it never
#: acts (f_geo = 0 and f_vol < 7.2 f_iso: K_vol ≥ −0.139).
DEFAULTS = (0.209741, 0.081384, 0.004140)
UNCLAMPED = (0.2, 0.1, 0.0)
#: The polynomials' largest error against the quadrature for θ ≤ 75°, measured on a 5° grid
#: (vol: −0.0248 at 75°; geo: +0.0063 at 65°); at 80° they reach −0.075 and −0.006, at 85°
#: −0.19 and −0.017, at 89° −0.42 and −0.030.
POLY_ERR = {"vol": 0.025, "geo": 0.0065}

#: The clamp's warning at load is tested in test_rtls.py.
pytestmark = pytest.mark.filterwarnings("ignore::mi_brdfs.errors.MiBrdfsWarning")


def test01_black_sky_polynomials_against_the_kernels_quadrature():
    """g0 + g1 θ² + g2 θ³ (Table 1) against ∫ K cosθo dωo/π by float64 quadrature: within
    :data:`POLY_ERR` up to 75°, a fit that worsens beyond (−0.075 for K_vol at 80°); the exact
    nadir values, −0.021079 and −1.288854, from the 1-D integrals of the kernels at θi = 0."""
    thetas = np.radians([0.0, 30.0, 45.0, 65.0, 75.0])
    quad = np.array([ref.kernel_black_sky(t, n_mu=128, n_phi=128) for t in thetas])
    np.testing.assert_allclose(quad[0], [-0.021079, -1.288854], atol=2e-6)
    for k, name in enumerate(("vol", "geo")):
        poly = ref.black_sky_polynomial(thetas, 0.0, k == 0, k == 1)
        assert np.max(np.abs(poly - quad[:, k])) < POLY_ERR[name], (name, poly - quad[:, k])
    vol80 = ref.kernel_black_sky(math.radians(80), n_mu=128, n_phi=128)[0]
    assert ref.black_sky_polynomial(math.radians(80), 0, 1, 0) - vol80 < -0.07


def test02_white_sky_is_the_integral_of_the_black_sky():
    """2 ∫ black-sky(θ) cosθ sinθ dθ of the kernels' quadrature = Table 1's white-sky
    integrals, 0.189184 and −1.377622, to 10⁻⁴; RTLS.white_sky is f_iso + 0.189184 f_vol −
    1.377622 f_geo."""
    vol, geo = ref.kernel_white_sky(n_theta=32, n_mu=128, n_phi=128)
    assert abs(vol - 0.189184) < 1e-4 and abs(geo + 1.377622) < 1e-4, (vol, geo)
    assert ref.RTLS(*DEFAULTS).white_sky()[0] == pytest.approx(
        0.209741 + 0.189184 * 0.081384 - 1.377622 * 0.004140, abs=1e-12)


@pytest.mark.parametrize("weights", [UNCLAMPED, DEFAULTS], ids=["unclamped", "defaults"])
def test03_white_furnace_of_the_plugin_is_the_kernels_integrals(variant_llvm_ad_rgb, weights):
    """The plugin's white-sky albedo (mean sample() weight over cosine-weighted ωi) equals
    f_iso + 0.189184 f_vol − 1.377622 f_geo within 5σ + 10⁻⁴; its black-sky albedo E(θ)
    at θ = 0° and 75° equals f_iso + f_vol ∫K_vol + f_geo ∫K_geo (quadrature) within 5σ +
    3·10⁻⁵ and the polynomial within its error. The clamp never acts for the unclamped set;
    for the defaults it changes E(θ) by less than 2·10⁻⁵ up to θ = 89° (the float64 model,
    clamped and not: 1.9·10⁻⁵ at 0°, 2·10⁻⁷ at 89°)."""
    bsdf = batch.load_bsdf(dict(type="rtls", f_iso=weights[0], f_vol=weights[1],
                                f_geo=weights[2]))
    sky = earth.white_sky_albedo(bsdf, n=200_000)
    expected = ref.white_sky_polynomial(*weights)
    assert abs(sky.value[0] - expected) < 5 * sky.err[0] + 1e-4, (sky.value, expected)
    for theta in np.radians([0.0, 75.0]):
        mean, err = albedo_sampled(bsdf, theta, n=200_000)
        vol, geo = ref.kernel_black_sky(theta, n_mu=128, n_phi=128)
        exact = weights[0] + weights[1] * vol + weights[2] * geo
        assert abs(mean[0] - exact) < 5 * err[0] + 3e-5, (theta, mean, exact)
        poly = ref.black_sky_polynomial(theta, *weights)
        assert abs(mean[0] - poly) < 5 * err[0] + weights[1] * POLY_ERR["vol"] + \
            weights[2] * POLY_ERR["geo"]


def test04_the_linear_inversion_recovers_the_weights(np_rng):
    """Least squares of the BRF over random pairs: the weights of a model (per the metric's
    weights or none) to 10⁻⁹, unbounded; with the [0, 1] bounds a weight the data push below
    0 is held at 0 and the others are the least squares with it fixed there."""
    wi, wo = batch.random_directions(np_rng, 400, sphere=False), \
        batch.random_directions(np_rng, 400, sphere=False)
    truth = np.array([0.15, 0.3, 0.02])
    brf = ref.RTLS(*truth).brf(wi, wo)[:, 0]
    w = np_rng.uniform(0.1, 2.0, len(wi))
    np.testing.assert_allclose(ref.invert(wi, wo, brf, bounds=None), truth, atol=1e-9)
    np.testing.assert_allclose(ref.invert(wi, wo, brf, w), truth, atol=1e-9)
    low = ref.RTLS(0.3, 0.2, 0.0).brf(wi, wo)[:, 0] - 0.01 * ref.RTLS(0, 0, 1).brf(wi, wo)[:, 0]
    assert ref.invert(wi, wo, low, bounds=None)[2] < 0
    bounded = ref.invert(wi, wo, low)
    assert bounded[2] == 0.0
    np.testing.assert_allclose(bounded[:2], _fixed_geo(wi, wo, low), atol=1e-12)


def _fixed_geo(wi, wo, brf):
    """(f_iso, f_vol) by least squares with f_geo = 0, written out: the normal equations."""
    k_vol = ref.RTLS().kernels(wi, wo)[0]
    a = np.stack([np.ones_like(k_vol), k_vol], axis=1)
    return np.linalg.solve(a.T @ a, a.T @ brf)


def _ngan_inversion(target, pairs: int):
    """The linear inversion on the fit's own pairs under its ``ngan`` metric: the fit
    minimises mean(w Σ_c (Δ f·cosθi)²), f = BRF/π, so the weights are w cos²θi and the
    grey model's best BRF is that of the channels' mean."""
    wi, wo = direction_pairs(pairs, 0)
    brf = math.pi * batch.evaluate(target, wi, wo).value.mean(axis=1) / wo[:, 2]
    return wi, wo, ref.invert(wi, wo, brf, metric_weights("ngan", wi, wo) * wi[:, 2] ** 2)


def _fitted(result) -> np.ndarray:
    return np.array([result.parameters[k] for k in ("f_iso", "f_vol", "f_geo")])


def test05_the_fit_recovers_an_rtls_targets_weights(variant_llvm_ad_rgb):
    """The AD fit of rtls to rtls (f_geo = 0.02: the clamp acts at 10 of the 389 pairs, in
    the target and the model alike) lands on the target's weights to 10⁻⁵; the linear
    inversion, blind to the clamp, does so only on the pairs where it does not act."""
    truth = (0.15, 0.3, 0.02)
    target = dict(type="rtls", f_iso=truth[0], f_vol=truth[1], f_geo=truth[2])
    result = fit(target, "rtls", metric="ngan", pairs=512, steps=200, starts="given",
                 thetas_deg=(0.0,))
    np.testing.assert_allclose(_fitted(result), truth, atol=1e-5)
    wi, wo, _ = _ngan_inversion(target, 512)
    kept = ref.RTLS(*truth).brf(wi, wo)[:, 0] >= 0
    assert 0 < (~kept).sum() < 20
    brf = ref.RTLS(*truth).brf(wi[kept], wo[kept])[:, 0]
    np.testing.assert_allclose(ref.invert(wi[kept], wo[kept], brf), truth, atol=1e-9)


@pytest.mark.parametrize("target, bound", [("orennayar sigma=0.5", None),
                                            ("roughplastic", 2)], ids=["orennayar", "roughplastic"])
def test06_the_fit_to_another_bsdf_is_the_linear_inversion(variant_llvm_ad_rgb, target, bound):
    """rtls fitted under ``ngan`` to Oren-Nayar (rough diffuse, backscattering: the three
    weights inside (0, 1)) and to roughplastic (a specular lobe the kernels cannot follow:
    f_geo held at its bound 0) equals MODIS's linear inversion on the same pairs to 10⁻⁴
    (measured at 512 pairs, 200 steps: 2.7·10⁻⁶ and 1.5·10⁻⁵; 3·10⁻⁷ at the CLI's 16384
    pairs and 800 steps); the inverted BRF is ≥ 0 on the pairs, so that the clamp does not
    make the two problems differ."""
    result = fit(target, "rtls", metric="ngan", pairs=512, steps=200, starts="given",
                 thetas_deg=(0.0,))
    wi, wo, inverted = _ngan_inversion(target, 512)
    inside = [k for k in range(3) if k != bound]
    assert np.all((inverted[inside] > 1e-3) & (inverted[inside] < 1)), inverted
    assert bound is None or inverted[bound] == 0.0, inverted
    assert np.all(ref.RTLS(*inverted).brf(wi, wo) >= 0)
    np.testing.assert_allclose(_fitted(result), inverted, atol=1e-4)


def test07_the_fitted_weights_stay_within_the_plugins_range(variant_llvm_ad_rgb):
    """Under the cube root rtls's best fit to roughplastic lies beyond f_iso = 1 (1.48 after
    200 steps, 1.24 after 40, when the fit's range was [0, ∞)): the fit holds each weight
    within the plugin's [0, 1] and says it is at its bound, instead of writing a BSDF the
    plugin refuses."""
    result = fit("roughplastic", "rtls", pairs=512, steps=40, starts="given",
                 thetas_deg=(0.0,))
    weights = _fitted(result)
    assert np.all((weights >= 0) & (weights <= 1)) and weights[0] == 1.0, weights
    assert any("f_iso = 1 is at the upper bound 1" in flag for flag in result.flags), \
        result.flags
