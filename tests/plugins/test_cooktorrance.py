"""
The cooktorrance plugin: the two printed forms, the float64 reference, equality with
roughconductor / roughdielectric / conductor / dielectric where the models coincide, χ², the
consistency of sample/eval/pdf, the white furnace, stability, bad input, rendering and AD.
"""

import math
import warnings

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from helpers import assert_matches_reference, eval_pdf, random_directions, sample

import mi_brdfs
from mi_brdfs import checks
from mi_brdfs.errors import MiBrdfsWarning
from mi_brdfs.reference import cooktorrance as ref
from mi_brdfs.reference import for_spec

CT = "cooktorrance"
GLOSSY = int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
DIFFUSE = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)


def small(n_jit: int) -> int:
    """Scalar variants call Python once per direction: fewer there."""
    return 64 if mi.variant().startswith("scalar") else n_jit


def assert_rel(a, b, rtol, floor=1e-12, what=""):
    """|a − b| ≤ rtol·max(|a|, |b|) wherever either exceeds ``floor`` (float32 tails vanish)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    scale = np.maximum(np.abs(a), np.abs(b))
    rel = np.where(scale > floor, np.abs(a - b) / np.maximum(scale, floor), 0.0)
    assert rel.max() <= rtol, f"{what}: max relative difference {rel.max():.3g} > {rtol:g}"
    return rel.max()


# -- creation, defaults, the diffuse base ----------------------------------------------------

def test01_create_and_defaults(variants_all):
    bsdf = mi.load_dict({"type": CT})
    assert type(bsdf).__name__ == "CookTorrance"
    assert bsdf.component_count() == 1 and bsdf.flags() == bsdf.flags(0) == GLOSSY
    text = str(bsdf)
    for line in ("distribution = beckmann", "shadowing = vcavity", "fresnel = exact",
                 "sample_visible = true", "material = Cu", "no diffuse lobe"):
        assert line in text
    assert set(mi.traverse(bsdf).keys()) >= {"alpha.value", "specular_reflectance.value"}
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict({"type": CT, "roughness": 0.3})


def test02_diffuse_base_is_a_second_lobe(variants_rgb):
    """ρd ≠ 0 adds lobe 1 (DiffuseReflection), exposed; eval_diffuse_reflectance returns ρd."""
    bsdf = mi.load_dict({"type": CT, "diffuse_reflectance": 0.3})
    assert bsdf.component_count() == 2
    assert (bsdf.flags(0), bsdf.flags(1), bsdf.flags()) == (GLOSSY, DIFFUSE, GLOSSY | DIFFUSE)
    assert "diffuse_reflectance.value" in mi.traverse(bsdf)
    si = checks.batch.interaction([0, 0, 1], 1)
    assert np.ravel(bsdf.eval_diffuse_reflectance(si))[0] == pytest.approx(0.3)
    plain = mi.load_dict({"type": CT})
    assert np.ravel(plain.eval_diffuse_reflectance(si))[0] == 0.0
    assert "diffuse_reflectance.value" not in mi.traverse(plain)


# -- the model: the two printed forms, the float64 reference ---------------------------------

def test03_the_two_printed_forms_are_one_model(variant_llvm_ad_rgb, np_rng):
    """
    (F/π)·D'·G/((N·L)(N·V)) with D' = exp(−tan²β/m²)/(4m²cos⁴β) equals F·D·G/(4(N·L)(N·V)) with
    the normalised Beckmann D, in float64 to 1e-12, and the plugin computes it in float32
    (1e-4: float32 directions move the exponent tan²θh/α², up to ~40, by ~1e-6 of itself).
    The frequently quoted D' without the 4 is 4× the model.
    """
    model = ref.CookTorrance(0.3, eta=1.5)
    wi, wo = random_directions(np_rng, 5000, lower=False), random_directions(np_rng, 5000,
                                                                             lower=False)
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
    nl, nv = wo[:, 2], wi[:, 2]
    F, G = model.F(np.sum(wi * h, axis=1))[:, 0], model.G(wi, wo, h)
    printed = F / math.pi * ref.ndf_printed_1982(0.3, h) * G / (nl * nv)
    walter = F * ref.ndf("beckmann", 0.3, h) * G / (4 * nl * nv)
    np.testing.assert_allclose(printed, walter, rtol=1e-12)
    np.testing.assert_allclose(model.brdf(wi, wo)[:, 0], walter, rtol=1e-12)
    plugin = mi.load_dict({"type": CT, "alpha": 0.3, "eta": 1.5})
    assert_rel(eval_pdf(plugin, wi, wo)[0][:, 0] / nl, printed, 1e-4, what="plugin")
    without_4 = F / math.pi * (4 * ref.ndf_printed_1982(0.3, h)) * G / (nl * nv)
    np.testing.assert_allclose(without_4, 4 * walter, rtol=1e-12)


CONFIGS = {
    "textbook": {"alpha": 0.3, "eta": 1.5},
    "ggx-smith-schlick": {"alpha": 0.2, "distribution": "ggx", "shadowing": "smith",
                          "fresnel": "schlick", "eta": 0.4, "k": 3.0},
    "rgb-conductor-diffuse": {"alpha": 0.6, "eta": {"type": "rgb", "value": [0.2, 0.9, 1.1]},
                              "k": {"type": "rgb", "value": [3.9, 2.4, 2.1]},
                              "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.3, 0.5]},
                              "specular_reflectance": 0.7},
    "no-fresnel-rough": {"alpha": 1.5, "fresnel": "none", "shadowing": "smith",
                         "sample_visible": False},
}


@pytest.mark.parametrize("name", CONFIGS)
def test04_eval_equals_the_float64_reference(variants_rgb, np_rng, name):
    """eval/cosθo against the reference BRDF at random pairs over the sphere (zero below)."""
    spec = dict(CONFIGS[name], type=CT)
    n = small(20_000)
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n)
    value = eval_pdf(mi.load_dict(spec), wi, wo)[0]
    model = for_spec(spec)
    # the tolerance follows the float32 conditioning of f·cosθo at each pair (near grazing
    # a float32 direction moves tan²θh/α² by far more than its own rounding)
    assert_matches_reference(value, lambda a, b: model.brdf(a, b) * np.maximum(b[:, 2:3], 0),
                             wi, wo, 1e-4, what=name)
    assert not value[wo[:, 2] <= 0].any()


# -- the built-ins where the models coincide ------------------------------------------------

IORS = {"eta-k": {"eta": 0.2, "k": 3.9}, "Au": {"material": "Au"}}
#: Each distribution with each sampler, the two ways of giving the conductor alternating (the
#: product with Au, Cu, Al and η, k runs in ``make validate``, section cooktorrance)
EQUAL_CASES = [("beckmann", True, "Au"), ("beckmann", False, "eta-k"), ("ggx", True, "eta-k"),
               ("ggx", False, "Au")]


@pytest.mark.parametrize("distribution,visible,ior", EQUAL_CASES,
                         ids=[f"{d}-{'visible' if v else 'all-normals'}-{i}"
                              for d, v, i in EQUAL_CASES])
def test05_smith_equals_roughconductor(variants_all, np_rng, distribution, visible, ior):
    """
    ``shadowing=smith``, exact Fresnel: eval, pdf and eval_pdf equal roughconductor's pointwise
    to 1e-5 relative (scalar variants compute in double, the built-in in float32), with the
    material's spectra per wavelength in spectral variants. The V-cavity model differs from it,
    so the comparison has teeth.
    """
    common = dict(IORS[ior], alpha=0.25, distribution=distribution, sample_visible=visible)
    ours = mi.load_dict(dict(common, type=CT, shadowing="smith"))
    theirs = mi.load_dict(dict(common, type="roughconductor"))
    n = small(20_000)
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n)
    a, b = eval_pdf(ours, wi, wo), eval_pdf(theirs, wi, wo)
    for x, y, what in zip(a, b, ("eval", "pdf", "eval_pdf value", "eval_pdf pdf")):
        assert_rel(x, y, 1e-5, what=what)
    if visible and mi.variant() == "llvm_ad_rgb":
        # the same operations in the same order (vector.dot's fused multiply-adds as dr.dot's):
        # separate products and sums made these 1.8e-6 apart
        np.testing.assert_array_equal(a[1], b[1])
        assert_rel(a[0], b[0], 1e-6, what="eval")
    vcavity = eval_pdf(mi.load_dict(dict(common, type=CT)), wi, wo)[0]
    with pytest.raises(AssertionError):
        assert_rel(vcavity, b[0], 1e-3)


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test06_samples_equal_roughconductors(variant_llvm_ad_rgb, np_rng, distribution):
    """
    With visible normals both draw with Mitsuba's sampler: the same directions bit for bit, and
    our weight and bs.pdf equal roughconductor's eval/pdf there (1e-5). roughconductor's own
    sample() weight departs from its eval/pdf by up to 1e-3 at cosθ < 0.01 (it reuses the
    sampled normal where pdf() recomputes the half vector); ours is eval/pdf at the stored bs.wo.
    """
    common = dict(material="Cu", alpha=0.25, distribution=distribution)
    ours = mi.load_dict(dict(common, type=CT, shadowing="smith"))
    theirs = mi.load_dict(dict(common, type="roughconductor"))
    n = 50_000
    wi = random_directions(np_rng, n, lower=False)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    a, b = sample(ours, wi, s1, s2), sample(theirs, wi, s1, s2)
    np.testing.assert_array_equal(a["wo"], b["wo"])
    value, pdf = eval_pdf(theirs, wi, a["wo"])[:2]
    ok = pdf > 0
    assert_rel(a["pdf"][ok], pdf[ok], 1e-5, what="bs.pdf")
    assert_rel(a["weight"][ok], value[ok] / pdf[ok, None], 1e-5, what="weight")
    assert_rel(a["weight"][ok], b["weight"][ok], 2e-3, what="their sample weight")


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test07_k0_equals_roughdielectric_reflection(variants_rgb, np_rng, distribution):
    """
    k = 0: eval equals roughdielectric's reflection lobe (ext_ior 1, int_ior η) to 1e-5, and
    with visible normals its pdf to 1e-3 (roughdielectric applies the Jacobian as
    1/(4 ωo·m) to a pdf with |ωi·m|, which float32 rounding sets apart at grazing angles). Its sampler for all normals widens α by
    1.2 − 0.2√cosθi (Walter 2007), so that pdf differs by design.
    """
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.GlossyReflection)
    ours = mi.load_dict({"type": CT, "eta": 1.5, "shadowing": "smith", "alpha": 0.3,
                         "distribution": distribution})
    theirs = mi.load_dict({"type": "roughdielectric", "int_ior": 1.5, "ext_ior": 1.0,
                           "alpha": 0.3, "distribution": distribution})
    n = small(20_000)
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n)
    a, b = eval_pdf(ours, wi, wo), eval_pdf(theirs, wi, wo, ctx)
    assert_rel(a[0], b[0], 1e-5, what="eval")
    assert_rel(a[1], b[1], 1e-3, what="pdf")


@pytest.mark.parametrize("visible", [True, False], ids=["visible", "all-normals"])
def test08_smooth_limit_is_the_fresnel_reflectance(variant_llvm_ad_rgb, visible):
    """
    α → 0 (clamped to 1e-4): the directional albedo from sample() tends to the Fresnel
    reflectance of ``dielectric`` (its reflection lobe, η = 1.5) and ``conductor`` (Au, per
    channel), θ up to 87°.
    """
    reflection = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaReflection)
    pairs = (({"eta": 1.5}, {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0}, reflection),
             ({"material": "Au"}, {"type": "conductor", "material": "Au"}, None))
    for ior, smooth, ctx in pairs:
        with pytest.warns(MiBrdfsWarning, match="clamped to 0.0001"):
            ours = mi.load_dict(dict(ior, type=CT, alpha=0.0, sample_visible=visible))
        for theta in np.radians([0, 45, 80, 87]):
            rough = checks.albedo_sampled(ours, theta, n=50_000)[0]
            fresnel = checks.albedo_sampled(smooth, theta, n=16, ctx=ctx)[0]
            np.testing.assert_allclose(rough, fresnel, atol=2e-5)


# -- sampling ----------------------------------------------------------------------------------

#: Each distribution with each sampler (Smith's visible normals, the V-cavity's, D·cos: the
#: sampler and pdf depend on ``shadowing`` only through the visible normals, see test10) at
#: normal and grazing incidence (cosθ = 0.1), every α of the grid, the sharp lobe α = 0.02
#: among them.
CHI2 = [("beckmann", "smith", True, 0.5, 0.1), ("beckmann", "vcavity", True, 0.02, 1.0),
        ("beckmann", "vcavity", False, 1.0, 0.1), ("ggx", "smith", True, 0.1, 1.0),
        ("ggx", "vcavity", True, 0.5, 0.1), ("ggx", "vcavity", False, 0.1, 1.0)]
#: Šidák's correction is taken over the full grid (2 distributions × 3 samplers × 4 α × 2 θ,
#: and test12's 3), as when the grid ran here: each case is judged at the same level.
CHI2_TESTS = 2 * 3 * 4 * 2 + 3


@pytest.mark.parametrize("distribution,shadowing,visible,alpha,cos", CHI2,
                         ids=[f"{d}-{s}-{'vis' if v else 'all'}-a{a}-cos{c}"
                              for d, s, v, a, c in CHI2])
def test09_chi2(variant_llvm_ad_rgb, distribution, shadowing, visible, alpha, cos):
    """
    sample() against pdf() (Pearson χ², 2e5 samples, resolution from the lobe's sharpness up
    to res 401 / ires 32 for α = 0.02), Šidák-corrected over the grid. A path-complete subset
    of the grid: the full grid (both distributions × both masking functions × both samplers ×
    α ∈ {0.02, 0.1, 0.5, 1} × θ ∈ {0°, 84°}, 1e6 samples each) runs in ``make validate``,
    section cooktorrance (``mi-brdfs validate --only cooktorrance``).
    """
    spec = {"type": CT, "distribution": distribution, "shadowing": shadowing,
            "sample_visible": visible, "alpha": alpha, "fresnel": "none"}
    wi = [math.sqrt(1 - cos * cos), 0.0, cos]
    result = checks.chi2_bsdf(spec, wi=wi, res=None, ires=None, sample_count=200_000,
                              test_count=CHI2_TESTS)
    assert result.passed, result.message


def test10_shadowing_changes_sampling_only_through_the_visible_g1(variant_llvm_ad_rgb, np_rng):
    """Why test09 leaves out a quarter of the grid: there smith and vcavity sample identically."""
    n = 20_000
    wi = random_directions(np_rng, n, lower=False)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    for distribution, visible in (("beckmann", False), ("ggx", False)):
        common = {"type": CT, "distribution": distribution, "sample_visible": visible,
                  "alpha": 0.3, "fresnel": "none"}
        a = sample(mi.load_dict(dict(common, shadowing="smith")), wi, s1, s2)
        b = sample(mi.load_dict(dict(common, shadowing="vcavity")), wi, s1, s2)
        np.testing.assert_array_equal(a["wo"], b["wo"])
        np.testing.assert_array_equal(a["pdf"], b["pdf"])


def test11_vcavity_weights_at_most_f(variant_llvm_ad_rgb, np_rng):
    """
    The V-cavity visible normals make the sample weight F·G/G1_V(ωi) ≤ F (= 1 here), and exactly
    1 where neither direction is masked; Smith's visible normals under the V-cavity G (what the
    plugin sampled before) give weights G_V/G1_Smith above 1.05 near grazing incidence.
    """
    n = 50_000
    wi = random_directions(np_rng, n, lower=False)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    for distribution in ("beckmann", "ggx"):
        spec = {"type": CT, "distribution": distribution, "alpha": 0.5, "fresnel": "none"}
        weight = sample(mi.load_dict(spec), wi, s1, s2)["weight"][:, 0]
        # float32 rounding of the reflected direction and of G: 6.5e-5 at grazing incidence
        assert weight.max() <= 1 + 1e-4 and np.mean(abs(weight - 1) < 1e-5) > 0.5, weight.max()
        # the deliberately mismatched pair: Smith's visible normals, V-cavity G
        smith = sample(mi.load_dict(dict(spec, shadowing="smith")), wi, s1, s2)
        theirs = mi.load_dict(spec)
        value = eval_pdf(theirs, wi, smith["wo"])[0]
        ok = smith["pdf"] > 0
        assert (value[ok, 0] / smith["pdf"][ok]).max() > 1.05


@pytest.mark.parametrize("wi", [[0, 0, 1], [0.5, 0.2, 0.84]], ids=["normal", "oblique"])
def test12_chi2_with_diffuse_base(variant_llvm_ad_rgb, wi):
    """The mixture of the two lobes, lobe chosen by mean(ks·F(cosθi)) against mean(ρd); at
    grazing incidence (cosθ = 0.1) too in ``make validate``, section cooktorrance."""
    spec = {"type": CT, "alpha": 0.2, "eta": 1.5, "diffuse_reflectance": 0.5}
    result = checks.chi2_bsdf(spec, wi=wi, res=None, ires=None, sample_count=200_000,
                              test_count=CHI2_TESTS)
    assert result.passed, result.message


CONSISTENCY = {
    "default": {},
    "diffuse": {"diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.5, 0.1]}, "eta": 1.5},
    "ggx-smith-schlick-all": {"distribution": "ggx", "shadowing": "smith", "fresnel": "schlick",
                              "sample_visible": False, "material": "Al"},
    "smooth": {"alpha": 1e-4, "eta": 1.5, "diffuse_reflectance": 0.2},
    "smooth-alone": {"alpha": 1e-4, "eta": 1.5},
    "smith-ggx-rough": {"distribution": "ggx", "shadowing": "smith", "alpha": 0.8},
    "vcavity-dcos": {"sample_visible": False, "alpha": 0.5},
}


@pytest.mark.parametrize("name", CONSISTENCY)
def test13_weight_is_eval_over_pdf(variants_rgb, name):
    """weight == eval/pdf and bs.pdf == pdf(bs.wo) (the mixture pdf), one lobe or both."""
    spec = dict(CONSISTENCY[name], type=CT)
    result = checks.check_consistency(spec, n=small(50_000))
    assert result.passed, result.message
    # float32 rounding only: sample() has the same terms at the same half vector
    assert result.value < 1e-6, result.message
    if "diffuse_reflectance" in spec:
        for component in (0, 1):
            ctx = mi.BSDFContext()
            ctx.component = component
            result = checks.check_consistency(spec, n=small(20_000), ctx=ctx)
            assert result.passed, result.message


# -- energy ------------------------------------------------------------------------------------

THETAS = (0.0, 45.0, 70.0, 84.26, 89.0)
#: Each distribution with either sampler, each masking function with either sampler, and the
#: sharp lobe (α = 0.02); the product (α ∈ {0.1, 0.5, 1} with visible normals, α = 0.5 with
#: D·cos, and α = 0.02) runs in ``make validate``, section cooktorrance.
FURNACE = [("beckmann", "smith", True, 0.5), ("beckmann", "vcavity", False, 0.5),
           ("ggx", "smith", False, 0.5), ("ggx", "vcavity", True, 0.02)]


@pytest.mark.parametrize("distribution,shadowing,visible,alpha", FURNACE,
                         ids=[f"{d}-{s}-{'vis' if v else 'all'}-a{a}" for d, s, v, a in FURNACE])
def test14_white_furnace(variant_llvm_ad_rgb, distribution, shadowing, visible, alpha):
    """
    F ≡ 1: the directional albedo from sample() is ≤ 1 and equals the float64 quadrature of
    the same formula to 1e-3 (plus 4 standard errors of the Monte Carlo estimate). Beckmann
    with ``smith`` and visible normals inherits roughconductor's sampling bias
    (test15_smith_beckmann_samples_like_roughconductor), so there sample() is held to the
    reference within that bias, 3e-3. A path-complete subset: the grid over α runs in ``make
    validate``, section cooktorrance.
    """
    spec = {"type": CT, "distribution": distribution, "shadowing": shadowing,
            "sample_visible": visible, "alpha": alpha, "fresnel": "none"}
    curve = checks.albedo_curve(spec, THETAS, n=400_000, estimators=("reference",))
    assert checks.check_energy(spec, curve=curve).passed
    biased = distribution == "beckmann" and shadowing == "smith" and visible
    result = checks.check_albedo_agreement(spec, curve=curve, sigmas=4.0,
                                           rtol=3e-3 if biased else 1e-3)
    assert result.passed, result.message


def test15_smith_beckmann_samples_like_roughconductor(variant_llvm_ad_rgb):
    """
    roughconductor samples the exact Beckmann visible normals but divides by a pdf with
    Mitsuba's rational G1, so its sample() albedo departs from its eval() albedo by up to
    0.25 % near grazing; ``smith`` reproduces roughconductor, bias included (the same samples
    and weights to 1e-4), while ``vcavity`` samples its own visible normals, exactly.
    """
    theta = math.radians(84.26)
    ours = {"type": CT, "shadowing": "smith", "alpha": 0.5, "fresnel": "none"}
    theirs = {"type": "roughconductor", "alpha": 0.5}
    a = checks.albedo_sampled(ours, theta, n=1_000_000)
    b = checks.albedo_sampled(theirs, theta, n=1_000_000)
    np.testing.assert_allclose(a[0], b[0], rtol=1e-4)
    expected = for_spec(theirs).albedo(theta)  # 0.93860
    assert 1.5e-3 < expected[0] - a[0][0] < 3e-3 and a[1][0] < 2e-4


def test16_reference_albedo_at_most_one(np_rng):
    """The float64 model conserves energy (F ≡ 1) at the ends of α ∈ [1e-3, 10] and
    θ ∈ [0, 89.9°] and between, for each distribution and masking function; the grid
    (α ∈ {1e-3, 0.1, 0.5, 2, 10} × six θ) runs in ``make validate``, section cooktorrance."""
    worst = 0.0
    for distribution in ("beckmann", "ggx"):
        for shadowing in ("vcavity", "smith"):
            for alpha in (1e-3, 0.5, 10.0):
                model = ref.CookTorrance(alpha, distribution, shadowing, fresnel="none")
                for theta in np.radians([0, 80, 89.9]):
                    worst = max(worst, float(model.albedo(theta, 96, 256)[0]))
    assert worst <= 1 + 1e-5, worst
    # V-cavity Beckmann α = 0.5 at normal incidence: the single-scattering loss the plugin's
    # docstring quotes (E = 0.89)
    assert ref.CookTorrance(0.5, fresnel="none").albedo(0.0)[0] == pytest.approx(0.8924, abs=1e-4)


def test17_furnace_render(variant_llvm_ad_rgb):
    """The furnace image is finite and its mean is what the reference albedo predicts."""
    result = checks.check_furnace({"type": CT, "alpha": 0.3, "fresnel": "none"}, spp=64, res=32)
    assert result.passed, result.message


# -- stability and bad input --------------------------------------------------------------------

#: The extremes of (η, k): the dielectric limit η → 1, a huge η, a huge η and k, η = 0.
STABILITY_IORS = ((1.0 + 1e-6, 0.0), (1e3, 0.0), (1e3, 1e3), (0.0, 1.0))


def stability_grid(base: dict, extremes: list[dict]) -> list[dict]:
    """
    Each of the 8 (distribution, masking, sampler) paths with two entries of ``extremes`` (up
    to 8 of them), taken in turn so that every extreme meets at least two paths: the extremes
    on every path without their product, which the campaign's stability rows sweep.
    """
    paths = [dict(distribution=d, shadowing=s, sample_visible=v) for d in ("beckmann", "ggx")
             for s in ("vcavity", "smith") for v in (True, False)]
    return [dict(base, **path, **extremes[(3 * i + j) % len(extremes)])
            for i, path in enumerate(paths) for j in range(2)]


def test18_stability(variants_rgb):
    """
    No NaN/Inf/negative from eval, pdf, eval_pdf, sample() at the stress directions (grazing
    down to cosθ = 6e-17, V = −L, mirror, back side) at the extremes: α ∈ {0, 10} with η → 1,
    η and k up to 1e3 and η = 0, on every path (distribution × masking × sampler), and the
    diffuse base with Schlick's Fresnel at α ∈ {1e-4, 1}. The dense grid (α × (η, k) × every
    path × both Fresnel terms, 768 parameter sets) runs in ``make validate``, section
    cooktorrance.
    """
    extremes = [{"alpha": a, "eta": eta, "k": k} for eta, k in STABILITY_IORS
                for a in (0.0, 10.0)]
    grid = stability_grid({"type": CT}, extremes)
    grid += checks.parameter_grid({"type": CT, "diffuse_reflectance": 0.5, "fresnel": "schlick"},
                                  alpha=[1e-4, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)  # alpha = 0 is clamped
        result = checks.check_stability(grid, n_random=small(2000) // 4)
    assert result.passed, result.message
    assert not any(row.rejected for row in result.details["rows"])


@pytest.mark.parametrize("params,match", [
    ({"alpha": -0.1}, r'cooktorrance: parameter "alpha" = -0.1 is invalid: must be finite and '
                      r'≥ 0'),
    ({"alpha": float("nan")}, r'"alpha" = nan is invalid'),
    ({"eta": -1.0}, r'"eta" = -1 is invalid: must be finite and within \[0, 1e\+06\]'),
    ({"eta": 0.0}, r'"eta" = 0 is invalid: must be > 0 where k = 0'),
    ({"eta": 0.0, "k": 0.0}, r'"eta" = 0 is invalid'),
    ({"eta": {"type": "rgb", "value": [1.5, 0.0, 2.0]}}, r'"eta" = .* is invalid: must be > 0'),
    ({"eta": 1.5, "k": -0.5}, r'"k" = -0.5 is invalid: must be finite and within \[0, 1e\+06\]'),
    ({"k": 1.0}, r'"k" = 1 is invalid: needs eta as well'),
    ({"distribution": "phong"}, r'"distribution" = "phong" is invalid: must be one of '
                                r'"beckmann", "ggx"'),
    ({"shadowing": "schlick"}, r'"shadowing" = "schlick" is invalid: must be one of "vcavity", '
                               r'"smith"'),
    ({"fresnel": "conductor"}, r'"fresnel" = "conductor" is invalid: must be one of "exact", '
                               r'"schlick", "none"'),
    ({"material": "Unobtainium"}, r'"material" = "Unobtainium" is invalid: must name one of '
                                  r"Mitsuba's \d+ measured conductors, e.g. Ag, Al, Au, .*"
                                  r"conductor_names\(\)"),
    ({"material": "Au", "eta": 1.5}, r'"material" = "Au" is invalid: must not be given together '
                                     r'with eta or k'),
    ({"alpha_u": 0.1}, r'"alpha_u" = 0.1 is invalid: needs alpha_v as well'),
    ({"sample_visible": 1}, r'"sample_visible" = 1 is invalid: must be a boolean'),
    ({"specular_reflectance": 2.0}, r'"specular_reflectance" = 2 is invalid'),
], ids=["alpha<0", "alpha-nan", "eta<0", "eta0", "eta0-k0", "eta0-channel", "k<0", "k-alone",
        "distribution", "shadowing", "fresnel", "material", "material+eta", "alpha_u",
        "sample_visible", "specular>1"])
def test19_bad_input(variant_scalar_rgb, params, match):
    """One line naming the plugin, the parameter, the value and what is allowed."""
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict(dict(params, type=CT))


def test20_named_conductors_are_roughconductors(variants_all):
    """material = Au gives the η, k textures roughconductor resolves in this variant."""
    ours = mi.traverse(mi.load_dict({"type": CT, "material": "Au"}))
    theirs = mi.traverse(mi.load_dict({"type": "roughconductor", "material": "Au"}))
    keys = [k for k in theirs.keys() if k.startswith(("eta", "k."))]
    assert keys
    for key in keys:
        np.testing.assert_array_equal(np.array(ours[key]), np.array(theirs[key]))
    from mi_brdfs.plugins.cooktorrance import conductor_names
    assert {"Au", "Ag", "Al", "Cu", "Cr"} <= set(conductor_names())


def test21_conductor_ior_is_the_materials(variants_rgb, np_rng):
    """conductor_ior (the benchmark's and the campaign's η, k) given as eta, k renders the
    lobe of material = Au; aluminium's values would not."""
    from mi_brdfs.plugins.cooktorrance import conductor_ior
    wi, wo = random_directions(np_rng, 200, lower=False), random_directions(np_rng, 200)
    named = eval_pdf(mi.load_dict({"type": CT, "material": "Au"}), wi, wo)[0]
    for metal in ("Au", "Al"):
        eta, k = conductor_ior(metal)
        assert eta.shape == k.shape == (3,)
        given = eval_pdf(mi.load_dict({"type": CT, "eta": {"type": "rgb", "value": eta.tolist()},
                                       "k": {"type": "rgb", "value": k.tolist()}}), wi, wo)[0]
        close = np.allclose(given, named, rtol=1e-6, atol=1e-9)
        assert close == (metal == "Au"), metal


