"""
The ashikhmin plugin: structure, eval and pdf against the float64 reference (RGB and spectral,
isotropic and anisotropic), the sampler against the paper's recipe, χ² up to 85° and 1:100
anisotropy, consistency, reciprocity, the albedo against the reference, stability at the
exponents' extremes and grazing directions, a render, textures, gradients and bad input. The
heavier statistics are in the validation campaign (``mi_brdfs/campaign/ashikhmin.py``).
"""

import math

import mitsuba as mi
import numpy as np
import pytest
from conftest import set_variant
from helpers import assert_matches_reference, eval_gradient, eval_pdf, random_directions, sample
from test_ward import _sphere_scene

from mi_brdfs import checks
from mi_brdfs.reference import Ashikhmin


def ashikhmin(exponent=100.0, **kwargs):
    spec = {"type": "ashikhmin"}
    if isinstance(exponent, tuple):
        spec.update(nu=exponent[0], nv=exponent[1])
    elif exponent is not None:
        spec["exponent"] = exponent
    return dict(spec, **kwargs)


# -- structure ------------------------------------------------------------------------------------

def test01_create(variant_scalar_rgb):
    D = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
    G = int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
    A = int(mi.BSDFFlags.Anisotropic)
    cases = [({}, [D, G]), ({"nu": 10.0, "nv": 100.0}, [D, G | A]),
             ({"nu": 10.0, "nv": 10.0}, [D, G]), ({"diffuse_reflectance": 0.0}, [G]),
             ({"specular_reflectance": 1.0}, [G]), ({"specular_reflectance": 0.0}, [D, G]),
             ({"nu": {"type": "checkerboard"}, "nv": 10.0}, [D, G | A])]
    for params, components in cases:
        bsdf = mi.load_dict(ashikhmin(None, **params))
        assert type(bsdf).__name__ == "Ashikhmin"
        assert [bsdf.flags(i) for i in range(bsdf.component_count())] == components, params
    text = str(mi.load_dict(ashikhmin((10.0, 100.0))))
    assert text.startswith("Ashikhmin[") and "nu = " in text and "nv = " in text
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict(ashikhmin(alpha=0.1))


# -- bad input, and the scalar variant ------------------------------------------------------------

BAD = [
    ({"exponent": -1.0}, r'ashikhmin: parameter "exponent" = -1 is invalid: must be finite and '
                         r'within \[0, 1e\+30\]'),
    ({"nu": float("nan"), "nv": 1.0}, r'"nu" = nan is invalid'),
    ({"nv": 10.0}, r'"nv" = 10 is invalid: needs nu as well'),
    ({"exponent": 10.0, "nu": 5.0}, r'"nu" = 5 is invalid: must not be given together with '
                                    r'exponent'),
    ({"nu": {"type": "rgb", "value": [1.0, 2.0, 3.0]}, "nv": 1.0},
     r'"nu" = \[1.0, 2.0, 3.0\] is invalid: must be a float or a texture'),
    ({"diffuse_reflectance": 1.5}, r'"diffuse_reflectance" = 1.5 is invalid: must be finite and '
                                   r'within \[0, 1\]'),
    ({"specular_reflectance": -0.2}, r'"specular_reflectance" = -0.2 is invalid'),
]


@pytest.mark.parametrize("params,match", BAD, ids=[next(iter(p)) + str(i)
                                                   for i, (p, _) in enumerate(BAD)])
def test02_bad_input(variant_scalar_rgb, params, match):
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict(dict({"type": "ashikhmin"}, **params))


