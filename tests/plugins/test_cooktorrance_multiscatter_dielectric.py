"""
``cooktorrance`` with ``transmission`` and ``multiscatter``: Kulla & Conty's dielectric energy
compensation. Its tables E_R+T(μ, α, η) against a rebuild by the package's own command and
against the float64 quadrature of the single scattering, its lobe against the float64
reference, the white furnace reading 1 from both sides, χ² of the mixed sampler, consistency,
reciprocity across the interface, a render, the variants. The grids over α, θ and η, and the
comparison with the random walk of Heitz et al. 2016, run in ``make validate``, section
multiscatter.
"""

import math
import warnings

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from helpers import (
    assert_matches_reference, detailed_balance_error, eval_pdf, random_directions, sample,
    unbalance_the_shares,
)

from mi_brdfs import albedo_tables, checks
from mi_brdfs.plugins import cooktorrance_dielectric
from mi_brdfs.reference import for_spec
from mi_brdfs.reference import multiscatter as ref_ms
from mi_brdfs.reference.cooktorrance import RoughDielectric
from mi_brdfs.scattering import multiscatter

RADIANCE, IMPORTANCE = mi.TransportMode.Radiance, mi.TransportMode.Importance

#: A node of the table's η axis near glass (1.5): the compensation is exact there up to the
#: table's own error, which the furnace tests isolate from the interpolation in η.
ETA_NODE = float(albedo_tables.eta_nodes()[albedo_tables.N_ETA // 2 + 5])


def glass(**kw):
    return dict({"type": "cooktorrance", "transmission": True, "multiscatter": True,
                 "distribution": "ggx", "alpha": 1.0, "eta": ETA_NODE}, **kw)


def wi_at(theta_deg):
    t = math.radians(theta_deg)
    return [math.sin(t), 0.0, math.cos(t)]


# -- the tables ---------------------------------------------------------------------------------

def test01_a_table_slice_rebuilds_and_matches_the_quadrature(variant_llvm_ad_rgb):
    """``mi-brdfs tables``' own computation of one (η, α) row at six μ gives the shipped
    values, the stored E_avg is the integral of the interpolant, and the shipped values agree
    with the float64 quadrature of the single scattering (independent of the plugin)."""
    tables = multiscatter.load_tables()
    stored = tables["ET"]["ggx-smith"]
    j, row = albedo_tables.N_ETA // 2 + 5, 40
    eta = albedo_tables.eta_nodes()[j]
    alpha = albedo_tables.alpha_nodes(stored.shape[1], tables["alpha_max"])[row]
    mus = albedo_tables.mu_nodes(stored.shape[2])
    columns = np.arange(3, stored.shape[2], 6)
    rebuilt = albedo_tables.dielectric_row("ggx", alpha, eta, mus[columns])
    np.testing.assert_allclose(rebuilt, stored[j, row, columns], atol=2e-5)
    np.testing.assert_allclose(albedo_tables.average(stored[j, row].astype(np.float64)),
                               tables["ET_avg"]["ggx-smith"][j, row], atol=1e-6)
    model = RoughDielectric(alpha, "ggx", eta)
    quadrature = [model.albedo(math.acos(mu))[0] for mu in mus[columns]]
    np.testing.assert_allclose(stored[j, row, columns], quadrature, atol=1e-3)


def test02_tables_from_below_are_the_inverse_index(variant_llvm_ad_rgb):
    """The plugin lit from below at η has the albedo of the table at 1/η (the mirror image):
    the single-scattering albedo from inside equals the shipped value at 1/η."""
    below, above = multiscatter.dielectric_tables("ggx", ETA_NODE)[1], \
        multiscatter.dielectric_tables("ggx", 1.0 / ETA_NODE)[0]
    mu, alpha = mi.Float(0.6), mi.Float(0.5)
    assert dr.allclose(below.albedo(mu, alpha), above.albedo(mu, alpha))
    spec = glass(multiscatter=False, alpha=0.5)
    interface = mi.load_dict(glass(alpha=0.5)).lobes.lobes[0]  # the plugin's two-sided lookup
    e, _ = interface.albedo(None, mu, mi.Bool(False), True)
    assert dr.allclose(e, below.albedo(mu, alpha))
    mean, err = checks.albedo_sampled(spec, math.pi - math.acos(0.6), n=200_000,
                                      ctx=mi.BSDFContext(IMPORTANCE))
    assert mean[0] == pytest.approx(below.albedo(mu, alpha)[0], abs=1e-3 + 4 * err[0])


# -- the lobe -----------------------------------------------------------------------------------

@pytest.mark.parametrize("spec", [
    glass(),
    glass(distribution="beckmann", alpha=0.4, eta=1.33, specular_reflectance=0.8,
          specular_transmittance=0.6),
], ids=["ggx", "beckmann-water-tinted"])
def test03_eval_equals_the_float64_reference(variants_rgb, np_rng, spec):
    """eval/|cosθo| against single scattering plus the compensation in float64 (E read from
    the file and interpolated by NumPy, E_avg and F_avg integrated there), both sides, both
    modes; a reference without the 1/η² of radiance transport on the compensation's
    refraction is rejected."""
    bsdf, model = mi.load_dict(spec), for_spec(spec)
    assert isinstance(model, ref_ms.CompensatedDielectric)
    n = 24 if mi.variant().startswith("scalar") else 20_000
    wi, wo = random_directions(np_rng, n), random_directions(np_rng, n)
    for mode in (RADIANCE, IMPORTANCE):
        value = eval_pdf(bsdf, wi, wo, mi.BSDFContext(mode))[0]
        assert_matches_reference(
            value, lambda a, b: model.brdf(a, b, radiance=mode == RADIANCE) * np.abs(b[:, 2:3]),
            wi, wo, 1e-4, what=str(mode))
    with pytest.raises(AssertionError):
        value = eval_pdf(bsdf, wi, wo, mi.BSDFContext(RADIANCE))[0]
        assert_matches_reference(
            value, lambda a, b: (model.base.brdf(a, b) + model.lobe(a, b, radiance=False)) *
            np.abs(b[:, 2:3]), wi, wo, 1e-4)


@pytest.mark.parametrize("kind,alpha,theta", [
    ("ggx", 1.0, 0.0), ("ggx", 1.0, 80.0), ("ggx", 0.3, 120.0), ("ggx", 1.0, 175.0),
    ("beckmann", 1.0, 45.0), ("beckmann", 0.6, 150.0),
])
def test04_white_furnace_reads_one_from_both_sides(variant_llvm_ad_rgb, kind, alpha, theta):
    """Importance transport, ks = kt = 1: every photon arriving is reflected or refracted,
    |E − 1| ≤ 2e-3 + 4 SE (single scattering alone loses up to 65 % here)."""
    spec = glass(distribution=kind, alpha=alpha)
    mean, err = checks.albedo_sampled(spec, math.radians(theta), n=400_000,
                                      ctx=mi.BSDFContext(IMPORTANCE))
    assert abs(mean[0] - 1.0) <= 2e-3 + 4 * err[0], (mean, err)


def test05_a_table_off_by_one_percent_fails_the_furnace(variant_llvm_ad_rgb, monkeypatch):
    """The check of test04 rejects the plugin with its tables scaled by 0.99."""
    tables = multiscatter.load_tables()
    scaled = dict(tables, ET={k: v * 0.99 for k, v in tables["ET"].items()},
                  ET_avg={k: v * 0.99 for k, v in tables["ET_avg"].items()})
    monkeypatch.setattr(multiscatter, "load_tables", lambda: scaled)
    bsdf = mi.load_dict(glass())
    mean, err = checks.albedo_sampled(bsdf, math.radians(0.0), n=400_000,
                                      ctx=mi.BSDFContext(IMPORTANCE))
    assert abs(mean[0] - 1.0) > 2e-3 + 4 * err[0], (mean, err)


def test06_reciprocal_across_the_interface(variant_llvm_ad_rgb, np_rng, monkeypatch):
    """Detailed balance in importance transport: f(a→b)·η_a² = f(b→a)·η_b², a and b on
    either side (η = 1 above, η below), reflection and refraction; the compensation alone
    would break it without its 1/η² in the share from below (rejected)."""
    n = 20_000
    a, b = random_directions(np_rng, n), random_directions(np_rng, n)
    assert detailed_balance_error(mi.load_dict(glass(alpha=0.7)), a, b, ETA_NODE) < 1e-3
    unbalance_the_shares(monkeypatch)
    assert detailed_balance_error(mi.load_dict(glass(alpha=0.7)), a, b, ETA_NODE) > 1e-2


# -- sampling -----------------------------------------------------------------------------------

CHI2 = {"ggx-0": (glass(), 0.0), "ggx-45": (glass(alpha=0.5), 45.0),
        "beckmann-85": (glass(distribution="beckmann"), 85.0),
        "ggx-inside-150": (glass(alpha=0.5), 150.0)}


@pytest.mark.parametrize("name", CHI2)
def test07_chi2(variant_llvm_ad_rgb, name):
    """sample() against pdf() of the mixture (microfacet normals; the cosine hemisphere on
    either side for the compensation), from outside at 0°, 45° and 85°, and from inside."""
    spec, theta = CHI2[name]
    result = checks.chi2_bsdf(spec, wi=wi_at(theta), res=None, ires=None,
                              sample_count=200_000, test_count=len(CHI2))
    assert result.passed, result.message


def test08_a_sampler_without_the_compensation_fails_chi2(variant_llvm_ad_rgb, monkeypatch):
    """χ² rejects a sampler that never draws the compensation lobe (every sample from the
    microfacet normals) while pdf() counts it."""
    monkeypatch.setattr(cooktorrance_dielectric.InterfaceCompensation, "sample",
                        lambda self, *args: self.source.sample(*args))
    result = checks.chi2_bsdf(glass(), wi=wi_at(0.0), res=None, ires=None,
                              sample_count=200_000)
    assert not result.passed


@pytest.mark.parametrize("mode", [RADIANCE, IMPORTANCE])
def test09_consistency_and_components(variant_llvm_ad_rgb, np_rng, mode):
    """bs.pdf = pdf(bs.wo) and weight = eval/pdf in both modes; the compensation's samples
    carry the component and flags of the side they leave on, and bs.eta of a refraction."""
    spec = glass(alpha=0.8)
    result = checks.check_consistency(spec, n=20_000, ctx=mi.BSDFContext(mode))
    assert result.passed, result.message
    n = 20_000
    out = sample(mi.load_dict(spec), np.tile(wi_at(30.0), (n, 1)), np_rng.random(n),
                 np_rng.random((n, 2)))
    ok = out["pdf"] > 0  # (a microfacet normal that fails to reflect or refract: no sample)
    through = out["wo"][ok, 2] < 0
    assert np.all(out["component"][ok] == np.where(through, 1, 0))
    assert ok.mean() > 0.9 and 0.5 < through.mean() < 0.999


# -- rendering, variants ------------------------------------------------------------------------

def _sphere_mean(spec, res=24, spp=64):
    """The mean radiance over the pixels that see only the sphere, in the white furnace
    rendered with paths of up to 64 vertices (a lossless interface keeps the closed furnace
    at radiance 1 everywhere, inside the glass η² times that), and whether all are finite."""
    image = checks.furnace.furnace_render(spec, spp=spp, res=res, max_depth=64,
                                          predict=False).image
    on_sphere = np.isfinite(checks.furnace.view_cosines(res)).all(axis=2)
    return float(image[on_sphere].mean()), bool(np.isfinite(image).all())


def test10_furnace_render(variant_llvm_ad_rgb):
    """A rough glass sphere (α = 1) in the furnace, with all its internal paths: finite and
    at 1 within 0.02 (render noise), where single scattering reads below 0.75."""
    mean, finite = _sphere_mean(glass())
    assert finite and abs(mean - 1.0) <= 0.02, mean
    mean, finite = _sphere_mean(glass(multiscatter=False))
    assert finite and mean < 0.75, mean


def test11_every_variant_loads_evaluates_and_samples(variants_all):
    """Scalar, spectral and polarized variants too: finite, and the importance furnace of one
    sample batch near 1."""
    bsdf = mi.load_dict(glass())
    assert "multiscatter = true" in str(bsdf)
    n = 64 if mi.variant().startswith("scalar") else 4096
    rng = np.random.default_rng(3)
    out = sample(bsdf, np.tile(wi_at(60.0), (n, 1)), rng.random(n), rng.random((n, 2)),
                 mi.BSDFContext(IMPORTANCE))
    assert np.isfinite(out["weight"]).all()
    assert out["weight"][:, 0].mean() == pytest.approx(1.0, abs=0.1 if n == 64 else 0.03)


def test12_an_index_beyond_the_tables_warns(variant_scalar_rgb):
    """η outside the tables' [1/3, 3] loads, with one line saying the tables end there; inside
    it, no warning."""
    with pytest.warns(UserWarning, match="cooktorrance: multiscatter with eta = 4.*tables end"):
        mi.load_dict(glass(eta=4.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mi.load_dict(glass(eta=2.9))
