"""
The ``rtls`` plugin (Ross-Thick Li-Sparse-Reciprocal, Lucht, Schaaf & Strahler 2000) and its
float64 reference: the reference against the published white-sky integrals of the kernels
and closed forms (nadir, the hot spot, normal incidence), the phase angle against spherical
trigonometry; eval against the reference at random, backscatter and near-grazing pairs in
scalar_rgb and llvm_ad_rgb (and a kernel swapped on purpose rejected); finite and
non-negative at the horizon and exact backscatter; the clamp's warning at load; reciprocity,
consistency, χ² and the tabulated sampler against the cosine at a hot spot; weights set
through mi.traverse; one-line errors.
"""

import warnings

import mitsuba as mi
import numpy as np
import pytest
from earth_helpers import (
    assert_load_error, assert_one_glossy_lobe, cos_reference, direction, hot_spot_pairs,
    load_warnings, singular_pairs)
from helpers import assert_matches_reference, eval_pdf, sample

from mi_brdfs.errors import MiBrdfsWarning
from mi_brdfs.reference import rtls as ref
from mi_brdfs.reference.quadrature import gauss_legendre
from mi_brdfs.scattering import rtls as kernels
from mi_brdfs.testing import assert_consistent, assert_reciprocal, assert_sampling_matches_pdf

