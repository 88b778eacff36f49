"""
The ``hapke`` plugin (Hapke's regolith reflectance, Hapke 2012) and its float64 reference:
the reference's H-function against Chandrasekhar's exact one and his table, the conservative
albedo of 1 with the exact H, the opposition surge 1 + B_0 at g = 0, the phase function's
normalisation, the roughness correction's limits at i = 0 and θ̄ → 0 and its reciprocity;
eval against the reference at random, backscatter and near-grazing pairs (and a broken
H-function rejected); finite and non-negative at the singular places (the defaults' h = 0 at
g = 0, where Eradiate is NaN); the energy warning at load; reciprocity, consistency, χ²;
parameters through mi.traverse; one-line errors.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from earth_helpers import (
    assert_load_error, assert_one_glossy_lobe, cos_reference, direction, hot_spot_pairs,
    load_warnings, singular_pairs)
from helpers import assert_matches_reference, eval_pdf, sample

from mi_brdfs.reference import hapke as ref
from mi_brdfs.reference.quadrature import gauss_legendre, sphere_grid
from mi_brdfs.scattering import hapke as scattering
from mi_brdfs.testing import assert_consistent, assert_reciprocal, assert_sampling_matches_pdf

#: A lunar-like regolith with a narrow opposition surge (the docstring's example).
LUNAR = {"w": 0.3, "b": 0.25, "c": 0.7, "theta": 20.0, "B_0": 1.0, "h": 0.06}
#: A bright one whose directional albedo exceeds 1 (the energy warning).
BRIGHT = {"w": 0.99, "b": 0.3, "c": 0.9, "theta": 0.0, "B_0": 1.0, "h": 1.0}
#: float32 evaluation: within 10⁻⁵ of the float64 model beyond the directions' conditioning.
RTOL = 1e-5


# -- the reference ---------------------------------------------------------------------------

def test01_h_function():
    """The exact H (Chandrasekhar's integral): H(1) = 2.90781 at w = 1 (Chandrasekhar 1960,
    Table XI) and ∫₀¹ H dμ = (2/w)(1 − √(1 − w)) (his zeroth moment); Hapke's 2002
    approximation within 1 % of it at every w and μ (Hapke 2002 states < 1 %), H(0) = 1."""
    assert ref.h_exact(1.0, [1.0])[0] == pytest.approx(ref.H_CONSERVATIVE_1, abs=1e-5)
    x, w = gauss_legendre(64)
    mu, w_mu = 0.5 * (x + 1), 0.5 * w
    for a in (0.3, 0.9, 1.0):
        assert w_mu @ ref.h_exact(a, mu) == pytest.approx(2 / a * (1 - math.sqrt(1 - a)),
                                                          rel=1e-7)
    grid = np.linspace(0.0, 1.0, 101)
    for a in (0.1, 0.5, 0.9, 0.99, 1.0):
        assert np.max(np.abs(ref.h_function(a, grid) / ref.h_exact(a, grid) - 1)) < 0.01, a
    assert ref.h_function(0.7, 0.0) == 1.0


def test02_conservative_albedo_is_one_with_the_exact_h():
    """w = 1, isotropic particles (b = 0), smooth (θ̄ = 0), B_0 = 0: r = (1/4π) μ0/(μ0 + μ)
    H(μ0)H(μ), Chandrasekhar's exact reflection of a conservative half-space, whose albedo is
    1 at every incidence with the exact H; ~1.3 % below with Hapke's approximation."""
    exact = ref.Hapke(w=1.0, b=0.0, theta=0.0, exact_h=True)
    approx = ref.Hapke(w=1.0, b=0.0, theta=0.0)
    for theta in (0.0, 45.0, 80.0):
        assert exact.albedo(math.radians(theta), 64, 16)[0] == pytest.approx(1.0, abs=1e-6)
        assert 0.98 < approx.albedo(math.radians(theta), 64, 16)[0] < 0.995


