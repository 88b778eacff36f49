"""
The float64 random walk on the Smith microsurface (mi_brdfs.reference.randomwalk; Heitz, Hanika,
d'Eon & Dachsbacher 2016) against what does not depend on the walk: energy conservation, the
closed forms of single scattering (the height-correlated Smith G2 in reflection, its Beta-function
form in transmission) by quadrature, reciprocity, the Fresnel limit of a smooth conductor, and
the visible-normal samplers against quadrature of ⟨ωi, m⟩ D(m). Statistical tolerances are
several standard errors plus the quadrature's error; every seed is fixed.
"""

import math

import numpy as np
import pytest

from mi_brdfs.reference import randomwalk as rw
from mi_brdfs.reference.cooktorrance import _pair, fresnel_exact, ndf, smith_lambda
from mi_brdfs.reference.quadrature import direction, sphere_grid

_lgamma = np.vectorize(math.lgamma, otypes=[float])

#: A gold-like complex index of refraction per channel (η + ik).
GOLD = np.array([0.18 + 3.4j, 0.42 + 2.35j, 1.37 + 1.77j])


def _grid(alpha, n_mu=128, n_phi=256):
    """Directions h and weights over the upper hemisphere, Gauss-Legendre in cosθ on two panels
    split at tanθ = 4α (the peak of D, its tail) × the midpoint rule in φ."""
    split = 1 / math.sqrt(1 + (4 * max(_pair(alpha))) ** 2)
    parts = [sphere_grid(n_mu, n_phi, r) for r in ((0.0, split), (split, 1.0))]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


def _single_scattering(kind, alpha, wi, eta=None):
    """
    Order 1 by quadrature over the facet normal h on ωi's side, (reflection, transmission):
    ∫ D(h) (ωi·h)/|cosθi| · [F G2(ωi, ωr) , (1 − F) G2t(ωi, ωt)] dωh, with the height-correlated
    G2 = 1/(1 + Λ(ωi) + Λ(ωr)) and G2t = B(1 + Λ(ωi), 1 + Λ(ωt)) (B the Beta function), F ≡ 1
    for a conductor (``eta`` None). From below: the mirror image with η → 1/η.
    """
    if wi[2] < 0:
        wi, eta = wi * np.array([1.0, 1.0, -1.0]), 1 / eta
    h, weights = _grid(alpha)
    cih = h @ wi
    keep = cih > 0
    h, weights, cih = h[keep], weights[keep], cih[keep]
    lam_i = smith_lambda(kind, alpha, np.broadcast_to(wi, h.shape))
    common = weights * ndf(kind, alpha, h) * cih / wi[2]
    wr = 2 * cih[:, None] * h - wi
    g2 = np.where(wr[:, 2] > 0, 1 / (1 + lam_i + smith_lambda(kind, alpha, wr)), 0.0)
    if eta is None:
        return float(np.sum(common * g2)), 0.0
    f = fresnel_exact(cih, eta, 0.0)[:, 0]
    cos_t2 = 1 - (1 - cih**2) / eta**2
    wt = (cih / eta - np.sqrt(np.maximum(cos_t2, 0)))[:, None] * h - wi / eta
    lam_t = smith_lambda(kind, alpha, wt)  # of the mirror image: Λ takes |z|
    beta = np.exp(_lgamma(1 + lam_i) + _lgamma(1 + lam_t) - _lgamma(2 + lam_i + lam_t))
    g2t = np.where((cos_t2 > 0) & (wt[:, 2] < 0), beta, 0.0)
    return float(np.sum(common * f * g2)), float(np.sum(common * (1 - f) * g2t))


@pytest.mark.parametrize("kind", rw.KINDS)
def test01_white_furnace_conductor(kind):
    """F ≡ 1: every path leaves upwards with weight 1, so the albedo of all orders is
    1 − (the fraction cut at max_order), and that fraction is below 1e-4 at α ≤ 1 (none of
    these 60 000 paths reaches 100 events); an anisotropic case at grazing incidence. Cut at
    max_order = 2 the lost energy is counted exactly: total + lost = 1."""
    for alpha, theta, phi in ((1.0, 0.0, 0.0), ((1.0, 0.3), 80.0, 0.7)):
        w = rw.walk(direction(math.radians(theta), phi), kind, alpha, 30_000,
                    np.random.default_rng(1))
        escaped = w.order > 0
        assert np.all(w.wo[escaped, 2] > 0) and np.all(w.weight[escaped] == 1.0)
        assert w.lost < 1e-4 and np.mean(w.weight) > 1 - 1e-4, (alpha, theta, w.lost)
    a = rw.albedo(0.0, kind, 1.0, 20_000, np.random.default_rng(2), max_order=2)
    assert 0.01 < a.lost < 0.5 and a.total[0] + a.lost == pytest.approx(1.0, abs=1e-12)
    assert a.total[0] == pytest.approx(a.orders[:, 0].sum(), abs=1e-12)


