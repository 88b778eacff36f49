"""Lambert: f = ρ/π, E(θ) = ρ."""

from __future__ import annotations

import numpy as np


class Lambert:
    """f(wi, wo) = ρ/π for both directions above the surface, else 0 (one-sided, like Mitsuba)."""

    def __init__(self, reflectance):
        self.rho = np.atleast_1d(np.asarray(reflectance, dtype=np.float64))

    def brdf(self, wi, wo) -> np.ndarray:
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(above[:, None], self.rho[None, :] / np.pi, 0.0)

    def albedo(self, theta: float) -> np.ndarray:
        """Closed form: ρ for every incident angle above the surface."""
        return self.rho.copy() if np.cos(theta) > 0 else np.zeros_like(self.rho)
