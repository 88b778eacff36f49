"""
The adding-doubling tables of Hanrahan & Krueger's slab (:mod:`mi_brdfs.reference.hk_doubling`)
against the independent float64 random walk of :func:`mi_brdfs.reference.hk.walk` (the diffuse
light reflected and transmitted, in bins of μo and in total, and the unscattered beams), energy
conservation at albedo 1, reciprocity, and the first-order term and the base's direct term
against the closed forms of :class:`mi_brdfs.reference.hk.HK`.
"""

import numpy as np
import pytest

from mi_brdfs.reference import hk as ref
from mi_brdfs.reference import hk_doubling as hkd
from mi_brdfs.reference.quadrature import gauss_legendre

RHO = 0.8
#: Bins of μo for the walk, each integrated by Gauss-Legendre in μo.
EDGES, PER_BIN = np.linspace(0, 1, 5), 6


def _bin_nodes():
    x, w = gauss_legendre(PER_BIN)
    lo, hi = EDGES[:-1, None], EDGES[1:, None]
    return (0.5 * (hi - lo) * (x + 1) + lo).ravel(), (0.5 * (hi - lo) * w).ravel()


def _fluxes(tb, a, level, i, nodes, weights):
    """∫ f cosθo dωo (mode 0) over each bin of μo: (reflected (bins,), transmitted (bins,))
    for the incident direction mu[i], the base's series included."""
    r = tb.reflect[a, level, 0, i, :nodes.size]
    if tb.E is not None:
        r = r + RHO * tb.E[a, level, i] * tb.U[a, level, :nodes.size] / (1 - RHO * tb.S[a, level])
    t = tb.transmit[a, level, 0, i, :nodes.size]
    flux = 2 * np.pi * nodes * weights
    return ((f * flux).reshape(-1, PER_BIN).sum(axis=1) for f in (r, t))


def _check_against_walk(tb, a_index, level, albedo, g, eta, base, n):
    nodes, weights = _bin_nodes()
    i = nodes.size
    theta = np.arccos(tb.mu[i])
    tau = tb.tau[level]
    model = ref.HK(sigma_s=albedo * tau, sigma_a=(1 - albedo) * tau, thickness=1.0, g=g,
                   eta=eta, diffuse_reflectance=RHO if base else 0.0)
    walk = ref.walk(model, np.array([np.sin(theta), 0.0, np.cos(theta)]), n,
                    np.random.default_rng(17))
    mu_o, up = np.abs(walk.wo[:, 2]), walk.wo[:, 2] > 0
    scattered = walk.order >= 1
    for side, expected in zip((True, False), _fluxes(tb, a_index, level, i, nodes, weights)):
        sel = scattered & (up == side)
        bins = [sel & (mu_o >= lo) & (mu_o < hi) for lo, hi in zip(EDGES[:-1], EDGES[1:])]
        for mask, e in list(zip(bins, expected)) + [(sel, expected.sum())]:
            mc, se = walk.mean(mask)
            assert abs(mc - e) <= 4 * se + 2e-3 * e + 1e-6, (side, mc, e, se)
    if not base:  # the unscattered beams: through the slab and reflected between the faces
        for side, expected in zip((False, True), hkd.unscattered_series(tb.mu[i], tau, eta)):
            mc, se = walk.mean(~scattered & (up == side))
            # 5/n: a rare beam (a few paths expected) may draw none, se = 0
            assert abs(mc - expected) <= 4 * se + 5 / n, (side, mc, expected, se)


@pytest.mark.parametrize("base", [False, True])
@pytest.mark.parametrize("eta", [1.0, 1.5])
@pytest.mark.parametrize("g", [0.0, 0.7])
def test01_equal_to_the_random_walk(g, eta, base):
    """The walk's scattered exits (every order, internal reflections, the base) in 4 bins of
    μo per side and in total, for a = 0.99 at τ = 0.5 and a = 0.5 at τ = 4 (and a = 0.99 at
    τ = 4 for g = 0.7, η = 1.5), within 4 standard errors and 0.2 %."""
    nodes, _ = _bin_nodes()
    mu = np.concatenate([nodes, [np.cos(0.6)]])
    tb = hkd.tables([0.5, 0.99], 0.5, 3, g, eta, base, mu, 1)
    cases = [(1, 1), (0, 4)] + ([(1, 4)] if g == 0.7 and eta == 1.5 else [])
    for a_index, level in cases:
        _check_against_walk(tb, a_index, level, (0.5, 0.99)[a_index], g, eta, base, 20_000)


def _graded(n=64):
    """Gauss-Legendre in u with μ = u² (nodes crowd at grazing angles, where f μo of a
    grazing μi turns over on the scale of μi): (μ, weights of ∫ dμ)."""
    x, w = gauss_legendre(n)
    u = 0.5 * (x + 1)
    return u * u, w * u


INCIDENT = np.array([0.001, 0.01, 0.1, 0.3, 0.6, 1.0])


@pytest.mark.parametrize("g,eta,tol", [(0.0, 1.0, 1e-6), (0.7, 1.0, 1e-6), (0.0, 1.5, 1e-6),
                                        (0.7, 1.5, 1e-6), (0.9, 1.5, 1e-5)])