def test03_scalar_variant(variant_scalar_rgb):
    """
    In scalar_rgb (Python floats, one lane per call): weight = eval/pdf, bs.pdf = pdf(bs.wo),
    f(a, b) = f(b, a), and no NaN/Inf/negative value at exponents 0 and 10⁶ and the stress
    directions (the JIT variant: test06, test09).
    """
    spec = ashikhmin((10.0, 300.0), diffuse_reflectance=0.5, specular_reflectance=0.2)
    for check in (checks.check_consistency, checks.check_reciprocity):
        result = check(spec, n=200)
        assert result.passed, result.message
    extreme = ashikhmin((0.0, 1e6), diffuse_reflectance=0.5, specular_reflectance=0.5)
    result = checks.check_stability(extreme, n_random=10)
    assert result.passed and "rejected" not in result.message, result.message


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_spectral", "llvm_ad_rgb"])
def test04_eval_pdf_against_reference(variant, np_rng):
    """
    eval/cosθo = the reference's f (the paper's ρs + ρd) and pdf = the mixture of the cosine
    hemisphere and the paper's density p(k2) with the documented lobe probability, at
    random pairs and pairs near the mirror direction.
    """
    set_variant(variant)
    n = 40 if variant.startswith("scalar") else 1000
    wi = random_directions(np_rng, n, lower=False)
    near = wi[: n // 2] * [-1, -1, 1] + np_rng.normal(0, 0.05, (n // 2, 3))
    wo = np.concatenate([random_directions(np_rng, n - n // 2), near])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    rho_d, rho_s = 0.6, 0.1
    x = 0.5 * wi[:, 2]
    w_s = rho_s + (1 - rho_s) * (1 - x) ** 5
    w_d = rho_d * (1 - rho_s) * (1 - (1 - x) ** 5)
    p_s = w_s / (w_s + w_d)
    for exponent in (100.0, (10.0, 1000.0)):
        spec = ashikhmin(exponent, diffuse_reflectance=rho_d, specular_reflectance=rho_s)
        f, p, f2, p2 = eval_pdf(mi.load_dict(spec), wi, wo)
        ref = Ashikhmin(exponent, rho_d, rho_s)
        assert_matches_reference(f, lambda a, b: ref.brdf(a, b) * np.maximum(b[:, 2:3], 0.0),
                                 wi, wo, 1e-4, what=f"{variant} {exponent}")
        expected = p_s * ref.sampling_pdf(wi, wo) + (1 - p_s) * np.maximum(wo[:, 2], 0) / np.pi
        assert_matches_reference(p, lambda a, b: expected, wi, wo, 1e-4, what="pdf")
        np.testing.assert_array_equal(f2, f)
        np.testing.assert_array_equal(p2, p)


def test05_sampler_is_the_papers_recipe(variant_llvm_ad_rgb, np_rng):
    """
    The glossy lobe reflects ωi about h of the paper's recipe, written here with tan, atan:
    φ = atan(√((nu+1)/(nv+1)) tan(πξ/2)), ξ = 4u₁ mod 1 run backwards in the second and
    fourth quadrants, φ → π − φ, π + φ, 2π − φ there; cosθh = (1 − u₂)^(1/(nu cos²φ +
    nv sin²φ + 1)).
    """
    n, nu, nv = 2000, 10.0, 1000.0
    wi = random_directions(np_rng, n, lower=False)
    u = np_rng.random((n, 2)) * 0.998 + 0.001
    quadrant, xi = np.divmod(4 * u[:, 0], 1.0)
    xi = np.where(quadrant % 2 == 1, 1 - xi, xi)
    phi1 = np.arctan(math.sqrt((nu + 1) / (nv + 1)) * np.tan(0.5 * np.pi * xi))
    phi = np.choose(quadrant.astype(int), [phi1, np.pi - phi1, np.pi + phi1, 2 * np.pi - phi1])
    cos_t = (1 - u[:, 1]) ** (1 / (nu * np.cos(phi) ** 2 + nv * np.sin(phi) ** 2 + 1))
    sin_t = np.sqrt(1 - cos_t**2)
    h = np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=1)
    expected = 2 * np.sum(wi * h, axis=1, keepdims=True) * h - wi
    s = sample(mi.load_dict(ashikhmin((nu, nv), diffuse_reflectance=0.0)), wi,
               np.full(n, 0.5), u)
    ok = expected[:, 2] > 0
    np.testing.assert_allclose(s["wo"][ok], expected[ok], atol=5e-5)
    assert (s["weight"][~ok] == 0).all()


def test06_consistency_and_reciprocity(variant_llvm_ad_rgb):
    """weight = eval/pdf, bs.pdf = pdf(bs.wo), eval_pdf = (eval, pdf); f(a, b) = f(b, a)."""
    spec = ashikhmin((10.0, 300.0), diffuse_reflectance=0.5, specular_reflectance=0.2)
    for check in (checks.check_consistency, checks.check_reciprocity):
        result = check(spec, n=5_000)
        assert result.passed, result.message


# -- sampling and energy --------------------------------------------------------------------------

CHI2 = [(100.0, 0.0), ((10.0, 1000.0), 45.0), ((30.0, 3.0), 85.0)]


@pytest.mark.parametrize("exponent,theta", CHI2, ids=[f"{e}-{t:g}deg" for e, t in CHI2])
def test07_chi2(variant_llvm_ad_rgb, exponent, theta):
    """sample() draws what pdf() reports: normal to grazing incidence, 1:100 and 10:1
    anisotropy (sharper lobes and more angles: the campaign)."""
    spec = ashikhmin(exponent, diffuse_reflectance=0.5, specular_reflectance=0.1)
    t = math.radians(theta)
    wi = [0.6 * math.sin(t), 0.8 * math.sin(t), math.cos(t)]
    result = checks.chi2_bsdf(spec, wi=wi, res=None, ires=None, sample_count=200_000,
                              test_count=len(CHI2))
    assert result.passed, result.message


def test08_albedo_matches_reference_and_stays_below_one(variant_llvm_ad_rgb):
    """
    E(θ) from sample() weights equals the reference's quadrature (within 5σ + 1e-3) and is
    ≤ 1 (the paper's claim: energy is conserved), with Rd = 1 and a grazing 80° and 89°.
    """
    for exponent, rho_s, theta in ((20.0, 0.0, 80.0), ((10.0, 1000.0), 0.5, 89.0)):
        spec = ashikhmin(exponent, diffuse_reflectance=1.0, specular_reflectance=rho_s)
        t = math.radians(theta)
        mean, err = checks.albedo_sampled(spec, t, n=50_000)
        ref = Ashikhmin(exponent, 1.0, rho_s)
        expected = ref.diffuse_albedo(t) + ref.specular_albedo(t, n_t=64, n_phi=256)
        assert abs(mean[0] - expected[0]) <= 5 * err[0] + 1e-3, (mean, err, expected)
        assert expected[0] <= 1.0 and mean[0] <= 1.0 + 5 * err[0]


# -- stability, rendering, textures, AD -----------------------------------------------------------

def test09_stability(variant_llvm_ad_rgb):
    """No NaN/Inf/negative value anywhere: exponents 0 and 10⁶, both alike and as nu and nv,
    at grazing directions, ωo = ωi, ωo = −ωi, h = n."""
    grid = [ashikhmin(e, diffuse_reflectance=0.5, specular_reflectance=0.5)
            for e in (0.0, 1e6, (0.0, 1e6))]
    result = checks.check_stability(grid, n_random=100)
    assert result.passed, result.message
    assert "rejected" not in result.message


def test10_textures_and_render(variant_llvm_ad_rgb, tmp_path):
    """
    A bitmap for each reflectance and a checkerboard for each exponent: consistent, rendered
    (traced symbolically, as only mi.render does) to a finite, lit image, and at a pixel of
    each checker cell equal to the reference with that pixel's reflectances and that cell's
    exponents.
    """
    rng = np.random.default_rng(1)
    maps = {}
    for name in ("diffuse_reflectance", "specular_reflectance"):
        maps[name] = rng.uniform(0, 0.5, (8, 8, 3)).astype(np.float32)
        mi.Bitmap(maps[name]).write(str(tmp_path / f"{name}.exr"))
    spec = ashikhmin(None, nu={"type": "checkerboard", "color0": 10.0, "color1": 300.0},
                     nv={"type": "checkerboard", "color0": 100.0, "color1": 1.0},
                     **{name: {"type": "bitmap", "filename": str(tmp_path / f"{name}.exr")}
                        for name in maps})
    result = checks.check_consistency(spec, n=2_000, rtol=1e-5)
    assert result.passed, result.message
    image = np.array(mi.render(_sphere_scene(spec, res=8), spp=4))
    assert np.isfinite(image).all() and image.mean() > 0.05
    wi, wo = random_directions(rng, 200, lower=False), random_directions(rng, 200, lower=False)
    bsdf = mi.load_dict(spec)
    # (column, row) of a bitmap pixel, whose centre lies in the checker cell of (nu, nv)
    for (col, row), exponents in (((6, 1), (10.0, 100.0)), ((2, 1), (300.0, 1.0))):
        f = eval_pdf(bsdf, wi, wo, uv=((col + 0.5) / 8, (row + 0.5) / 8))[0]
        ref = Ashikhmin(exponents, maps["diffuse_reflectance"][row, col],
                        maps["specular_reflectance"][row, col])
        assert_matches_reference(f, lambda a, b: ref.brdf(a, b) * b[:, 2:3], wi, wo, 1e-4,
                                 what=f"textured, uv cell of {exponents}")


def test11_traverse_and_gradients(variant_llvm_ad_rgb, np_rng):
    """
    The parameters of existing lobes are exposed; d eval/dnu and d eval/dRs by AD equal
    central differences (no sampling involved: 1e-3).
    """
    bsdf = mi.load_dict(ashikhmin((10.0, 300.0)))
    params = mi.traverse(bsdf)
    assert set(params.keys()) == {"diffuse_reflectance.value", "specular_reflectance.value",
                                  "nu.value", "nv.value"}
    assert set(mi.traverse(mi.load_dict(ashikhmin(diffuse_reflectance=0.0))).keys()) == \
        {"specular_reflectance.value", "exponent.value"}
    wi = random_directions(np_rng, 500, lower=False)
    wo = wi * [-1, -1, 1] + np_rng.normal(0, 0.1, wi.shape)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for key, value, step in (("nu.value", 10.0, 0.01), ("specular_reflectance.value", 0.04,
                                                          0.001)):
        grad, finite = eval_gradient(bsdf, key, value, step, wi, wo)
        assert grad == pytest.approx(finite, rel=1e-3), key
