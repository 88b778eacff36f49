"""
The merl plugin: MERL's measured BRDFs in Mitsuba. Its value against the float64 NumPy
interpolation of the same file (itself checked against closed forms in
tests/measured/test_format.py) and against the closed-form BRDF the test file tabulates; MERL's
nearest-bin lookup; every variant's colours (RGB, luminance, Mitsuba's spectral upsampling);
the sampler (χ², consistency, a sampler whose pdf is off rejected, its efficiency against the
cosine); the scale through mi.traverse; one load per file; one-line errors.
"""

import os

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import (assert_matches_reference, eval_pdf, glossy_brdf, merl_file,
                     random_directions, sample)

from mi_brdfs.measured import data, lookup, merl, warp
from mi_brdfs.testing import assert_consistent, assert_sampling_matches_pdf

#: The relative rounding of half precision (11 significant bits), in which RGB and monochrome
#: variants store the bins (spectral ones: float32): a convex combination of values so stored,
#: the interpolation is within it of the float64 one.
HALF = 2.0 ** -11


def _rtol(rtol):
    """``rtol`` of a float32 computation, plus the rounding of the stored values."""
    return rtol if mi.is_spectral else rtol + HALF


def _spec(**extra):
    return dict({"type": "merl", "filename": str(merl_file())}, **extra)


def _pairs(rng, n):
    wi = random_directions(rng, n, lower=False)
    wo = random_directions(rng, n, lower=False)
    return wi, wo


def test01_create(variants_all):
    bsdf = mi.load_dict(_spec())
    assert type(bsdf).__name__ == "Merl" and bsdf.component_count() == 1
    assert bsdf.flags() == int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
    assert "Merl[" in str(bsdf) and "glossy-v1.binary" in str(bsdf)
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict(_spec(alpha=0.3))


@pytest.mark.parametrize("extra,message", [
    ({"filename": None}, 'merl: parameter "filename" = missing is invalid: the plugin needs a '
                         'file (.binary)'),
    ({"filename": "x.txt"}, 'parameter "filename" = "x.txt" is invalid: must be a file name '
                            'ending in .binary'),
    ({"filename": "/nonexistent/x.binary"}, "/nonexistent/x.binary: cannot read the MERL file"),
    ({"filter_type": "cubic"}, 'parameter "filter_type" = "cubic" is invalid: must be one of '
                               '"trilinear", "nearest"'),
    ({"scale": -1.0}, 'parameter "scale" = -1 is invalid: must be finite and ≥ 0'),
])
def test02_bad_parameters_are_one_line(variant_scalar_rgb, extra, message):
    spec = _spec(**extra)
    if spec["filename"] is None:
        del spec["filename"]
    with pytest.raises(RuntimeError) as e:
        mi.load_dict(spec)
    assert message in str(e.value)


def test03_a_bad_file_is_one_line(variant_scalar_rgb, tmp_path):
    path = tmp_path / "short.binary"
    path.write_bytes(np.array([90, 90, 180], "<i4").tobytes() + b"\0" * 8)
    with pytest.raises(RuntimeError, match=r"short.binary: 20 bytes where a MERL file has "
                                           r"34992012 .*truncated or padded"):
        mi.load_dict(_spec(filename=str(path)))


def _assert_eval_matches_numpy(bsdf, values, wi, wo, what):
    value, pdf, _, _ = eval_pdf(bsdf, wi, wo)
    assert_matches_reference(value, lambda a, b: merl.interpolate(values, a, b) * b[:, 2:3],
                             wi, wo, rtol=_rtol(1e-5), what=what)


def test04_eval_is_the_interpolated_table(variants_rgb, np_rng):
    """eval = f·cosθo with f the float64 NumPy trilinear interpolation of the file, to float32
    conditioning; at the bins' centres the closed form the file tabulates. A plugin whose
    lookup transposes θh and θd fails."""
    n = 64 if mi.variant().startswith("scalar") else 20000
    bsdf = mi.load_dict(_spec())
    values = merl.read(merl_file())
    wi, wo = _pairs(np_rng, n)
    _assert_eval_matches_numpy(bsdf, values, wi, wo, "merl")
    theta_h, theta_d, phi_d = (a.ravel() for a in merl.bin_centres())
    pick = np_rng.choice(len(theta_h), n, replace=False)
    wi, wo = merl.directions(theta_h[pick], np_rng.uniform(-np.pi, np.pi, n), theta_d[pick],
                             phi_d[pick])
    keep = (wi[:, 2] > 0.05) & (wo[:, 2] > 0.05) & (theta_h[pick] > 1e-3)
    assert_matches_reference(eval_pdf(bsdf, wi[keep], wo[keep])[0],
                             lambda a, b: glossy_brdf(a, b) * b[:, 2:3], wi[keep], wo[keep],
                             rtol=_rtol(2e-4), what="merl at the bins' centres")


