"""
The ``he`` plugin (He, Torrance, Sillion & Greenberg 1991) against the float64 reference
(mi_brdfs.reference.he): eval is the sum of the directional diffuse and uniform diffuse terms
at the RGB wavelengths, the spectral variants' sampled wavelengths and a conductor's index, in
the three readings and the smooth, intermediate and rough regimes; the delta's sample weight
and probability; the smooth limit; χ² at 45° and 80°; stability from σ0 = 0 to 10 µm; consistency, reciprocity, the
sampler's efficiency against the cosine; σ0 through mi.traverse; one-line errors. The terms
themselves: tests/scattering/test_he_terms.py.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import assert_matches_reference, eval_pdf, random_directions, sample

import mi_brdfs
from mi_brdfs.materials import conductor_ior
from mi_brdfs.reference import he as ref
from mi_brdfs.reference.cooktorrance import fresnel_exact
from mi_brdfs.testing import assert_consistent, assert_reciprocal, assert_sampling_matches_pdf

RGB = [0.645, 0.526, 0.444]
#: (σ0, τ) in µm: g at normal incidence and 526 nm about 0.2 (smooth), 2.3 (intermediate)
#: and 150 (rough: Beckmann's asymptote in the westin reading)
REGIMES = {"smooth": (0.01, 1.0), "intermediate": (0.04, 2.0), "rough": (0.3, 3.0)}
#: The float32 series' rounding: its terms' logarithms accumulate about 8·2⁻²⁴·(g + terms/2)
#: ·(ln g + 1) of relative error, 1e-4 for the 48 terms to g = 22
#: (tests/scattering/test_he_terms.py measures it).
RTOL = 1e-4


def _spec(**extra):
    return dict({"type": "he"}, **extra)


def _pairs(rng, n):
    return random_directions(rng, n, lower=False), random_directions(rng, n, lower=False)


def _reference(sigma0=0.18, tau=3.0, wavelength=RGB, eta=1.5, k=0.0, a=0.0, factor=1.0,
               variant="westin"):
    """f·cosθo of the non-delta terms, float64, (wi, wo) -> (n, channels)."""
    model = ref.HTSG(sigma0, tau, wavelength=wavelength, eta=eta, k=k, albedo=a,
                     variant=variant)

    def f(wi, wo):
        rho = model.directional_diffuse(wi, wo) * factor + model.uniform_diffuse(wi, wo)
        return rho * wo[:, 2:3]
    return f, model


def test01_create(variants_all):
    bsdf = mi.load_dict(_spec(diffuse_reflectance=0.2))
    assert bsdf.component_count() == 3
    assert int(bsdf.flags(0)) & int(mi.BSDFFlags.DeltaReflection)
    assert int(bsdf.flags(1)) & int(mi.BSDFFlags.GlossyReflection)
    assert int(bsdf.flags(2)) & int(mi.BSDFFlags.DiffuseReflection)
    assert mi.load_dict(_spec()).component_count() == 2  # no uniform diffuse term
    assert "He[" in str(bsdf) and 'variant = "westin"' in str(bsdf)


@pytest.mark.parametrize("extra,message", [
    ({"sigma0": -0.1}, 'he: parameter "sigma0" = -0.1 is invalid'),
    ({"tau": 0.0}, 'he: parameter "tau" = 0 is invalid'),
    ({"variant": "torrance"}, 'parameter "variant" = "torrance" is invalid: must be one of '
                              '"paper", "westin", "holzschuch"'),
    ({"terms": 0}, 'he: parameter "terms" = 0 is invalid'),
    ({"eta": 0.0}, 'he: parameter "eta" = 0 is invalid: must be > 0 where k = 0'),
    ({"material": "Xx"}, 'he: parameter "material" = "Xx" is invalid'),
    ({"specular_reflectance": -1.0}, 'he: parameter "specular_reflectance" = -1 is invalid'),
    ({"diffuse_reflectance": 1.5}, 'he: parameter "diffuse_reflectance" = 1.5 is invalid'),
])
def test02_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    with pytest.raises(RuntimeError) as e:
        mi.load_dict(_spec(**extra))
    assert message in str(e.value)


@pytest.mark.parametrize("regime", REGIMES)
@pytest.mark.parametrize("variant", ["westin", "holzschuch"])
def test03_eval_is_the_reference(variant_llvm_ad_rgb, np_rng, regime, variant):
    """eval = (ρ_dd·specular_reflectance + a/π)·cosθo at the RGB wavelengths, a conductor's
    index (Al) in the rough regime."""
    sigma0, tau = REGIMES[regime]
    extra = {"material": "Al"} if regime == "rough" else {"eta": 1.4}
    eta, k = conductor_ior("Al") if regime == "rough" else (1.4, 0.0)
    bsdf = mi.load_dict(_spec(sigma0=sigma0, tau=tau, variant=variant, diffuse_reflectance=0.2,
                              specular_reflectance=0.7, **extra))
    wi, wo = _pairs(np_rng, 3000)
    f, _ = _reference(sigma0, tau, eta=eta, k=k, a=0.2, factor=0.7, variant=variant)
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], f, wi, wo, RTOL, f"he {regime}")


def test03b_the_paper_reading_and_a_wrong_reading(variant_scalar_rgb, np_rng):
    """``variant=paper`` is the printed equations (a scalar variant: nothing to compile), and
    the comparison tells the readings apart: westin's eval against the paper's reference is
    rejected."""
    wi, wo = _pairs(np_rng, 12)
    f, _ = _reference(0.04, 2.0, variant="paper")
    paper = mi.load_dict(_spec(sigma0=0.04, tau=2.0, variant="paper"))
    assert_matches_reference(eval_pdf(paper, wi, wo)[0], f, wi, wo, RTOL, "he paper")
    westin = mi.load_dict(_spec(sigma0=0.04, tau=2.0))
    with pytest.raises(AssertionError):
        assert_matches_reference(eval_pdf(westin, wi, wo)[0], f, wi, wo, RTOL, "he westin")


def test04_spectral_variants_evaluate_at_the_sampled_wavelengths(np_rng):
    """llvm_ad_spectral: each sampled wavelength (µm = nm/1000) and Au's η, k there."""
    mi_brdfs.use_variant("llvm_ad_spectral")
    bsdf = mi.load_dict(_spec(sigma0=0.05, tau=1.5, material="Au"))
    wi, wo = _pairs(np_rng, 500)
    lam = np.array([420.0, 510.0, 600.0, 690.0])
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wavelengths = mi.Spectrum(*[mi.Float(np.full(len(wi), x, np.float32)) for x in lam])
    si.wi = mi.Vector3f(*[mi.Float(wi[:, i].astype(np.float32)) for i in range(3)])
    value = bsdf.eval(mi.BSDFContext(), si,
                      mi.Vector3f(*[mi.Float(wo[:, i].astype(np.float32)) for i in range(3)]))
    one = dr.zeros(mi.SurfaceInteraction3f)
    one.wavelengths = mi.Spectrum(*[float(x) for x in lam])
    eta, k = conductor_ior("Au", one)
    f, _ = _reference(0.05, 1.5, wavelength=lam / 1000, eta=eta, k=k)
    assert_matches_reference(np.array(value).T, f, wi, wo, RTOL, "he spectral")


