"""
The ``ocean`` plugin (Cox & Munk 1954's wind-roughened sea, Mishchenko & Travis 1997's glint)
and its float64 reference: the reference's slope density normalised with Cox & Munk's
variances, its Fresnel reflectance against the closed form at normal incidence, Monahan's
whitecap coverage at 10 m/s computed by hand; eval against the reference at random and
near-specular pairs (isotropic, along the wind, with whitecaps, absorbing water under another
exterior) in scalar_rgb and llvm_ad_rgb, and a wrong roughness rejected; the glint's peak at
the mirror direction; finite and non-negative at grazing, backscatter and the mirror
direction; sample weights ≤ 1 for a perfect reflector at every wind speed (the glint's albedo
≤ 1); wind speed through mi.traverse; polarized variants; one-line errors. Slow tier: χ² of
the visible-normal sampler (alone and mixed with the whitecaps), reciprocity, consistency.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from conftest import set_variant
from earth_helpers import assert_load_error, cos_reference, direction
from helpers import assert_matches_reference, eval_pdf, random_directions, sample

from mi_brdfs.errors import MiBrdfsWarning
from mi_brdfs.reference import ocean as ref
from mi_brdfs.scattering import ocean as terms
from mi_brdfs.testing import assert_consistent, assert_reciprocal, assert_sampling_matches_pdf

#: float32 terms (D's exponential, Λ's erf, Fresnel) each within a few ulps; the directions'
#: rounding is the conditioning of assert_matches_reference.
RTOL = 2e-5
#: Parameter sets: the defaults; a windy sea of slightly absorbing water; along the wind;
#: whitecaps (Koepke's 0.22) in a storm; coloured whitecaps, along the wind, another exterior.
SETS = [
    {},
    {"wind_speed": 7.0, "eta": 1.34, "k": 0.01},
    {"wind_speed": 3.0, "wind_direction": 40.0},
    {"wind_speed": 12.0, "whitecaps": True},
    {"wind_speed": 12.0, "whitecaps": {"type": "rgb", "value": [0.5, 0.3, 0.2]},
     "wind_direction": -70.0, "ext_ior": 1.2, "eta": 1.5},
]


def _model(params):
    """The reference of a parameter set (an <rgb> as its channels)."""
    p = dict(params)
    wc = p.pop("whitecaps", None)
    wc = 0.22 if wc is True else (wc["value"] if isinstance(wc, dict) else wc)
    return ref.Ocean(**p, whitecaps=wc)


def _pairs(rng, n):
    """Random pairs, a third of them within a few degrees of the mirror direction."""
    wi, wo = random_directions(rng, n, lower=False), random_directions(rng, n, lower=False)
    k = n // 3
    near = wi[:k] * [-1, -1, 1] + rng.normal(0.0, 0.05, (k, 3))
    near[:, 2] = np.abs(near[:, 2]) + 1e-3
    wo[:k] = near / np.linalg.norm(near, axis=1, keepdims=True)
    return wi, wo


# -- the reference ---------------------------------------------------------------------------

def test01_reference_slopes_and_fresnel():
    """∫ D cosθm dωm = 1 and the slopes' variances are Cox & Munk's (isotropic σ² = 0.003 +
    0.00512 U in total; along and across a wind at 25°: 0.00316 U and 0.003 + 0.00192 U), by
    quadrature over slope space; F at normal incidence is ((n − 1)² + κ²)/((n + 1)² + κ²) of
    n + iκ = (η + ik)/n_ext, and → 1 at grazing."""
    z = np.linspace(-1.2, 1.2, 481)  # beyond 7σ of every axis here
    zx, zy = np.meshgrid(z, z, indexing="ij")
    dz = (z[1] - z[0]) ** 2
    # per axis: (0.003 + 0.00512·6)/2 twice; 0.00316·8 and 0.003 + 0.00192·8
    for params, var_u, var_c in (({"wind_speed": 6.0}, 0.01686, 0.01686),
                                 ({"wind_speed": 8.0, "wind_direction": 25.0}, 0.02528, 0.01836)):
        model = ref.Ocean(**params)
        p = model.slope_pdf(zx, zy)
        assert abs(p.sum() * dz - 1) < 1e-9
        c, s = math.cos(math.radians(params.get("wind_direction", 0.0))), \
            math.sin(math.radians(params.get("wind_direction", 0.0)))
        zu, zc = c * zx + s * zy, c * zy - s * zx
        assert (p * zu ** 2).sum() * dz == pytest.approx(var_u, rel=1e-9)
        assert (p * zc ** 2).sum() * dz == pytest.approx(var_c, rel=1e-9)
        # D per solid angle: the same integral over normals (θm < 56°, where the slopes end)
        m = np.stack([-zx, -zy, np.ones_like(zx)], -1).reshape(-1, 3)
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        jac = m[:, 2] ** 3  # dωm = cos³θm dzx dzy
        assert (model.ndf(m) * m[:, 2] * jac).sum() * dz == pytest.approx(1.0, abs=1e-9)
    n = (1.5 + 0.3j) / 1.2
    f = ref.fresnel(np.array([1.0, 1e-9]), 1.5, 0.3, 1.2)[:, 0]
    assert f[0] == pytest.approx(abs((n - 1) / (n + 1)) ** 2, rel=1e-12)
    assert f[1] == pytest.approx(1.0, abs=1e-8)


def test02_whitecap_coverage_at_10_m_s(variant_scalar_rgb):
    """Monahan & O'Muircheartaigh's W(10 m/s) = 2.95·10⁻⁶ × 10^3.52 = 2.95·10⁻⁶ × 3311.31 =
    0.0097684 (by hand), in the reference and the plugin's terms; 1 beyond 37.25 m/s."""
    assert ref.coverage(10.0) == pytest.approx(0.0097684, rel=1e-5)
    assert terms.coverage(10.0) == pytest.approx(0.0097684, rel=1e-5)
    assert terms.coverage(37.54) == 1.0 and ref.coverage(37.54) == 1.0


