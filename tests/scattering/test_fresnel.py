"""Fresnel reflectance (mi_brdfs.scattering.fresnel) against Mitsuba's, the float64
complex-arithmetic reference and the 1982 paper's dielectric formula."""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.reference import cooktorrance as ref
from mi_brdfs.scattering import fresnel

ETA_K = [(1.5, 0.0), (0.67, 0.0), (1.0 + 1e-6, 0.0), (0.2, 3.9), (1e3, 1e3), (1e3, 0.0),
         (0.0, 1.0)]


@pytest.mark.parametrize("eta,k", ETA_K)
def test01_fresnel_exact(variant_llvm_ad_rgb, eta, k):
    """
    Against mi.fresnel_conductor (float32) and, for dielectrics, mi.fresnel; against the float64
    complex-arithmetic reference and the 1982 paper's dielectric formula. Never negative or
    NaN: Mitsuba's own expanded form gives −5.7e-8 at η = 1 + 1e-6 and NaN at grazing η = 1.
    """
    cos = np.linspace(0, 1, 2001)
    ours = np.array(fresnel.exact(mi.Float(cos), mi.Float(eta), mi.Float(k)))
    assert np.isfinite(ours).all() and ours.min() >= 0 and ours.max() <= 1
    np.testing.assert_allclose(ours, np.array(mi.fresnel_conductor(mi.Float(cos),
                                                                   mi.Complex2f(eta, k))),
                               atol=5e-7)
    eta32 = float(np.float32(eta))  # what the float32 variant computes with
    expected = ref.fresnel_exact(cos, eta32, k)[:, 0]
    if eta == 1.0 + 1e-6:
        # F = ((η−1)/(η+1))² = 2e-13 at normal incidence; float32 resolves η² − 1 = 2e-6
        # against 1 − sin²θ only to ~10 % (Mitsuba's form: to below 0), so compare absolutely
        assert np.all(np.abs(ours - expected) <= 1e-12 + 0.2 * expected)
        assert ours[cos >= 0.5].max() < 1e-11  # F → 0 as η → 1
        return
    # 5e-6: the slope of F is unbounded at the critical angle of η < 1 (0.67)
    np.testing.assert_allclose(ours, expected, atol=5e-6)
    if k == 0:
        np.testing.assert_allclose(ours, np.array(mi.fresnel(mi.Float(cos), eta)[0]), atol=5e-6)
        np.testing.assert_allclose(ref.fresnel_dielectric_1982(cos, eta)[:, 0],
                                   ref.fresnel_exact(cos, eta, 0.0)[:, 0], rtol=1e-10, atol=1e-14)


def test02_fresnel_per_channel_and_schlick(variants_all):
    """Spectrum-valued η, k, per channel, in every variant; Schlick with R0 from η and k."""
    n = dr.size_v(mi.Spectrum)  # 3 RGB channels, 4 wavelengths, 1 (mono)
    eta, k = [0.143, 0.375, 1.442, 0.6][:n], [3.983, 2.386, 1.603, 2.9][:n]
    for cos in (0.0, 0.3, 1.0):
        for ours, theirs in ((fresnel.exact, ref.fresnel_exact),
                             (fresnel.schlick, ref.fresnel_schlick)):
            value = np.ravel(np.array(ours(mi.Float(cos), mi.Spectrum(eta), mi.Spectrum(k))))
            np.testing.assert_allclose(value, theirs([cos], eta, k)[0], atol=1e-6)
    assert np.ravel(fresnel.r0(mi.Float(1.5), mi.Float(0.0)))[0] == pytest.approx(0.04)


def test03_exact_on_python_floats(variant_scalar_rgb):
    """On the Python floats of scalar variants (one channel at a time), the same function agrees
    with the float64 reference and stays finite in [0, 1], the degenerate η = 1 included."""
    for cos in np.linspace(0, 1, 101):
        for eta, k in ETA_K:
            got = fresnel.exact(float(cos), eta, k)
            assert type(got) is float and 0.0 <= got <= 1.0
            assert got == pytest.approx(float(ref.fresnel_exact([cos], eta, k)[0, 0]),
                                        rel=1e-9, abs=1e-15)
