"""
``cooktorrance`` with ``multiscatter``: Kulla & Conty's energy compensation. Its tables against
a rebuild by the package's own command, its lobe against the float64 reference, the white
furnace reading 1, the Fresnel colouring, χ² of the mixed sampler, the consistency of
sample/eval/pdf, reciprocity, a render, the variants, AD and bad input. The grids over α and θ,
and the comparison with the true multiple scattering (the random walk of Heitz et al. 2016),
run in ``make validate``, section multiscatter.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from helpers import assert_matches_reference, eval_pdf, random_directions, sample

from mi_brdfs import albedo_tables, checks
from mi_brdfs.plugins import cooktorrance_conductor
from mi_brdfs.reference import for_spec
from mi_brdfs.reference import multiscatter as ref_ms
from mi_brdfs.scattering import multiscatter

CT = "cooktorrance"
WHITE = {"type": CT, "multiscatter": True, "fresnel": "none"}


def spec(**kw):
    return dict(WHITE, **kw)


# -- the tables ---------------------------------------------------------------------------------

@pytest.mark.parametrize("kind,shadowing,row", [("ggx", "smith", 90), ("beckmann", "vcavity", 40)])
def test01_a_table_slice_rebuilds(variant_llvm_ad_rgb, kind, shadowing, row):
    """``mi-brdfs tables``' own computation of one row (one α) at eight μ gives the shipped
    values (the file was written by the same code), and the stored E_avg is the integral of
    the interpolant."""
    tables = multiscatter.load_tables()
    key = multiscatter.table_key(kind, shadowing)
    stored = tables["E"][key]
    mus = albedo_tables.mu_nodes(stored.shape[1])
    alpha = albedo_tables.alpha_nodes(stored.shape[0], tables["alpha_max"])[row]
    columns = np.arange(8, stored.shape[1], 7)
    rebuilt = albedo_tables.albedo_row(kind, shadowing, alpha, mus[columns])
    np.testing.assert_allclose(rebuilt, stored[row, columns], atol=2e-5)
    np.testing.assert_allclose(albedo_tables.average(stored[row].astype(np.float64)),
                               tables["E_avg"][key][row], atol=1e-6)


def test02_table_interpolation_matches_numpy(variants_rgb, np_rng):
    """The plugin's bilinear lookup (gathers in JIT, NumPy in scalar) equals the reference's
    ``numpy.interp`` one, off the nodes and at the ends of both axes."""
    table = multiscatter.conductor_table("ggx", "smith")
    E, alpha_max = ref_ms._table("ggx", "smith")
    cases = [(mu, a) for mu, a in zip(np_rng.random(6), np_rng.random(6) * 2.5)]
    cases += [(0.0, 0.0), (1.0, 2.0), (1.0, 3.0), (1e-3, 1e-4)]
    for mu, a in cases:
        got = table.albedo(mi.Float(mu), mi.Float(a))
        got = float(got[0] if dr.is_jit_v(mi.Float) else got)
        assert got == pytest.approx(ref_ms.albedo(E, alpha_max, mu, a), abs=2e-6), (mu, a)


# -- the lobe against the reference ---------------------------------------------------------

CONFIGS = {
    "white-ggx-smith": spec(distribution="ggx", shadowing="smith", alpha=0.7),
    "white-beckmann-vcavity": spec(alpha=0.4),
    "gold-exact": {"type": CT, "multiscatter": True, "distribution": "ggx", "shadowing": "smith",
                   "alpha": 0.9, "eta": {"type": "rgb", "value": [0.143, 0.374, 1.442]},
                   "k": {"type": "rgb", "value": [3.983, 2.385, 1.603]}},
    "schlick-diffuse": {"type": CT, "multiscatter": True, "fresnel": "schlick", "eta": 2.0,
                        "k": 1.0, "alpha": 0.5, "diffuse_reflectance": 0.3},
    "anisotropic": spec(distribution="ggx", shadowing="smith", alpha_u=0.2, alpha_v=0.9),
}


def test03b_a_textured_roughness_takes_the_2d_lookup(variants_rgb, np_rng):
    """A bitmap α of one value evaluates through the 2D table lookup as the uniform α does
    through the row at its roughness (:meth:`Table.at`), to float32 rounding."""
    base = spec(distribution="ggx", shadowing="smith")
    textured = dict(base, alpha={"type": "bitmap", "raw": True, "filter_type": "nearest",
                                 "bitmap": mi.Bitmap(np.full((4, 4), 0.55, np.float32))})
    n = 32 if mi.variant().startswith("scalar") else 4096
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n, lower=False)
    a = eval_pdf(mi.load_dict(dict(base, alpha=0.55)), wi, wo)
    b = eval_pdf(mi.load_dict(textured), wi, wo)
    assert mi.load_dict(textured).lobes.lobes[0].table.row is None
    np.testing.assert_allclose(b[0], a[0], rtol=2e-5, atol=1e-7)
    np.testing.assert_allclose(b[1], a[1], rtol=2e-5, atol=1e-7)


@pytest.mark.parametrize("name", CONFIGS)
def test03_eval_equals_the_float64_reference(variants_rgb, np_rng, name):
    """eval against single scattering plus Kulla & Conty's lobe in float64 (E read from the
    file and interpolated by NumPy, E_avg and F_avg integrated there): catches a missing
    Fresnel colouring, a wrong E_avg or a lobe without one of its (1 − E) factors."""
    n = 24 if mi.variant().startswith("scalar") else 20_000
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n)
    value = eval_pdf(mi.load_dict(CONFIGS[name]), wi, wo)[0]
    model = for_spec(CONFIGS[name])
    assert isinstance(model, ref_ms.Compensated)
    assert_matches_reference(value, lambda a, b: model.brdf(a, b) * np.maximum(b[:, 2:3], 0),
                             wi, wo, 1e-4, what=name)


def test04_fresnel_average(variant_llvm_ad_rgb):
    """F_avg by 5 Gauss-Legendre nodes (split at the critical angle where k = 0 and η < 1)
    against 3000 nodes in float64 (within 7e-5 in float64, 1e-4 allowed for float32);
    Schlick's closed form R0 + (1 − R0)/21 likewise."""
    cases = [(0.143, 3.983), (1.1, 2.5), (1.5, 0.0), (3.0, 0.0), (0.5, 0.0), (0.9, 0.0),
             (0.05, 0.5)]
    for eta, k in cases:
        got = multiscatter.fresnel_average(mi.Float(eta), mi.Float(k))[0]
        want = ref_ms.fresnel_average("exact", eta, k)[0]
        assert got == pytest.approx(want, abs=1e-4), (eta, k)
        got = multiscatter.schlick_average(((eta - 1) ** 2 + k * k) / ((eta + 1) ** 2 + k * k))
        assert got == pytest.approx(ref_ms.fresnel_average("schlick", eta, k)[0], abs=1e-6)