#: A surface with a strong hot spot (forest-like: shadowing dominates) and crowns of
#: h/b = 1.5, b/r = 2 (the primed angles differ from the true ones).
HOTSPOT = {"f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.04}
SHAPE = {"h": 3.0, "r": 1.0, "b": 2.0}
#: float32 kernels: the BRF is a sum of terms up to sec²θ' ≈ 10 times it away from the
#: horizon, each rounded to 2⁻²⁴: 10⁻⁵ covers their sum; the directions' own rounding is the
#: conditioning of assert_matches_reference.
RTOL = 1e-5


# -- the reference ---------------------------------------------------------------------------

def test01_reference_closed_values():
    """Both kernels 0 at nadir/nadir (K_vol = (π/2)/2 − π/4); at the hot spot (b/r = 1)
    K_vol = (π/4)(secθ − 1) and K_geo = sec²θ − secθ (D = 0, t = π/2, O = secθ); at normal
    incidence K_geo = O − ½ − ½ secθo with cos t = (h/b) tanθo/(1 + secθo), 0 where that
    reaches 1. The defaults' BRF is negative at normal incidence from θo ≈ 89.5° on."""
    model = ref.RTLS()
    z = np.array([[0.0, 0.0, 1.0]])
    np.testing.assert_allclose(model.kernels(z, z), [[0.0], [0.0]], atol=1e-15)
    theta = np.radians([10.0, 45.0, 70.0, 85.0])
    w = direction(theta, 0.7)
    sec = 1 / np.cos(theta)
    k_vol, k_geo = model.kernels(w, w)
    np.testing.assert_allclose(k_vol, np.pi / 4 * (sec - 1), rtol=1e-12)
    np.testing.assert_allclose(k_geo, sec ** 2 - sec, rtol=1e-7)  # t = acos(0 ± 1e-16)
    wo = direction(theta, 1.3)
    cos_t = np.minimum(2 * np.tan(theta) / (1 + sec), 1.0)
    t = np.arccos(cos_t)
    overlap = (t - np.sin(t) * cos_t) * (1 + sec) / np.pi
    np.testing.assert_allclose(model.kernels(np.repeat(z, 4, 0), wo)[1],
                               overlap - 0.5 - 0.5 * sec, rtol=1e-12)
    brf = model.brf(np.repeat(z, 2, 0), direction(np.radians([89.0, 89.9])))[:, 0]
    assert brf[0] > 0 > brf[1], brf


def test02_reference_phase_angle_is_spherical_trigonometry(np_rng):
    """K_vol with ξ from cos ξ = cosθi cosθo + sinθi sinθo cos(φi − φo), the papers' form,
    equals the reference's (which takes cos ξ = ωi·ωo)."""
    ti, to = np_rng.uniform(0, 1.5, 500), np_rng.uniform(0, 1.5, 500)
    pi_, po = np_rng.uniform(-np.pi, np.pi, 500), np_rng.uniform(-np.pi, np.pi, 500)
    cos_xi = np.cos(ti) * np.cos(to) + np.sin(ti) * np.sin(to) * np.cos(pi_ - po)
    xi = np.arccos(np.clip(cos_xi, -1, 1))
    k_vol = ((np.pi / 2 - xi) * np.cos(xi) + np.sin(xi)) / (np.cos(ti) + np.cos(to)) - np.pi / 4
    got = ref.RTLS().kernels(direction(ti, pi_), direction(to, po))[0]
    np.testing.assert_allclose(got, k_vol, rtol=1e-9, atol=1e-12)


def white_sky(model, n=48, n_phi=96):
    """∫∫ K cosθi cosθo dωi dωo/π² of each kernel (Gauss-Legendre in the cosines, the
    midpoint rule in the relative azimuth)."""
    x, w = gauss_legendre(n)
    mu, w_mu = 0.5 * (x + 1), 0.5 * w
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    a, b, c = (g.ravel() for g in np.meshgrid(mu, mu, phi, indexing="ij"))
    weight = np.einsum("i,j,k->ijk", w_mu * mu, w_mu * mu, np.full(n_phi, 4.0 / n_phi)).ravel()
    k_vol, k_geo = model.kernels(direction(np.arccos(a)), direction(np.arccos(b), c))
    return weight @ k_vol, weight @ k_geo


def test03_reference_white_sky_integrals_are_lucht_et_als():
    """The kernels' white-sky albedos for h/b = 2, b/r = 1: 0.189184 and −1.377622 (Lucht et
    al. 2000, Table 1), to the quadrature's 10⁻⁴."""
    vol, geo = white_sky(ref.RTLS())
    assert abs(vol - ref.WHITE_SKY["vol"]) < 1e-4, vol
    assert abs(geo - ref.WHITE_SKY["geo"]) < 1e-4, geo


# -- eval ------------------------------------------------------------------------------------

def test04_eval_is_the_reference(variants_rgb, np_rng):
    """eval = max(BRF, 0)/π·cosθo per channel at random, backscatter and near-grazing pairs,
    for the defaults (negative near the horizon: the clamp included) and a hot-spot surface
    of other crowns with RGB weights."""
    n = 60 if variants_rgb.startswith("scalar") else 3000
    wi, wo = hot_spot_pairs(np_rng, n)
    rgb = {"type": "rgb", "value": [0.1, 0.05, 0.02]}
    for params in ({}, dict(HOTSPOT, f_iso=rgb, **SHAPE)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", MiBrdfsWarning)
            bsdf = mi.load_dict(dict(type="rtls", **params))
        f_iso = [0.1, 0.05, 0.02] if params else ref.RTLS().f_iso
        model = ref.RTLS(**dict(params, f_iso=f_iso)) if params else ref.RTLS()
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                                 RTOL, f"rtls {params}")


def test05_a_swapped_kernel_is_rejected(variant_llvm_ad_rgb, np_rng, monkeypatch):
    """The comparison tells the kernels apart: a plugin whose f_vol weighs K_geo and f_geo
    K_vol fails it."""
    def swapped(f_iso, f_vol, f_geo, wi, wo, h_over_b, b_over_r):
        return f_iso + f_geo * kernels.ross_thick(wi, wo) + \
            f_vol * kernels.li_sparse_r(wi, wo, h_over_b, b_over_r)

    monkeypatch.setattr(kernels, "brf", swapped)
    wi, wo = hot_spot_pairs(np_rng, 200)
    bsdf = mi.load_dict(dict(type="rtls", **HOTSPOT))
    with pytest.raises(AssertionError, match="against the float64 reference"):
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(ref.RTLS(**HOTSPOT)),
                                 wi, wo, RTOL, "rtls swapped")


