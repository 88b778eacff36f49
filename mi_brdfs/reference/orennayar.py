r"""
Oren-Nayar in float64, as the paper writes it (Oren & Nayar 1994, "Generalization of Lambert's
Reflectance Model", §4.4, eqs. 26 to 30): angles θi, θo, φi − φo computed with arccos and
arctan2, α = max(θi, θo), β = min(θi, θo). Independent of :mod:`mi_brdfs.scattering.orennayar`,
which avoids the trigonometry. The albedo by quadrature of the hemisphere, split at θo = θi
(where α and β swap and the integrand has a kink).
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import hemisphere_albedo

FORMS = ("qualitative", "full")


class OrenNayar:
    """f(ωi, ωo) of ``form`` for facet albedo ρ and slope-angle deviation σ (radians)."""

    def __init__(self, reflectance=0.5, sigma=0.2, form="qualitative"):
        if form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}")
        self.rho = np.atleast_1d(np.asarray(reflectance, dtype=np.float64))
        self.sigma, self.form = float(sigma), form

    def brdf(self, wi, wo) -> np.ndarray:
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        s2 = self.sigma ** 2
        theta_i = np.arccos(np.clip(wi[:, 2], -1, 1))
        theta_o = np.arccos(np.clip(wo[:, 2], -1, 1))
        delta = np.arctan2(wi[:, 1], wi[:, 0]) - np.arctan2(wo[:, 1], wo[:, 0])
        cos_phi = np.where((np.hypot(wi[:, 0], wi[:, 1]) > 0) & (np.hypot(wo[:, 0], wo[:, 1]) > 0),
                           np.cos(delta), 0.0)
        alpha, beta = np.maximum(theta_i, theta_o), np.minimum(theta_i, theta_o)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        a = 1 - 0.5 * s2 / (s2 + 0.33)
        b = 0.45 * s2 / (s2 + 0.09)
        rho = self.rho[None, :]
        if self.form == "qualitative":
            factor = a + b * np.maximum(0.0, cos_phi) * np.sin(alpha) * np.tan(beta)
            f = rho / math.pi * factor[:, None]
        else:
            c2 = np.where(cos_phi >= 0, b * np.sin(alpha),
                          b * (np.sin(alpha) - (2 * beta / math.pi) ** 3))
            c3 = 0.125 * s2 / (s2 + 0.09) * (4 * alpha * beta / math.pi ** 2) ** 2
            single = a + cos_phi * c2 * np.tan(beta) + \
                (1 - np.abs(cos_phi)) * c3 * np.tan((alpha + beta) / 2)
            double = 0.17 * s2 / (s2 + 0.13) * (1 - cos_phi * (2 * beta / math.pi) ** 2)
            f = rho / math.pi * single[:, None] + rho ** 2 / math.pi * double[:, None]
        return np.where(above[:, None], f, 0.0)

    def albedo(self, theta: float, n_mu: int = 256, n_phi: int = 512) -> np.ndarray:
        """E(θ) per channel, Gauss-Legendre in cosθo on [0, cosθ] and [cosθ, 1]."""
        c = math.cos(theta)
        if c <= 0:
            return np.zeros_like(self.rho)
        return sum(hemisphere_albedo(self.brdf, theta, n_mu, n_phi, mu_range=r)
                   for r in ((0.0, c), (c, 1.0)) if r[1] > r[0])