# -- eval ------------------------------------------------------------------------------------

def test03_eval_is_the_reference(variants_rgb, np_rng):
    """eval = f·cosθo of the float64 reference per channel at random and near-specular pairs,
    for every set of :data:`SETS` in scalar_rgb; in llvm_ad_rgb (a kernel per set) the
    defaults and the set with every option."""
    scalar = variants_rgb.startswith("scalar")
    wi, wo = _pairs(np_rng, 60 if scalar else 2000)
    for params in SETS if scalar else (SETS[0], SETS[4]):
        bsdf = mi.load_dict({"type": "ocean", **params})
        assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(_model(params)),
                                 wi, wo, RTOL, f"ocean {params}")


def test04_a_wrong_roughness_is_rejected(variant_llvm_ad_rgb, np_rng, monkeypatch):
    """α² = σ²/2 (the variance of one axis for Beckmann's α², a factor 2 off) fails the
    comparison (along the wind here; test_ocean_eradiate.py: isotropic)."""
    right = terms.roughness

    def halved(wind_speed, anisotropic):
        a_u, a_v = right(wind_speed, anisotropic)
        return a_u / math.sqrt(2), None if a_v is None else a_v / math.sqrt(2)

    monkeypatch.setattr(terms, "roughness", halved)
    wi, wo = _pairs(np_rng, 300)
    for params in SETS[2:3]:
        bsdf = mi.load_dict({"type": "ocean", **params})
        with pytest.raises(AssertionError, match="against the float64 reference"):
            assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], cos_reference(_model(params)),
                                     wi, wo, RTOL, "ocean halved")


def test05_the_glint_peaks_at_the_mirror_direction(variant_scalar_rgb):
    """In the plane of incidence, eval of a calm sea (U = 0: the narrowest glint) is largest
    at θo = θi forward, within the 0.25° step, for θi = 20°, 40°; towards grazing and for a
    windier sea the peak moves forward, where Fresnel's reflectance and 1/(cosθi cos⁴θm)
    grow (0.75° at θi = 60°; 2.25° at U = 5 m/s, θi = 40°); the reference's peaks are the
    same."""
    for u, ti, shift in ((0.0, 20.0, 0.0), (0.0, 40.0, 0.0), (0.0, 60.0, 0.75),
                         (5.0, 40.0, 2.25)):
        theta_o = np.radians(np.arange(ti - 6.0, ti + 6.0, 0.25))  # the peak within ±6°
        bsdf = mi.load_dict({"type": "ocean", "wind_speed": u})
        wi = np.repeat(direction(np.radians(ti))[None], len(theta_o), 0)
        wo = direction(theta_o, np.pi)
        ours = eval_pdf(bsdf, wi, wo)[0][:, 0]
        theirs = ref.Ocean(u).brdf(wi, wo)[:, 0] * wo[:, 2]
        for values in (ours, theirs):
            peak = math.degrees(theta_o[np.argmax(values)])
            assert abs(peak - ti - shift) <= 0.25, (u, ti, peak)