# -- energy -------------------------------------------------------------------------------------

#: (distribution, masking, α, sample_visible): Beckmann with Smith's visible normals is left
#: out, whose sample weights carry Mitsuba's rational-G1 bias (test_cooktorrance.py, test15);
#: there D·cosθ sampling measures the BRDF's albedo.
FURNACE = [("ggx", "smith", 1.0, True), ("beckmann", "smith", 0.6, False),
           ("ggx", "vcavity", 0.3, True)]


@pytest.mark.parametrize("kind,shadowing,alpha,visible", FURNACE)
def test05_white_furnace_reads_one(variant_llvm_ad_rgb, kind, shadowing, alpha, visible):
    """
    F ≡ 1: the albedo from sample() is 1 within 2e-3 (the target; the table's interpolation
    error is below 1e-3) plus 4 standard errors, at 0°, 60° and 85°. A table 1 % low fails
    (test06). The grid over α ∈ [0.05, 1] and θ up to 89° runs in ``make validate``.
    """
    s = spec(distribution=kind, shadowing=shadowing, alpha=alpha, sample_visible=visible)
    for theta in (0.0, 60.0, 85.0):
        mean, err = checks.albedo_sampled(mi.load_dict(s), math.radians(theta), n=400_000)
        assert abs(mean[0] - 1.0) <= 2e-3 + 4 * err[0], (theta, mean, err)


