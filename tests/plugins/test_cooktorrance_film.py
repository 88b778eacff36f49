"""
cooktorrance with a thin film (``film_thickness``, ``film_eta``): the film's reflectance from
the float64 transfer-matrix reference (mi_brdfs.reference.thinfilm) in place of F, on a
conductor and on a dielectric (reflection, and refraction with the reference's T: R + T = 1),
exact at the sampled wavelengths, integrated against the sRGB sensitivities in RGB, the
Mueller matrix of Mitsuba's Fresnel term at zero thickness, no film at all (bit-equal, no
cost) without one, its one-line errors, the compensated conductor's and dielectric's white
furnace (the dielectric's albedo tables shifted by the film, mi_brdfs.scattering.
multiscatter_film), the compensated dielectric's sampling, consistency and reciprocity, and the
gradients through the thickness and the indices.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from helpers import detailed_balance_error, random_directions, unbalance_the_shares

from mi_brdfs import albedo_tables, checks
from mi_brdfs.checks import albedo, batch
from mi_brdfs.reference import thinfilm as ref

CT = "cooktorrance"
#: ωi, ωo in reflection and ωo in refraction (normalised where used)
WI, WO, WT = np.array([0.5, 0.1, 0.86]), np.array([-0.3, -0.4, 0.6]), np.array([-0.4, 0.0, -0.8])
CONDUCTOR = dict(type=CT, eta=0.2, k=3.0, alpha=0.3, shadowing="smith")
DIELECTRIC = dict(type=CT, eta=1.33, transmission=True, alpha=0.3)
FILM = dict(film_thickness=320.0, film_eta=1.47)


def _unit(v):
    return v / np.linalg.norm(v)


def _eval(spec, wi, wo):
    """One eval (per channel), at batch.WAVELENGTHS in spectral variants."""
    bsdf = mi.load_dict(spec)
    value = bsdf.eval(mi.BSDFContext(), batch.interaction(_unit(wi)),
                      mi.Vector3f(*[float(x) for x in _unit(wo)]))
    return np.array(value, np.float64).ravel(), bsdf


def _half(wi, wo, eta):
    """(the facet cosine |ωi·m|, and whether ωi is outside) of the (generalised) half vector."""
    wi, wo = _unit(wi), _unit(wo)
    if wi[2] * wo[2] > 0:
        m = wi + wo
    else:
        m = wi + (eta if wi[2] > 0 else 1 / eta) * wo
    m = _unit(m) * np.sign(m[2])
    return abs(wi @ m), wi[2] > 0


@pytest.mark.parametrize("given, hint", [
    (dict(film_eta=1.4), "needs film_thickness"),
    (dict(film_thickness=300.0, fresnel="schlick"), "needs fresnel"),
    (dict(film_thickness=-1.0), "within [0"),
    (dict(film_thickness=300.0, film_eta=0.0), "within (0"),
])
def test01_errors_are_one_line(variant_scalar_rgb, given, hint):
    with pytest.raises(RuntimeError) as e:
        mi.load_dict({**CONDUCTOR, **given})
    line = str(e.value).strip().splitlines()[-1]
    assert line.startswith("ParameterError: cooktorrance: parameter \"film_") and hint in line


def test02_no_film_is_no_code_and_bit_equal(variant_scalar_rgb):
    """A thickness of 0 (the default) builds no film: the lobes hold None, traverse has no
    film parameters, and eval is bit-equal to the plugin without the parameter."""
    for spec in (CONDUCTOR, DIELECTRIC):
        bare, b0 = _eval(spec, WI, WO)
        zero, b1 = _eval({**spec, "film_thickness": 0.0}, WI, WO)
        assert np.array_equal(bare, zero) and b1.m_film is None
        assert b1.lobes.lobes[0].film is None
        assert not any("film" in key for key in mi.traverse(b1).keys())


def _film_ratio(spec, wi, wo, wavelengths, weights=None):
    """eval with the film over eval without, against the reference's R (or T) of the film
    over the bare base's, at the facet cosine; per channel, integrated with ``weights``."""
    with_film = _eval({**spec, **FILM}, wi, wo)[0]
    bare = _eval(spec, wi, wo)[0]
    assert np.all(bare > 1e-4), "a pair the lobe does not reach"
    cos_m, outside = _half(wi, wo, spec["eta"])
    base = spec["eta"] + 1j * spec.get("k", 0.0)
    n1, n3 = (1.0, base) if outside else (spec["eta"], 1.0)
    key = "R" if wi[2] * wo[2] > 0 else "T"
    film = ref.film(cos_m, wavelengths, 1.47, 320.0, n3, n1)[key]
    plain = ref.stack(cos_m, wavelengths, n1, [], n3)[key]
    if weights is not None:
        film, plain = weights @ film, weights @ plain
    return with_film / bare, film / plain


