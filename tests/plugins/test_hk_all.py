"""
``hk`` with ``scattering = all`` (every order, by the adding-doubling tables of
mi_brdfs.reference.hk_doubling) against the float64 random walk of mi_brdfs.reference.hk,
which shares no code with the tables: the light a slab sends into bands of the outgoing cosine
(reflected and transmitted; under glass, over a base, a thick conservative slab), the
unscattered beams, and the white furnace of a conservative slab by the plugin's own sampler.
The volumetric path tracer's comparison is in ``mi-brdfs validate --only hk``.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.checks import batch
from mi_brdfs.reference import hk as ref
from mi_brdfs.scattering.hk_orders import PROMISE

#: (the plugin's parameters, the walk's paths): under glass forward-scattering, over a base,
#: a thick conservative index-matched slab.
CASES = [
    ({"sigma_s": 1.35, "sigma_a": 0.15, "thickness": 1.0, "g": 0.6, "eta": 1.5}, 40_000),
    ({"sigma_s": 0.64, "sigma_a": 0.16, "thickness": 1.0, "g": 0.3, "eta": 1.33,
      "diffuse_reflectance": 0.6}, 40_000),
    ({"sigma_s": 4.95, "sigma_a": 0.05, "thickness": 1.0, "g": 0.0}, 20_000),
]
#: Bands of μo per hemisphere, each split into the half of azimuths towards ωi (|Δφ| < 90°)
#: and the half away from it.
BANDS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
WI = np.array([np.sin(np.radians(40.0)), 0.0, np.cos(np.radians(40.0))])


def _plugin_bands(params) -> np.ndarray:
    """∫ f·|cosθo| dωo of the plugin over each band and half (reflected, then transmitted),
    by a midpoint rule in (μo, φo); ωi lies at φ = 0."""
    n_mu, n_phi = 128, 256
    mu = (np.arange(n_mu) + 0.5) / n_mu
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
    m, p = (a.ravel() for a in np.meshgrid(mu, phi, indexing="ij"))
    s = np.sqrt(1 - m * m)
    out = []
    for side in (1.0, -1.0):
        wo = np.stack([s * np.cos(p), s * np.sin(p), side * m], axis=1)
        value = batch.evaluate({"type": "hk", "scattering": "all", **params}, WI,
                               wo).value[:, 0]
        w = value * (1.0 / n_mu) * (2 * np.pi / n_phi)
        near = np.cos(p) > 0
        out += [w[(m >= lo) & (m < hi) & (near == half)].sum()
                for lo, hi in zip(BANDS[:-1], BANDS[1:]) for half in (True, False)]
    return np.array(out)


def _walk_bands(params, n) -> tuple[np.ndarray, np.ndarray, tuple]:
    """The walk's scattered light per band (orders ≥ 1) with standard errors, and its
    unscattered light (order 0)."""
    exits = ref.walk(ref.HK(**params), WI, n, np.random.default_rng(11))
    mu, scattered, near = exits.wo[:, 2], exits.order >= 1, exits.wo[:, 0] > 0
    means, errors = [], []
    for side in (1.0, -1.0):
        for lo, hi in zip(BANDS[:-1], BANDS[1:]):
            for half in (True, False):
                band = scattered & (side * mu >= lo) & (side * mu < hi) & (side * mu > 0) \
                    & (near == half)
                mean, err = exits.mean(band)
                means.append(mean)
                errors.append(err)
    return np.array(means), np.array(errors), exits.mean(exits.order == 0)


@pytest.mark.parametrize("case", range(len(CASES)))
def test01_bands_equal_the_random_walk(variant_llvm_ad_rgb, case):
    """The scattered light in 4 bands of μo × 2 halves of azimuth, above and below, within 4
    standard errors of the walk plus the tables' promised error."""
    params, n = CASES[case]
    plugin = _plugin_bands(params)
    walk, error, _ = _walk_bands(params, n)
    slack = 4 * error + PROMISE * walk + 1e-4
    assert np.all(np.abs(plugin - walk) <= slack), (plugin, walk, slack)


def test02_unscattered_beams_equal_the_walk(variant_llvm_ad_rgb):
    """A thin slab under a high index (F = 0.25 at normal incidence: the round trips carry
    6 % of the beam): the unscattered light of every internal reflection (the beam through
    and the extra mirror beam, closed-form series) against the walk's order-0 exits."""
    params, n = {"sigma_s": 0.05, "sigma_a": 0.05, "g": 0.0, "eta": 3.0}, 40_000
    bsdf = mi.load_dict({"type": "hk", "scattering": "all", **params})
    _, _, (walk, error) = _walk_bands(params, n)
    model = ref.HK(**params)
    s = batch.sample(bsdf, np.tile(WI, (4000, 1)), np.linspace(0, 1, 4000, endpoint=False),
                     np.full((4000, 2), 0.3))
    c = s.sampled_component
    per = {int(k): float((s.weight[:, 0] * s.pdf)[c == k][0]) for k in np.unique(c[c >= 1])}
    unscattered = per[1] + per[2] - float(model.specular(WI[2])[0, 0])
    assert abs(unscattered - walk) <= 4 * error + 1e-6, (unscattered, walk, error)


def test03_white_furnace_of_a_conservative_slab(variant_llvm_ad_rgb):
    """σa = 0 under glass, no base: every bit of light leaves, so the mean sample weight
    (deltas included) is 1 within the tables' error."""
    bsdf = mi.load_dict({"type": "hk", "scattering": "all", "sigma_s": 2.0, "sigma_a": 0.0,
                         "g": 0.6, "eta": 1.5})
    n = 400_000
    rng = np.random.default_rng(3)
    for wi in (np.array([0.0, 0.0, 1.0]), np.array([0.8, 0.0, 0.6])):
        s = batch.sample(bsdf, np.tile(wi, (n, 1)), rng.random(n), rng.random((n, 2)))
        mean, err = s.weight[:, 0].mean(), s.weight[:, 0].std() / np.sqrt(n)
        assert abs(mean - 1.0) <= 4 * err + PROMISE, (wi, mean, err)
        dr.eval()


@pytest.mark.parametrize("base", [False, True])
def test04_each_channel_is_its_own_grey_layer(variant_llvm_ad_rgb, base):
    """σs, σa (and ρ) of three different channels: each channel of f·cosθo equals that of the
    layer made of its own values alone (uniform, read once for all channels)."""
    rgb = {"sigma_s": [0.4, 1.5, 3.0], "sigma_a": [0.3, 0.1, 0.02]}
    layer = {"g": 0.6, "eta": 1.5, "scattering": "all"}
    if base:
        layer = {"g": 0.3, "eta": 1.33, "scattering": "all"}
        rgb["diffuse_reflectance"] = [0.2, 0.6, 0.9]
    rng = np.random.default_rng(2)
    wi, wo = batch.random_directions(rng, 500, False), batch.random_directions(rng, 500)
    value = batch.evaluate({"type": "hk", **layer, **{k: {"type": "rgb", "value": v}
                                                      for k, v in rgb.items()}}, wi, wo).value
    for c in range(3):
        grey = batch.evaluate({"type": "hk", **layer, **{k: v[c] for k, v in rgb.items()}},
                              wi, wo).value[:, 0]
        np.testing.assert_allclose(value[:, c], grey, rtol=1e-5, atol=1e-7)
