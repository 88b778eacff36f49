"""
The terms of He et al.'s BRDF in drjit (mi_brdfs.scattering.he) against the float64 reference
(mi_brdfs.reference.he), for the three readings: the directional diffuse part and the specular
weight at random pairs and four surfaces (g from 0.3 to 800), the effective roughness's Newton
solve against bisection, the series' window and where it stops, and a reading with the wrong
shadowing rejected.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

import mi_brdfs
from mi_brdfs.reference import he as ref
from mi_brdfs.scattering import he

LAMBDA, ETA, K = (0.645, 0.526, 0.444), (0.2, 0.4, 1.3), (3.5, 2.5, 1.9)
#: (σ0, τ) in µm: g at normal incidence and 444 nm about 0.3, 26, 200 and 800
SURFACES = [(0.02, 1.0), (0.18, 3.0), (0.5, 2.0), (1.0, 4.0)]


def _pairs(n, seed=0):
    rng = np.random.default_rng(seed)

    def dirs():
        theta, phi = np.arccos(rng.random(n)), rng.random(n) * 2 * np.pi
        return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi),
                         np.cos(theta)], axis=1)
    return dirs(), dirs()


def _vec(a):
    if mi.variant().startswith("scalar"):
        return [mi.Vector3f(*map(float, row)) for row in a]
    return [mi.Vector3f(*[mi.Float(a[:, i].astype(np.float32)) for i in range(3)])]


def _rows(value, n):
    a = np.array(value, dtype=np.float64)
    return a.reshape(3, n).T if a.shape[0] == 3 else a.reshape(n, 3)


def _evaluate(wi, wo, surfaces, reading, terms=None):
    """(ρ_dd (n, 3), ρ_s (n, 3)) of the terms in the current variant; ``surfaces``: one
    (σ0, τ), or one per pair (as arrays, so that one kernel serves them all)."""
    sigma0, tau = (np.broadcast_to(np.asarray(v, np.float64), (len(wi),))
                   for v in np.asarray(surfaces, np.float64).T)
    lam, eta, k = (mi.Color3f(*c) for c in (LAMBDA, ETA, K))
    dd, sp = [], []
    scalar = mi.variant().startswith("scalar")
    for i, (a, b) in enumerate(zip(_vec(wi), _vec(wo))):
        s0, t = (float(sigma0[i]), float(tau[i])) if scalar else \
            (mi.Float(sigma0.astype(np.float32)), mi.Float(tau.astype(np.float32)))
        n = dr.width(a.z)
        dd.append(_rows(he.directional_diffuse(a, b, s0, t, lam, eta, k, reading, terms), n))
        sp.append(_rows(he.specular_weight(a.z, s0, t, lam, eta, k, reading), n))
    return np.concatenate(dd), np.concatenate(sp)


def _evaluate_lanes(wi, wo, surfaces, reading):
    """:func:`_evaluate` in a JIT variant with the three channels as lanes of one Float
    computation: a kernel a third the size of the per-channel one (LLVM compiles a kernel of
    128 terms per channel in tens of seconds)."""
    n = len(wi)
    lanes = [mi.Float(np.repeat(np.asarray(c, np.float32), n)) for c in (LAMBDA, ETA, K)]
    wi3, wo3 = (_vec(np.tile(d, (3, 1)))[0] for d in (wi, wo))
    sigma0, tau = (mi.Float(np.tile(np.asarray(v, np.float32), 3))
                   for v in np.asarray(surfaces, np.float64).T)
    dd = he.directional_diffuse(wi3, wo3, sigma0, tau, *lanes, reading)
    sp = he.specular_weight(wi3.z, sigma0, tau, *lanes, reading)
    return (np.array(x, dtype=np.float64).reshape(3, n).T for x in (dd, sp))


def _reference(wi, wo, surface, name):
    model = ref.HTSG(*surface, LAMBDA, ETA, K, variant=name,
                     terms=None if name == "paper" else "variant")
    return model.directional_diffuse(wi, wo), model.specular(wi)


def _check(dd, sp, want_dd, want_sp, rtol=1e-4):
    floor = 1e-6 * np.abs(want_dd).max()
    bad = np.abs(dd - want_dd) > rtol * np.abs(want_dd) + floor
    assert not bad.any(), (dd[bad][:3], want_dd[bad][:3])
    np.testing.assert_allclose(sp, want_sp, rtol=rtol, atol=1e-7)


def _assert_matches(wi, wo, surface, name, reading):
    _check(*_evaluate(wi, wo, surface, reading), *_reference(wi, wo, surface, name))


@pytest.mark.parametrize("name", ["westin", "holzschuch"])
@pytest.mark.parametrize("surface", SURFACES, ids=lambda s: f"s{s[0]}-t{s[1]}")
def test01_terms_match_the_reference(variant_llvm_ad_rgb, name, surface):
    """Within 1e-4 relative at 4000 random pairs (measured: 1.1e-5 at most)."""
    wi, wo = _pairs(4000)
    _assert_matches(wi, wo, surface, name, he.READINGS[name])


def test01b_scalar_variant(variant_scalar_rgb):
    wi, wo = _pairs(40, seed=3)
    _assert_matches(wi, wo, (0.18, 3.0), "westin", he.READINGS["westin"])


def test02_the_paper_reading_and_where_its_window_stops(variant_llvm_ad_rgb):
    """
    The paper's reading (a window of 128 terms centred on g) on the four surfaces in one
    kernel, the channels as lanes (a kernel of 128 terms per channel takes LLVM seconds to
    compile): within 1e-4
    where the window holds the series (g ≤ 163: the first three), and more than 0.1 % off
    on the fourth (g up to 800); there, 512 centred terms hold the series again (checked in
    a scalar variant, where nothing is compiled). The window's part left out against the
    converged float64 series: below 1e-6 up to g = 22 for 48 terms from m = 1 and up to
    g = 163 for 128 centred, to within float32's rounding of the terms' logarithms.
    """
    n = 1500
    wi, wo = _pairs(n)
    surfaces = np.repeat(np.array(SURFACES), n, axis=0)
    dd, sp = _evaluate_lanes(np.tile(wi, (4, 1)), np.tile(wo, (4, 1)), surfaces,
                             he.READINGS["paper"])
    for j, surface in enumerate(SURFACES):
        want_dd, want_sp = _reference(wi, wo, surface, "paper")
        got = dd[j * n:(j + 1) * n], sp[j * n:(j + 1) * n]
        if j < 3:
            _check(*got, want_dd, want_sp)
        else:
            big = want_dd > 1e-3 * want_dd.max()
            assert np.max(np.abs(got[0][big] / want_dd[big] - 1)) > 1e-3
    for g, terms, centred in ((22.0, 48, False), (163.0, 128, True)):
        rounding = 8 * 2.0**-24 * (g + 0.5 * terms) * (math.log(g) + 1.0)
        for c in (0.0, 5.0, 50.0):
            got = float(np.ravel(he.series(mi.Float(g), mi.Float(c), terms, centred))[0])
            want = float(ref.series(np.array([g]), np.array([c]))[0])
            assert abs(got / want - 1.0) < 1e-6 + rounding, (g, terms, c)
    mi_brdfs.use_variant("scalar_rgb")
    for c in (0.0, 50.0):
        got = he.series(800.0, c, 512, True)
        assert got == pytest.approx(float(ref.series(np.array([800.0]), np.array([c]))[0]),
                                    rel=1e-9)


def test03_effective_roughness_solve(variant_llvm_ad_rgb):
    """Newton's x e^(x²/2) = f0 against the reference's bisection, f0 from 1e-8 to 1e8."""
    f0 = np.logspace(-8, 8, 400)
    got = np.array(he.solve_x(mi.Float(f0.astype(np.float32))), dtype=np.float64)
    want = ref.solve_z0(f0.astype(np.float32).astype(np.float64))
    np.testing.assert_allclose(got, want, rtol=2e-6)


def test04_a_wrong_reading_is_rejected(variant_llvm_ad_rgb):
    """Westin's reading with the printed shadowing (no e^(−a²)) fails the comparison."""
    wi, wo = _pairs(2000)
    broken = he.Reading(False, True, 48, False, 18.5)
    with pytest.raises(AssertionError):
        _assert_matches(wi, wo, (0.5, 2.0), "westin", broken)
