"""
Thin-film interference: the float64 transfer-matrix reference (mi_brdfs.reference.thinfilm)
against closed forms of Born & Wolf, and the drjit Airy summation
(mi_brdfs.scattering.thinfilm) against the reference: exact amplitudes at a wavelength, and
the reflectance integrated against the sRGB channels' sensitivities (Mitsuba's CIE 1931 tables
under D65) against that integral computed in float64 from the reference.
"""

import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.reference import thinfilm as ref
from mi_brdfs.scattering import thinfilm

COS = np.linspace(0.02, 1.0, 50)


def _fresnel(cos1, n1, n2):
    """Born & Wolf 1.5.(21): the amplitudes of a bare interface, written out."""
    cos2 = np.sqrt(1 - (n1 / n2) ** 2 * (1 - cos1 ** 2) + 0j)
    rs = (n1 * cos1 - n2 * cos2) / (n1 * cos1 + n2 * cos2)
    rp = (n2 * cos1 - n1 * cos2) / (n2 * cos1 + n1 * cos2)
    return rs, rp


def test01_reference_closed_forms():
    """Zero thickness is the bare base's Fresnel amplitude; a quarter-wave layer of index
    sqrt(n1 n3) at normal incidence reflects nothing; a half-wave layer (for the angle's
    path, λ/(2 q₂)) is absent; frustrated total reflection and a multilayer conserve energy."""
    rs, rp = _fresnel(COS, 1.0, 1.5)
    bare = ref.film(COS, 550.0, 1.38, 0.0, 1.5)
    assert np.allclose(bare["rs"], rs, atol=1e-14) and np.allclose(bare["rp"], rp, atol=1e-14)
    n2 = np.sqrt(1.0 * 1.69)
    assert ref.film(1.0, 600.0, n2, 600.0 / (4 * n2), 1.69)["R"] < 1e-28
    q2 = np.sqrt(1.38 ** 2 - (1 - COS ** 2))
    for i, c in enumerate(COS):
        half = ref.film(c, 600.0, 1.38, 600.0 / (2 * q2[i]), 1.5)
        assert abs(half["rs"] + 0j - rs[i]) < 1e-12 and abs(half["rp"] - rp[i]) < 1e-12
    layers = [(1.38, 120.0), (2.1, 80.0), (1.4, 300.0)]
    for n1, sub in ((1.0, 1.52), (1.52, 1.0)):  # the second frustrates total reflection
        out = ref.stack(COS[:, None], np.array([420.0, 550.0, 700.0]), n1, layers, sub)
        for pol in "sp":
            assert np.abs(out["R" + pol] + out["T" + pol] - 1).max() < 1e-12


CASES = [(1.0, 1.47, 1.33, 0.0),   # oil on water
         (1.33, 1.47, 1.0, 0.0),   # the same film seen from the water
         (1.0, 1.33, 0.2, 3.0),    # a conductor
         (1.5, 1.38, 1.0, 0.0),    # from glass: total reflection beyond 41.8°
         (1.0, 0.8, 1.5, 0.0)]     # evanescent in the film at cosθ < 0.6


THICKNESS = (0.0, 50.0, 150.0, 400.0, 700.0, 2000.0)


def _grid():
    """Every (case, thickness, cosine) as lanes: (n1, n2, η, k, d, cos), NumPy arrays, so that
    one kernel computes them all."""
    rows = [(*case, d, c) for case in CASES for d in THICKNESS for c in COS]
    return [np.array(col) for col in zip(*rows)]


def _reference(fn):
    """The reference's values ``fn(case, d)`` (each over COS) in the lanes' order."""
    return np.concatenate([fn(case, d) for case in CASES for d in THICKNESS], axis=0)