def test03_opposition_and_phase_closed_forms():
    """At g = 0, smooth: f(B_0) − f(0) = w p(0) B_0/(8π cos i) (the surge multiplies the
    single scattering by 1 + B_0), for h = 0.06 and h = 0 (B(0) = B_0 at every h); B(g) =
    B_0/(1 + tan(g/2)/h) elsewhere; p's mean over the sphere is 1."""
    w = direction(np.radians([0.0, 30.0, 70.0]), 0.3)
    b, c = 0.4, 0.7
    p0 = (1 - c) * (1 - b * b) / (1 + b) ** 3 + c * (1 - b * b) / (1 - b) ** 3
    for h in (0.06, 0.0):
        params = dict(w=0.6, b=b, c=c, theta=0.0, h=h)
        diff = ref.Hapke(B_0=0.8, **params).brdf(w, w) - ref.Hapke(B_0=0.0, **params).brdf(w, w)
        np.testing.assert_allclose(diff[:, 0], 0.6 * p0 * 0.8 / (8 * np.pi * w[:, 2]),
                                   rtol=1e-12)
    assert ref.opposition(0.8, 0.06, 0.5) == pytest.approx(0.8 / (1 + math.tan(0.25) / 0.06))
    assert ref.opposition(0.8, 0.0, 0.5) == 0.0
    v, weights = sphere_grid(256, 8, (-1.0, 1.0))
    assert weights @ ref.phase(b, c, v[:, 2]) / (4 * np.pi) == pytest.approx(1.0, rel=1e-9)


def test04_roughness_limits_and_reciprocity(np_rng):
    """The roughness correction at i = 0 (e = 0) is the limit of its formulas, whatever ψ:
    i = 10⁻⁷ at ψ = 0, π/2, π gives the value at i = 0 within 10⁻⁶; θ̄ = 10⁻⁶ gives the
    smooth model; f(a, b) = f(b, a) at random pairs (μ0e ↔ μe under i ↔ e, and S's cos i
    cancels f's 1/cos i) to 10⁻¹⁰."""
    e = np.full(3, math.radians(50.0))
    psi = np.array([0.0, np.pi / 2, np.pi])
    at_zero = ref.roughness(np.zeros(3), e, psi, math.radians(30.0))
    near = ref.roughness(np.full(3, 1e-7), e, psi, math.radians(30.0))
    for a, b in zip(at_zero, near):
        np.testing.assert_allclose(b, a, rtol=1e-6)
        np.testing.assert_allclose(b, b[0], rtol=1e-6)  # ψ does not matter there
    wi, wo = hot_spot_pairs(np_rng, 400)
    smooth = ref.Hapke(**dict(LUNAR, theta=0.0)).brdf(wi, wo)
    np.testing.assert_allclose(ref.Hapke(**dict(LUNAR, theta=1e-6)).brdf(wi, wo), smooth,
                               rtol=1e-6)
    model = ref.Hapke(**LUNAR)
    np.testing.assert_allclose(model.brdf(wo, wi), model.brdf(wi, wo), rtol=1e-10)


# -- eval ------------------------------------------------------------------------------------

def test05_eval_is_the_reference(variants_rgb, np_rng):
    """eval = f·cosθo per channel at random, backscatter and near-grazing pairs, for the
    defaults, a lunar regolith with RGB w and a rough bright one (θ̄ = 60°)."""
    n = 60 if variants_rgb.startswith("scalar") else 3000
    wi, wo = hot_spot_pairs(np_rng, n)
    rgb = {"type": "rgb", "value": [0.2, 0.3, 0.4]}
    for params, w in (({}, 0.5), (dict(LUNAR, w=rgb), [0.2, 0.3, 0.4]),
                      ({"w": 0.9, "theta": 60.0, "B_0": 0.5, "h": 0.3}, 0.9)):
        bsdf = mi.load_dict(dict(type="hapke", **params))
        model = ref.Hapke(**dict(params, w=w))
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                                 RTOL, f"hapke {params}")