#: Pairs at the model's singular places: θi = θo = 0, exact backscatter up to the horizon,
#: grazing views (cosθo = 10⁻²⁵, whose sec² overflows float32, 10⁻⁸ and 0), both grazing.
def _singular():
    return singular_pairs([0.0, 30.0, 89.0, 89.999, 89.99999, 90.0], (1e-25, 1e-8))


def test06_finite_and_non_negative_at_the_singular_places(variants_rgb):
    """eval, pdf and sample weights are finite and ≥ 0 in float32 where the model is 0/0 or
    ±∞: f_geo = 1 makes K_geo's ±sec² terms as large as they get."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        bsdf = mi.load_dict({"type": "rtls", "f_iso": 0.1, "f_vol": 1.0, "f_geo": 1.0})
    wi, wo = _singular()
    value, pdf, value2, pdf2 = eval_pdf(bsdf, wi, wo)
    for x in (value, pdf, value2, pdf2):
        assert np.isfinite(x).all() and (x >= 0).all(), x
    assert value[0, 0] == pytest.approx(0.1 / np.pi, rel=1e-5)  # nadir/nadir: f_iso/π
    s = sample(bsdf, np.repeat(wi[:6], 4, 0), np.full(24, 0.5),
               np.tile([[0.0, 0.0], [0.5, 0.5], [0.999, 0.2], [0.3, 0.999]], (6, 1)))
    assert np.isfinite(s["weight"]).all() and (s["weight"] >= 0).all(), s["weight"]
    assert np.isfinite(s["pdf"]).all()


# -- the clamp's warning ---------------------------------------------------------------------

def test07_the_clamp_warns_at_load(variant_scalar_rgb):
    """The defaults (f_geo > 0: −∞ at the horizon) and f_vol > 7.2 f_iso (K_vol ≥ −0.139)
    warn in one line naming rtls, the weights, the share and the place; a set that stays ≥ 0
    (f_geo = 0, f_vol ≤ 7.2 f_iso) and spatially varying weights (cosine-sampled) do not."""
    _, lines = load_warnings({"type": "rtls"})
    assert len(lines) == 1 and "\n" not in lines[0], lines
    assert lines[0].startswith("rtls: f_iso = 0.209741, f_vol = 0.081384, f_geo = 0.00414: "
                               "the kernel model's BRF goes below 0 on ")
    assert "max(BRF, 0)/π" in lines[0]
    share, low, _ = ref.RTLS().negative_share(32, 16)
    assert 0 < share < 1e-3 and low < 0
    assert len(load_warnings({"type": "rtls", "f_iso": 0.02, "f_vol": 0.2, "f_geo": 0.0})[1]) == 1
    bsdf, lines = load_warnings({"type": "rtls", "f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.0})
    assert lines == [] and type(bsdf.lobes.lobes[0]).__name__ == "Tabulated"
    checker = {"type": "checkerboard", "color0": 0.0, "color1": 0.3}
    bsdf, lines = load_warnings({"type": "rtls", "f_geo": checker})
    assert lines == [] and type(bsdf.lobes.lobes[0]).__name__ == "Cosine"


# -- sampling, reciprocity, traverse ---------------------------------------------------------

def test08_reciprocal_and_consistent(variant_llvm_ad_rgb):
    """f(a, b) = f(b, a) (Li-Sparse-Reciprocal is, Ross-Thick is) for crowns with b/r ≠ 1,
    with the defaults' weights: where the BRF crosses 0 (the hot-spot surface's forward
    grazing pairs) it is the difference of terms 10⁴ times larger, and float32 rounds the
    two orders apart by more than the check's 10⁻⁴; weight = eval/pdf and bs.pdf =
    pdf(bs.wo) for the tabulated and the cosine sampler."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        assert_reciprocal(dict(type="rtls", **SHAPE))
    spec = dict(type="rtls", **HOTSPOT, **SHAPE)
    assert_consistent(spec, n=20_000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        assert_consistent(dict(spec, f_vol={"type": "checkerboard"}), n=20_000)


def test09_hot_spot_sampling(variant_llvm_ad_rgb, np_rng):
    """χ² of sample() against pdf() at θi = 60°, where the hot spot is strong, for the
    tabulated sampler and the cosine one (a weight varying over the surface): a sample where
    the clamp makes f 0 fails, and the pdf is 0 there (a pdf > 0 there is rejected); the
    tabulated sampler's weights vary less than the cosine's (the same mean)."""
    spec = dict(type="rtls", **HOTSPOT)
    wi = direction(np.radians(60.0))
    assert_sampling_matches_pdf(spec, wi=list(wi), sample_count=200_000)
    varying = dict(spec, f_vol={"type": "checkerboard", "color0": 0.1, "color1": 0.1})
    assert_sampling_matches_pdf(varying, wi=list(wi), sample_count=200_000)
    bsdf, n = mi.load_dict(spec), 100_000
    ours = sample(bsdf, wi[None], np_rng.random(n), np_rng.random((n, 2)))["weight"].mean(1)
    wo = np.array(mi.warp.square_to_cosine_hemisphere(mi.Point2f(np_rng.random((2, n))))).T
    plain = eval_pdf(bsdf, np.repeat(wi[None], n, 0), wo)[0].mean(1) / (wo[:, 2] / np.pi)
    assert abs(ours.mean() - plain.mean()) < 5 * np.sqrt(plain.var() / n)
    assert plain.var() > 5 * ours.var(), (plain.var(), ours.var())


def test10_weights_through_traverse(variant_llvm_ad_rgb, np_rng):
    """f_geo set through mi.traverse: eval follows the reference at the new value and the
    sampler is rebuilt (bs.pdf = pdf(bs.wo)); a value above 1 acts as 1."""
    bsdf = mi.load_dict(dict(type="rtls", **HOTSPOT))
    params = mi.traverse(bsdf)
    assert {"f_iso.value", "f_vol.value", "f_geo.value"} <= set(params.keys())
    wi, wo = hot_spot_pairs(np_rng, 500)
    for value, acts in ((0.3, 0.3), (2.0, 1.0)):
        params["f_geo.value"] = value
        params.update()
        model = ref.RTLS(**dict(HOTSPOT, f_geo=acts))
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(model), wi, wo,
                                 RTOL, f"rtls f_geo = {value}")
    assert bsdf.lobes.lobes[0].surface.constants == pytest.approx((0.2, 0.1, 1.0))
    assert_consistent(bsdf, n=20_000)


@pytest.mark.parametrize("extra,message", [
    ({"f_iso": 1.5}, 'rtls: parameter "f_iso" = 1.5 is invalid: must be finite and within '
                     '[0, 1]'),
    ({"f_geo": -0.1}, 'rtls: parameter "f_geo" = -0.1 is invalid'),
    ({"h": 0.0}, 'rtls: parameter "h" = 0 is invalid: must be finite and within [0.001, '
                 '1000]'),
    ({"b": 1e4}, 'rtls: parameter "b" = 10000 is invalid'),
    ({"f_volume": 0.1}, "did you mean f_vol"),
])
def test11_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    assert_load_error(dict(type="rtls", **extra), message)


def test12_structure(variant_scalar_rgb):
    """One component, glossy reflection on the front side; the string names every
    parameter."""
    assert_one_glossy_lobe(mi.load_dict(dict(type="rtls", **HOTSPOT)), "RTLS",
                           ("f_iso", "f_vol", "f_geo", "h", "r", "b"))