def test02_airy_amplitudes_equal_the_transfer_matrix(variant_llvm_ad_rgb):
    """s and p amplitudes (complex) at 550 nm within 1e-4 of the reference (float32's phase of
    a 2 µm film), for each case and thickness; at the film's critical angle (q₂ = 0, case 5 at
    cosθ = 0.6) within 1e-3."""
    n1, n2, eta, k, d, c = _grid()
    rs, rp = thinfilm.amplitudes(mi.Float(c), mi.Float(n1), mi.Float(n2), mi.Float(eta),
                                 mi.Float(k), mi.Float(d), 550.0)
    critical = np.isclose(n1 * n1 * (1 - c ** 2), n2 * n2)
    for got, pol in ((rs, "s"), (rp, "p")):
        want = _reference(lambda case, d: ref.film(COS, 550.0, case[1], d,
                                                   case[2] + 1j * case[3], case[0])["r" + pol])
        err = np.abs(np.array(got[0]) + 1j * np.array(got[1]) - want)
        assert err[~critical].max() < 1e-4 and err.max() < 1e-3, pol


def srgb_weights(lam):
    """w_c(λ) of the three channels, normalised: D65 times the sRGB colour-matching
    functions, from Mitsuba's own tables."""
    xyz = np.array(mi.cie1931_xyz(mi.Float(lam))).reshape(3, -1)
    w = thinfilm.SRGB @ xyz * np.array(mi.cie_d65(mi.Float(lam))).ravel()
    return w / w.sum(axis=1, keepdims=True)


def test03_colour_equals_the_integrated_reference(variant_llvm_ad_rgb):
    """
    The Fourier-space colour against ∑ w_c(λ) R(λ) over 1 nm: within 1e-4 for dielectric
    bases under a denser film, and elsewhere within 0.015 at cosθ ≥ 0.1 and 0.05 below (the
    conductor: the truncated series, ``thinfilm.ORDERS``; the evanescent film: its mean
    wavelength). The series cut after ORDERS terms without its geometric rest fails.
    """
    lam = np.arange(360.0, 831.0)
    w = srgb_weights(lam)
    n1, n2, eta, k, d, c = _grid()
    out = thinfilm.colour(mi.Float(c), mi.Float(n1), mi.Float(n2), mi.Color3f(mi.Float(eta)),
                          mi.Color3f(mi.Float(k)), mi.Float(d), thinfilm.Sensitivity())
    tight = (k == 0) & (n2 > n1)
    tol = np.where(tight, 1e-4, np.where(c >= 0.1, 0.015, 0.05))
    films = [ref.film(COS[:, None], lam, n2_, d_, eta_ + 1j * k_, n1_)
             for n1_, n2_, eta_, k_ in CASES for d_ in THICKNESS]
    for j, pol in enumerate("sp"):
        # (a colour outside sRGB's gamut is clipped into it, as the kernel clips it)
        want = np.clip(np.concatenate([f["R" + pol] @ w.T for f in films]), 0.0, 1.0)
        err = np.abs(np.array([np.array(o[j]) for o in out]).T - want).max(axis=1)
        worst = int(np.argmax(err - tol))
        assert err[worst] <= tol[worst], (pol, n1[worst], n2[worst], eta[worst], d[worst],
                                          c[worst], err[worst])


def test04_colour_pointwise_in_scalar(variant_scalar_rgb):
    """The scalar variant's colour (NumPy lookups) equals the JIT one's reference, one point."""
    lam = np.arange(360.0, 831.0)
    xyz = np.array([[float(v) for v in mi.cie1931_xyz(float(x))] for x in lam]).T
    w = thinfilm.SRGB @ xyz * np.array([float(mi.cie_d65(float(x))) for x in lam])
    w = w / w.sum(axis=1, keepdims=True)
    out = thinfilm.colour(0.7, 1.0, 1.47, mi.Color3f(1.33), mi.Color3f(0.0), 300.0,
                          thinfilm.Sensitivity())
    want = ref.film(0.7, lam, 1.47, 300.0, 1.33)
    for j, pol in enumerate("sp"):
        assert [o[j] for o in out] == pytest.approx(np.clip(want["R" + pol] @ w.T, 0, 1),
                                                    abs=1e-4)