def _singular():
    """θi = θo = 0, exact backscatter and the mirror direction up to the horizon, grazing
    views (cosθo = 10⁻⁷ and 0) from nadir and from grazing."""
    theta = np.radians([0.0, 30.0, 89.0, 89.99999, 90.0])
    w = direction(theta, 0.4)
    z = np.array([[0.0, 0.0, 1.0]])
    graze = direction(np.arccos([1e-7, 0.0]), [0.0, 2.0])
    wi = np.concatenate([w, w, np.repeat(z, 2, 0), graze, graze])
    wo = np.concatenate([w, w * [-1, -1, 1], graze, graze, graze[::-1]])
    return wi, wo


def test06_finite_and_non_negative_at_the_singular_places(variants_rgb):
    """eval, pdf and sample weights finite and ≥ 0 in float32, calm (the narrowest glint)
    and stormy along the wind with whitecaps."""
    wi, wo = _singular()
    for params in ({"wind_speed": 0.0}, {"wind_speed": 30.0, "wind_direction": 10.0,
                                         "whitecaps": True}):
        bsdf = mi.load_dict({"type": "ocean", **params})
        for x in eval_pdf(bsdf, wi, wo):
            assert np.isfinite(x).all() and (x >= 0).all(), (params, x)
        s = sample(bsdf, np.repeat(wi[:5], 4, 0), np.full(20, 0.3),
                   np.tile([[0.0, 0.0], [0.5, 0.5], [0.999, 0.2], [0.3, 0.999]], (5, 1)))
        assert np.isfinite(s["weight"]).all() and (s["weight"] >= 0).all(), s["weight"]
        assert np.isfinite(s["pdf"]).all()


def test07_the_glint_reflects_at_most_the_light_it_receives(variant_llvm_ad_rgb, np_rng):
    """A perfect reflector's glint (η = 10⁵: F ≈ 1): every sample weight S/G1(ωi) ≤ 1 and
    their mean, the albedo, in (0, 1], at every wind speed from calm to 37.54 m/s (set
    through mi.traverse: one kernel) and θi up to 89.9°."""
    n = 1000
    theta = np.radians([0.0, 45.0, 80.0, 89.0, 89.9])
    wi = np.repeat(direction(theta), n, 0)
    u1, u2 = np_rng.random(len(wi)), np_rng.random((len(wi), 2))
    bsdf = mi.load_dict({"type": "ocean", "eta": 1e5})
    params = mi.traverse(bsdf)
    for u in (0.0, 1.0, 5.0, 15.0, 37.54):
        params["wind_speed"] = u
        params.update()
        w = sample(bsdf, wi, u1, u2)["weight"][:, 0].reshape(len(theta), n)
        assert w.max() <= 1.0 + 1e-5, (u, w.max())
        assert (w.mean(axis=1) > 0.5).all(), (u, w.mean(axis=1))


# -- parameters ------------------------------------------------------------------------------

def test08_wind_speed_through_traverse(variant_llvm_ad_rgb, np_rng):
    """mi.traverse exposes wind_speed, eta.value, k.value, ext_ior.value; eval follows the
    reference at a new wind speed and index."""
    bsdf = mi.load_dict({"type": "ocean"})
    params = mi.traverse(bsdf)
    assert {"wind_speed", "eta.value", "k.value", "ext_ior.value"} <= set(params.keys())
    params["wind_speed"] = 9.0
    params["eta.value"] = 1.36
    params.update()
    wi, wo = _pairs(np_rng, 600)
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0],
                             cos_reference(ref.Ocean(9.0, eta=1.36)), wi, wo, RTOL,
                             "ocean traversed")


