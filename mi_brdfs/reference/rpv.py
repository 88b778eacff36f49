r"""
The Rahman-Pinty-Verstraete model in float64, as the paper writes it, with angles (θ from
arccos, φ from arctan2), independent of :mod:`mi_brdfs.scattering.rpv`, which works with
vectors.

Rahman, Pinty & Verstraete 1993, "Coupled surface-atmosphere reflectance (CSAR) model 2.
Semiempirical surface model usable with NOAA advanced very high resolution radiometer data",
JGR 98(D11), 20791-20801, eqs. 2-6; with ρc apart from ρ0, the four-parameter form of
Widlowski et al. 2006 (JGR 111, D16107):

    BRF = ρ0 M(k) F(g) H(ρc, G),    f = BRF/π,
    M = [cosθi cosθo (cosθi + cosθo)]^(k − 1),
    F = (1 − Θ²)/[1 + Θ² − 2Θ cos(π − g)]^(3/2),
    H = 1 + (1 − ρc)/(1 + G),    G = √(tan²θi + tan²θo − 2 tanθi tanθo cos φ),

θi the sun's zenith (ωi), θo the viewer's (ωo), φ their relative azimuth (0 when the viewer
looks back along the sun's azimuth, the backscatter side) and g the phase angle, cos g =
cosθi cosθo + sinθi sinθo cos φ: g = 0 and G = 0 at the hot spot ωo = ωi; π − g is the
scattering angle, so that Θ > 0 scatters forward and Θ < 0 backward (the plugin's ``g`` is
the paper's Θ). The paper's three-parameter model has ρc = ρ0.

M diverges as either cosine goes to 0 for k < 1, and with it the directional albedo
E(θi) ~ cos^(k−1)θi: :meth:`RPV.albedo` integrates it with the substitution cosθo = t³,
which smooths the integrable cosθo^(2k−1) at grazing incidence.
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import direction, gauss_legendre

#: Eradiate's defaults (src/bsdfs/rpv.cpp of its Mitsuba fork); ρc = ρ0 unless given.
RHO_0, K, G = 0.1, 0.1, 0.0


def angles(w) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit vectors (n, 3)."""
    w = np.atleast_2d(np.asarray(w, dtype=np.float64))
    return np.arccos(np.clip(w[:, 2], -1.0, 1.0)), np.arctan2(w[:, 1], w[:, 0])


class RPV:
    """BRF = ρ0 M F H per channel (each parameter a scalar or per-channel array; ``rho_c``
    None: ρ0, the paper's three-parameter model)."""

    def __init__(self, rho_0=RHO_0, k=K, g=G, rho_c=None):
        rho_c = rho_0 if rho_c is None else rho_c
        arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=np.float64))
                                       for x in (rho_0, k, g, rho_c)))
        self.rho_0, self.k, self.g, self.rho_c = (np.array(a) for a in arrays)

    def factors(self, wi, wo) -> tuple[np.ndarray, ...]:
        """(cosθi cosθo (cosθi + cosθo), cos g, G), (n,) each, at pairs above the surface."""
        (ti, pi_), (to, po) = angles(wi), angles(wo)
        phi = pi_ - po
        ci, co = np.cos(ti), np.cos(to)
        cos_g = ci * co + np.sin(ti) * np.sin(to) * np.cos(phi)
        big_g = np.sqrt(np.maximum(np.tan(ti) ** 2 + np.tan(to) ** 2
                                   - 2.0 * np.tan(ti) * np.tan(to) * np.cos(phi), 0.0))
        return ci * co * (ci + co), cos_g, big_g

    def brf(self, wi, wo) -> np.ndarray:
        """The model's BRF, (n, channels); 0 unless both directions are above the surface."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        safe = np.array([0.0, 0.0, 1.0])
        wi, wo = np.where(above[:, None], wi, safe), np.where(above[:, None], wo, safe)
        m_base, cos_g, big_g = (x[:, None] for x in self.factors(wi, wo))
        theta = self.g[None, :]
        m = m_base ** (self.k[None, :] - 1.0)
        f = (1.0 - theta ** 2) / (1.0 + theta ** 2 - 2.0 * theta * np.cos(np.pi - np.arccos(
            np.clip(cos_g, -1.0, 1.0)))) ** 1.5
        h = 1.0 + (1.0 - self.rho_c[None, :]) / (1.0 + big_g)
        return np.where(above[:, None], self.rho_0[None, :] * m * f * h, 0.0)

    def brdf(self, wi, wo) -> np.ndarray:
        """f = BRF/π, (n, channels)."""
        return self.brf(wi, wo) / math.pi

    def albedo(self, theta: float, n_t: int = 96, n_phi: int = 96) -> np.ndarray:
        """E(θ) = ∫ f cosθo dωo per channel: Gauss-Legendre in t with cosθo = t³ (dμ =
        3t² dt), the midpoint rule in φ."""
        if math.cos(theta) <= 0:
            return np.zeros_like(self.rho_0)
        x, w = gauss_legendre(n_t)
        t, w_t = 0.5 * (x + 1.0), 0.5 * w
        mu, w_mu = t ** 3, 3.0 * t ** 2 * w_t
        phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
        m, p = (a.ravel() for a in np.meshgrid(mu, phi, indexing="ij"))
        s = np.sqrt(1.0 - m ** 2)
        wo = np.stack([s * np.cos(p), s * np.sin(p), m], axis=1)
        weight = np.outer(w_mu, np.full(n_phi, 2.0 * math.pi / n_phi)).ravel() * m
        wi = np.broadcast_to(direction(theta), wo.shape)
        return weight @ self.brdf(wi, wo)

    def energy(self, cos_min: float = 1e-6, n: int = 48) -> tuple[float | None, float, float]:
        """
        Where the directional albedo exceeds 1 (the model creates energy): (θi in degrees
        from which E > 1 in some channel, rounded down to 0.001°, or None where it does not on
        θi ∈ [0°, arccos ``cos_min``]; E(89°); E at cosθi = ``cos_min``, the most of any θi
        where the cosines are held at ``cos_min`` or above), over the channels. E grows
        towards the horizon for k < 1; the search bisects between the first of 46 angles
        (0°, 2°, …, 88°, 89°, then cosθi = ``cos_min``) where it exceeds 1 and the one before;
        :meth:`albedo` on ``n`` × ``n`` nodes (within 10⁻⁴ of 96 × 96 for the defaults).
        """
        thetas = [*range(0, 89, 2), 89.0, math.degrees(math.acos(cos_min))]
        e = [float(self.albedo(math.radians(t), n, n).max()) for t in thetas]
        e89, top = e[-2], e[-1]
        over = [i for i, v in enumerate(e) if v > 1.0]
        if not over:
            return None, e89, top
        if over[0] == 0:
            return 0.0, e89, top
        lo, hi = thetas[over[0] - 1], thetas[over[0]]
        while hi - lo > 5e-4:
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if self.albedo(math.radians(mid), n, n).max() > 1.0 else (mid, hi)
        return math.floor(lo * 1000) / 1000, e89, top