def test02_energy_is_conserved_at_albedo_one(g, eta, tol):
    """a = 1, free-standing: diffuse R + T + the mirror F + the unscattered beams = 1 at every
    μi; over a white base (ρ = 1): diffuse R with the base's series + F = 1. To 1e-6 (g = 0.9:
    1e-5, the sharp forward lobe at normal incidence between the graded nodes)."""
    nodes, w = _graded()
    mu = np.concatenate([nodes, INCIDENT])
    flux = 2 * np.pi * nodes * w
    i, o = slice(nodes.size, None), slice(None, nodes.size)
    f = ref.fresnel(INCIDENT, eta)
    free = hkd.tables([1.0], 0.25, 4, g, eta, False, mu, 1)
    white = hkd.tables([1.0], 0.25, 4, g, eta, True, mu, 1)
    for level, tau in enumerate(free.tau):
        through, mirror = hkd.unscattered_series(INCIDENT, tau, eta)
        r, t = (x[0, level, 0, i, o] @ flux for x in (free.reflect, free.transmit))
        np.testing.assert_allclose(r + t + f + through + mirror, 1.0, atol=tol)
        series = np.outer(white.E[0, level, i], white.U[0, level, o]) / (1 - white.S[0, level])
        r = (white.reflect[0, level, 0, i, o] + series) @ flux
        np.testing.assert_allclose(r + f, 1.0, atol=tol)


@pytest.mark.parametrize("base", [False, True])
def test03_reciprocal(base):
    """f_m(μi, μo) = f_m(μo, μi) in every mode, reflected and transmitted, and the base's
    E[i] U[o] symmetric."""
    mu = np.linspace(0.05, 1.0, 9)
    tb = hkd.tables([0.3, 0.95], 0.2, 3, 0.6, 1.4, base, mu, 5)
    for table in (tb.reflect, tb.transmit):
        np.testing.assert_allclose(table, np.swapaxes(table, -1, -2), rtol=1e-10, atol=1e-14)
    assert np.all(tb.reflect[:, 1:, 0] > 0)
    if base:
        eu = tb.E[..., :, None] * tb.U[..., None, :]
        np.testing.assert_allclose(eu, np.swapaxes(eu, -1, -2), rtol=1e-10)


def _from_modes(coeffs, dphi):
    """Σ c_m f_m cos(mΔφ), c_0 = 1, c_m = 2."""
    m = np.arange(coeffs.shape[0])
    c = np.where(m == 0, 1.0, 2.0)
    return np.sum((c * coeffs)[:, None] * np.cos(np.outer(m, dphi)), axis=0)


@pytest.mark.parametrize("g,modes,tol", [(0.0, 2, 1e-10), (0.7, 64, 1e-8)])
@pytest.mark.parametrize("eta", [1.0, 1.5])
def test04_single_term_equals_the_closed_form(g, modes, tol, eta):
    """single_* summed over the modes equals HK.brdf (Δφ = φo − φi, both directions away from
    the surface), reflected and transmitted, at every pair of mu and 7 azimuths; at g = 0 the
    phase function has no mode above 0."""
    mu = np.array([0.15, 0.5, 0.95])
    tb = hkd.tables([0.7], 0.3, 2, g, eta, False, mu, modes)
    dphi = np.linspace(0, 2 * np.pi, 7)
    for level in (1, 3):
        tau = tb.tau[level]
        model = ref.HK(sigma_s=0.7 * tau, sigma_a=0.3 * tau, thickness=1.0, g=g, eta=eta)
        for i, (a, b) in enumerate(np.ndindex(3, 3)):
            wi = np.tile([np.sqrt(1 - mu[a] ** 2), 0.0, mu[a]], (dphi.size, 1))
            s = np.sqrt(1 - mu[b] ** 2)
            for side, table in ((1, tb.single_reflect), (-1, tb.single_transmit)):
                wo = np.stack([s * np.cos(dphi), s * np.sin(dphi),
                               np.full(dphi.size, side * mu[b])], axis=1)
                exact = model.brdf(wi, wo)[:, 0]
                mine = _from_modes(table[0, level, :, a, b], dphi)
                np.testing.assert_allclose(mine, exact, rtol=tol, atol=tol * exact.max())


@pytest.mark.parametrize("eta", [1.0, 1.33])
def test05_base_direct_term_equals_the_closed_form(eta):
    """ρ E0[i] U0[o] = the base term of HK.brdf, ρ T_i T_o e^{−τ(1/μi' + 1/μo')}/(πη²)."""
    mu = np.array([0.2, 0.6, 1.0])
    tb = hkd.tables([0.4], 0.5, 2, 0.3, eta, True, mu, 1)
    wi = np.array([[np.sqrt(1 - m * m), 0.0, m] for m in mu])
    wo = np.array([[0.0, np.sqrt(1 - m * m), m] for m in mu])
    for level, tau in enumerate(tb.tau):
        with_base, without = (ref.HK(sigma_s=0.4 * tau, sigma_a=0.6 * tau, thickness=1.0,
                                     g=0.3, eta=eta, diffuse_reflectance=rho)
                              for rho in (RHO, 0.0))
        for i in range(3):
            for o in range(3):
                pair = (wi[i:i + 1], wo[o:o + 1])
                expected = with_base.brdf(*pair)[0, 0] - without.brdf(*pair)[0, 0]
                mine = RHO * tb.E0[0, level, i] * tb.U0[0, level, o]
                assert mine == pytest.approx(expected, rel=1e-12)
    assert np.all(tb.E[:, 0] == tb.E0[:, 0]) and np.all(tb.E >= tb.E0 - 1e-15)