def test03_spectral_eval_is_the_films_reflectance(variant_scalar_spectral):
    """Conductor and dielectric, reflection and refraction from both sides: within 1e-4 of
    the reference at each sampled wavelength; the refraction's 1 − R is the reference's T."""
    lam = np.array(batch.WAVELENGTHS)
    flip = np.array([1, 1, -1])
    cases = [(CONDUCTOR, WI, WO), (DIELECTRIC, WI, WO), (DIELECTRIC, WI, WT),
             (DIELECTRIC, WI * flip, WO * flip), (DIELECTRIC, WI * flip, WT * flip)]
    for spec, wi, wo in cases:
        got, want = _film_ratio(spec, wi, wo, lam)
        assert got == pytest.approx(want, rel=1e-4, abs=1e-6), (spec, wi, wo)


def test04_rgb_eval_integrates_the_spectrum(variant_scalar_rgb):
    """In RGB the same ratio integrated against D65 times the sRGB colour-matching functions
    (Mitsuba's tables): within 1e-3 of the reference for the conductor and for the dielectric
    in reflection and refraction (the colour tabulated per material, interpolated)."""
    lam = np.arange(360.0, 831.0)
    xyz = np.array([[float(v) for v in mi.cie1931_xyz(float(x))] for x in lam]).T
    from mi_brdfs.scattering.thinfilm import SRGB
    w = SRGB @ xyz * np.array([float(mi.cie_d65(float(x))) for x in lam])
    w = w / w.sum(axis=1, keepdims=True)
    for spec, wo in ((CONDUCTOR, WO), (DIELECTRIC, WO), (DIELECTRIC, WT)):
        got, want = _film_ratio(spec, WI, wo, lam, w)
        assert got == pytest.approx(want, rel=1e-3), (spec, wo)


def test05_polarized_zero_thickness_is_mitsubas_fresnel_matrix(variant_scalar_spectral_polarized):
    """A film of thickness 0 everywhere (a texture, so the film code runs) gives the Mueller
    matrix of the bare conductor (Mitsuba's mueller.specular_reflection, rotated), element by
    element within 2e-5 of its largest; with 320 nm it differs."""
    zero = {"type": "checkerboard", "color0": 0.0, "color1": 0.0}
    bare, b = _eval(CONDUCTOR, WI, WO)
    film, bf = _eval({**CONDUCTOR, "film_thickness": zero}, WI, WO)
    assert bf.m_film is not None
    assert np.abs(film - bare).max() <= 2e-5 * np.abs(bare).max()
    thick = _eval({**CONDUCTOR, **FILM}, WI, WO)[0]
    assert np.abs(thick - bare).max() > 0.01 * np.abs(bare).max()


def test06_compensated_white_furnace_with_a_film(variant_llvm_ad_rgb):
    """multiscatter over a perfect mirror (η = 0, k = 1) under a film that absorbs nothing:
    the film reflects everything, its F_avg is 1, and the albedo from sample() is 1 within
    3e-3 + 4 standard errors at 0°, 60° and 85° (GGX, α = 0.8)."""
    spec = dict(type=CT, eta=0.0, k=1.0, alpha=0.8, distribution="ggx", shadowing="smith",
                multiscatter=True, **FILM)
    for theta in (0.0, 60.0, 85.0):
        mean, err = albedo.albedo_sampled(spec, np.radians(theta), n=200_000)
        assert np.all(np.abs(mean - 1.0) <= 3e-3 + 4 * err), (theta, mean, err)