def test06_a_table_off_by_one_percent_fails_the_furnace(variant_llvm_ad_rgb, monkeypatch):
    """The check of test05 rejects the plugin with its table scaled by 0.99."""
    tables = multiscatter.load_tables()
    key = multiscatter.table_key("ggx", "smith")
    scaled = dict(tables, E={key: tables["E"][key] * 0.99},
                  E_avg={key: tables["E_avg"][key] * 0.99})
    monkeypatch.setattr(multiscatter, "load_tables", lambda: scaled)
    bsdf = mi.load_dict(spec(distribution="ggx", shadowing="smith", alpha=1.0))
    mean, err = checks.albedo_sampled(bsdf, math.radians(85.0), n=400_000)
    assert abs(mean[0] - 1.0) > 2e-3 + 4 * err[0], (mean, err)


def test07_coloured_compensation_is_bounded(variant_llvm_ad_rgb):
    """With gold's Fresnel term the compensated albedo exceeds single scattering by
    ks·F_ms·(1 − E(μi)) (reference) and stays below F ≡ 1's, at α = 1."""
    gold = CONFIGS["gold-exact"]
    model = for_spec(gold)
    for theta in (0.0, 70.0):
        mean, err = checks.albedo_sampled(mi.load_dict(gold), math.radians(theta), n=400_000)
        want = model.albedo(math.radians(theta))
        assert np.all(np.abs(mean - want) <= 1e-3 + 4 * err), (theta, mean, want)
        assert np.all(want < 1.0) and np.all(want > model.base.albedo(math.radians(theta)))


# -- sampling -----------------------------------------------------------------------------------

CHI2 = {
    "ggx-smith-0": (spec(distribution="ggx", shadowing="smith", alpha=1.0), 1.0),
    "beckmann-vcavity-45": (spec(alpha=0.5), math.cos(math.radians(45))),
    "gold-diffuse-85": (dict(CONFIGS["gold-exact"], diffuse_reflectance=0.2),
                        math.cos(math.radians(85))),
}


@pytest.mark.parametrize("name", CHI2)
def test08_chi2(variant_llvm_ad_rgb, name):
    """sample() against pdf() of the mixture (microfacet normals; the cosine hemisphere for
    the compensation and the diffuse base), at normal, 45° and 85° incidence."""
    s, cos = CHI2[name]
    result = checks.chi2_bsdf(s, wi=[math.sqrt(1 - cos * cos), 0.0, cos], res=None, ires=None,
                              sample_count=200_000, test_count=len(CHI2))
    assert result.passed, result.message


def test09_a_sampler_without_the_compensation_fails_chi2(variant_llvm_ad_rgb, monkeypatch):
    """χ² rejects a sampler that never draws the compensation lobe (every sample from the
    microfacet normals) while pdf() counts it."""
    monkeypatch.setattr(cooktorrance_conductor.Compensation, "sample",
                        lambda self, *args: self.source.sample(*args))
    s, _ = CHI2["ggx-smith-0"]
    result = checks.chi2_bsdf(s, wi=[0.0, 0.0, 1.0], res=None, ires=None, sample_count=200_000)
    assert not result.passed


@pytest.mark.parametrize("name", ["gold-exact", "schlick-diffuse", "anisotropic"])
def test10_consistency_and_reciprocity(variant_llvm_ad_rgb, name):
    """bs.pdf = pdf(bs.wo), weight = eval/pdf, the sampled flags; f(ωi, ωo) = f(ωo, ωi)."""
    result = checks.check_consistency(CONFIGS[name], n=20_000)
    assert result.passed, result.message
    result = checks.check_reciprocity(CONFIGS[name], n=20_000)
    assert result.passed, result.message


def test11_sampled_component_of_the_cosine_samples(variant_llvm_ad_rgb, np_rng):
    """With a diffuse base, cosine samples are labelled compensation (glossy, component 0) or
    base (diffuse, component 1) in proportion to their albedos at ωi."""
    s = dict(CONFIGS["schlick-diffuse"])
    bsdf = mi.load_dict(s)
    n = 100_000
    wi = np.tile([0.0, 0.0, 1.0], (n, 1))
    out = sample(bsdf, wi, np_rng.random(n), np_rng.random((n, 2)))
    diffuse = (out["component"] == 1).mean()
    # the mixture at normal incidence: ρd against E(1)·F_avg and F_ms·(1 − E(1))
    model = for_spec(s)
    e_i = ref_ms.albedo(model.E, model.alpha_max, 1.0, model.alpha)
    f_avg = ref_ms.fresnel_average("schlick", 2.0, 1.0)[0]
    weights = np.array([f_avg * e_i, model.F_ms[0] * (1 - e_i), 0.3])
    assert diffuse == pytest.approx(weights[2] / weights.sum(), abs=0.01)


