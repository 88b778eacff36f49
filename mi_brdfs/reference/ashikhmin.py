r"""
Ashikhmin & Shirley (2000, "An Anisotropic Phong BRDF Model", Journal of Graphics Tools 5(2)) in
float64, written as the paper writes it: with h = (k1 + k2)/|k1 + k2| at azimuth φh,

- the specular term ρs = √((nu+1)(nv+1))/(8π) · (n·h)^(nu cos²φh + nv sin²φh) / ((h·k)
  max(n·k1, n·k2)) · F(k·h), with Schlick's F(k·h) = Rs + (1 − Rs)(1 − k·h)⁵,
- the diffuse term ρd = 28 Rd/(23π) · (1 − Rs)(1 − (1 − n·k1/2)⁵)(1 − (1 − n·k2/2)⁵),

f = ρs + ρd, one-sided; and the density of the paper's sampler, p(k2) = p_h(h)/(4 k·h) with
p_h(h) = √((nu+1)(nv+1))/(2π) (n·h)^(nu cos²φh + nv sin²φh). Independent of
:mod:`mi_brdfs.scattering.ashikhmin`, which rewrites the terms for float32: trigonometry for φh,
``pow`` for the lobe, the polynomials as written.

The albedo: the diffuse part by Gauss-Legendre in cosθo (its integrand is a polynomial in it);
the specular part over the half vector (k2 the mirror image of k1 about h, dω2 = 4 (k1·h) dωh),
in the lobe's own variable t = (n·h)^(e(φh)+1) on rings of constant φh (midpoint rule in φh,
Gauss-Legendre in t), which resolves any exponent. On each ring k2 stays above the surface
from the normal down to one angle θh* (below: k2 is below the surface, the integrand 0), where
the t-integral stops, so that no node straddles the horizon.
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import direction, gauss_legendre, sphere_grid


def _channels(x) -> np.ndarray:
    return np.atleast_1d(np.asarray(x, dtype=np.float64))


class Ashikhmin:
    """f(k1, k2) = ρs + ρd; ``exponent`` a number or (nu, nv)."""

    def __init__(self, exponent=100.0, diffuse=0.5, specular=0.04):
        nu, nv = (exponent, exponent) if np.ndim(exponent) == 0 else exponent
        self.nu, self.nv = float(nu), float(nv)
        self.rho_d, self.rho_s = _channels(diffuse), _channels(specular)

    @classmethod
    def from_spec(cls, spec: dict, color) -> "Ashikhmin | None":
        """The reference of an ``ashikhmin`` dict, with ``color`` reading its reflectances
        (:func:`mi_brdfs.reference.color`); None for textures."""
        exponent = (spec.get("nu"), spec.get("nv")) if "nu" in spec else \
            spec.get("exponent", 100.0)
        rho_d = color(spec.get("diffuse_reflectance"), 0.5)
        rho_s = color(spec.get("specular_reflectance"), 0.04)
        numbers = exponent if isinstance(exponent, tuple) else (exponent,)
        if rho_d is None or rho_s is None or \
                not all(isinstance(n, (int, float)) for n in numbers):
            return None
        return cls(exponent, rho_d, rho_s)

    def exponent(self, h) -> np.ndarray:
        """nu cos²φh + nv sin²φh, with φh the azimuth of h, (n,)."""
        phi = np.arctan2(h[:, 1], h[:, 0])
        return self.nu * np.cos(phi) ** 2 + self.nv * np.sin(phi) ** 2

    def half_pdf(self, h) -> np.ndarray:
        """The paper's half-vector density p_h(h) for unit h, (n,); 0 below the surface."""
        hz = np.clip(h[:, 2], 0.0, 1.0)
        norm = math.sqrt((self.nu + 1) * (self.nv + 1)) / (2 * math.pi)
        return np.where(h[:, 2] > 0, norm * hz ** self.exponent(h), 0.0)

    @staticmethod
    def _half(wi, wo):
        h = wi + wo
        return h / np.linalg.norm(h, axis=1, keepdims=True)

    def specular_term(self, wi, wo) -> np.ndarray:
        """ρs, (n, channels); 0 unless both directions are above the surface."""
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = self._half(wi, wo)
            kh = np.sum(wi * h, axis=1)
            norm = math.sqrt((self.nu + 1) * (self.nv + 1)) / (8 * math.pi)
            lobe = norm * np.clip(h[:, 2], 0.0, 1.0) ** self.exponent(h) / (
                kh * np.maximum(wi[:, 2], wo[:, 2]))
            fresnel = self.rho_s[None, :] + (1 - self.rho_s[None, :]) * (1 - kh[:, None]) ** 5
            value = lobe[:, None] * fresnel
        return np.where(above[:, None], value, 0.0)

    def diffuse_term(self, wi, wo) -> np.ndarray:
        """ρd, (n, channels); 0 unless both directions are above the surface."""
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        shape = (1 - (1 - wi[:, 2] / 2) ** 5) * (1 - (1 - wo[:, 2] / 2) ** 5)
        value = 28 * self.rho_d[None, :] / (23 * math.pi) * (1 - self.rho_s[None, :]) * \
            shape[:, None]
        return np.where(above[:, None], value, 0.0)

    def brdf(self, wi, wo) -> np.ndarray:
        """f(k1, k2) = ρs + ρd, (n, channels)."""
        return self.specular_term(wi, wo) + self.diffuse_term(wi, wo)

    def sampling_pdf(self, wi, wo) -> np.ndarray:
        """p(k2) = p_h(h)/(4 k·h), the density of the glossy lobe's sampler, (n,)."""
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = self._half(wi, wo)
            p = self.half_pdf(h) / (4 * np.sum(wi * h, axis=1))
        return np.where(above, p, 0.0)

    def specular_albedo(self, theta: float, phi: float = 0.0, n_t: int = 256,
                        n_phi: int = 512) -> np.ndarray:
        """∫ ρs cosθo dωo for k1 at polar angle θ and azimuth ``phi`` (radians), per channel
        (module docstring)."""
        wi = direction(theta, phi)
        if wi[2] <= 0:
            return np.zeros_like(self.rho_s)
        x, w = gauss_legendre(n_t)
        phis = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
        e = self.nu * np.cos(phis) ** 2 + self.nv * np.sin(phis) ** 2
        # k2 is above the surface where θh < θh* = δ/2 + π/4, δ = atan2(sinθ cos(φh − φ), cosθ)
        # (n·k2 = cos(2θh − δ)·√(…)): t from t* = cos(θh*)^(e+1) to 1 on each ring
        delta = np.arctan2(math.sin(theta) * np.cos(phis - phi), math.cos(theta))
        t_min = np.cos(0.5 * delta + 0.25 * math.pi) ** (e + 1)
        t = t_min[:, None] + (1 - t_min[:, None]) * 0.5 * (x[None, :] + 1)
        w_t = (1 - t_min[:, None]) * 0.5 * w[None, :] * (2 * math.pi / n_phi)
        e, P = np.repeat(e, n_t), np.repeat(phis, n_t)
        mu = t.ravel() ** (1 / (e + 1))  # t = μ^(e+1): dμ = dt / ((e+1) μ^e)
        s = np.sqrt(np.maximum(1 - mu * mu, 0.0))
        h = np.stack([s * np.cos(P), s * np.sin(P), mu], axis=1)
        cos_ih = h @ wi
        wo = 2 * cos_ih[:, None] * h - wi[None, :]
        keep = (cos_ih > 0) & (wo[:, 2] > 0)  # all but rounding at the edge
        jacobian = 4 * cos_ih[keep] * wo[keep, 2] / ((e[keep] + 1) * mu[keep] ** e[keep])
        f = self.specular_term(np.broadcast_to(wi, wo[keep].shape), wo[keep])
        return np.einsum("n,nc->c", w_t.ravel()[keep] * jacobian, f)

    def diffuse_albedo(self, theta: float) -> np.ndarray:
        """∫ ρd cosθo dωo at polar angle θ, per channel: Gauss-Legendre in cosθo."""
        wi = direction(theta)
        wo, weights = sphere_grid(16, 4)
        f = self.diffuse_term(np.broadcast_to(wi, wo.shape), wo)
        return np.einsum("n,nc->c", weights * wo[:, 2], f)

    def albedo(self, theta: float, phi: float = 0.0) -> np.ndarray:
        """E(θ) = ∫ f cosθo dωo per channel, 0 below the surface."""
        if math.cos(theta) <= 0:
            return np.zeros(np.broadcast_shapes(self.rho_d.shape, self.rho_s.shape))
        return self.diffuse_albedo(theta) + self.specular_albedo(theta, phi)
