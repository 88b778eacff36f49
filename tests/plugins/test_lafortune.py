"""
The lafortune plugin: structure and lobe numbering, eval and pdf against the float64 reference
(both normalisations, three lobes), the mirror lobe against ``phong``, χ² with three lobes up to
grazing incidence, consistency, reciprocity, the lobes' features (retro-reflection, off-specular
peaks), energy, stability at the extremes, rendering with textures, AD and bad input. The heavy
statistics are in the campaign (``mi_brdfs/campaign/lafortune.py``, ``make validate``).

The tests run in ``llvm_ad_rgb``, then ``llvm_ad_spectral``, then ``scalar_rgb``, where the
value checks are repeated: each change to an LLVM variant costs a tenth of a second.
"""

import math

import mitsuba as mi
import numpy as np
import pytest
from helpers import assert_matches_reference, eval_gradient, eval_pdf, random_directions, sample
from test_ward import _sphere_scene

import mi_brdfs
from conftest import set_variant
from mi_brdfs import checks
from mi_brdfs.reference import Lafortune, Phong, for_spec

#: Three lobes: off-specular (|Cz| < −Cx = −Cy), retro-reflective, anisotropic and sharp.
THREE = {"cx_0": -1.0, "cy_0": -1.0, "cz_0": 0.6, "exponent_0": 20.0,
         "specular_reflectance_0": 0.3,
         "cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0, "exponent_1": 5.0, "specular_reflectance_1": 0.2,
         "cx_2": -0.5, "cy_2": -1.0, "cz_2": 1.0, "exponent_2": 200.0,
         "specular_reflectance_2": 0.25, "diffuse_reflectance": 0.1}


def lafortune(**kwargs):
    return dict({"type": "lafortune"}, **kwargs)


def scalar():
    return mi.variant().startswith("scalar")


@pytest.fixture
def variant_llvm_ad_spectral():
    return set_variant("llvm_ad_spectral")


# -- structure ------------------------------------------------------------------------------------

def test01_create(variant_llvm_ad_rgb):
    """Lobes from the indices given (one, lobe 0, by default); components diffuse first, a
    zero lobe left out; Cx ≠ Cy anisotropic; every property read."""
    D = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
    G = int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
    A = int(mi.BSDFFlags.Anisotropic)
    cases = [({}, [D, G]), (THREE, [D, G, G, G | A]),
             ({"specular_reflectance_0": 0.0, "exponent_1": 3.0}, [D, G]),
             ({"diffuse_reflectance": 0.0, "specular_reflectance_0": 0.0}, [])]
    for params, components in cases:
        bsdf = mi.load_dict(lafortune(**params))
        assert type(bsdf).__name__ == "Lafortune"
        assert [bsdf.flags(i) for i in range(bsdf.component_count())] == components, params
    # parameter names keep the lobe's index where a lobe before it is left out
    keys = mi.traverse(mi.load_dict(lafortune(**cases[2][0]))).keys()
    assert "specular_reflectance_1.value" in keys and "exponent_1" in keys, keys
    assert not any(k.endswith("_0") or "_0." in k for k in keys), keys
    text = str(mi.load_dict(lafortune(normalize=False, **THREE)))
    assert "Lafortune[" in text and "normalize = false" in text and "lobe 2 = [" in text
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict(lafortune(cw_0=1.0))


