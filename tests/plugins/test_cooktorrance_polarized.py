"""
cooktorrance in polarized variants: with ``shadowing=smith`` and the exact Fresnel term, its
Mueller matrices equal ``roughconductor``'s (the Fresnel matrix of the facet, its Stokes frames
rotated between the incident and outgoing directions), in eval, sample and a render through
the ``stokes`` integrator; Schlick's Fresnel, ``fresnel=none`` and the unpolarized lobes
(diffuse base, compensation) are depolarizers, as Mitsuba's ``diffuse``.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from conftest import set_variant
from helpers import random_directions

from mi_brdfs.checks import batch
from mi_brdfs.plugins import cooktorrance_conductor

CT = "cooktorrance"
WAVELENGTHS = [450.0, 520.0, 600.0, 680.0]
#: gold α = 0.3; GGX η = 0.2, k = 3; anisotropic copper
CONFIGS = {"gold": dict(material="Au", alpha=0.3),
           "ggx-eta-k": dict(distribution="ggx", eta=0.2, k=3.0, alpha=0.25),
           "anisotropic-copper": dict(material="Cu", alpha_u=0.1, alpha_v=0.4)}
MODES = (mi.TransportMode.Radiance, mi.TransportMode.Importance)


@pytest.fixture(params=["llvm_ad_spectral_polarized", "scalar_spectral_polarized"])
def variants_polarized(request):
    return set_variant(request.param)


def _mueller(bsdf, wi, wo, mode):
    """eval's Mueller matrices at pairs (wi, wo) as (n, 4, 4, channels), at WAVELENGTHS."""
    ctx = mi.BSDFContext(mode)
    if batch.is_jit():
        si = batch.interaction(wi, len(wi))
        si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS)
        return np.moveaxis(np.array(bsdf.eval(ctx, si, batch.vectors(wo))), -1, 0)
    out = []
    for a, b in zip(wi, wo):
        si = batch.interaction(a)
        si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS)
        out.append(np.array(bsdf.eval(ctx, si, mi.Vector3f(*b))))
    return np.array(out)


def _assert_mueller_equal(a, b, rtol):
    """Every element within ``rtol`` (one value, or one per pair) of the largest element of the
    pair's matrix."""
    scale = np.maximum(np.abs(b).max(axis=(1, 2, 3)), 1e-30)
    excess = np.abs(a - b).max(axis=(1, 2, 3)) / scale - rtol
    worst = int(np.argmax(excess))
    assert excess[worst] <= 0, (f"difference {excess[worst] + np.ravel(rtol)[0]:.3g} of the "
                                f"matrix at pair {worst}, above its tolerance")


def _frame_conditioning(wi, wo):
    """1/|m × ωo| per pair (m the half vector): the Stokes frames' rotation divides by it, so a
    rounding of the directions moves the rotation angle by about ε·that (near normal incidence,
    where the plane of reflection is barely defined)."""
    m = (wi + wo) / np.linalg.norm(wi + wo, axis=1, keepdims=True)
    return 1.0 / np.maximum(np.linalg.norm(np.cross(m, wo), axis=1), 1e-12)


@pytest.mark.parametrize("name", CONFIGS)
def test01_eval_equals_roughconductors_mueller_matrix(variants_polarized, np_rng, name):
    """Both transport modes: every element to float32 rounding: 1e-5 of the matrix's largest
    element, plus in scalar variants (where the plugin computes in double and the built-in in
    float32) 32 float32 ulps times the frame rotation's conditioning. A depolarizing conductor,
    as the plugin was, is rejected (differences of 0.5-1 of the matrix)."""
    common = CONFIGS[name]
    ours = mi.load_dict(dict(common, type=CT, shadowing="smith"))
    theirs = mi.load_dict(dict(common, type="roughconductor"))
    n = 2000 if batch.is_jit() else 24
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n, lower=False)
    rtol = 1e-5 + (0.0 if batch.is_jit() else 32 * 2.0 ** -24 * _frame_conditioning(wi, wo))
    for mode in MODES:
        _assert_mueller_equal(_mueller(ours, wi, wo, mode), _mueller(theirs, wi, wo, mode), rtol)
    depolarized = mi.load_dict(dict(common, type=CT, shadowing="smith"))
    unpolarized = depolarized.lobes.lobes[0]
    unpolarized.fresnel = "schlick-that-is-exact"  # _reflect's polarized branch is off
    unpolarized.fresnel_term = cooktorrance_conductor.FRESNEL_TERMS["exact"]
    with pytest.raises(AssertionError):
        _assert_mueller_equal(_mueller(depolarized, wi, wo, MODES[0]),
                              _mueller(theirs, wi, wo, MODES[0]), 1e-2)


