"""
The film's shift of the dielectric's albedo tables (mi_brdfs.scattering.multiscatter_film):
Σ_j K_j(μ) ΔF_j against the change of the single-scattering albedo that the float64
quadrature over microfacet normals (mi_brdfs.reference.cooktorrance.RoughDielectric.albedo)
computes with the film's reflectance from the transfer-matrix reference
(mi_brdfs.reference.thinfilm) in place of F, lit from above and from below; the hat functions' averages in closed form.
"""

import math

import numpy as np
import pytest

from mi_brdfs.reference import thinfilm as ref_film
from mi_brdfs.reference.cooktorrance import RoughDielectric, fresnel_exact
from mi_brdfs.scattering import multiscatter_film as mf

WAVELENGTH, FILM_ETA = 550.0, 1.47


class FilmDielectric(RoughDielectric):
    """The float64 rough dielectric with a film of ``thickness`` nm on its outer face: the
    film's reflectance as F, from outside over the base, from inside towards the air (R = 1
    where the transfer matrix has no transmitted wave: total reflection)."""

    def __init__(self, thickness, **kw):
        super().__init__(**kw)
        self.thickness = thickness

    def _fresnel(self, cos_im):
        c = np.abs(cos_im)
        outside = ref_film.film(c, WAVELENGTH, FILM_ETA, self.thickness, self.eta)["R"]
        with np.errstate(invalid="ignore", divide="ignore"):
            inside = ref_film.film(c, WAVELENGTH, FILM_ETA, self.thickness, 1.0,
                                   n1=self.eta)["R"]
        inside = np.where(1 - (1 - c ** 2) * self.eta ** 2 > 0, inside, 1.0)
        return np.where(cos_im < 0, inside, outside)


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
    bare = RoughDielectric(alpha=alpha, distribution=kind, eta=eta)
    film = FilmDielectric(thickness, alpha=alpha, distribution=kind, eta=eta)
    delta = _node_deltas(eta, thickness)
    thetas = (0.0, 70.0, 180.0, 120.0)
    want = np.array([film.albedo(math.radians(t), n_mu=96, n_phi=256)[0] -
                     bare.albedo(math.radians(t), n_mu=96, n_phi=256)[0] for t in thetas])
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
