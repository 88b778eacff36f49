"""
The float64 Ward and Oren-Nayar references (mi_brdfs.reference.ward, .orennayar): their albedo
quadratures against closed forms and one-dimensional integrals at normal incidence, against
brute-force quadrature of their own brdf(), and the convergence the Ward docstring states. The
Ward quadrature's brute-force comparison and convergence run over a wider grid in ``make
validate``, section "Ward: three forms, anisotropic" (``mi_brdfs/campaign/ward.py``).
"""

import math

import numpy as np
import pytest

from mi_brdfs.reference import OrenNayar, Ward, hemisphere_albedo
from mi_brdfs.reference.quadrature import direction, gauss_legendre, sphere_grid


def _radial(integrand, alpha, nodes=256):
    """(2/α²) ∫₀¹ e^(−t²/α²) t g(t) dt, t = tanθh (normal incidence: ωo above iff t < 1).
    256 nodes (the reference's own count, so no other Gauss-Legendre rule is computed): within
    1e-8 of 4000 nodes for α from 0.02 to 2, a hundredth of the tolerance below."""
    x, w = gauss_legendre(nodes)
    t, w = 0.5 * (x + 1), 0.5 * w
    return float(np.sum(w * 2 / alpha**2 * np.exp(-t * t / alpha**2) * t * integrand(t)))


def _normal_incidence(form, alpha):
    """E(0) of each form as a one-dimensional integral over t = tanθh (isotropic α): with
    c² = 1/(1 + t²), cosθo = 2c² − 1; balanced in closed form."""
    c2 = lambda t: 1 / (1 + t * t)  # noqa: E731
    if form == "balanced":  # ∫ (1 − t²) = 1 − α² + α² e^(−1/α²)
        return 1 - alpha**2 + alpha**2 * math.exp(-1 / alpha**2)
    if form == "duer":
        return _radial(lambda t: c2(t) ** 2, alpha)
    return _radial(lambda t: c2(t) ** 2 * np.sqrt(np.maximum(2 * c2(t) - 1, 0)), alpha)


@pytest.mark.parametrize("form", ("original", "duer", "balanced"))
def test01_ward_albedo_at_normal_incidence(form):
    """The half-vector quadrature equals the closed form (balanced: 1 − α² + α² e^(−1/α²))
    or the one-dimensional integral, to 1e-6: the sharpest and the widest lobe here (α from
    0.02 to 2 in seven steps: make validate)."""
    for alpha in (0.05, 2.0):
        got = Ward(alpha, 0.0, 1.0, form).specular_albedo(0.0)
        assert got == pytest.approx(_normal_incidence(form, alpha), rel=1e-6), alpha


def test02_a_wrong_form_is_caught():
    """The check above can fail: duer's albedo is not balanced's closed form (0.3: by 6 %)."""
    got = Ward(0.3, 0.0, 1.0, "duer").specular_albedo(0.0)
    assert abs(got - _normal_incidence("balanced", 0.3)) > 0.02


#: (form, (θ in degrees, φ) pairs): each form at two incident directions, every θ ∈ {0°, 45°,
#: 70°} and azimuth ∈ {0, 0.7, 1.6} among them (each form at all seven: make validate).
BRUTE_FORCE = [("original", ((0.0, 0.0), (45.0, 0.7))), ("duer", ((45.0, 1.6), (70.0, 0.7))),
               ("balanced", ((70.0, 0.0), (70.0, 1.6)))]


@pytest.mark.parametrize("form,angles", BRUTE_FORCE, ids=[f for f, _ in BRUTE_FORCE])
def test03_ward_albedo_against_brute_force(form, angles):
    """Broad anisotropic lobes (which a plain hemisphere grid resolves), at several azimuths:
    the half-vector quadrature = a plain quadrature of brdf() within 2e-4 (the half-vector
    quadrature's own error towards grazing incidence: up to 9e-5, duer at 70°). The plain
    256² grid has converged for these lobes: within 1e-10 of 2048 × 1536 nodes at every
    angle here."""
    model = Ward((0.2, 0.5), 0.0, 1.0, form)
    wo, weights = sphere_grid(256, 256)
    for theta, phi in angles:
        wi = direction(math.radians(theta), phi)
        brute = float(np.sum(weights * wo[:, 2] * model.lobe(np.broadcast_to(wi, wo.shape), wo)))
        got = model.specular_albedo(math.radians(theta), phi)
        assert got == pytest.approx(brute, rel=2e-4, abs=1e-5), (theta, phi)


