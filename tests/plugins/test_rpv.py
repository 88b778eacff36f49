"""
The ``rpv`` plugin (Rahman, Pinty & Verstraete 1993) and its float64 reference: the reference
against the paper's closed forms (nadir, the hot spot, the forward principal plane) and
reciprocity; eval against the reference at random, backscatter and near-grazing pairs in
scalar_rgb and llvm_ad_rgb (a wrong exponent rejected); finite and non-negative at the
horizon and exact backscatter; the energy warning at load and its numbers against an
independent quadrature; reciprocity, consistency, χ² and the tabulated sampler against the
cosine at a hot spot; parameters through mi.traverse (ρc following ρ0); one-line errors.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from earth_helpers import (
    assert_load_error, assert_one_glossy_lobe, cos_reference, direction, hot_spot_pairs,
    load_quietly, load_warnings, singular_pairs)
from helpers import assert_matches_reference, eval_pdf, sample

from mi_brdfs.reference import rpv as ref
from mi_brdfs.reference.quadrature import hemisphere_albedo
from mi_brdfs.scattering import rpv as scattering
from mi_brdfs.testing import assert_consistent, assert_reciprocal, assert_sampling_matches_pdf

#: A bell (k > 1) with a backward hot spot and ρc apart from ρ0.
HOTSPOT = {"rho_0": 0.2, "k": 1.4, "g": -0.3, "rho_c": 0.05}
#: float32: M = exp((k − 1) log(…)) loses (k − 1)·|log(…)|·2⁻²⁴ ≈ 10⁻⁶ near the horizon;
#: the directions' own rounding is the conditioning of assert_matches_reference.
RTOL = 2e-6


# -- the reference ---------------------------------------------------------------------------

def test01_reference_closed_forms():
    """At the hot spot (ωo = ωi: g = 0, G = 0) BRF = ρ0 (2cos³θ)^(k−1) (1 − Θ)/(1 + Θ)²
    (2 − ρc); in the forward principal plane at θi = θo = θ (φ = π: cos g = cos 2θ,
    G = 2 tanθ) F = (1 − Θ²)/(1 + Θ² + 2Θ cos 2θ)^(3/2); k = 1, Θ = 0, ρc = 1 is Lambert's
    ρ0/π."""
    theta = np.radians([0.0, 20.0, 50.0, 80.0])
    w = direction(theta, 0.4)
    p = HOTSPOT
    model = ref.RPV(**p)
    c = np.cos(theta)
    th = p["g"]
    expected = p["rho_0"] * (2 * c ** 3) ** (p["k"] - 1) * (1 - th) / (1 + th) ** 2 * \
        (2 - p["rho_c"])
    np.testing.assert_allclose(model.brf(w, w)[:, 0], expected, rtol=1e-12)
    wo = direction(theta, 0.4 + np.pi)
    f = (1 - th ** 2) / (1 + th ** 2 + 2 * th * np.cos(2 * theta)) ** 1.5
    h = 1 + (1 - p["rho_c"]) / (1 + 2 * np.tan(theta))
    np.testing.assert_allclose(model.brf(w, wo)[:, 0],
                               p["rho_0"] * (2 * c ** 3) ** (p["k"] - 1) * f * h, rtol=1e-12)
    lam = ref.RPV(0.3, 1.0, 0.0, 1.0)
    np.testing.assert_allclose(lam.brdf(w, wo[::-1]), 0.3 / np.pi, rtol=1e-14)


def test02_reference_is_reciprocal(np_rng):
    """f(ωi, ωo) = f(ωo, ωi): every factor is symmetric (Rahman et al. 1993 is reciprocal)."""
    wi, wo = hot_spot_pairs(np_rng, 400)
    model = ref.RPV(**HOTSPOT)
    np.testing.assert_allclose(model.brf(wi, wo), model.brf(wo, wi), rtol=1e-12)


# -- eval ------------------------------------------------------------------------------------

def test03_eval_is_the_reference(variants_rgb, np_rng):
    """eval = BRF/π·cosθo per channel at random, backscatter and near-grazing pairs, for the
    defaults (k = 0.1, ρc = ρ0) and the hot-spot bell with an RGB ρ0."""
    n = 60 if variants_rgb.startswith("scalar") else 3000
    wi, wo = hot_spot_pairs(np_rng, n)
    rgb = {"type": "rgb", "value": [0.1, 0.05, 0.02]}
    for params, model in (({}, ref.RPV()),
                          (dict(HOTSPOT, rho_0=rgb), ref.RPV(**dict(HOTSPOT,
                                                                    rho_0=[0.1, 0.05, 0.02])))):
        bsdf = load_quietly(dict(type="rpv", **params))
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                                 RTOL, f"rpv {params}")


def test04_a_wrong_exponent_is_rejected(variant_llvm_ad_rgb, np_rng, monkeypatch):
    """The comparison tells M apart: a plugin with the exponent k for k − 1 fails it."""
    def wrong(k, wi, wo):
        ci, co = dr.maximum(wi.z, scattering.COS_MIN), dr.maximum(wo.z, scattering.COS_MIN)
        return dr.exp(k * dr.log(ci * co * (ci + co)))

    monkeypatch.setattr(scattering, "minnaert", wrong)
    wi, wo = hot_spot_pairs(np_rng, 200)
    bsdf = mi.load_dict(dict(type="rpv", **HOTSPOT))
    with pytest.raises(AssertionError, match="against the float64 reference"):
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(ref.RPV(**HOTSPOT)),
                                 wi, wo, RTOL, "rpv wrong exponent")


def _singular():
    """θi = θo = 0, exact backscatter up to the horizon, grazing views (cosθo = 10⁻²⁵, 10⁻⁸,
    0), both grazing."""
    return singular_pairs([0.0, 30.0, 89.0, 89.999, 89.99999, 90.0], (1e-25, 1e-8))


@pytest.mark.parametrize("params", [{"k": 0.0, "g": -0.999, "rho_0": 1.0, "rho_c": 0.0},
                                    {"k": 0.0, "g": 0.999, "rho_c": 2.0}])
def test05_finite_and_non_negative_at_the_singular_places(variant_scalar_rgb, params):
    """eval, pdf and sample weights are finite and ≥ 0 in float32 where the model is +∞
    (k = 0 at the horizon, M ≤ 5·10¹⁷) with the sharpest F (|g| = 0.999) and H at its
    extremes (ρc = 0: 2 at the hot spot; ρc = 2: 0 there)."""
    bsdf = load_quietly(dict(type="rpv", **params))
    wi, wo = _singular()
    for x in eval_pdf(bsdf, wi, wo):
        assert np.isfinite(x).all() and (x >= 0).all(), x
    s = sample(bsdf, np.repeat(wi[:6], 4, 0), np.full(24, 0.5),
               np.tile([[0.0, 0.0], [0.5, 0.5], [0.999, 0.2], [0.3, 0.999]], (6, 1)))
    assert np.isfinite(s["weight"]).all() and (s["weight"] >= 0).all(), s["weight"]
    assert np.isfinite(s["pdf"]).all()


# -- energy ----------------------------------------------------------------------------------

def test06_the_energy_warning(variant_scalar_rgb):
    """The defaults (k = 0.1) warn in one line with where E exceeds 1, E(89°) (21, as the
    issue's furnace of Eradiate's rpv found) and the horizon's; E(89°) and E just past the
    onset agree with the package's hemisphere quadrature; k = 1.5 does not warn; a k
    texture reaching below 1 warns without numbers."""
    _, lines = load_warnings({"type": "rpv"})
    assert len(lines) == 1 and "\n" not in lines[0], lines
    assert lines[0].startswith("rpv: rho_0 = 0.1, k = 0.1, g = 0, rho_c = 0.1: the model's "
                               "directional albedo exceeds 1 (it creates energy) from θi = 74.6")
    assert "E(89°) = 21.1" in lines[0] and "values kept" in lines[0]
    start, e89, _ = ref.RPV().energy()
    model = ref.RPV()
    assert hemisphere_albedo(model.brdf, math.radians(89.0), 1024, 32)[0] == \
        pytest.approx(e89, rel=1e-3)
    assert hemisphere_albedo(model.brdf, math.radians(start - 0.05), 1024, 32)[0] < 1.0 < \
        hemisphere_albedo(model.brdf, math.radians(start + 0.05), 1024, 32)[0]
    assert load_warnings({"type": "rpv", "k": 1.5})[1] == []
    checker = {"type": "checkerboard", "color0": 0.5, "color1": 1.2}
    bsdf, lines = load_warnings({"type": "rpv", "k": checker})
    assert lines == ["rpv: k reaches 0.5 < 1: the model's directional albedo grows without "
                     "bound towards grazing incidence (it creates energy there); values kept"]
    assert type(bsdf.lobes.lobes[0]).__name__ == "Cosine"


# -- sampling, reciprocity, traverse ---------------------------------------------------------

def test07_reciprocal_and_consistent(variant_llvm_ad_rgb):
    """f(a, b) = f(b, a) for a bowl and a bell; weight = eval/pdf and bs.pdf = pdf(bs.wo)
    for the tabulated and the cosine sampler."""
    assert_reciprocal({"type": "rpv", "k": 0.6, "g": 0.2, "rho_c": 0.3})
    assert_reciprocal(dict(type="rpv", **HOTSPOT))
    spec = dict(type="rpv", **HOTSPOT)
    assert_consistent(spec, n=20_000)
    assert_consistent(dict(spec, g={"type": "checkerboard", "color0": -0.3, "color1": 0.1}),
                      n=20_000)


def test08_hot_spot_sampling(variant_llvm_ad_rgb, np_rng):
    """χ² of sample() against pdf() at θi = 60° for the tabulated sampler and the cosine one
    (a parameter varying over the surface); the tabulated sampler's weights vary less than the
    cosine's (the same mean)."""
    spec = {"type": "rpv", "rho_0": 0.2, "k": 0.8, "g": -0.4, "rho_c": 0.0}
    wi = direction(np.radians(60.0))
    assert_sampling_matches_pdf(spec, wi=list(wi), sample_count=200_000)
    varying = dict(spec, k={"type": "checkerboard", "color0": 0.8, "color1": 0.8})
    assert_sampling_matches_pdf(varying, wi=list(wi), sample_count=200_000)
    bsdf, n = load_quietly(spec), 100_000
    ours = sample(bsdf, wi[None], np_rng.random(n), np_rng.random((n, 2)))["weight"].mean(1)
    wo = np.array(mi.warp.square_to_cosine_hemisphere(mi.Point2f(np_rng.random((2, n))))).T
    plain = eval_pdf(bsdf, np.repeat(wi[None], n, 0), wo)[0].mean(1) / (wo[:, 2] / np.pi)
    assert abs(ours.mean() - plain.mean()) < 5 * np.sqrt(plain.var() / n)
    assert plain.var() > 5 * ours.var(), (plain.var(), ours.var())