@pytest.mark.parametrize("variant", ["scalar_spectral_polarized", "llvm_ad_spectral_polarized"])
def test09_polarized_variants(variant):
    """The glint is Fresnel's Mueller matrix: its (0, 0) element is the unpolarized value
    (the float64 reference's at 550 nm, η = 1.33), its (0, 1) element (F_s − F_p)/2·… is not
    0 (reflection polarizes); sampling gives finite weights. The matrix test renders every
    variant."""
    set_variant(variant)
    bsdf = mi.load_dict({"type": "ocean", "wind_speed": 5.0, "whitecaps": True})
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0.6, 0.0, 0.8)
    si.wavelengths = mi.UnpolarizedSpectrum(550.0)
    wo = np.array([-0.55, 0.1, 0.829])
    wo /= np.linalg.norm(wo)
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*map(float, wo)))
    expected = ref.Ocean(5.0, whitecaps=0.22).brdf(np.array([[0.6, 0.0, 0.8]]), wo[None])
    assert np.ravel(value[0, 0])[0] == pytest.approx(expected[0, 0] * wo[2], rel=1e-4)
    assert abs(np.ravel(value[0, 1])[0]) > 1e-3 * np.ravel(value[0, 0])[0]
    bs, weight = bsdf.sample(mi.BSDFContext(), si, 0.3, mi.Point2f(0.4, 0.6))
    assert np.isfinite(np.ravel(weight[0, 0])).all() and np.ravel(weight[0, 0])[0] > 0


@pytest.mark.parametrize("extra,message", [
    ({"wind_speed": -1.0}, 'ocean: parameter "wind_speed" = -1 is invalid: must be finite and '
                           'within [0, 37.54]'),
    ({"wind_speed": 40.0}, 'ocean: parameter "wind_speed" = 40 is invalid'),
    ({"eta": 0.0}, 'ocean: parameter "eta" = 0 is invalid'),
    ({"whitecaps": 1.5}, 'ocean: parameter "whitecaps" = 1.5 is invalid'),
    ({"wind_direction": "north"}, 'ocean: parameter "wind_direction" = "north" is invalid: '
                                  'must be a number'),
    ({"wind_dir": 10.0}, "did you mean wind_direction"),
])
def test10_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    assert_load_error(dict(type="ocean", **extra), message)


def test11_structure(variant_scalar_rgb):
    """One glossy component; with whitecaps a diffuse one too, whose reflectance
    eval_diffuse_reflectance returns: W·0.22."""
    bsdf = mi.load_dict({"type": "ocean"})
    assert bsdf.component_count() == 1
    assert bsdf.flags(0) == int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
    foam = mi.load_dict({"type": "ocean", "wind_speed": 10.0, "whitecaps": True})
    assert foam.component_count() == 2
    assert foam.flags(1) == int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0, 0, 1)
    assert foam.eval_diffuse_reflectance(si)[0] == pytest.approx(0.22 * 0.0097684, rel=1e-4)
    text = str(foam)
    assert text.startswith("Ocean[") and all(f"{k} = " in text for k in
                                             ("wind_speed", "eta", "k", "ext_ior", "whitecaps"))


# -- slow tier: sampling, reciprocity --------------------------------------------------------

def test12_visible_normal_sampling(variant_llvm_ad_rgb):
    """χ² of sample() against pdf() at θi = 60°: isotropic, along the wind, and mixed with
    the whitecaps' cosine lobe (a storm: W = 0.49); bs.pdf = pdf(bs.wo), weight = eval/pdf."""
    wi = list(direction(np.radians(60.0), 0.3))
    for params in ({"wind_speed": 5.0}, {"wind_speed": 8.0, "wind_direction": 60.0},
                   {"wind_speed": 30.0, "whitecaps": True}):
        spec = {"type": "ocean", **params}
        assert_sampling_matches_pdf(spec, wi=wi, sample_count=200_000)
        assert_consistent(spec, n=20_000)


def test13_reciprocal(variant_llvm_ad_rgb):
    """f(a, b) = f(b, a): F(ωi·m) = F(ωo·m), D and S are symmetric; the whitecaps are
    Lambertian."""
    assert_reciprocal({"type": "ocean", "wind_speed": 6.0, "wind_direction": 20.0,
                       "whitecaps": True})


def test14_without_shadowing_the_albedo_exceeds_1(variant_llvm_ad_rgb, np_rng):
    """shadowing = false (S dropped): a perfect reflector's glint reflects F·(1 + Λ(ωi)) > 1
    at θi = 89.9°, and the plugin warns at load, in one line."""
    with pytest.warns(MiBrdfsWarning, match="ocean: shadowing = false"):
        bare = mi.load_dict({"type": "ocean", "eta": 1e5, "wind_speed": 15.0,
                             "shadowing": False})
    n = 4000
    wi = np.repeat(direction(np.radians([89.9])), n, 0)
    assert sample(bare, wi, np_rng.random(n), np_rng.random((n, 2)))["weight"][:, 0].mean() > 1.2