def test04b_eval_of_random_data(variant_llvm_ad_rgb, np_rng, tmp_path):
    """Random values in every bin (no symmetry to hide a misplaced axis or a φd clamped
    instead of periodic) spanning eight decades up to 10⁵, beyond half precision's range
    (65504) unless stored in a unit that fits them, some unmeasured: eval = the NumPy
    interpolation."""
    values = 10.0 ** np_rng.uniform(-3.0, 5.0, (3,) + merl.RES)
    values[:, np_rng.random(merl.RES) < 0.01] = np.nan
    path = tmp_path / "random.binary"
    merl.write(path, values)
    wi, wo = _pairs(np_rng, 50000)
    _assert_eval_matches_numpy(mi.load_dict(_spec(filename=str(path))), merl.read(path), wi,
                               wo, "random data")


def test04c_the_table_starts_on_a_cache_line(variant_llvm_ad_rgb, monkeypatch):
    """The table's first byte sits on a 64-byte boundary (NumPy's own 16-byte alignment
    renders much slower: validation/merl_layout.py), with its rows in MERL's order; a table
    built without plugins.merl._aligned fails (here from memory placed 16 bytes past a line)."""
    from mi_brdfs.plugins import merl as merl_plugin  # the plugin's module needs a variant

    def start():
        table = merl_plugin.Table(data.load(merl_file()))
        dr.eval(table.buffer)
        return np.from_dlpack(table.buffer).ctypes.data % 64, table

    offset, table = start()
    rows = np.array(np.from_dlpack(table.buffer)).view(np.float16).reshape(-1, 4)
    want = data.load(merl_file()).rgb[12345] / table.unit
    assert offset == 0 and np.allclose(rows[12345, :3], want, rtol=HALF)

    aligned = merl_plugin._aligned
    monkeypatch.setattr(merl_plugin, "_aligned", lambda rows: aligned(rows, offset=16))
    assert start()[0] == 16


def test05_a_transposed_lookup_is_caught(variant_llvm_ad_rgb, np_rng, monkeypatch):
    monkeypatch.setattr(lookup, "_flat", lambda i, j, k: mi.UInt32((j * 90 + i) * 180 + k))
    bsdf = mi.load_dict(_spec())
    with pytest.raises(AssertionError, match="against the float64 reference"):
        _assert_eval_matches_numpy(bsdf, merl.read(merl_file()), *_pairs(np_rng, 4000),
                                   "transposed")


def test06_nearest_is_merl_lookup(variants_rgb, np_rng):
    """filter_type=nearest: MERL's reader's bin (merl.lookup); pairs within float32 rounding
    of a bin's edge are left out."""
    n = 64 if mi.variant().startswith("scalar") else 20000
    bsdf = mi.load_dict(_spec(filter_type="nearest"))
    values = merl.read(merl_file())
    wi, wo = _pairs(np_rng, n)
    x, y, z = merl.coordinates(*np.delete(merl.half_diff(wi, wo), 1, axis=0))
    edge = np.min([np.abs(c + 0.5 - np.round(c + 0.5)) for c in (x, y, z)], axis=0)
    keep = edge > 1e-3
    value = eval_pdf(bsdf, wi, wo)[0][keep] / wo[keep, 2:3]
    want = np.nan_to_num(merl.lookup(values, wi[keep], wo[keep]))
    np.testing.assert_allclose(value, want, rtol=_rtol(2e-5), atol=1e-6)