#: (kind, α, θi in degrees, φi): normal and grazing incidence, isotropic and anisotropic.
SINGLE = [("ggx", 0.5, 0.0, 0.0), ("ggx", 1.0, 80.0, 0.0), ("beckmann", 0.5, 85.0, 0.0),
          ("beckmann", 1.0, 0.0, 0.0), ("ggx", (0.8, 0.2), 60.0, 1.0),
          ("beckmann", (0.3, 0.9), 70.0, 0.4)]


@pytest.mark.parametrize("kind,alpha,theta,phi", SINGLE)
def test02_order_one_is_height_correlated_smith(kind, alpha, theta, phi):
    """The walk's order 1 = ∫ D(h) G2 (ωi·h)/cosθi dωh with the height-correlated
    G2 = 1/(1 + Λi + Λo) (Heitz et al. 2016) within 4.5 standard errors + 1e-4 (the quadrature:
    within 4e-5 of 16× its nodes); at grazing incidence the separable G1·G1 lies outside
    three times that tolerance (the check can fail)."""
    wi = direction(math.radians(theta), phi)
    a = rw.albedo(math.radians(theta), kind, alpha, 30_000, np.random.default_rng(3), phi_i=phi)
    expected, _ = _single_scattering(kind, alpha, wi)
    got, se = a.orders[0, 0], a.orders_se[0, 0]
    assert abs(got - expected) < 4.5 * se + 1e-4, (got, expected, se)
    if theta >= 80:
        h, weights = _grid(alpha)
        wo = 2 * (h @ wi)[:, None] * h - wi
        ok = (h @ wi > 0) & (wo[:, 2] > 0)
        g1g1 = 1 / ((1 + smith_lambda(kind, alpha, np.broadcast_to(wi, h.shape))) *
                    (1 + smith_lambda(kind, alpha, wo)))
        separable = np.sum(np.where(ok, weights * ndf(kind, alpha, h) * (h @ wi) * g1g1, 0.0))
        assert abs(expected - separable / wi[2]) > 3 * (4.5 * se + 1e-4), separable / wi[2]


def _cap(axis_theta, axis_phi, half_angle, n, rng):
    """n directions uniform in solid angle in the cap of ``half_angle`` about an axis."""
    cos_g = 1 - rng.random(n) * (1 - math.cos(half_angle))
    psi = 2 * math.pi * rng.random(n)
    local = np.stack([np.sqrt(1 - cos_g**2) * np.cos(psi), np.sqrt(1 - cos_g**2) * np.sin(psi),
                      cos_g], axis=1)
    st, ct, sp, cp = (math.sin(axis_theta), math.cos(axis_theta), math.sin(axis_phi),
                      math.cos(axis_phi))
    frame = np.array([[ct * cp, -sp, st * cp], [ct * sp, cp, st * sp], [-st, 0.0, ct]])
    return local @ frame.T


def _transfer(kind, alpha, a, b, half_angle, n, rng, fresnel):
    """∫_A ∫_B f_ms(ωi, ωo) cosθi cosθo dωo dωi over two caps, f_ms the orders ≥ 2: ωi uniform
    in A, X = Ω_A cosθi · weight · [ωo ∈ B]; symmetric in (A, B) iff f_ms is reciprocal."""
    wi = _cap(*a, half_angle, n, rng)
    w = rw.walk(wi, kind, alpha, n, rng, fresnel=fresnel)
    axis_b = direction(*b)
    in_b = (w.wo @ axis_b > math.cos(half_angle)) & (w.order >= 2)
    x = 2 * math.pi * (1 - math.cos(half_angle)) * wi[:, 2:3] * w.weight * in_b[:, None]
    return x.mean(0), x.std(0) / math.sqrt(n)


@pytest.mark.parametrize("kind,alpha,a,b", [
    ("ggx", (1.0, 0.4), (0.35, 0.3), (1.15, 2.4)),
    ("beckmann", 0.8, (0.0, 0.0), (1.2, 3.0))])