def _eval_pdf_matches_reference(rng):
    """eval/cosθo = the reference's f (three lobes, both forms, an RGB lobe reflectance where
    RGB means RGB); pdf = the reference's mixture; eval_pdf = (eval, pdf)."""
    n_pairs = 40 if scalar() else 3000
    wi = random_directions(rng, n_pairs, lower=False)
    for normalize in (True, False):
        spec = lafortune(normalize=normalize, **THREE)
        if not mi.is_spectral:
            spec["specular_reflectance_1"] = {"type": "rgb", "value": [0.1, 0.2, 0.3]}
        ref = for_spec(spec)
        axes = ref._axis(0, wi[: n_pairs // 2])[0]  # half of the pairs near lobe 0's peak
        wo = np.concatenate([random_directions(rng, n_pairs - n_pairs // 2),
                             axes + rng.normal(0, 0.1, axes.shape)])
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        f, p, f2, p2 = eval_pdf(mi.load_dict(spec), wi, wo)
        assert_matches_reference(f, lambda a, b: ref.brdf(a, b) * np.maximum(b[:, 2:3], 0),
                                 wi, wo, 1e-4, what=f"{mi.variant()}, normalize = {normalize}")
        np.testing.assert_allclose(p, ref.sampling_pdf(wi, wo), rtol=1e-4, atol=1e-7)
        np.testing.assert_array_equal(f2, f)
        np.testing.assert_array_equal(p2, p)


def test02_eval_pdf_against_reference(variant_llvm_ad_rgb, np_rng, recwarn):
    _eval_pdf_matches_reference(np_rng)


def _mirror_lobe_is_phong(rng, n):
    """
    Cx = Cy = −Cz: with ``normalize`` (any scale of C) exactly phong's ``normalized`` mirror
    form, eval, pdf and samples alike; the paper's form with C = (−1, −1, 1) is phong's
    ``lecture`` form, with −Cx = −Cy = Cz = ((n+2)/(2π))^(1/n) (the paper's Phong lobe) the
    ``normalized`` one. Never ``original``: its f/f_lafortune = 1/(N·L) is not constant.
    """
    n_pairs = 30 if scalar() else 2000
    wi, wo = random_directions(rng, n_pairs, False), random_directions(rng, n_pairs, False)
    ours = mi.load_dict(lafortune(cx_0=-2.5, cy_0=-2.5, cz_0=2.5, exponent_0=n))
    phong = mi.load_dict({"type": "phong", "exponent": n})
    for a, b in zip(eval_pdf(ours, wi, wo), eval_pdf(phong, wi, wo)):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9)
    u1, u2 = rng.random(n_pairs), rng.random((n_pairs, 2))
    a, b = sample(ours, wi, u1, u2), sample(phong, wi, u1, u2)
    for key in ("wo", "pdf", "weight", "component"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-5, atol=1e-7, err_msg=key)
    c = ((7.0 + 2) / (2 * math.pi)) ** (1 / 7.0)
    pairs = {"lecture": lafortune(normalize=False, exponent_0=7.0),
             "normalized": lafortune(normalize=False, cx_0=-c, cy_0=-c, cz_0=c, exponent_0=7.0)}
    for form, spec in pairs.items():
        phong = {"type": "phong", "form": form, "exponent": 7.0}
        np.testing.assert_allclose(eval_pdf(mi.load_dict(spec), wi, wo)[0],
                                   eval_pdf(mi.load_dict(phong), wi, wo)[0], rtol=2e-5)
    # original = lecture / (N·L): with L = ωo in radiance transport, the ratio is cosθo
    original = Phong(0.0, 0.2, 7.0, "original").brdf(wi, wo)[:, 0]
    lecture = Lafortune([{"exponent": 7.0}], 0.0, normalize=False).brdf(wi, wo)[:, 0]
    lit = lecture > 1e-3
    np.testing.assert_allclose(lecture[lit] / original[lit], wo[lit, 2], rtol=1e-9)
    assert wo[lit, 2].max() / wo[lit, 2].min() > 2


def test03_mirror_lobe_is_phong(variant_llvm_ad_rgb, np_rng):
    _mirror_lobe_is_phong(np_rng, 1000.0)  # n = 0 (a uniform lobe): test13


# -- sampling, consistency, reciprocity -----------------------------------------------------------

@pytest.mark.parametrize("theta", [0.0, 60.0, 85.0])
def test04_chi2_three_lobes(variant_llvm_ad_rgb, theta):
    """sample() draws what pdf() reports, three lobes and the diffuse term, normal to grazing
    (out of the incidence plane: the anisotropic lobe turns)."""
    t = math.radians(theta)
    wi = [0.6 * math.sin(t), 0.8 * math.sin(t), math.cos(t)]
    result = checks.chi2_bsdf(lafortune(**THREE), wi=wi, res=101, ires=4,
                              sample_count=100_000, test_count=3)
    assert result.passed, result.message


def _consistent():
    """weight = eval/pdf, bs.pdf = pdf(bs.wo), eval_pdf = (eval, pdf), flags, with one lobe
    alone (ctx.component) in importance transport (the same as radiance: reciprocal); every
    lobe together: test10."""
    one = mi.BSDFContext(mi.TransportMode.Importance)
    one.component = 3  # lobe 2
    result = checks.check_consistency(lafortune(**THREE), n=200 if scalar() else 10_000,
                                      rtol=1e-5, ctx=one)
    assert result.passed, result.message
    s = sample(mi.load_dict(lafortune(**THREE)), [0.6, 0.0, 0.8], np.full(50, 0.5),
               np.random.default_rng(1).random((50, 2)), one)
    assert set(s["component"][s["weight"][:, 0] > 0]) == {3}


def test05_consistency(variant_llvm_ad_rgb):
    _consistent()


def test06_reciprocal_in_every_configuration(variant_llvm_ad_rgb, recwarn):
    """
    f(a, b) = f(b, a) for both forms with arbitrary signs, anisotropy, a lobe below the
    horizon: g is symmetric in u and v and K depends on C and n alone, so no configuration is
    non-reciprocal. The check can fail: phong's ``original`` form is measured asymmetric.
    """
    rng = np.random.default_rng(7)
    for normalize in (True, False):
        coefficients = rng.uniform(-1.2, 1.2, (3, 3))
        spec = lafortune(normalize=normalize, **{f"c{a}_{i}": float(coefficients[i, j])
                                                for i in range(3) for j, a in enumerate("xyz")},
                         exponent_0=2.0, exponent_1=9.0, exponent_2=0.5)
        result = checks.check_reciprocity(spec, n=20_000)
        assert result.passed and result.details["reciprocal"], result.message
    phong = checks.check_reciprocity({"type": "phong", "form": "original", "exponent": 2.0},
                                     n=20_000)
    assert not phong.details["reciprocal"]


# -- what the lobes are for, energy ---------------------------------------------------------------

def _peak(spec, theta_i):
    """θo (degrees, signed: negative on ωi's side) where f(ωi, ·) peaks in the plane of
    incidence, from eval on a 0.05° grid."""
    theta_o = np.radians(np.arange(-89.95, 90.0, 0.05))
    wo = np.stack([np.sin(theta_o), 0 * theta_o, np.cos(theta_o)], axis=1)
    wi = np.tile([-math.sin(math.radians(theta_i)), 0.0, math.cos(math.radians(theta_i))],
                 (len(wo), 1))
    f = eval_pdf(mi.load_dict(spec), wi, wo)[0][:, 0] / wo[:, 2]
    return float(np.degrees(theta_o[int(np.argmax(f))]))


def test07_lobe_features(variant_llvm_ad_rgb):
    """
    At θi = 40°: Phong's lobe (Cx = Cy = −Cz) peaks at the mirror direction, +40°; a
    retro-reflective one (C = (1, 1, 1)) back towards the light, −40°; an off-specular one
    (|Cz| < |Cx|) further from the normal than the mirror direction, at
    atan(|Cx|/Cz · tan 40°) where that lies above the horizon (Lafortune et al. 1997).
    """
    lobe = dict(diffuse_reflectance=0.0, exponent_0=30.0)
    assert _peak(lafortune(**lobe), 40.0) == pytest.approx(40.0, abs=0.05)
    assert _peak(lafortune(cx_0=1.0, cy_0=1.0, cz_0=1.0, **lobe), 40.0) == \
        pytest.approx(-40.0, abs=0.05)
    off = _peak(lafortune(cx_0=-1.0, cy_0=-1.0, cz_0=0.5, **lobe), 40.0)
    assert off == pytest.approx(math.degrees(math.atan(2 * math.tan(math.radians(40.0)))),
                                abs=0.05)
    assert off > 55.0


def test08_energy(variant_llvm_ad_rgb, recwarn):
    """
    A normalised lobe's albedo is at most ρs (the reference's quadrature), reached at normal
    incidence where |Cz| = max|C| (Phong's and the retro-reflective lobe); sample() agrees with
    the reference (5σ). The paper's form reflects (2π/(n+2))·cⁿ·ρs at normal incidence for
    Phong's lobe, here 1.6: no energy bound.
    """
    for C in ((-1.0, -1.0, 1.0), (1.0, 1.0, 1.0), (-1.0, -1.0, 0.5), (0.7, -1.0, -0.2)):
        ref = Lafortune([dict(cx=C[0], cy=C[1], cz=C[2], exponent=10.0)], 0.0)
        curve = [ref.lobe_albedo(0, math.radians(t)) for t in range(0, 90, 5)]
        assert max(curve) <= 1.0 + 1e-12
        assert (curve[0] == pytest.approx(1.0, rel=1e-9)) == (abs(C[2]) == 1.0)
    spec = lafortune(cx_0=-1.0, cy_0=-1.0, cz_0=0.5, exponent_0=10.0, diffuse_reflectance=0.0,
                     specular_reflectance_0=1.0)
    mean, err = checks.albedo_sampled(spec, math.radians(60.0), n=50_000)
    expected = for_spec(spec).albedo(math.radians(60.0))[0]
    assert abs(mean[0] - expected) <= 5 * err[0] + 1e-5, (mean, expected)
    paper = lafortune(normalize=False, cx_0=-1.2, cy_0=-1.2, cz_0=1.2, exponent_0=5.0,
                      diffuse_reflectance=0.0, specular_reflectance_0=1.0)
    e0 = 2 * math.pi / 7 * 1.2 ** 5
    assert for_spec(paper).albedo(0.0)[0] == pytest.approx(e0, rel=1e-9) and e0 > 1.5
    mean, err = checks.albedo_sampled(paper, 0.0, n=50_000)
    assert abs(mean[0] - e0) <= 5 * err[0] + 1e-5


# -- stability, rendering, textures, AD -----------------------------------------------------------

def _stable(shift, normalize):
    """
    No NaN/Inf/negative value anywhere (stress and random directions): exponents 0, 0.5, 1e6
    and 1e30 on C = 0, a lobe along the normal only (its principal direction at grazing
    incidence), an off-specular and an anisotropic one. Four lobes a BSDF (a NaN or Inf of one
    lobe shows in the sum), the exponents shifted by ``shift``: the two variants run two
    arrangements, so that each exponent meets two of the coefficient sets.
    """
    coefficients = ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (-1.0, -1.0, 0.3), (1.0, 0.5, 1.0))
    exponents = (0.0, 0.5, 1e6, 1e30)  # 0.5: pow of a negative cosine would be NaN
    params = {}
    for i, c in enumerate(coefficients):
        params.update({f"cx_{i}": c[0], f"cy_{i}": c[1], f"cz_{i}": c[2],
                       f"exponent_{i}": exponents[(i + shift) % 4],
                       f"specular_reflectance_{i}": 0.25})
    spec = lafortune(normalize=normalize, diffuse_reflectance=0.5 * normalize, **params)
    result = checks.check_stability(spec, n_random=20 if scalar() else 2_000)
    assert result.passed, result.message
    assert "rejected" not in result.message


def test09_stability(variant_llvm_ad_rgb, recwarn):
    _stable(0, True)  # the other arrangement, in the paper's form: test13


def test10_textures_and_render(variant_llvm_ad_rgb, tmp_path):
    """Bitmaps for ρd and every ρs (each texture parameter), rendered symbolically in
    mi.render: finite, lit; consistent, every lobe together; a uniform texture equals the
    float."""
    bitmap = mi.Bitmap(np.random.default_rng(1).uniform(0, 0.2, (8, 8, 3)).astype(np.float32))
    path = str(tmp_path / "tex.exr")
    bitmap.write(path)
    textured = dict(THREE, diffuse_reflectance={"type": "bitmap", "filename": path},
                    **{f"specular_reflectance_{i}": {"type": "bitmap", "filename": path}
                       for i in range(3)})
    spec = lafortune(**textured)
    image = np.array(mi.render(_sphere_scene(spec), spp=4))
    assert np.isfinite(image).all() and image.mean() > 0.05
    result = checks.check_consistency(spec, n=5_000, rtol=1e-5)
    assert result.passed, result.message
    rng = np.random.default_rng(2)
    wi, wo = random_directions(rng, 20, lower=False), random_directions(rng, 20, lower=False)
    uniform = {"type": "checkerboard", "color0": 0.3, "color1": 0.3}
    a = eval_pdf(mi.load_dict(lafortune(**dict(THREE, specular_reflectance_2=uniform))), wi, wo)
    b = eval_pdf(mi.load_dict(lafortune(**dict(THREE, specular_reflectance_2=0.3))), wi, wo)
    np.testing.assert_allclose(a[0], b[0], rtol=1e-6)


def test11_traverse_and_gradients(variant_llvm_ad_rgb, np_rng, recwarn):
    """Every parameter of an existing lobe is exposed and updatable; d eval/dp by AD equals
    central differences for the exponent and the coefficients (away from a tie for max|C|,
    where c = max|C| has a kink)."""
    spec = lafortune(cx_0=-1.0, cy_0=-0.8, cz_0=0.6, exponent_0=20.0, specular_reflectance_0=0.4,
                     cx_1=0.9, cy_1=0.7, cz_1=1.0, exponent_1=5.0)
    keys = {"diffuse_reflectance.value"} | {f"{p}_{i}{'.value' if p[0] == 's' else ''}"
                                            for p in ("cx", "cy", "cz", "exponent",
                                                      "specular_reflectance") for i in (0, 1)}
    assert set(mi.traverse(mi.load_dict(spec)).keys()) == keys
    wi = random_directions(np_rng, 300, lower=False)
    wo = wi * [-1, -1, 1] + np_rng.normal(0, 0.2, wi.shape)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for key, value, step in (("exponent_0", 20.0, 0.5), ("cz_0", 0.6, 0.01), ("cx_1", 0.9, 0.01)):
        grad, finite = eval_gradient(mi.load_dict(spec), key, value, step, wi, wo)
        assert grad == pytest.approx(finite, rel=5e-3), key
    bsdf = mi.load_dict(spec)
    params = mi.traverse(bsdf)
    params["cz_0"] = mi.Float(0.9)
    params.update()
    ref = for_spec(dict(spec, cz_0=0.9))
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0],
                             lambda a, b: ref.brdf(a, b) * b[:, 2:3], wi, wo, 1e-4)