# -- rendering, variants, AD, bad input -------------------------------------------------------

def test12_furnace_render(variant_llvm_ad_rgb):
    """A rough white sphere in the furnace renders finite and at 1 (within the render's
    noise), where single scattering reads 0.31 at its centre."""
    result = checks.check_furnace(spec(distribution="ggx", shadowing="smith", alpha=1.0),
                                  spp=64, res=32)
    assert result.passed, result.message


def test13_every_variant_loads_evaluates_and_samples(variants_all):
    """Scalar, spectral and polarized variants too: finite, and the furnace albedo of
    one sample batch near 1."""
    bsdf = mi.load_dict(spec(distribution="ggx", shadowing="smith", alpha=1.0))
    assert "multiscatter = true" in str(bsdf)
    n = 64 if mi.variant().startswith("scalar") else 4096
    rng = np.random.default_rng(3)
    wi = np.tile([0.6, 0.0, 0.8], (n, 1))
    out = sample(bsdf, wi, rng.random(n), rng.random((n, 2)))
    assert np.isfinite(out["weight"]).all()
    assert out["weight"][:, 0].mean() == pytest.approx(1.0, abs=0.1 if n == 64 else 0.03)


def test14_gradient_through_alpha(variant_llvm_ad_rgb):
    """d eval/d α through the table lookup equals a central difference."""
    bsdf = mi.load_dict(spec(distribution="ggx", shadowing="smith", alpha=0.6))
    params = mi.traverse(bsdf)
    wi, wo = mi.Vector3f(0.6, 0.0, 0.8), mi.Vector3f(-0.3, 0.4, math.sqrt(0.75))
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = wi
    alpha = mi.Float(0.6)
    dr.enable_grad(alpha)
    params["alpha.value"] = alpha
    params.update()
    value = bsdf.eval(mi.BSDFContext(), si, wo)
    dr.backward(value.x)
    grad = float(dr.grad(alpha)[0])

    def at(a):
        params["alpha.value"] = mi.Float(a)
        params.update()
        return float(bsdf.eval(mi.BSDFContext(), si, wo).x[0])

    h = 1e-3
    assert grad == pytest.approx((at(0.6 + h) - at(0.6 - h)) / (2 * h), rel=2e-2)


@pytest.mark.parametrize("variant", ["scalar_spectral", "llvm_ad_spectral"])
def test15_spectral_f_avg_table(variant, np_rng):
    """In spectral variants F_avg of an index the same everywhere (gold's tabulated η, k) is a
    table over the wavelengths: at random wavelengths it equals the float64 quadrature of the
    exact Fresnel term at the index there, within float32 rounding and the interpolation
    (largest at the kinks of gold's tabulated index; a table a quarter of a nanometre off,
    one node, is 1.2e-4 away)."""
    from conftest import set_variant

    set_variant(variant)
    bsdf = mi.load_dict({"type": CT, "multiscatter": True, "material": "Au"})
    lobe = bsdf.lobes.lobes[0]
    assert lobe.f_avg_table is not None
    lam = np_rng.uniform(mi.MI_CIE_MIN, mi.MI_CIE_MAX, (4, 64))
    lam[0, :2] = (mi.MI_CIE_MIN, mi.MI_CIE_MAX)
    got, eta, k = [], [], []
    for column in lam.T if not dr.is_jit_v(mi.Float) else [lam]:
        si = dr.zeros(mi.SurfaceInteraction3f, 1 if column.ndim == 1 else column.shape[1])
        si.wavelengths = mi.UnpolarizedSpectrum(column)
        got.append(np.array(lobe.fresnel_average(si, True)))
        eta.append(np.array(lobe.eta.eval(si)))
        k.append(np.array(lobe.k.eval(si)))
    got, eta, k = (np.array(a, dtype=np.float64).reshape(-1) for a in (got, eta, k))
    # the same order in all three: the wavelength, η and k of each channel of each lane
    want = ref_ms.fresnel_average("exact", eta, k)
    assert got.shape == want.shape == (256,)
    assert np.abs(got - want).max() < 2e-5, np.abs(got - want).max()