# -- rendering and differentiation ------------------------------------------------------------

@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test22_render_equals_roughconductor(variant_llvm_ad_rgb, distribution):
    """
    The metal Cornell box renders as with roughconductor, same seed, far within the built-in's
    own noise (the difference of two of its renders with other seeds), as both trace the same
    paths. Images finite, the textbook's too.
    """
    def render(metal, seed):
        scene = mi_brdfs.scenes.load_scene("metalbox", metal=metal, res=32,
                                           distribution=distribution)
        return np.array(mi.render(scene, spp=16, seed=seed))

    ours, theirs = render("cooktorrance-smith", 1), render("roughconductor", 1)
    assert np.isfinite(ours).all() and ours.mean() > 0.02
    noise = np.abs(render("roughconductor", 2) - render("roughconductor", 3)).mean()
    assert np.abs(ours - theirs).mean() < 1e-3 * noise and np.abs(ours - theirs).max() < 1e-4
    assert np.isfinite(render("cooktorrance", 1)).all()


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "llvm_ad_mono", "scalar_spectral"])
def test23_render_other_variants(variant):
    """The textbook model renders finite images in the spectral and mono variants."""
    from conftest import set_variant
    set_variant(variant)
    scene = mi_brdfs.scenes.load_scene("metalbox", metal="cooktorrance", res=8)
    image = np.array(mi.render(scene, spp=4, seed=0))
    assert np.isfinite(image).all() and image.mean() > 0