def test06_a_broken_h_function_is_rejected(variant_scalar_rgb, np_rng, monkeypatch):
    """The comparison tells H apart: a plugin with r0 = 0 (Hapke's 1981 H) fails it."""
    def h_1981(w, x):
        return (1 + 2 * x) / (1 + 2 * x * dr.sqrt(1 - w))

    monkeypatch.setattr(scattering, "h_function", h_1981)
    wi, wo = hot_spot_pairs(np_rng, 60)
    bsdf = mi.load_dict(dict(type="hapke", **LUNAR))
    with pytest.raises(AssertionError, match="against the float64 reference"):
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(ref.Hapke(**LUNAR)),
                                 wi, wo, RTOL, "hapke broken H")


def _singular():
    """θi = θo = 0, exact backscatter up to the horizon, grazing views (cosθo = 10⁻⁷, 0),
    grazing incidence."""
    return singular_pairs([0.0, 30.0, 89.0, 89.99999, 90.0], (1e-7, 1e-7))


def test07_finite_and_non_negative_at_the_singular_places(variant_scalar_rgb):
    """eval, pdf and sample weights finite and ≥ 0 where Eradiate is 0·∞ (its defaults' h = 0
    at g = 0), for the defaults, B_0 = 1 with h = 0, and θ̄ = 90°; at normal incidence
    looking back, smooth: f = (w/8π)[p(0)(1 + B_0) + H(1)² − 1], the surge at its B_0."""
    wi, wo = _singular()
    for params in ({}, {"B_0": 1.0, "h": 0.0}, {"theta": 90.0, "B_0": 1.0, "h": 0.5}):
        bsdf = mi.load_dict({"type": "hapke", **params})
        for x in eval_pdf(bsdf, wi, wo):
            assert np.isfinite(x).all() and (x >= 0).all(), (params, x)
        s = sample(bsdf, np.repeat(wi[:4], 3, 0), np.full(12, 0.5),
                   np.tile([[0.0, 0.0], [0.5, 0.5], [0.999, 0.2]], (4, 1)))
        assert np.isfinite(s["weight"]).all() and (s["weight"] >= 0).all(), s["weight"]
    bsdf = mi.load_dict({"type": "hapke", "theta": 0.0, "B_0": 1.0, "h": 0.0})
    b, c = 0.2, 0.5
    p0 = (1 - c) * (1 - b * b) / (1 + b) ** 3 + c * (1 - b * b) / (1 - b) ** 3
    expected = 0.5 / (8 * np.pi) * (p0 * 2 + ref.h_function(0.5, 1.0) ** 2 - 1)
    assert eval_pdf(bsdf, wi[:1], wo[:1])[0][0, 0] == pytest.approx(expected, rel=1e-6)


# -- the energy warning ----------------------------------------------------------------------

def test08_energy_warning_at_load(variant_scalar_rgb):
    """A bright surface with a broad surge (albedo 1.15 at θi = 89°) warns in one line naming
    hapke, the parameters, the albedo and θi; the defaults, the lunar regolith and
    spatially varying parameters (cosine-sampled) do not."""
    _, lines = load_warnings({"type": "hapke", **BRIGHT})
    assert len(lines) == 1 and "\n" not in lines[0], lines
    assert lines[0].startswith("hapke: w = 0.99, b = 0.3, c = 0.9, theta = 0, B_0 = 1, h = 1: "
                               "the model's directional albedo reaches 1.1")
    assert "at θi = 89°" in lines[0]
    for spec in ({}, LUNAR):
        bsdf, lines = load_warnings({"type": "hapke", **spec})
        assert lines == [] and type(bsdf.lobes.lobes[0]).__name__ == "Tabulated"
    bsdf, lines = load_warnings({"type": "hapke", **dict(BRIGHT, w={"type": "checkerboard"})})
    assert lines == [] and type(bsdf.lobes.lobes[0]).__name__ == "Cosine"