def test09_parameters_through_traverse(variant_llvm_ad_rgb, np_rng):
    """rho_0, k and g exposed, rho_c too where it is given (else it is ρ0's texture and
    follows it, as in Eradiate's); eval follows the reference at the new values; g beyond
    its range acts as 0.999."""
    bsdf = load_quietly({"type": "rpv"})
    params = mi.traverse(bsdf)
    assert set(params.keys()) == {"rho_0.value", "k.value", "g.value"}
    wi, wo = hot_spot_pairs(np_rng, 500)
    params["rho_0.value"], params["k.value"] = 0.4, 1.2
    params.update()
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(ref.RPV(0.4, 1.2, 0.0)),
                             wi, wo, RTOL, "rpv rho_0 = 0.4 through traverse")
    bsdf = mi.load_dict(dict(type="rpv", **HOTSPOT))
    params = mi.traverse(bsdf)
    assert "rho_c.value" in params.keys()
    params["rho_c.value"], params["g.value"] = 0.7, 1.5
    params.update()
    g = float(np.float32(0.999))  # as stored: F moves 10³ times g's rounding at g ≈ 1
    model = ref.RPV(**dict(HOTSPOT, rho_c=0.7, g=g))
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                             RTOL, "rpv g = 1.5 through traverse")
    assert bsdf.lobes.lobes[0].surface.constants == pytest.approx((0.2, 1.4, 0.999, 0.7))