def _sphere(bsdf):
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "prb", "max_depth": 2},
        "emitter": {"type": "constant"}, "shape": {"type": "sphere", "bsdf": bsdf},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16}}})


def test24_traverse_update_and_gradient(variant_llvm_ad_rgb):
    """
    alpha, eta, k and the reflectances are exposed; an update of alpha takes effect; the
    gradient of the image with respect to alpha flows and equals roughconductor's (smith).
    """
    common = {"material": "Cu", "alpha": 0.3}
    result = {}
    for bsdf in (dict(common, type=CT, shadowing="smith"), dict(common, type="roughconductor")):
        scene = _sphere(bsdf)
        params = mi.traverse(scene)
        key = "shape.bsdf.alpha.value"
        assert {key, "shape.bsdf.eta.value", "shape.bsdf.k.value"} <= set(params.keys())
        before = np.array(mi.render(scene, spp=16, seed=2)).mean()
        params[key] = mi.Float(0.6)
        params.update()
        after = np.array(mi.render(scene, spp=16, seed=2)).mean()
        dr.enable_grad(params[key])
        params.update()
        dr.backward(dr.mean(mi.render(scene, params, spp=16, seed=2), axis=None))
        result[bsdf["type"]] = (before, after, float(np.array(dr.grad(params[key]))[0]))
    before, after, grad = result[CT]
    assert abs(after - before) > 1e-3 and np.isfinite(grad) and grad != 0
    np.testing.assert_allclose(result[CT], result["roughconductor"], rtol=1e-4)