def test04_walters_density_is_a_density():
    """∫ p dωo over the upper hemisphere at normal incidence = the fraction of half vectors
    that reflect above it, 1 − e^(−1/α²) (isotropic). 256² nodes: within 1e-15 of 2048 × 512."""
    for alpha in (0.3, 1.0):
        wo, weights = sphere_grid(256, 256)
        wi = np.broadcast_to([0.0, 0.0, 1.0], wo.shape)
        total = float(np.sum(weights * Ward(alpha).sampling_pdf(wi, wo)))
        assert total == pytest.approx(1 - math.exp(-1 / alpha**2), rel=1e-5)


def test05_ward_quadrature_converges():
    """Doubling the nodes moves the albedo by ≤ 1e-4 relative (the docstring's bound), at one
    of the worst cases: grazing incidence, an anisotropic lobe, the form whose lobe is largest
    at the horizon (the quadrature is the same for every form; each form at α ∈ {0.05, 0.5, 1,
    (0.05, 0.5)} × θ ∈ {0°, 60°, 85°, 89°}: make validate)."""
    model = Ward((0.05, 0.5), 0.0, 1.0, "duer")
    a = model.specular_albedo(math.radians(85.0), 0.6)
    b = model.specular_albedo(math.radians(85.0), 0.6, n_mu=512, n_phi=2048)
    assert abs(a - b) <= 1e-4 * b, (a, b)


@pytest.mark.parametrize("form", ("qualitative", "full"))
def test06_orennayar_closed_forms(form):
    """σ = 0 is Lambert; at normal incidence E = ρA (+ ρ²C4 for full), and the quadrature
    gives it to 1e-9; without the interreflection term, full would miss it (the check can
    fail)."""
    rng = np.random.default_rng(0)
    wi, wo = rng.normal(size=(100, 3)), rng.normal(size=(100, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    np.testing.assert_allclose(OrenNayar(0.6, 0.0, form).brdf(wi, wo), 0.6 / math.pi)
    for sigma in (0.2, 1.0):
        s2 = sigma**2
        a, c4 = 1 - 0.5 * s2 / (s2 + 0.33), 0.17 * s2 / (s2 + 0.13)
        expected = 0.7 * a + (0.49 * c4 if form == "full" else 0.0)
        assert float(OrenNayar(0.7, sigma, form).albedo(0.0)[0]) == pytest.approx(expected,
                                                                                 rel=1e-9)
        if form == "full":
            assert abs(expected - 0.7 * a) > 0.01


def test07_orennayar_albedo_against_brute_force():
    """The split quadrature = a plain hemisphere quadrature at 512² within 1e-5 (one incident
    angle per form; both at 30° and 75° on 1024²: make validate, section "Oren-Nayar: rough
    diffuse"), and the model is reciprocal in float64. The 512² grid differs from 2048² by
    3e-7 at most at these angles."""
    for form, theta in (("qualitative", 30.0), ("full", 75.0)):
        model = OrenNayar(0.8, 0.7, form)
        plain = hemisphere_albedo(model.brdf, math.radians(theta), 512, 512)
        np.testing.assert_allclose(model.albedo(math.radians(theta)), plain, rtol=1e-5)
        rng = np.random.default_rng(1)
        a, b = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
        a[:, 2], b[:, 2] = np.abs(a[:, 2]), np.abs(b[:, 2])
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        b /= np.linalg.norm(b, axis=1, keepdims=True)
        np.testing.assert_allclose(model.brdf(a, b), model.brdf(b, a), rtol=1e-12)
