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


def _dielectric_table(kind: str, eta: float, path=TABLE_PATH):
    """E_R+T(μ, α) of the dielectric's table at relative index ``eta``: the file's
    (n_eta, n_alpha, n_mu) array, linear in log η between its nodes; and α_max."""
    with np.load(path) as data:
        E = np.asarray(data[f"ET_{kind}-smith"], np.float64)
        alpha_max, eta_max = float(data["alpha_max"]), float(data["eta_max"])
    log_nodes = np.linspace(-math.log(eta_max), math.log(eta_max), len(E))
    flat = E.reshape(len(E), -1)
    at = [np.interp(math.log(eta), log_nodes, flat[:, c]) for c in range(flat.shape[1])]
    return np.array(at).reshape(E.shape[1:]), alpha_max


class CompensatedDielectric:
    """
    ``cooktorrance`` with ``transmission`` and ``multiscatter``: the float64 rough dielectric
    ``base`` (a :class:`~mi_brdfs.reference.cooktorrance.RoughDielectric`) plus Kulla & Conty's
    dielectric compensation as the plugin documents it:

        f_ms(ωi, ωo) = (1 − E_s(μi)) (1 − E_s'(μo)) / (π (1 − E_avg,s')) · (1 − x_s or x_s),

    s the side of ωi, s' that of ωo (the same for a reflection, with share 1 − x_s; the other
    for a refraction, with share x_s, and 1/η² in radiance transport), times ks or kt. E_s is
    the table at η lit from above and at 1/η from below, read here with ``numpy.interp``;
    E_avg integrated from it; the shares x = T_avg·K/(1 − E_avg) with T_avg = 1 − F_avg(η)
    above and T_avg/η² below (F_avg from 3000 nodes), K the smaller 1 − E_avg.
    """

    def __init__(self, base, path=TABLE_PATH):
        self.base = base
        au, av = base.alpha if np.ndim(base.alpha) else (base.alpha, base.alpha)
        self.alpha = math.sqrt(au * av)
        self.tables = [_dielectric_table(base.distribution, e, path)
                       for e in (base.eta, 1.0 / base.eta)]
        self.E_avg = [average_albedo(E, a_max, self.alpha) for E, a_max in self.tables]
        t_above = 1.0 - fresnel_average("exact", base.eta, 0.0)[0]
        missing = [1.0 - e for e in self.E_avg]
        k = min(missing)
        self.x = [t_above * k / missing[0], t_above / base.eta ** 2 * k / missing[1]]

    def _albedo(self, side: int, mu) -> np.ndarray:
        E, alpha_max = self.tables[side]
        return albedo(E, alpha_max, np.abs(mu), self.alpha)

    def lobe(self, wi, wo, radiance: bool = True) -> np.ndarray:
        """f_ms (without the cosine), (n, channels)."""
        wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
        side_i = np.where(wi[:, 2] > 0, 0, 1)
        side_o = np.where(wo[:, 2] > 0, 0, 1)
        e_i = np.where(side_i == 0, self._albedo(0, wi[:, 2]), self._albedo(1, wi[:, 2]))
        e_o = np.where(side_o == 0, self._albedo(0, wo[:, 2]), self._albedo(1, wo[:, 2]))
        avg_o = np.where(side_o == 0, self.E_avg[0], self.E_avg[1])
        x = np.where(side_i == 0, self.x[0], self.x[1])
        reflect = side_i == side_o
        shape = (1.0 - e_i) * (1.0 - e_o) / (math.pi * (1.0 - avg_o))
        eta = np.where(side_i == 0, self.base.eta, 1.0 / self.base.eta)
        refracted = x * shape / (eta ** 2 if radiance else 1.0)
        ok = (wi[:, 2] != 0) & (wo[:, 2] != 0)
        fr = np.where(ok & reflect, (1.0 - x) * shape, 0.0)[:, None] * self.base.specular[None, :]
        ft = np.where(ok & ~reflect, refracted, 0.0)[:, None] * self.base.transmittance[None, :]
        return fr + ft

    def brdf(self, wi, wo, radiance: bool = True) -> np.ndarray:
        return self.base.brdf(wi, wo, radiance=radiance) + self.lobe(wi, wo, radiance)

    def albedo(self, theta: float, radiance: bool = False, **kwargs) -> np.ndarray:
        """E(θ) of the single scattering (by quadrature) plus :meth:`lobe_albedo`."""
        return self.base.albedo(theta, radiance=radiance, **kwargs) + \
            self.lobe_albedo(theta, radiance)

    def lobe_albedo(self, theta: float, radiance: bool = False) -> np.ndarray:
        """The compensation's albedo in closed form: (1 − E_s(μi)) times (1 − x_s)·ks +
        x_s·kt (over η² in radiance transport)."""
        mu = math.cos(theta)
        side = 0 if mu > 0 else 1
        e_i = float(self._albedo(side, np.array([mu]))[0])
        eta = self.base.eta if side == 0 else 1.0 / self.base.eta
        x = self.x[side]
        return (1.0 - e_i) * ((1.0 - x) * self.base.specular +
                              x * self.base.transmittance / (eta ** 2 if radiance else 1.0))