# -- the same value checks in a spectral variant and in scalar_rgb --------------------------------

def test12_spectral(variant_llvm_ad_spectral, np_rng, recwarn):
    """eval and pdf against the reference (float reflectances: upsampled RGB is not RGB)."""
    _eval_pdf_matches_reference(np_rng)


def test13_scalar(variant_scalar_rgb, np_rng, recwarn):
    """eval, pdf, the mirror lobe, consistency and stability in scalar_rgb, where Mitsuba calls
    the methods once per ray with Python floats."""
    _eval_pdf_matches_reference(np_rng)
    _mirror_lobe_is_phong(np_rng, 0.0)
    _consistent()
    _stable(2, False)
    assert "cx_0" not in mi.traverse(mi.load_dict(lafortune()))  # a float cannot be updated


# -- bad input ------------------------------------------------------------------------------------

BAD = [
    ({"cx_0": -1.0, "cy_0": -1.0, "cz_0": 1.0, "exponent_2": 3.0},
     r'lafortune: parameter "exponent_2" = 3 is invalid: lobe indices must run 0, 1, 2, … '
     r'without a gap, and lobe 1 has no property'),
    ({"exponent_1": 3.0}, r'"exponent_1" = 3 is invalid: .* lobe 0 has no property'),
    ({"cx_01": 1.0, "cy_01": 1.0, "cz_01": 1.0},
     r'"cx_01" = 1 is invalid: a lobe\'s index is written without a leading zero'),
    ({"exponent_0": -1.0}, r'"exponent_0" = -1 is invalid: must be finite and within '
                           r'\[0, 1e\+30\]'),
    ({"exponent_0": float("nan")}, r'"exponent_0" = nan is invalid'),
    ({"cx_0": 1.0, "cy_0": 1.0}, r'"cx_0" = 1 is invalid: needs cz_0 as well'),
    ({"cx_0": float("inf"), "cy_0": 1.0, "cz_0": 1.0}, r'"cx_0" = inf is invalid: must be finite'),
    ({"cx_0": "a", "cy_0": 1.0, "cz_0": 1.0}, r'"cx_0" = "a" is invalid: must be a number'),
    ({"specular_reflectance_0": 1.5}, r'"specular_reflectance_0" = 1.5 is invalid: must be '
                                      r'finite and within \[0, 1\]'),
    ({"diffuse_reflectance": -0.1}, r'"diffuse_reflectance" = -0.1 is invalid'),
    ({"exponent": 30.0}, r'"exponent" = 30 is invalid: lafortune\'s lobe properties carry the '
                         r'lobe\'s index: cx_0'),
    ({"normalize": "yes"}, r'"normalize" = "yes" is invalid: must be a boolean'),
    ({"normalize": False, "cx_0": 2.0, "cy_0": 2.0, "cz_0": 2.0, "exponent_0": 200.0},
     r'"exponent_0" = 200 is invalid: with max\(\|cx_0\|, \|cy_0\|, \|cz_0\|\) = 2 the lobe\'s '
     r'peak cⁿ = 10\^60.21 must be ≤ 1e\+30'),
]


@pytest.mark.parametrize("params,match", BAD, ids=[next(iter(p)) + str(i)
                                                   for i, (p, _) in enumerate(BAD)])
def test14_bad_input(variant_scalar_rgb, params, match):
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict(lafortune(**params))


def test15_bad_input_from_xml_and_the_energy_warning(variant_scalar_rgb):
    """One line through the package's loader; ρd + Σ ρs,i > 1 warns (values kept)."""
    with pytest.raises(mi_brdfs.MiBrdfsError, match=r'^string \(line 1, col 2\): lafortune: '
                                                     r'parameter "cz_2" = 1 is invalid: lobe '
                                                     r'indices must run'):
        mi_brdfs.bsdfspec.load_bsdf('<bsdf type="lafortune"><float name="cz_2" value="1"/>'
                                    '</bsdf>')
    with pytest.warns(mi_brdfs.MiBrdfsWarning, match=r"lafortune: ρd \+ Σ ρs,i·Kᵢ·2π/\(nᵢ\+2\), "
                                                     r"the bound of the albedo, reaches 1.1 > 1"):
        mi.load_dict(lafortune(**dict(THREE, diffuse_reflectance=0.35)))