def _ad_and_difference(bsdf, key: str, x: float, h: float, traced=lambda: None,
                       wo=WO, same_path: bool = False) -> tuple:
    """(d Σeval/dx by AD through mi.traverse at x, the central difference over ±h, what
    ``traced()`` returns while the gradient is enabled) at (WI, ``wo``); ``same_path``: the
    difference of values computed with the gradient enabled too (where a table stands in for
    the film's series only without one, the difference of the series itself)."""
    params = mi.traverse(bsdf)
    si = batch.interaction(_unit(WI), 1)
    wo = mi.Vector3f(*[float(v) for v in _unit(wo)])

    def value(v, grad=False):
        params[key] = mi.Float(v)
        if grad:
            dr.enable_grad(params[key])
        params.update()
        return bsdf.eval(mi.BSDFContext(), si, wo), params[key]
    out, var = value(x, True)
    seen = traced()
    dr.eval(out)  # the primal first: else the backward kernel recomputes it, far larger
    dr.backward(dr.sum(out))
    got = dr.grad(var)[0]
    want = float(dr.sum(value(x + h, same_path)[0] - value(x - h, same_path)[0])[0]) / (2.0 * h)
    return got, want, seen


def test07_gradient_through_the_thickness(variant_llvm_ad_spectral):
    """d eval/d film_thickness by AD (mi.traverse) against a central difference of ±0.5 nm."""
    got, want, _ = _ad_and_difference(mi.load_dict({**CONDUCTOR, **FILM}),
                                      "film_thickness.value", 320.0, 0.5)
    assert got == pytest.approx(want, rel=2e-2) and abs(got) > 1e-4


def test08_rgb_gradient_through_the_film_index(variant_llvm_ad_rgb):
    """In RGB, with a gradient enabled on film_eta the colour is not taken from the numbers of
    a table: d eval/d film_eta by AD against a central difference of ±1e-3."""
    bsdf = mi.load_dict({**CONDUCTOR, **FILM})
    assert bsdf.lobes.lobes[0].film_table is not None  # tabulated while nothing is traced
    got, want, table = _ad_and_difference(bsdf, "film_eta.value", 1.47, 1e-3,
                                          lambda: bsdf.lobes.lobes[0].film_table)
    assert table is None
    assert got == pytest.approx(want, rel=2e-2) and abs(got) > 1e-3


def test09_rgb_uniform_thickness_table_and_its_gradient(variant_llvm_ad_rgb):
    """In RGB a thickness that is one number takes a table of that thickness alone (looked up
    in the cosine only, which has no slope in the thickness); with a gradient enabled on
    film_thickness there is no table (the kernel sums the series): d eval/d film_thickness by
    AD against a central difference of ±0.5 nm, within 2 %."""
    bsdf = mi.load_dict({**CONDUCTOR, **FILM})
    assert bsdf.lobes.lobes[0].film_table.uniform
    got, want, table = _ad_and_difference(bsdf, "film_thickness.value", 320.0, 0.5,
                                          lambda: bsdf.lobes.lobes[0].film_table)
    assert table is None
    assert bsdf.lobes.lobes[0].film_table.uniform
    assert got == pytest.approx(want, rel=2e-2) and abs(got) > 1e-4