def test07_colours_in_every_variant(variants_all, np_rng):
    """Monochrome variants: the luminance of the RGB values; spectral ones: each bin's RGB
    upsampled as Mitsuba upsamples unbounded RGB (scalar ``srgb_model_fetch`` of RGB/s,
    s = 2·max), at the nearest bin."""
    bsdf = mi.load_dict(_spec(filter_type="nearest"))
    wi, wo = _pairs(np_rng, 8)
    rgb = np.nan_to_num(merl.lookup(merl.read(merl_file()), wi, wo))
    for a, b, f in zip(wi, wo, rgb):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*map(float, a))
        si.wavelengths = mi.UnpolarizedSpectrum(450.0, 520.0, 600.0, 680.0) \
            if mi.is_spectral else si.wavelengths
        got = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*map(float, b)))).ravel() / b[2]
        if mi.is_monochromatic:
            want = [f @ [0.212671, 0.715160, 0.072169]]
        elif mi.is_spectral:
            s = 2.0 * f.max()
            coeff = mi.srgb_model_fetch(mi.ScalarColor3f(*(f / s)))
            want = np.array(mi.srgb_model_eval(mi.Vector3f(*coeff), si.wavelengths)).ravel() * s
        else:
            want = f
        np.testing.assert_allclose(got, np.ravel(want), rtol=_rtol(2e-5), atol=1e-6)


def test07b_spectral_coefficients_in_float32(variant_llvm_ad_spectral):
    """Spectral variants keep each bin's coefficients (Jakob & Hanika 2019) in float32
    (test07 checks them to 2e-5): rounded to half precision, they would move the spectra more
    than ten times as much as the values' own rounding to half precision (the polynomial in
    a sigmoid amplifies it)."""
    from mi_brdfs.plugins import merl as merl_plugin  # the plugin's module needs a variant

    rgb = data.load(merl_file()).rgb.reshape(-1, 180, 3)[::97].reshape(-1, 3)
    columns = merl_plugin._columns(rgb)
    assert merl_plugin._stored(columns)[0].dtype == np.float32
    lam = mi.Float(np.linspace(400.0, 700.0, len(columns)).astype(np.float32))

    def spectra(c):
        return np.array(mi.srgb_model_eval(mi.Vector3f(c[:, :3].T), lam))

    exact, rounded = spectra(columns), spectra(columns.astype(np.float16).astype(np.float32))
    keep = exact > 1e-3
    assert np.max(np.abs(rounded[keep] / exact[keep] - 1.0)) > 10 * HALF


@pytest.mark.parametrize("theta", [0.0, 45.0, 80.0])
def test08_sampling_matches_pdf(variant_llvm_ad_rgb, theta):
    """χ² of sample() against pdf() at normal, 45° and 80° incidence."""
    t = np.radians(theta)
    assert_sampling_matches_pdf(_spec(), wi=[np.sin(t), 0.0, np.cos(t)],
                                sample_count=400_000)


def test09_a_sampler_whose_pdf_is_off_is_rejected(variant_llvm_ad_rgb, monkeypatch):
    """The density reported 10 % too high about the specular peak (u < 0.3 in the sampler's
    square) and the same elsewhere: sample() no longer draws what pdf() says, and χ² (sample()'s
    histogram against pdf()) rejects it."""
    original = warp.Sampler.pdf

    def off(self, wi, wo, active):
        uv, _ = warp.to_square(wi, wo)
        return original(self, wi, wo, active) * dr.select(uv.x < 0.3, 1.1, 1.0)

    monkeypatch.setattr(warp.Sampler, "pdf", off)
    with pytest.raises(AssertionError, match="χ²"):
        assert_sampling_matches_pdf(_spec(), wi=[0.5, 0.0, np.sqrt(0.75)],
                                    sample_count=400_000)


def test10_consistent_and_efficient(variant_llvm_ad_rgb, np_rng):
    """weight = eval/pdf and bs.pdf = pdf(bs.wo); the variance of the sample weights on the
    glossy file is at least 10 times under that of cosine sampling at 0°, 45° and 80°."""
    assert_consistent(_spec())
    bsdf = mi.load_dict(_spec())
    n = 200_000
    for theta in np.radians([0.0, 45.0, 80.0]):
        wi = np.array([[np.sin(theta), 0.0, np.cos(theta)]])
        ours = sample(bsdf, wi, np_rng.random(n), np_rng.random((n, 2)))["weight"].mean(1)
        cosine = mi.warp.square_to_cosine_hemisphere(mi.Point2f(np_rng.random((2, n))))
        wo = np.array(cosine).T
        f = eval_pdf(bsdf, np.repeat(wi, n, 0), wo)[0].mean(1)
        plain = f / (wo[:, 2] / np.pi)
        assert abs(ours.mean() - plain.mean()) < 5 * np.sqrt(plain.var() / n)
        assert plain.var() > 10 * ours.var(), (np.degrees(theta), plain.var(), ours.var())


