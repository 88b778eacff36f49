"""
cooktorrance with ``transmission``: the rough dielectric of Walter et al. 2007 against Mitsuba's
roughdielectric (eval, pdf, samples, renders, gradients), the float64 reference, the smooth
limit (dielectric), energy in importance transport, the white furnace, the cases of Mitsuba's
own roughdielectric tests (grazing, from inside, total internal reflection, the denser side,
single lobes, attached sampling), parameters and their errors.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import assert_matches_reference, eval_pdf, random_directions, sample
from test_cooktorrance import assert_rel, small

import mi_brdfs
from mi_brdfs import checks
from mi_brdfs.campaign.transmission import UPSTREAM_CHI2
from mi_brdfs.reference import for_spec

CT = "cooktorrance"
RADIANCE, IMPORTANCE = mi.TransportMode.Radiance, mi.TransportMode.Importance


def glass(**params) -> dict:
    return dict({"type": CT, "transmission": True}, **params)


def rough_dielectric(**params) -> dict:
    return dict({"type": "roughdielectric"}, **params)


def _rel_tol() -> float:
    """Scalar variants compute in double, the built-in in float32: near grazing and total
    internal reflection their last bits part further."""
    return 1e-4 if mi.variant().startswith("scalar") else 1e-5


#: Each distribution with each sampler, isotropic and anisotropic roughness alternating (the
#: isotropic product, 2e5 pairs, runs in ``make validate``, section transmission)
EQUAL_CASES = [("beckmann", True, "iso"), ("beckmann", False, "aniso"), ("ggx", True, "aniso"),
               ("ggx", False, "iso")]
ALPHAS = {"iso": {"alpha": 0.3}, "aniso": {"alpha_u": 0.1, "alpha_v": 0.4}}


@pytest.mark.parametrize("distribution,visible,roughness", EQUAL_CASES,
                         ids=[f"{r}-{d}-{'visible' if v else 'all-normals'}"
                              for d, v, r in EQUAL_CASES])
def test01_equals_roughdielectric(variants_all, np_rng, distribution, visible, roughness):
    """eval, pdf and eval_pdf of both lobes, ωi and ωo over the whole sphere (from outside and
    inside), in radiance and importance transport, equal roughdielectric's pointwise (1e-5
    relative in JIT variants); the reflection-only model differs."""
    alpha = ALPHAS[roughness]
    common = dict(alpha, distribution=distribution, sample_visible=visible, int_ior=1.5,
                  ext_ior=1.0)
    ours, theirs = mi.load_dict(glass(**common)), mi.load_dict(rough_dielectric(**common))
    n = small(20_000)
    wi, wo = random_directions(np_rng, n), random_directions(np_rng, n)
    for mode in (RADIANCE, IMPORTANCE):
        ctx = mi.BSDFContext(mode)
        a, b = eval_pdf(ours, wi, wo, ctx), eval_pdf(theirs, wi, wo, ctx)
        for x, y, what in zip(a, b, ("eval", "pdf", "eval_pdf value", "eval_pdf pdf")):
            assert_rel(x, y, _rel_tol(), floor=1e-6, what=f"{mode} {what}")
    assert (a[0][(wi[:, 2] * wo[:, 2]) < 0] > 0).any()  # the refraction lobe is there
    reflection_only = mi.load_dict(dict(alpha, type=CT, distribution=distribution,
                                        sample_visible=visible, shadowing="smith", eta=1.5))
    with pytest.raises(AssertionError):
        assert_rel(eval_pdf(reflection_only, wi, wo)[0], b[0], 1e-3, floor=1e-6)


@pytest.mark.parametrize("distribution,mode", [("beckmann", RADIANCE), ("ggx", IMPORTANCE)],
                         ids=["beckmann-radiance", "ggx-importance"])
def test02_samples_equal_roughdielectrics(variant_llvm_ad_rgb, np_rng, distribution, mode):
    """
    Visible normals, the same random numbers: the same bs.wo bit for bit, the same lobe
    (chosen with probability F), bs.eta and sampled type, and the weight to 1e-5, wherever
    roughdielectric's weight is not 0 (where it is, the sample failed and its other fields are
    undefined). Our bs.pdf equals roughdielectric's pdf() at bs.wo to 1e-5; its own bs.pdf,
    taken at the sampled normal rather than at bs.wo, departs from that by up to 1e-3. Each
    distribution and each transport mode once (the sampler does not depend on the mode; the
    weight of a refraction does).
    """
    common = dict(distribution=distribution, alpha_u=0.2, alpha_v=0.4, int_ior="bk7")
    ours, theirs = mi.load_dict(glass(**common)), mi.load_dict(rough_dielectric(**common))
    n = 50_000
    wi = random_directions(np_rng, n)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    ctx = mi.BSDFContext(mode)
    a, b = sample(ours, wi, s1, s2, ctx), sample(theirs, wi, s1, s2, ctx)
    ok = b["weight"][:, 0] > 0
    assert ok.mean() > 0.8
    np.testing.assert_array_equal(a["wo"][ok], b["wo"][ok])
    np.testing.assert_array_equal(a["type"][ok], b["type"][ok])
    np.testing.assert_array_equal(a["component"][ok], b["component"][ok])
    assert set(np.unique(a["component"][ok])) == {0, 1}
    assert_rel(a["weight"][ok], b["weight"][ok], 1e-5, what="weight")
    assert_rel(a["pdf"][ok], eval_pdf(theirs, wi, a["wo"], ctx)[1][ok], 1e-5, what="bs.pdf")
    assert_rel(a["pdf"][ok], b["pdf"][ok], 2e-3, what="their bs.pdf")
    s = mi_brdfs.checks.batch
    si = s.interaction(wi, n)
    bs, _ = ours.sample(ctx, si, mi.Float(s1.astype(np.float32)),
                        mi.Point2f(*[mi.Float(c) for c in s2.T.astype(np.float32)]))
    bs_theirs, _ = theirs.sample(ctx, si, mi.Float(s1.astype(np.float32)),
                                 mi.Point2f(*[mi.Float(c) for c in s2.T.astype(np.float32)]))
    np.testing.assert_array_equal(np.array(bs.eta)[ok], np.array(bs_theirs.eta)[ok])


def test03_weight_is_eval_over_pdf_where_roughdielectric_is_not(variant_llvm_ad_rgb, np_rng):
    """
    Our weights are f·|cosθo|/pdf at bs.wo (1e-4), with both samplers. roughdielectric's are
    too with visible normals; drawing from D·cos it widens α (Walter et al. 2007, §5.3) in the
    pdf but leaves D/D_widened out of the weight, so its weight departs from its own eval/pdf
    (by tens of percent) — measured here so that a change in Mitsuba is seen.
    """
    n = 100_000
    wi = random_directions(np_rng, n)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    worst = {}
    for name, spec in (("ours", glass(alpha=0.3, sample_visible=False)),
                       ("theirs", rough_dielectric(alpha=0.3, sample_visible=False)),
                       ("ours-visible", glass(alpha=0.3))):
        bsdf = mi.load_dict(spec)
        x = sample(bsdf, wi, s1, s2)
        value, pdf = eval_pdf(bsdf, wi, x["wo"])[:2]
        ok = (x["weight"][:, 0] > 0) & (pdf > 0)
        ratio = x["weight"][ok, 0] / (value[ok, 0] / pdf[ok])
        worst[name] = np.abs(ratio - 1).max()
        if name.startswith("ours"):  # bs.pdf is pdf(bs.wo)
            np.testing.assert_array_equal(x["pdf"][ok], pdf[ok])
    assert worst["ours"] < 1e-4 and worst["ours-visible"] < 1e-3, worst
    assert worst["theirs"] > 0.1, worst


@pytest.mark.parametrize("spec", [
    glass(alpha=0.3, eta=1.5),
    glass(alpha_u=0.1, alpha_v=0.4, distribution="ggx", int_ior="water",
          specular_transmittance=0.7),
], ids=["beckmann", "ggx-aniso-water"])
def test04_eval_equals_the_float64_reference(variants_rgb, np_rng, spec):
    """eval/|cosθo| against the float64 reference, both lobes, both sides, both modes; a
    reference that forgets 1/η² in radiance transport is rejected."""
    bsdf, model = mi.load_dict(spec), for_spec(spec)
    n = small(20_000)
    wi, wo = random_directions(np_rng, n), random_directions(np_rng, n)
    for mode in (RADIANCE, IMPORTANCE):
        value = eval_pdf(bsdf, wi, wo, mi.BSDFContext(mode))[0]

        def expected(a, b, radiance=mode == RADIANCE):
            return model.brdf(a, b, radiance=radiance) * np.abs(b[:, 2:3])

        assert_matches_reference(value, expected, wi, wo, 1e-4, what=str(mode))
    with pytest.raises(AssertionError):
        assert_matches_reference(
            eval_pdf(bsdf, wi, wo)[0],
            lambda a, b: model.brdf(a, b, radiance=False) * np.abs(b[:, 2:3]), wi, wo, 1e-2)


def _albedo(spec, theta_deg, mask=None, n=200_000):
    """E(θ) from sample() in importance transport, optionally restricted to a lobe type."""
    ctx = mi.BSDFContext(IMPORTANCE)
    if mask is not None:
        ctx.type_mask = mask
    return float(checks.albedo_sampled(spec, math.radians(theta_deg), n=n, ctx=ctx)[0][0])


@pytest.mark.parametrize("theta", [0.0, 80.0, 136.0, 140.0])
def test05_smooth_limit_is_dielectric(variant_llvm_ad_rgb, theta):
    """
    As α → 0 (1e-4) the reflected and the transmitted fractions tend to the smooth dielectric's
    F and 1 − F, from outside (θ < 90°) and inside (θ > 90°: 180° − θ from the inner normal),
    on both sides of the critical angle (41.8° for η = 1.5: θ = 136° lies just beyond it,
    where all is reflected, 140° just within); within 1e-3. The curve over θ (0° to 170°, 11
    angles) runs in ``make validate``, section transmission.
    """
    ours, smooth = glass(alpha=1e-4, eta=1.5), {"type": "dielectric", "int_ior": 1.5,
                                                 "ext_ior": 1.0}
    reflection, transmission = +mi.BSDFFlags.Reflection, +mi.BSDFFlags.Transmission
    for mask in (reflection, transmission):
        a, b = _albedo(ours, theta, mask), _albedo(smooth, theta, mask)
        assert abs(a - b) <= 1e-3, (mask, a, b)
    if theta == 136.0:  # total internal reflection
        assert _albedo(ours, theta, transmission) == 0.0


@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test06_energy_and_the_reference_albedo(variant_llvm_ad_rgb, distribution):
    """
    In importance transport (the energy) the albedo from sample() is ≤ 1 from both sides and
    equals the float64 reference (GGX 1e-3; Beckmann within the 3e-3 bias of the rational G1
    that weights exact visible normals, as roughconductor's); the reference itself stays ≤ 1.
    From outside at normal and grazing incidence, from inside beyond the critical angle and
    near the normal; the curve over 11 angles, for α ∈ {0.1, 0.3, 0.5}, runs in ``make
    validate``, section transmission.
    """
    spec = glass(alpha=0.3, eta=1.5, distribution=distribution)
    thetas = (0.0, 80.0, 100.0, 170.0)
    curve = checks.albedo_curve(spec, thetas, n=400_000, estimators=("reference",))
    assert checks.check_energy(spec, curve=curve).passed
    rtol = 1e-3 if distribution == "ggx" else 3e-3
    result = checks.check_albedo_agreement(spec, curve=curve, sigmas=4.0, rtol=rtol)
    assert result.passed, result.message
    assert curve.reference.max() <= 1 + 1e-6 and curve.reference.min() > 0.5


def test07_radiance_transport_is_not_energy(variant_llvm_ad_rgb):
    """Why the energy is taken in importance transport: in radiance transport the refracted
    radiance from inside glass gains η², and E(θ) exceeds 1 without creating energy."""
    ctx = mi.BSDFContext(RADIANCE)
    spec = glass(alpha=0.3, eta=1.5)
    inside = checks.albedo_sampled(spec, math.radians(170.0), n=100_000, ctx=ctx)[0][0]
    outside = checks.albedo_sampled(spec, math.radians(10.0), n=100_000, ctx=ctx)[0][0]
    assert inside > 1.5 and outside < 0.5, (inside, outside)
    model = for_spec(spec)
    assert model.albedo(math.radians(170.0), radiance=True)[0] == pytest.approx(inside, rel=3e-3)


def test08_furnace(variant_llvm_ad_rgb):
    """
    The white furnace: a smooth glass sphere (α = 1e-4) vanishes (mean 1 within noise) when
    paths may bounce inside it; with one bounce the image is what the reflected fraction E_r(θ)
    predicts, for a rough sphere too (check_furnace).
    """
    render = checks.furnace.furnace_render(glass(alpha=1e-4, eta=1.5), spp=256, res=24,
                                           max_depth=64, predict=False)
    assert abs(render.mean - 1) < 4e-3 and render.nonfinite == 0, render.mean
    result = checks.check_furnace(glass(alpha=0.3, eta=1.5), spp=64, res=32)
    assert result.passed, result.message


def test09_furnace_check_rejects_a_wrong_reflection(variant_llvm_ad_rgb):
    """check_furnace can fail for a transmitting BSDF: a glass whose reflection sample weights
    are doubled while its eval() is right (the prediction comes from eval(), without a float64
    reference for the wrapper: 5e4 directions per angle, |Δ| 0.016 against the tolerance
    0.005), while the same wrapper passing every call through unchanged passes (|Δ| 7e-4)."""
    from broken import register_wrapper

    def doubled(inner, ctx, si, s1, s2, active):
        bs, weight = inner.sample(ctx, si, s1, s2, active)
        return bs, weight * dr.select(si.wi.z * bs.wo.z > 0, 2.0, 1.0)

    spec = register_wrapper("test_doubled_reflection", mi.load_dict(glass(alpha=0.3, eta=1.5)),
                            sample=doubled)
    result = checks.check_furnace(spec, spp=64, res=32, n=50_000)
    assert not result.passed, result.message
    same = register_wrapper("test_passed_through", mi.load_dict(glass(alpha=0.3, eta=1.5)))
    result = checks.check_furnace(same, spp=64, res=32, n=50_000)
    assert result.passed, result.message


# -- the cases of Mitsuba's own roughdielectric tests, run on cooktorrance --------------------

#: Both distributions with both samplers, from outside (grazing), from inside (beyond the
#: critical angle too), from the denser side, and each lobe alone
UPSTREAM_CASES = ["beckmann-all-normals", "ggx-visible-grazing", "from-inside-tir",
                  "from-inside-all-normals", "from-the-denser-side", "reflection-lobe-aniso",
                  "transmission-lobe-aniso"]


@pytest.mark.parametrize("name", UPSTREAM_CASES)
def test10_chi2_upstream_cases(variant_llvm_ad_rgb, name):
    """sample() against pdf() over the whole sphere in the configurations of Mitsuba's
    roughdielectric χ² tests (``campaign.transmission.UPSTREAM_CHI2``: grazing, from inside,
    total internal reflection, from the denser side, each lobe alone through ctx.component),
    Šidák-corrected over the set. A path-complete subset; ``make validate`` (section
    transmission) runs every case at 1e6 samples."""
    params, wi, component = UPSTREAM_CHI2[name]
    ctx = None
    if component is not None:
        ctx = mi.BSDFContext()
        ctx.component = component
    result = checks.chi2_bsdf(glass(**params), wi=wi, ctx=ctx, res=None, ires=None,
                              sample_count=200_000, test_count=len(UPSTREAM_CHI2) + 2)
    assert result.passed, result.message


def test11_eval_pdf_consistent_at_normal_incidence(variant_scalar_rgb):
    """eval_pdf returns what eval and pdf return, over θo from the normal to the horizon and
    beyond it (refraction), defaults (bk7 in air)."""
    bsdf = mi.load_dict(glass())
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0, 0, 1)
    ctx = mi.BSDFContext()
    for i in range(40):
        theta = i / 39.0 * math.pi
        wo = mi.Vector3f(math.sin(theta), 0, math.cos(theta))
        value, pdf = bsdf.eval_pdf(ctx, si, wo)
        assert np.allclose(np.array(bsdf.eval(ctx, si, wo)), np.array(value), rtol=1e-6)
        assert bsdf.pdf(ctx, si, wo) == pytest.approx(float(pdf), rel=1e-6)


def test12_attached_sampling(variant_llvm_ad_rgb):
    """The sample weight is attached to ωi: its derivative with respect to a rotation of the
    shading normal is roughdielectric's (forward mode)."""
    grads = []
    for spec in (glass(alpha=0.5), rough_dielectric(alpha=0.5)):
        bsdf = mi.load_dict(spec)
        angle = mi.Float(0.0)
        dr.enable_grad(angle)
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.n = mi.Normal3f(dr.sin(angle), 0, dr.cos(angle))
        si.sh_frame = mi.Frame3f(si.n)
        si.wi = si.sh_frame.to_local(mi.Vector3f(0, 0, 1))
        _, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(0.0), mi.Point2f(0.3, 0.3))
        assert dr.grad_enabled(weight)
        dr.forward(angle)
        grads.append(float(np.array(mi.unpolarized_spectrum(dr.grad(weight)))[0, 0]))
    assert grads[0] != 0 and grads[0] == pytest.approx(grads[1], rel=1e-4), grads