def test03_multiple_scattering_is_reciprocal(kind, alpha, a, b):
    """Orders ≥ 2 with a coloured Fresnel term: the energy from cap A to cap B (15° caps) equals
    that from B to A within 4 standard errors of the difference, per channel (the symmetric
    binned form of f(ωi, ωo) = f(ωo, ωi), exact for any cap size)."""
    half = math.radians(15.0)
    ab, se_ab = _transfer(kind, alpha, a, b, half, 40_000, np.random.default_rng(4), GOLD)
    ba, se_ba = _transfer(kind, alpha, b, a, half, 40_000, np.random.default_rng(5), GOLD)
    assert np.all(ab > 10 * se_ab), (ab, se_ab)  # far from zero: the check has power
    assert np.all(np.abs(ab - ba) < 4 * np.hypot(se_ab, se_ba)), (ab, ba, se_ab, se_ba)


def test04_lobe_histogram_integrates_to_the_albedo():
    """The binned lobe of orders ≥ 2, times each bin's solid angle and summed over the upper
    hemisphere, is their albedo (the same paths: same seed), coloured or white; for F ≡ 1 the
    fraction p of the paths in a bin has the binomial standard error √(p(1 − p)/(n − 1))."""
    kind, alpha, theta, n = "ggx", 0.7, math.radians(40.0), 20_000
    edges = np.linspace(0, math.pi / 2, 10)
    bins = ((-math.pi, -1.0), (-1.0, 1.0), (1.0, math.pi))
    omega = (np.cos(edges[:-1]) - np.cos(edges[1:]))[:, None, None] * \
        np.array([hi - lo for lo, hi in bins])[None, :, None]
    for fresnel in (GOLD, None):
        dens, se = rw.lobe_histogram(theta, kind, alpha, n, np.random.default_rng(6), edges,
                                     bins, fresnel=fresnel)
        a = rw.albedo(theta, kind, alpha, n, np.random.default_rng(6), fresnel=fresnel)
        np.testing.assert_allclose((omega * dens).sum((0, 1)), a.orders[1:].sum(0), rtol=1e-12)
    p = omega * dens
    assert np.all(p > 0)
    np.testing.assert_allclose(omega * se, np.sqrt(p * (1 - p) / (n - 1)), rtol=1e-9)


@pytest.mark.parametrize("kind", rw.KINDS)
def test05_dielectric_conserves_energy(kind):
    """A dielectric (η = 1.5, α = 0.5) in importance transport: reflection + transmission of all
    orders = 1 − lost from above and from below (total internal reflection included), lost
    < 1e-4, reflected paths on ωi's side and transmitted ones across. In radiance transport
    (same paths) the transmitted weight is the importance one × (η_i/η_t)² of the two media."""
    for theta in (30.0, 80.0, 110.0, 150.0):
        wi = direction(math.radians(theta))
        imp = rw.walk(wi, kind, 0.5, 20_000, np.random.default_rng(7), eta=1.5,
                      transport="importance")
        rad = rw.walk(wi, kind, 0.5, 20_000, np.random.default_rng(7), eta=1.5)
        assert imp.lost < 1e-4 and np.mean(imp.weight) == pytest.approx(1 - imp.lost, abs=1e-12)
        across = imp.wo[:, 2] * wi[2] < 0
        assert 0.01 < np.mean(across) < 0.99, theta
        scale = 1 / 1.5**2 if wi[2] > 0 else 1.5**2
        np.testing.assert_allclose(rad.weight[across, 0], scale, rtol=1e-12)
        np.testing.assert_allclose(rad.weight[~across & (imp.order > 0), 0], 1.0, rtol=1e-12)


@pytest.mark.parametrize("kind,theta", [("ggx", 40.0), ("beckmann", 75.0), ("ggx", 140.0),
                                        ("beckmann", 120.0)])
def test06_dielectric_order_one(kind, theta):
    """Order 1 of the dielectric walk (η = 1.5, α = 0.6; from above and below) = the quadrature of
    D (ωi·h)/|cosθi| times F G2 in reflection and (1 − F) B(1 + Λi, 1 + Λt) in transmission
    (the uncorrelated heights seen from both sides), within 4.5 standard errors + 2e-4 (the
    quadrature: within 6e-5 of 16× its nodes, the kink at total internal reflection)."""
    wi = direction(math.radians(theta))
    w = rw.walk(wi, kind, 0.6, 30_000, np.random.default_rng(8), eta=1.5, transport="importance")
    first = w.order == 1
    across = w.wo[:, 2] * wi[2] < 0
    expected = _single_scattering(kind, 0.6, wi, eta=1.5)
    for got, value in zip((first & ~across, first & across), expected):
        p = np.mean(got)
        se = math.sqrt(p * (1 - p) / len(got))
        assert abs(p - value) < 4.5 * se + 2e-4, (theta, p, value, se)