def test02_samples_equal_roughconductors(np_rng):
    """llvm_ad_spectral_polarized, visible normals: the same directions bit for bit, and the
    sample weights' Mueller matrices equal roughconductor's where its weight is eval/pdf
    (roughconductor reuses the sampled normal: 2e-3 at grazing, as in RGB)."""
    set_variant("llvm_ad_spectral_polarized")
    n = 20_000
    common = CONFIGS["gold"]
    ours = mi.load_dict(dict(common, type=CT, shadowing="smith"))
    theirs = mi.load_dict(dict(common, type="roughconductor"))
    si = batch.interaction(random_directions(np_rng, n, lower=False), n)
    si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS)
    u1, u2 = mi.Float(np_rng.random(n)), mi.Point2f(np_rng.random((2, n)))
    (a, wa), (b, wb) = (bsdf.sample(mi.BSDFContext(), si, u1, u2) for bsdf in (ours, theirs))
    np.testing.assert_array_equal(np.array(a.wo), np.array(b.wo))
    wa, wb = np.moveaxis(np.array(wa), -1, 0), np.moveaxis(np.array(wb), -1, 0)
    _assert_mueller_equal(wa, wb, 2e-3)


@pytest.mark.parametrize("spec", [
    dict(type=CT, fresnel="schlick", eta=0.2, k=3.0),
    dict(type=CT, fresnel="none", shadowing="smith"),
    dict(type=CT, multiscatter=True, alpha=0.6, fresnel="none"),
], ids=["schlick", "none", "multiscatter-none"])
def test03_unpolarized_fresnel_terms_are_depolarizers(variants_polarized, np_rng, spec):
    """Schlick's approximation and F ≡ 1 model no polarization: the matrix is a depolarizer,
    ρ in its first element alone, equal to the value of the scalar_spectral variant."""
    n = 200 if batch.is_jit() else 8
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n, lower=False)
    m = _mueller(mi.load_dict(spec), wi, wo, MODES[0])
    assert np.abs(m[:, 1:, :, :]).max() == 0 and np.abs(m[:, 0, 1:, :]).max() == 0
    assert m[:, 0, 0, :].max() > 0


def test04_compensation_and_diffuse_base_add_depolarized(np_rng):
    """With multiscatter and a diffuse base, the Mueller matrix is the microfacet lobe's plus a
    depolarizer of the other lobes (the same plugin without them, compared element by
    element), in both modes; sample() weights are finite."""
    set_variant("llvm_ad_spectral_polarized")
    n = 2000
    base = dict(type=CT, material="Au", alpha=0.6, shadowing="smith")
    full = mi.load_dict(dict(base, multiscatter=True, diffuse_reflectance=0.2))
    alone = mi.load_dict(base)
    wi, wo = random_directions(np_rng, n, lower=False), random_directions(np_rng, n, lower=False)
    for mode in MODES:
        difference = _mueller(full, wi, wo, mode) - _mueller(alone, wi, wo, mode)
        off_first = difference.copy()
        off_first[:, 0, 0, :] = 0.0
        assert np.abs(off_first).max() < 1e-6 and difference[:, 0, 0, :].min() > 0
    si = batch.interaction(wi, n)
    si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS)
    _, weight = full.sample(mi.BSDFContext(), si, mi.Float(np_rng.random(n)),
                            mi.Point2f(np_rng.random((2, n))))
    assert np.isfinite(np.array(weight)).all()


def _stokes_scene(bsdf):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 3}},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16},
                   "sampler": {"type": "independent", "sample_count": 4}},
        "light": {"type": "directional", "direction": [1, -0.5, -1], "irradiance": 5.0},
        "sky": {"type": "constant", "radiance": 0.2},
        "sphere": {"type": "sphere", "bsdf": bsdf}})


def test05_polarized_render_equals_roughconductors():
    """A gold sphere through the stokes integrator (channels: RGB, then S0-S3): the image of
    cooktorrance smith equals roughconductor's, same seed, to float32 rounding, polarization
    (S1-S3) included, which a depolarizing conductor does not reflect."""
    set_variant("llvm_ad_spectral_polarized")
    spec = dict(material="Au", alpha=0.3)
    ours = np.array(mi.render(_stokes_scene(dict(spec, type=CT, shadowing="smith")), seed=1))
    theirs = np.array(mi.render(_stokes_scene(dict(spec, type="roughconductor")), seed=1))
    assert np.isfinite(ours).all()
    np.testing.assert_allclose(ours, theirs, atol=1e-5 * np.abs(theirs).max())
    polarization = np.abs(theirs[..., 6:]).max()
    assert polarization > 0.02 * np.abs(theirs).max()
    schlick = np.array(mi.render(_stokes_scene(dict(spec, type=CT, fresnel="schlick")), seed=1))
    assert np.abs(schlick[..., 6:]).max() == 0.0
    assert dr.isfinite(dr.sum(mi.Float(schlick.ravel())))