# -- rendering, gradients, variants --------------------------------------------------------------

@pytest.mark.parametrize("distribution", ["beckmann", "ggx"])
def test13_glass_render_equals_roughdielectric(variant_llvm_ad_rgb, distribution):
    """The glass scene renders as with roughdielectric, same seed, far within the built-in's
    own noise (the same paths: the same samples)."""
    def render(name, seed):
        scene = mi_brdfs.scenes.load_scene("glass", glass=name, res=32,
                                           distribution=distribution)
        return np.array(mi.render(scene, spp=16, seed=seed))

    ours, theirs = render("cooktorrance", 1), render("roughdielectric", 1)
    assert np.isfinite(ours).all() and ours.mean() > 0.05
    noise = np.abs(render("roughdielectric", 2) - render("roughdielectric", 3)).mean()
    assert np.abs(ours - theirs).mean() < 1e-2 * noise


def test14_traverse_update_and_gradient_through_prb(variant_llvm_ad_rgb):
    """eta (a Float, as roughdielectric's) and alpha are exposed and updated; the gradient of a
    prb render of a glass sphere with respect to alpha equals roughdielectric's."""
    from test_cooktorrance import _sphere
    result = {}
    for spec in (glass(alpha=0.2), rough_dielectric(alpha=0.2)):
        scene = _sphere(spec)
        params = mi.traverse(scene)
        assert {"shape.bsdf.eta", "shape.bsdf.alpha.value"} <= set(params.keys())
        before = np.array(mi.render(scene, spp=16, seed=2)).mean()
        params["shape.bsdf.eta"] = 1.33
        params.update()
        after = np.array(mi.render(scene, spp=16, seed=2)).mean()
        params["shape.bsdf.eta"] = 1.5046 / 1.000277
        key = "shape.bsdf.alpha.value"
        dr.enable_grad(params[key])
        params.update()
        dr.backward(dr.mean(mi.render(scene, params, spp=16, seed=2), axis=None))
        result[spec["type"]] = (before, after, float(np.array(dr.grad(params[key]))[0]))
    before, after, grad = result[CT]
    assert abs(after - before) > 1e-4 and np.isfinite(grad) and grad != 0
    np.testing.assert_allclose(result[CT], result["roughdielectric"], rtol=1e-3)