#: The compensated rough glass (at a node of the tables' η axis, 1.48: the furnace is then
#: exact up to the tables' own error, apart from their interpolation in η) under a film of a
#: higher index (a film of about the glass's own index would change little)
ETA_NODE = float(albedo_tables.eta_nodes()[albedo_tables.N_ETA // 2 + 5])
COMPENSATED = dict(type=CT, transmission=True, multiscatter=True, distribution="ggx",
                   alpha=1.0, eta=ETA_NODE, film_thickness=320.0, film_eta=2.0)
IMPORTANCE = mi.TransportMode.Importance


def _furnace(bsdf, theta):
    """(the largest |E − 1| over the channels, its bound 2e-3 + 4 SE) at ``theta`` degrees
    (> 90: from inside), importance transport."""
    mean, err = albedo.albedo_sampled(bsdf, np.radians(theta), n=400_000,
                                      ctx=mi.BSDFContext(IMPORTANCE))
    return np.abs(mean - 1.0).max(), 2e-3 + 4 * err.max()


@pytest.mark.parametrize("theta", [0.0, 60.0, 180.0, 120.0])
def test10_compensated_dielectric_white_furnace_with_a_film(variants_llvm_rgb_spectral, theta):
    """ks = kt = 1 and a film that absorbs nothing on rough glass: every photon arriving is
    reflected or refracted, |E − 1| ≤ 2e-3 + 4 SE per channel (per wavelength in spectral),
    from outside and inside; the film alone moves the single scattering's albedo by up to 3 %
    here, and with the bare interface's tables (no shift) the furnace at 0° fails."""
    bsdf = mi.load_dict(COMPENSATED)
    error, bound = _furnace(bsdf, theta)
    assert error <= bound, (theta, error, bound)
    if theta == 0.0:
        bsdf.lobes.lobes[0].film_shift = None
        error, bound = _furnace(bsdf, theta)
        assert error > bound, (error, bound)


@pytest.mark.parametrize("theta", [0.0, 150.0])
def test11_compensated_dielectric_with_a_film_samples_its_pdf(variant_llvm_ad_rgb, theta):
    """χ² of the mixture (the compensation's side chosen by the mean of its per-channel
    share) from outside and inside, and bs.pdf = pdf(bs.wo), weight = eval/pdf."""
    t = np.radians(theta)
    result = checks.chi2_bsdf(COMPENSATED, wi=[np.sin(t), 0.0, np.cos(t)], res=None, ires=None,
                              sample_count=200_000, test_count=2)
    assert result.passed, result.message
    if theta == 0.0:
        result = checks.check_consistency(COMPENSATED, n=20_000,
                                          ctx=mi.BSDFContext(IMPORTANCE))
        assert result.passed, result.message


def test12_compensated_dielectric_with_a_film_is_reciprocal(variant_llvm_ad_rgb, np_rng,
                                                             monkeypatch):
    """Detailed balance in importance transport, per channel: f(a→b)·η_a² = f(b→a)·η_b², a
    and b on either side, within 2e-3 (the film's colour from inside is the table from
    outside read at Snell's image of the cosine, so the single scattering is reciprocal up to
    rounding); the compensation's per-channel shares without their 1/η² from below break it."""
    n = 20_000
    a, b = random_directions(np_rng, n), random_directions(np_rng, n)
    spec = dict(COMPENSATED, alpha=0.7)
    assert detailed_balance_error(mi.load_dict(spec), a, b, ETA_NODE) < 2e-3
    unbalance_the_shares(monkeypatch)
    assert detailed_balance_error(mi.load_dict(spec), a, b, ETA_NODE) > 1e-2


@pytest.mark.parametrize("key, x, h, rel", [("film_thickness.value", 320.0, 0.5, 1e-2),
                                            ("eta", 1.33, 1e-3, 2e-3)])
def test13_compensated_dielectric_gradients(variant_llvm_ad_rgb, key, x, h, rel):
    """d eval/d film_thickness and d eval/d η by AD against central differences of the same
    code path, in reflection and refraction: the film's reflectance at the shift's nodes, and
    the shift's kernels' slope in η, carry their derivatives (within 0.2 % in η, which lies
    between the tables' η nodes, where their slope is one-sided; without the kernels' slope
    it is 3 % off; within 1 % in the thickness, where the series reads the sensitivities'
    transforms from a piecewise-linear table whose slope is one-sided at its nodes)."""
    for wo in (WO, WT):
        got, want, _ = _ad_and_difference(mi.load_dict(dict(COMPENSATED, eta=1.33)), key, x, h,
                                          wo=wo, same_path=True)
        assert got == pytest.approx(want, rel=rel) and abs(got) > 1e-6, (key, wo)


def test14_compensated_dielectric_with_a_film_in_every_variant(variants_all):
    """Scalar, spectral and mono variants too: loads, samples finite weights whose mean (the
    importance furnace of one batch at 60°) is near 1; in llvm_ad_rgb a tiny render of the
    glass sphere in the furnace is finite."""
    from helpers import sample

    bsdf = mi.load_dict(COMPENSATED)
    n = 64 if mi.variant().startswith("scalar") else 4096
    rng = np.random.default_rng(3)
    t = np.radians(60.0)
    out = sample(bsdf, np.tile([np.sin(t), 0.0, np.cos(t)], (n, 1)), rng.random(n),
                 rng.random((n, 2)), mi.BSDFContext(IMPORTANCE))
    assert np.isfinite(out["weight"]).all()
    assert out["weight"].mean() == pytest.approx(1.0, abs=0.1 if n == 64 else 0.03)
    if mi.variant() == "llvm_ad_rgb":
        image = checks.furnace.furnace_render(COMPENSATED, spp=4, res=16, max_depth=16,
                                              predict=False).image
        assert np.isfinite(image).all() and image.mean() > 0.5