def test07_coloured_conductor():
    """A gold-like conductor (complex IOR per channel): on the same paths each order's albedo is
    below the white one's, the orders ≥ 2 relatively more (F^k); at α = 0.01 the albedo is the
    Fresnel term F(cosθi) of the exact reference within 3e-3 (its first order in α² is below)."""
    theta = math.radians(50.0)
    white = rw.albedo(theta, "ggx", 0.6, 20_000, np.random.default_rng(9))
    gold = rw.albedo(theta, "ggx", 0.6, 20_000, np.random.default_rng(9), fresnel=GOLD)
    assert np.all(gold.orders <= white.orders + 1e-15) and np.all(gold.total < white.total)
    ratio_1 = gold.orders[0] / white.orders[0]
    ratio_ms = gold.orders[1:].sum(0) / white.orders[1:].sum(0)
    assert np.all(ratio_ms < ratio_1 - 0.02), (ratio_ms, ratio_1)
    for kind in rw.KINDS:
        for theta in (0.0, 60.0):
            c = math.cos(math.radians(theta))
            a = rw.albedo(math.radians(theta), kind, 0.01, 5_000, np.random.default_rng(10),
                          fresnel=GOLD)
            np.testing.assert_allclose(a.total, fresnel_exact(c, GOLD.real, GOLD.imag)[0],
                                       atol=3e-3)


@pytest.mark.parametrize("kind,alpha,theta", [("ggx", (0.7, 0.3), 50.0),
                                              ("ggx", 0.6, 120.0),
                                              ("beckmann", (0.4, 1.0), 60.0),
                                              ("beckmann", 0.8, 105.0),
                                              ("beckmann", 0.5, 160.0)])
def test08_visible_normals(kind, alpha, theta):
    """The samplers against D_ωi(m) = ⟨ωi, m⟩ D(m)/∫⟨ωi, m⟩ D by quadrature, ωi above and below
    the horizon (the latter in the walk's upward rays), at an azimuth off the axes: E[mx], E[my],
    E[mz], E[mx²] within 4.5 standard errors + 3e-4 (the quadrature: within 5e-5 of 16× its
    nodes); and the normalisation ∫⟨ωi, m⟩ D dm is ωz (1 + Λ(ωi)) with Λ extended below the
    horizon (at 160°, Beckmann 0.5, both are below 1e-12: there the moments are the check)."""
    wi = direction(math.radians(theta), 0.8)
    m = rw.sample_visible_normal(kind, alpha, np.broadcast_to(wi, (40_000, 3)),
                                 np.random.default_rng(11))
    assert np.allclose(np.linalg.norm(m, axis=1), 1) and np.all(m @ wi >= 0)
    h, weights = _grid(alpha, 256, 512)
    density = weights * np.maximum(h @ wi, 0) * ndf(kind, alpha, h)
    norm = density.sum()
    assert norm == pytest.approx(wi[2] * (1 + rw.smith_lambda_signed(kind, alpha, wi)[0]),
                                 rel=1e-4)
    samples = (m[:, 0], m[:, 1], m[:, 2], m[:, 0] ** 2)
    exact = (h[:, 0], h[:, 1], h[:, 2], h[:, 0] ** 2)
    for s, e in zip(samples, exact):
        expected = float(np.sum(density * e) / norm)
        assert abs(s.mean() - expected) < 4.5 * s.std() / math.sqrt(len(s)) + 3e-4, \
            (s.mean(), expected)


def test09_heights():
    """G1(ω, h) = C1(h)^Λ(ω): the next height leaves with that probability, and the free path
    from far above a ray going down ends at a height with C1 distributed as u^(1/(1 + Λ(−ω)))
    (mean (1 + Λ)/(2 + Λ)); a ray going down always meets the surface."""
    rng = np.random.default_rng(12)
    up, down = direction(math.radians(70.0), 0.4), -direction(math.radians(60.0), 1.1)
    for kind in rw.KINDS:
        n = 40_000
        g = rw.masking(kind, 0.7, up, 0.2)[0]
        hn = rw.sample_height(kind, 0.7, np.broadcast_to(up, (n, 3)), np.full(n, 0.2),
                              rng.random(n))
        p = np.mean(np.isinf(hn))
        assert abs(p - g) < 4.5 * math.sqrt(g * (1 - g) / n) and np.all(hn[~np.isinf(hn)] >= 0.2)
        hd = rw.sample_height(kind, 0.7, np.broadcast_to(down, (n, 3)), np.full(n, np.inf),
                              rng.random(n))
        lam = smith_lambda(kind, 0.7, down[None])[0]
        c = rw.c1(hd)
        assert np.all(np.isfinite(hd))
        assert abs(c.mean() - (1 + lam) / (2 + lam)) < 4.5 * c.std() / math.sqrt(n)