@pytest.mark.parametrize("variant", ["llvm_ad_spectral", "llvm_ad_mono", "scalar_rgb",
                                     "llvm_ad_spectral_polarized"])
def test15_render_other_variants(variant):
    """The glass scene renders finite images in the spectral, mono, scalar and polarized
    variants."""
    from conftest import set_variant
    set_variant(variant)
    scene = mi_brdfs.scenes.load_scene("glass", glass="cooktorrance", res=8)
    image = np.array(mi.render(scene, spp=4, seed=0))
    assert np.isfinite(image).all() and image.mean() > 0


def test16_flags_and_components_are_roughdielectrics(variants_rgb):
    for common in ({}, {"alpha_u": 0.1, "alpha_v": 0.3}):
        ours = mi.load_dict(glass(**common))
        theirs = mi.load_dict(rough_dielectric(**common))
        assert ours.flags() == theirs.flags()
        assert ours.component_count() == theirs.component_count() == 2
        for i in range(2):
            assert ours.flags(i) == theirs.flags(i)


def test17_stability(variants_rgb):
    """No NaN/Inf/negative at the stress directions (both sides, grazing, TIR) at the extremes
    of α (1e-4, 10) and η (close to 1, 0.5, 1e3), each on two of the four paths (distribution ×
    sampler) in turn, every path seeing both extremes of α; α × η × both distributions × both
    samplers runs in ``make validate``, section transmission."""
    extremes = [(1e-4, 1.0 + 1e-5), (10.0, 1e3), (1e-4, 0.5), (10.0, 1.0 + 1e-5),
                (1e-4, 1e3), (10.0, 0.5), (0.3, 1.5), (0.3, 1e3)]
    paths = [(d, v) for d in ("beckmann", "ggx") for v in (True, False)]
    grid = [glass(alpha=a, eta=eta, distribution=d, sample_visible=v)
            for i, (a, eta) in enumerate(extremes) for d, v in (paths[i % 4], paths[(i + 1) % 4])]
    result = checks.check_stability(grid, n_random=small(2000) // 4)
    assert result.passed, result.message
    assert not any(row.rejected for row in result.details["rows"])


@pytest.mark.parametrize("params,match", [
    ({"material": "Au"}, r'"material" = "Au" is invalid: must not be given with transmission'),
    ({"eta": 1.5, "k": 1.0}, r'"k" = 1 is invalid: must be 0 \(or absent\) with transmission'),
    ({"shadowing": "vcavity"}, r'"shadowing" = "vcavity" is invalid: must be "smith" with '
                               r'transmission = true: the V-cavity masking'),
    ({"fresnel": "schlick"}, r'"fresnel" = "schlick" is invalid: must be "exact"'),
    ({"eta": 1.0}, r'"eta" = 1 is invalid: must make the relative index'),
    ({"eta": -1.5}, r'"eta" = -1.5 is invalid: must be finite and within \(0, 1e\+06\]'),
    ({"int_ior": "glas"}, r'"int_ior" = "glas" is invalid: must be a number > 0 or one of '
                          r"Mitsuba's named dielectrics: vacuum, .*bk7"),
    ({"eta": 1.5, "int_ior": 1.5}, r'"int_ior" = 1.5 is invalid: must not be given together '
                                   r'with eta'),
    ({"diffuse_reflectance": 0.5}, r'"diffuse_reflectance" = 0.5 is invalid: must not be given '
                                   r'with transmission'),
    ({"int_ior": 1.0, "ext_ior": 1.0}, r'"int_ior" = 1 is invalid: must make the relative'),
])
def test18_bad_input(variant_scalar_rgb, params, match):
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict(glass(**params))


@pytest.mark.parametrize("name", ["specular_transmittance", "int_ior", "ext_ior"])
def test19_refraction_parameters_need_transmission(variant_scalar_rgb, name):
    with pytest.raises(RuntimeError, match=f'"{name}" = .* is invalid: is a parameter of the '
                                           f'refraction lobe: give transmission = true'):
        mi.load_dict({"type": CT, name: 0.5})


def test20_named_media_are_mitsubas(variant_scalar_rgb):
    """int_ior/ext_ior names give the relative index roughdielectric gets from them."""
    for inside, outside in (("water", "air"), ("diamond", "water"), ("bk7", "vacuum")):
        ours = mi.load_dict(glass(int_ior=inside, ext_ior=outside))
        theirs = mi.load_dict(rough_dielectric(int_ior=inside, ext_ior=outside))
        assert float(mi.traverse(ours)["eta"]) == float(mi.traverse(theirs)["eta"])
    assert float(mi.traverse(mi.load_dict(glass()))["eta"]) == \
        float(mi.traverse(mi.load_dict(rough_dielectric()))["eta"])