def test25_reciprocity_and_positivity(variants_rgb):
    for spec in ({"type": CT}, {"type": CT, "distribution": "ggx", "shadowing": "smith",
                                "diffuse_reflectance": 0.3, "fresnel": "schlick"}):
        for check in (checks.check_reciprocity, checks.check_positivity):
            result = check(spec)
            assert result.passed, result.message


def test26_scalar_constants_follow_updates_and_textures(variant_scalar_rgb, np_rng):
    """
    Scalar RGB reads constant α, ks, η and k once as floats (``parameters_changed``): after an
    update of α, η and k through mi.traverse the plugin (smith) still equals roughconductor
    given the same values, and with a bitmap α (evaluated per call) too.
    """
    wi, wo = random_directions(np_rng, 48, lower=False), random_directions(np_rng, 48)
    s1, s2 = np_rng.random(48), np_rng.random((48, 2))
    bitmap = {"type": "bitmap", "raw": True,
              "bitmap": mi.Bitmap(np.array([[0.05, 0.6], [0.3, 0.9]], dtype=np.float32))}
    update = {"alpha.value": mi.Float(0.55), "eta.value": mi.Color3f(0.3, 0.5, 1.2),
              "k.value": mi.Color3f(3.0, 2.5, 2.0)}
    for alpha, changes in ((0.2, update), (bitmap, {})):
        pair = [mi.load_dict(dict(t, material="Au", alpha=alpha)) for t in
                ({"type": CT, "shadowing": "smith"}, {"type": "roughconductor"})]
        for bsdf in pair:
            params = mi.traverse(bsdf)
            for key, value in changes.items():
                params[key] = value
            params.update()
        a, b = eval_pdf(pair[0], wi, wo), eval_pdf(pair[1], wi, wo)
        for x, y, what in zip(a, b, ("eval", "pdf", "eval_pdf value", "eval_pdf pdf")):
            assert_rel(x, y, 1e-5, what=what)
        a, b = sample(pair[0], wi, s1, s2), sample(pair[1], wi, s1, s2)
        ok = (a["pdf"] > 1e-3) & (b["pdf"] > 1e-3)
        assert ok.sum() > 24
        assert_rel(a["weight"][ok], b["weight"][ok], 1e-4, what="weight")