def test05_the_delta_weight_and_probability(variant_llvm_ad_rgb):
    """A sample of the delta: ωo = M(ωi), bs.pdf = its probability ρ̄_s/(ρ̄_s + E_dd + a)
    (E_dd the tabulated albedo), weight·pdf = ρ_s·specular_reflectance. A mixture that took
    the delta for a density (the lobe not marked delta) is rejected."""
    spec = _spec(sigma0=0.02, tau=1.0, diffuse_reflectance=0.3, specular_reflectance=0.8)
    theta = np.radians([10.0, 40.0, 70.0])
    wi = np.stack([np.sin(theta), 0 * theta, np.cos(theta)], 1)
    _, model = _reference(0.02, 1.0)
    rho = model.specular(wi) * 0.8

    def check():
        s = sample(mi.load_dict(spec), wi, np.full(3, 1e-4), np.full((3, 2), 0.5))
        np.testing.assert_allclose(s["wo"], wi * [-1, -1, 1], atol=1e-6)
        assert np.all(s["type"] & int(mi.BSDFFlags.DeltaReflection))
        np.testing.assert_allclose(s["weight"] * s["pdf"][:, None], rho, rtol=1e-4)
        assert np.all((s["pdf"] > rho.mean(1) / (rho.mean(1) + 1.3)) & (s["pdf"] < 1))

    check()
    # the registry runs the plugin's module once per variant: this variant's Specular
    specular = mi_brdfs.plugin_class("he").__init__.__globals__["Specular"]
    with pytest.MonkeyPatch.context() as m:
        m.setattr(specular, "delta", False)
        with pytest.raises(AssertionError):
            check()


def test06_the_smooth_limit(variant_llvm_ad_rgb, np_rng):
    """σ0 = 0: a Fresnel mirror (the delta's weight is |F(θi)|², the directional diffuse term
    0) plus the uniform diffuse term."""
    bsdf = mi.load_dict(_spec(sigma0=0.0, eta=1.7, diffuse_reflectance=0.25))
    wi, wo = _pairs(np_rng, 500)
    value = eval_pdf(bsdf, wi, wo)[0]
    np.testing.assert_allclose(value, 0.25 / np.pi * wo[:, 2:3] * np.ones(3), rtol=1e-5)
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.DeltaReflection)
    s = sample(bsdf, wi, np_rng.random(500), np_rng.random((500, 2)), ctx)
    f = np.ravel(fresnel_exact(wi[:, 2], 1.7, 0.0))
    np.testing.assert_allclose(s["weight"], np.repeat(f[:, None], 3, 1), rtol=1e-5)