# -- sampling, reciprocity, traverse ---------------------------------------------------------

def test09_reciprocal_and_consistent(variant_llvm_ad_rgb):
    """f(a, b) = f(b, a); weight = eval/pdf and bs.pdf = pdf(bs.wo) for the tabulated and the
    cosine sampler."""
    assert_reciprocal(dict(type="hapke", **LUNAR))
    assert_consistent(dict(type="hapke", **LUNAR), n=20_000)
    assert_consistent(dict(type="hapke", **dict(LUNAR, h={"type": "checkerboard"})), n=20_000)


def test10_opposition_sampling(variant_llvm_ad_rgb, np_rng):
    """χ² of sample() against pdf() at θi = 30° and 75° for the tabulated sampler (the narrow
    surge of the lunar regolith) and the cosine one; the tabulated sampler's weights vary
    less than the cosine's (the same mean)."""
    spec = dict(type="hapke", **LUNAR)
    for theta in (30.0, 75.0):
        assert_sampling_matches_pdf(spec, wi=list(direction(np.radians(theta))),
                                    sample_count=200_000)
    varying = dict(spec, h={"type": "checkerboard", "color0": 0.06, "color1": 0.06})
    assert_sampling_matches_pdf(varying, wi=list(direction(np.radians(30.0))),
                                sample_count=200_000)
    wi = direction(np.radians(75.0))
    bsdf, n = mi.load_dict(spec), 100_000
    ours = sample(bsdf, wi[None], np_rng.random(n), np_rng.random((n, 2)))["weight"].mean(1)
    wo = np.array(mi.warp.square_to_cosine_hemisphere(mi.Point2f(np_rng.random((2, n))))).T
    plain = eval_pdf(bsdf, np.repeat(wi[None], n, 0), wo)[0].mean(1) / (wo[:, 2] / np.pi)
    assert abs(ours.mean() - plain.mean()) < 5 * np.sqrt(plain.var() / n)
    assert plain.var() > 5 * ours.var(), (plain.var(), ours.var())


def test11_parameters_through_traverse(variant_llvm_ad_rgb, np_rng):
    """B_0 set through mi.traverse: eval follows the reference at the new value and the
    sampler is rebuilt; a value above 1 acts as 1."""
    bsdf = mi.load_dict(dict(type="hapke", **LUNAR))
    params = mi.traverse(bsdf)
    assert {f"{k}.value" for k in ("w", "b", "c", "theta", "B_0", "h")} <= set(params.keys())
    wi, wo = hot_spot_pairs(np_rng, 500)
    for value, acts in ((0.3, 0.3), (2.0, 1.0)):
        params["B_0.value"] = value
        params.update()
        model = ref.Hapke(**dict(LUNAR, B_0=acts))
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                                 RTOL, f"hapke B_0 = {value}")
    assert bsdf.lobes.lobes[0].surface.constants[4] == pytest.approx(1.0)
    assert_consistent(bsdf, n=20_000)


@pytest.mark.parametrize("extra,message", [
    ({"w": 1.5}, 'hapke: parameter "w" = 1.5 is invalid: must be finite and within [0, 1]'),
    ({"theta": 95.0}, 'hapke: parameter "theta" = 95 is invalid: must be finite and within '
                      '[0, 90]'),
    ({"h": -0.1}, 'hapke: parameter "h" = -0.1 is invalid'),
    ({"B0": 0.1}, "did you mean B_0"),
])
def test12_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    assert_load_error(dict(type="hapke", **extra), message)


def test13_structure(variant_scalar_rgb):
    """One component, glossy reflection on the front side; the string names every
    parameter; 0 below the surface."""
    assert_one_glossy_lobe(mi.load_dict(dict(type="hapke", **LUNAR)), "Hapke", LUNAR)
