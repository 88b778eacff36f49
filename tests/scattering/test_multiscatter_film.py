"""
The film's shift of the dielectric's albedo tables (mi_brdfs.scattering.multiscatter_film):
Σ_j K_j(μ) ΔF_j against the change of the single-scattering albedo that the float64
quadrature over microfacet normals (mi_brdfs.reference.cooktorrance.RoughDielectric) computes
with the film's reflectance from the transfer-matrix reference (mi_brdfs.reference.thinfilm)
in place of F, lit from above and from below; the hat functions' averages in closed form.
"""

import math

import numpy as np
import pytest

from mi_brdfs.reference import thinfilm as ref_film
from mi_brdfs.reference.cooktorrance import RoughDielectric, fresnel_exact, ndf
from mi_brdfs.reference.quadrature import direction, sphere_grid
from mi_brdfs.scattering import multiscatter_film as mf

WAVELENGTH, FILM_ETA = 550.0, 1.47


def _albedo(model: RoughDielectric, theta: float, reflectance) -> float:
    """E(θ) = ∫ D |ωi·h| G1(ωi)/|cosθi| [F G1(ωo,r) + (1 − F) G1(ωo,t)] dωh (importance
    transport) with ``reflectance(|ωi·h|, inside)`` as F: the reference's quadrature (two
    panels in cosθh, the peak and the tail, by Gauss-Legendre × the midpoint rule in φh)."""
    wi = direction(theta, 0.0)
    inside = wi[2] < 0
    w = wi * np.array([1.0, 1.0, -1.0]) if inside else wi
    eta = 1 / model.eta if inside else model.eta
    split = 1 / math.sqrt(1 + (4 * model.alpha) ** 2)
    total = 0.0
    for mu_range in ((0.0, split), (split, 1.0)):
        h, weights = sphere_grid(96, 256, mu_range)
        cih = h @ w
        keep = cih > 0
        h, weights, cih = h[keep], weights[keep], cih[keep]
        ws = np.broadcast_to(w, h.shape)
        common = weights * ndf(model.distribution, model.alpha, h) * cih * \
            model._g1(ws, h) / w[2]
        wo_r = 2 * cih[:, None] * h - ws
        g_r = np.where(wo_r[:, 2] > 0, model._g1(wo_r, h), 0.0)
        cos_t2 = 1 - (1 - cih ** 2) / eta ** 2
        wo_t = (cih / eta - np.sqrt(np.maximum(cos_t2, 0)))[:, None] * h - ws / eta
        g_t = np.where((cos_t2 > 0) & (wo_t[:, 2] < 0), model._g1(wo_t, h), 0.0)
        f = reflectance(cih, inside)
        total += np.sum(common * (f * g_r + (1 - f) * g_t))
    return total


def _bare(eta):
    return lambda c, inside: fresnel_exact(c, 1 / eta if inside else eta, 0.0)[:, 0]


def _film(eta, thickness):
    """The film's reflectance: from outside over the base, from inside towards the air
    (total reflection there where the transfer matrix has no transmitted wave: R = 1)."""
    def reflectance(c, inside):
        if inside:
            r = ref_film.film(c, WAVELENGTH, FILM_ETA, thickness, 1.0, n1=eta)["R"]
            return np.where(1 - (1 - c ** 2) * eta ** 2 > 0, r, 1.0)
        return ref_film.film(c, WAVELENGTH, FILM_ETA, thickness, eta)["R"]
    return reflectance


def _node_deltas(eta, thickness):
    """ΔF_j = R − F at the nodes from outside (the reference's numbers)."""
    c = np.maximum(mf.NODES, 1e-12)
    return ref_film.film(c, WAVELENGTH, FILM_ETA, thickness, eta)["R"] - \
        fresnel_exact(c, eta, 0.0)[:, 0]


@pytest.mark.parametrize("kind,alpha,eta,thickness", [
    ("ggx", 1.0, 1.33, 320.0), ("beckmann", 0.8, 1.33, 320.0)])
def test01_shift_equals_the_quadrature(kind, alpha, eta, thickness):
    """From above (0°, 70°) and below (180°, 120°): Σ K_j ΔF_j within 5e-4 of the float64
    albedo with the film less the bare one (a change of up to 3 %); the kernels of the wrong
    side are rejected."""
    model = RoughDielectric(alpha=alpha, distribution=kind, eta=eta)
    delta = _node_deltas(eta, thickness)
    thetas = (0.0, 70.0, 180.0, 120.0)
    want = np.array([_albedo(model, math.radians(t), _film(eta, thickness)) -
                     _albedo(model, math.radians(t), _bare(eta)) for t in thetas])
    mus = np.abs(np.cos(np.radians(thetas)))
    below = np.array(thetas) > 90.0

    def shift(flip):
        rows = [mf.kernel_row(kind, eta, alpha, [mu], b != flip)[0] for mu, b in zip(mus, below)]
        return np.array(rows) @ delta
    assert np.abs(want).max() > 5e-3
    np.testing.assert_allclose(shift(False), want, atol=5e-4)
    assert np.abs(shift(True) - want).max() > 2e-3


def test02_hat_averages():
    """2∫h_j c dc sums to 1 (a reflectance of 1) and gives 2∫c² dc = 2/3 for R = c; the
    nodes' hat functions add to 1 wherever they are read."""
    a = mf.hat_averages()
    assert a.sum() == pytest.approx(1.0, abs=1e-12)
    assert a @ mf.NODES == pytest.approx(2.0 / 3.0, abs=1e-12)
    weights = mf._hats(np.array([[0.0, 0.37, 0.999, 1.0]]), np.ones((1, 4)))
    assert weights.sum() == pytest.approx(4.0, abs=1e-12)