@pytest.mark.parametrize("theta", [45.0, 80.0])
def test07_sampling_matches_pdf(variant_llvm_ad_rgb, theta):
    """χ² of sample() against pdf() (the delta's samples counted as failed, as the battery
    does), an intermediate surface with a uniform diffuse term, at 45° and 80° (normal
    incidence too in the validation campaign's battery, `make validate`)."""
    t = np.radians(theta)
    assert_sampling_matches_pdf(_spec(sigma0=0.05, tau=1.5, diffuse_reflectance=0.2),
                                wi=[np.sin(t), 0.0, np.cos(t)], sample_count=400_000)


def test08_consistent_reciprocal_and_efficient(variant_llvm_ad_rgb, np_rng):
    """weight = eval/pdf and bs.pdf = pdf(bs.wo); f(a, b) = f(b, a); on a glossy surface
    (α ≈ 2σ0/τ = 0.07) the variance of the sample weights is at least 10 times under that of
    cosine sampling at 0°, 45° and 80°."""
    spec = _spec(sigma0=0.1, tau=3.0, material="Al")
    assert_consistent(spec)
    assert_reciprocal(spec)
    bsdf = mi.load_dict(spec)
    n = 100_000
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, mi.BSDFFlags.GlossyReflection)
    for theta in np.radians([0.0, 45.0, 80.0]):
        wi = np.array([[np.sin(theta), 0.0, np.cos(theta)]])
        ours = sample(bsdf, wi, np_rng.random(n), np_rng.random((n, 2)), ctx)["weight"].mean(1)
        cosine = mi.warp.square_to_cosine_hemisphere(mi.Point2f(np_rng.random((2, n))))
        wo = np.array(cosine).T
        plain = eval_pdf(bsdf, np.repeat(wi, n, 0), wo, ctx)[0].mean(1) / (wo[:, 2] / np.pi)
        assert abs(ours.mean() - plain.mean()) < 5 * np.sqrt(plain.var() / n)
        assert plain.var() > 10 * ours.var(), (np.degrees(theta), plain.var(), ours.var())


def test09_sigma0_through_traverse(variant_llvm_ad_rgb, np_rng):
    """σ0 set through mi.traverse: eval follows the reference at the new σ0, and the sampler
    is rebuilt for it (bs.pdf = pdf(bs.wo) still)."""
    bsdf = mi.load_dict(_spec(sigma0=0.05, tau=2.0))
    params = mi.traverse(bsdf)
    params["sigma0"] = 0.2
    params.update()
    wi, wo = _pairs(np_rng, 1000)
    f, _ = _reference(0.2, 2.0)
    assert_matches_reference(eval_pdf(bsdf, wi, wo)[0], f, wi, wo, RTOL, "he σ0 = 0.2")
    assert_consistent(bsdf)


def test10_energy_warnings(variant_scalar_rgb):
    """The albedo can exceed 1: the paper's and Holzschuch's readings on a rough surface (the
    directional diffuse albedo alone reaches hundreds here) and an uncoupled uniform diffuse
    term; westin's rough surface alone warns of nothing."""
    import warnings

    from mi_brdfs.errors import MiBrdfsWarning
    with pytest.warns(MiBrdfsWarning, match="directional diffuse term's albedo reaches"):
        mi.load_dict(_spec(variant="holzschuch", sigma0=0.3))
    with pytest.warns(MiBrdfsWarning, match="diffuse_reflectance \\+ specular_reflectance"):
        mi.load_dict(_spec(diffuse_reflectance=0.3))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MiBrdfsWarning)
        mi.load_dict(_spec(sigma0=0.3))


def test11_stable_from_smooth_to_rough(variant_llvm_ad_rgb):
    """No NaN, Inf or negative value at the stability sweep's stress directions (grazing,
    normal, mirror, retro-reflection) from σ0 = 0 to σ0 = 10 µm (g from 0 to 10⁶), and in
    Holzschuch's reading, with a uniform diffuse term."""
    import warnings

    from mi_brdfs.testing import assert_stable
    specs = [_spec(sigma0=s, tau=3.0, variant=v, material="Au", diffuse_reflectance=0.1)
             for s, v in ((0.0, "westin"), (0.003, "westin"), (0.3, "westin"),
                          (10.0, "westin"), (0.3, "holzschuch"))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the holzschuch reading's albedo above 1, as it is
        assert_stable(specs)