@pytest.mark.parametrize("name", ["rgb-conductor-diffuse", "textbook"])
def test27_mixture_pdf_against_the_reference(variants_rgb, np_rng, name):
    """
    With the diffuse base, pdf = p·pdf_microfacet + (1 − p)·cosθo/π with p = mean(ks·F(cosθi))
    / (mean(ks·F(cosθi)) + mean(ρd)), F from the float64 reference; pdf_microfacet from the
    plugin without the base (scalar variants compute p on floats from constants read once).
    """
    spec = dict(CONFIGS[name], type=CT, diffuse_reflectance={"type": "rgb",
                                                             "value": [0.1, 0.3, 0.5]})
    alone = {k: v for k, v in spec.items() if k != "diffuse_reflectance"}
    reference = for_spec(spec)
    for _ in range(small(64) // 8):
        wi = random_directions(np_rng, 1, lower=False)[0]
        wo = random_directions(np_rng, 8, lower=False)
        both = eval_pdf(mi.load_dict(spec), wi, wo)[1]
        lobe = eval_pdf(mi.load_dict(alone), wi, wo)[1]
        ws = np.mean(reference.specular * reference.F(np.array([wi[2]]))[0])
        p = ws / (ws + np.mean(reference.diffuse))
        assert_rel(both, p * lobe + (1 - p) * wo[:, 2] / np.pi, 2e-5, what="mixture pdf")


@pytest.mark.parametrize("params,match", [
    ({"eta": 1e10, "k": 1.0}, r'"eta" = 1e\+10 is invalid: must be finite and within \[0, 1e\+06\]'),
    ({"eta": 1.0, "k": 1e10}, r'"k" = 1e\+10 is invalid: must be finite and within \[0, 1e\+06\]'),
    ({"transmission": True, "eta": 1e10}, r'"eta" = 1e\+10 is invalid'),
    ({"transmission": True, "int_ior": 1e10}, r'"int_ior" = 1e\+10 is invalid: must make the '
                                              r'relative index'),
])
def test28_an_index_float32_cannot_hold_is_refused(variant_scalar_rgb, params, match):
    """η or k of 1e10 evaluated to NaN (their squares overflow float32 in the Fresnel
    terms): refused at load, with the range."""
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict(dict(params, type=CT))


def test29_multiscatter_beyond_the_tables_warns(variant_scalar_rgb):
    """α above the tables' last node (2) reads their end: the compensation falls short, and
    the plugin says so (the index beyond the dielectric's tables warned already)."""
    with pytest.warns(MiBrdfsWarning, match="tables end at alpha = 2"):
        mi.load_dict({"type": CT, "multiscatter": True, "alpha": 3.0})
    with warnings.catch_warnings():
        warnings.simplefilter("error", MiBrdfsWarning)
        mi.load_dict({"type": CT, "multiscatter": True, "alpha": 1.5})
