r"""
Kulla & Conty's energy compensation (2017, "Revisiting Physically Based Shading at
Imageworks", SIGGRAPH course "Physically Based Shading in Theory and Practice") in float64, on
top of the single-scattering :class:`~mi_brdfs.reference.cooktorrance.CookTorrance`:

    f = f_ss + ks·F_ms·(1 − E(μi))(1 − E(μo)) / (π (1 − E_avg)),
    F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)),  F_avg = 2∫F(μ)μ dμ,

E the albedo of the single-scattering lobe with F ≡ 1. Independent of the plugin's code: E is
read from the shipped table file and interpolated here with ``numpy.interp`` (bilinear in
sqrt μ and sqrt(α/α_max), the nodes the file defines), E_avg integrated from that interpolant
by a fine Gauss-Legendre rule (not read from the file), and F_avg integrated from the exact
Fresnel term with 2000 nodes. Anisotropic α uses sqrt(αu·αv), as the plugin documents.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .cooktorrance import CookTorrance, fresnel_exact, fresnel_schlick
from .quadrature import gauss_legendre

TABLE_PATH = Path(__file__).resolve().parent.parent / "data" / "microfacet_albedo.npz"


def _table(kind: str, shadowing: str, path=TABLE_PATH):
    with np.load(path) as data:
        return np.asarray(data[f"E_{kind}-{shadowing}"], np.float64), float(data["alpha_max"])


def albedo(E: np.ndarray, alpha_max: float, mu, alpha: float) -> np.ndarray:
    """E(μ, α) of table ``E`` (n_alpha, n_mu), bilinear in (sqrt μ, sqrt(α/α_max))."""
    n_alpha, n_mu = E.shape
    y = min(max(math.sqrt(alpha / alpha_max), 0.0), 1.0) * (n_alpha - 1)
    x_nodes = np.linspace(0.0, 1.0, n_mu)
    x = np.sqrt(np.clip(np.asarray(mu, np.float64), 0.0, 1.0))
    below = min(int(y), n_alpha - 2)
    t = y - below
    rows = [np.interp(x, x_nodes, E[j]) for j in (below, below + 1)]
    return (1.0 - t) * rows[0] + t * rows[1]


def average_albedo(E: np.ndarray, alpha_max: float, alpha: float, n: int = 2000) -> float:
    """E_avg = 2∫E(μ)μ dμ of :func:`albedo` by Gauss-Legendre in μ (the kinks of the
    interpolant at its nodes converge as n⁻², below 1e-6 at 2000 nodes)."""
    x, w = gauss_legendre(n)
    mu = (x + 1.0) / 2.0  # 2∫₀¹ g dμ = Σ w g over the nodes mapped from [−1, 1]
    return float(np.sum(w * albedo(E, alpha_max, mu, alpha) * mu))


def fresnel_average(fresnel: str, eta, k, n: int = 3000) -> np.ndarray:
    """F_avg = 2∫F(μ)μ dμ per channel (Gauss-Legendre in t with μ = t², which keeps the
    steep rise of a dielectric's F past its critical angle from converging slowly); 1 for
    ``fresnel`` 'none'."""
    if fresnel == "none":
        return np.ones(1)
    x, w = gauss_legendre(n)
    t = (x + 1.0) / 2.0  # 4∫₀¹ F(t²) t³ dt = Σ 2 w F t³ over the nodes mapped from [−1, 1]
    term = fresnel_exact if fresnel == "exact" else fresnel_schlick
    return np.einsum("n,nc->c", w * 2.0 * t ** 3, term(t * t, eta, k))


class Compensated:
    """
    ``cooktorrance`` with ``multiscatter``: the single-scattering reference ``base`` (a
    :class:`CookTorrance`) plus Kulla & Conty's lobe. ``brdf`` and ``albedo`` as every
    reference model.
    """

    def __init__(self, base: CookTorrance, path=TABLE_PATH):
        self.base = base
        self.E, self.alpha_max = _table(base.distribution, base.shadowing, path)
        au, av = base.alpha if np.ndim(base.alpha) else (base.alpha, base.alpha)
        self.alpha = math.sqrt(au * av)
        self.E_avg = average_albedo(self.E, self.alpha_max, self.alpha)
        f_avg = fresnel_average(base.fresnel, base.eta, base.k)
        self.F_ms = f_avg ** 2 * self.E_avg / (1.0 - f_avg * (1.0 - self.E_avg))

    def lobe(self, wi, wo) -> np.ndarray:
        """ks·F_ms·(1 − E(μi))(1 − E(μo)) / (π (1 − E_avg)), (n, channels); 0 below."""
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        e_i = albedo(self.E, self.alpha_max, wi[:, 2], self.alpha)
        e_o = albedo(self.E, self.alpha_max, wo[:, 2], self.alpha)
        shape = (1.0 - e_i) * (1.0 - e_o) / (math.pi * (1.0 - self.E_avg))
        return np.where(above, shape, 0.0)[:, None] * (self.F_ms * self.base.specular)[None, :]

    def brdf(self, wi, wo) -> np.ndarray:
        return self.base.brdf(wi, wo) + self.lobe(wi, wo)

    def albedo(self, theta: float, **kwargs) -> np.ndarray:
        """E(θ) of the single scattering (by quadrature) plus the lobe's, in closed form:
        ks·F_ms·(1 − E(μi))·(2∫(1 − E)μ dμ)/(1 − E_avg) = ks·F_ms·(1 − E(μi))."""
        e_i = albedo(self.E, self.alpha_max, math.cos(theta), self.alpha)
        return self.base.albedo(theta, **kwargs) + self.F_ms * self.base.specular * (1.0 - e_i)