@pytest.mark.parametrize("extra,message", [
    ({"rho_0": 1.5}, 'rpv: parameter "rho_0" = 1.5 is invalid: must be finite and within '
                     '[0, 1]'),
    ({"k": -0.1}, 'rpv: parameter "k" = -0.1 is invalid: must be finite and within [0, 3]'),
    ({"g": 1.0}, 'rpv: parameter "g" = 1 is invalid: must be finite and within [-0.999, '
                 '0.999]'),
    ({"rho_c": 2.5}, 'rpv: parameter "rho_c" = 2.5 is invalid: must be finite and within '
                     '[0, 2]'),
    ({"rho": 0.1}, "did you mean rho_c or rho_0?"),
])
def test10_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    assert_load_error(dict(type="rpv", **extra), message)


def test11_structure(variant_scalar_rgb):
    """One component, glossy reflection on the front side; the string names every
    parameter; 0 below the surface."""
    assert_one_glossy_lobe(mi.load_dict(dict(type="rpv", **HOTSPOT)), "RPV", HOTSPOT)


def test12_the_reference_of_a_spec_without_rho_c(variant_scalar_rgb):
    """ρc = ρ0 where rho_c is not given, the plugin's default: the reference of such a spec
    was None (no reference for the defaults), so that the albedo check compared sample() with
    a quadrature of eval, not with the float64 model."""
    from mi_brdfs import reference

    for spec, rho in (({"type": "rpv"}, 0.1), ({"type": "rpv", "rho_0": 0.3, "k": 0.6}, 0.3)):
        model = reference.for_spec(spec)
        assert isinstance(model, ref.RPV), spec
        assert (model.rho_0[0], model.rho_c[0]) == (rho, rho)
    assert reference.for_spec({"type": "rpv", "rho_c": 0.5}).rho_c[0] == 0.5