def test11_scale_through_traverse(variant_llvm_ad_rgb, np_rng):
    """scale (exposed, differentiable) multiplies eval and the weights, not the pdf; its
    derivative is f·cosθo."""
    bsdf = mi.load_dict(_spec())
    wi, wo = _pairs(np_rng, 1000)
    before, pdf, _, _ = eval_pdf(bsdf, wi, wo)
    params = mi.traverse(bsdf)
    params["scale.value"] = 0.5
    params.update()
    after, pdf2, _, _ = eval_pdf(bsdf, wi, wo)
    np.testing.assert_allclose(after, 0.5 * before, rtol=1e-6)
    np.testing.assert_array_equal(pdf2, pdf)
    assert not params.flags("scale.value") & int(mi.ParamFlags.NonDifferentiable)


def test12_one_load_per_file(variants_rgb, tmp_path):
    """Two instances naming the file share one table; the file is read once per process; a
    file rewritten since is read again (its new values, not the old table's)."""
    before = data._load.cache_info()
    a, b = mi.load_dict(_spec()), mi.load_dict(_spec(filter_type="nearest"))
    assert a.table is b.table
    after = data._load.cache_info()
    assert after.misses - before.misses <= 1 and after.hits - before.hits >= 1
    path = tmp_path / "changing.binary"
    values = merl.read(merl_file())
    merl.write(path, values)
    first = mi.load_dict(_spec(filename=str(path)))
    merl.write(path, values * 2.0)
    os.utime(path, ns=(1, 1))  # a different modification time, whatever the clock's step
    second = mi.load_dict(_spec(filename=str(path)))
    assert second.table is not first.table
    wi, wo = np.array([[0.3, 0.0, 0.954]]), np.array([[-0.3, 0.0, 0.954]])
    np.testing.assert_allclose(eval_pdf(second, wi, wo)[0], 2 * eval_pdf(first, wi, wo)[0],
                               rtol=1e-6)


def _write_merl(path, values):
    """An independent writer of MERL's format: three int32 dimensions, then red, green and
    blue float64, each divided by MERL's scale, -1 where NaN (unmeasured)."""
    raw = values / np.array([1.0, 1.15, 1.66]).reshape(3, 1, 1, 1) * 1500.0
    raw = np.where(np.isnan(raw), -1.0, raw)
    path.write_bytes(np.array([90, 90, 180], "<i4").tobytes() + raw.astype("<f8").tobytes())


def test13_unmeasured_bins_are_counted_per_channel(variant_scalar_rgb, tmp_path):
    """Near normal incidence (θh and θd below 1.2° and 10°: both directions above the
    horizon) red is unmeasured in 10·10·180 bins, green in half of them, blue in a quarter,
    inside green's: 4500 bins miss every channel, 13500 others some (red all of those, green
    4500, blue none); bins below the horizon, unmeasured in every channel, are not counted.
    The warning once counted red's 18000 alone as "bins unmeasured". Where red alone is
    missing, green and blue are used."""
    values = np.full((3, 90, 90, 180), 0.1)
    values[0, :10, :10] = np.nan
    values[1, :10, :5] = np.nan
    values[2, :5, :5] = np.nan
    values[:, 80:, 60:, :10] = np.nan  # θh ≥ 71°, θd ≥ 60°, φd < 10°: one direction below
    path = tmp_path / "red.binary"
    _write_merl(path, values)
    with pytest.warns(UserWarning) as record:
        bsdf = mi.load_dict(_spec(filename=str(path)))
    messages = [str(w.message) for w in record]
    assert f"merl: {path}: 4500 of 1458000 bins unmeasured in every channel, 13500 more in " \
           "some channels only (red 13500, green 4500, blue 0); an unmeasured value is " \
           "evaluated as 0" in messages, messages
    s = np.sin(np.radians(7.0))  # θh = 0, θd = 7°: between θd bins 6 and 7, red alone missing
    wi, wo = np.array([[s, 0.0, np.cos(np.radians(7.0))]]), np.array([[-s, 0.0,
                                                                       np.cos(np.radians(7.0))]])
    value = eval_pdf(bsdf, wi, wo)[0][0]
    np.testing.assert_allclose(value, [0.0, 0.1 * wo[0, 2], 0.1 * wo[0, 2]], rtol=2 * HALF)
