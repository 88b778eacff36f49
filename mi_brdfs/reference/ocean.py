r"""
Cox & Munk's wind-roughened sea surface in float64, as the papers write it: the probability
density of the surface's slopes, the Fresnel reflectance of a complex index from the
amplitude coefficients, Mishchenko & Travis's shadowing with erfc, Monahan's whitecap
coverage; independent of :mod:`mi_brdfs.scattering.ocean`, which works with microfacet
distributions.

The glint of a sea of Gaussian slopes (Cox & Munk 1954, "Measurement of the roughness of the
sea surface from photographs of the sun's glitter", JOSA 44(11); in the BRDF form of Mishchenko
& Travis 1997, "Satellite retrieval of aerosol properties over the ocean using polarization as
well as intensity of reflected sunlight", JGR 102(D14), eqs. 8-13):

    f = F(ωi·m) P(zx, zy) S(ωi, ωo) / (4 cosθi cosθo cos⁴θm),

m the half vector of ωi, ωo, (zx, zy) = −(mx, my)/mz its slopes, P their density:
isotropic P = exp(−(zx² + zy²)/σ²)/(πσ²), σ² = 0.003 + 0.00512 U (U the wind speed in m/s at
12.5 m); along the wind (azimuth φw; zu, zc the slopes along and across it)
P = exp(−zu²/(2σu²) − zc²/(2σc²))/(2π σu σc), σu² = 0.00316 U, σc² = 0.003 + 0.00192 U (each
held at 0.0015 or above, as the plugin holds it). F is the reflectance of unpolarised light
(|r_s|² + |r_p|²)/2 with the complex index n = (η + ik)/n_ext. S = 1/(1 + Λ(ωi) + Λ(ωo)),
Λ(μ) = ½[√((1 − μ²)/π) (s/μ) exp(−μ²/(s²(1 − μ²))) − erfc(μ/(s√(1 − μ²)))], s² the mean square
slope in the direction's azimuth (σ² isotropic; 2(σu² cos²φ + σc² sin²φ) along the wind).
With whitecaps of reflectance ρ (Koepke 1984, "Effective reflectance of oceanic whitecaps",
Applied Optics 23(11): 0.22), covering W = 2.95·10⁻⁶ U^3.52 of the surface (Monahan &
O'Muircheartaigh 1980, J. Phys. Oceanogr. 10(12)): f = W ρ/π + (1 − W) f_glint.
"""

from __future__ import annotations

import math

import numpy as np


#: The least variance of one slope axis (the plugin's floor: half the isotropic fit's 0.003).
AXIS_VARIANCE_MIN = 0.0015
#: erfc per element, in float64 (the standard library's).
erfc = np.vectorize(math.erfc, otypes=[float])


def fresnel(cos_theta, eta, k=0.0, ext_ior=1.0) -> np.ndarray:
    """Unpolarised reflectance at incidence cosθ (n,) from medium ``ext_ior`` onto η + ik,
    per channel (n, channels): the amplitude coefficients of s and p light (Born & Wolf
    §1.5, §14.2) with the complex cosine of refraction."""
    n = ((np.atleast_1d(np.asarray(eta, float)) + 1j * np.atleast_1d(np.asarray(k, float)))
         / np.atleast_1d(np.asarray(ext_ior, float)))[None, :]
    c = np.clip(np.asarray(cos_theta, float), 0.0, 1.0)[:, None]
    ct = np.sqrt(1.0 - (1.0 - c ** 2) / n ** 2 + 0j)
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def coverage(wind_speed: float) -> float:
    """Monahan & O'Muircheartaigh's whitecap coverage, clipped to 1."""
    return min(2.95e-6 * wind_speed ** 3.52, 1.0)


class Ocean:
    """The model at wind speed ``wind_speed`` (m/s), optionally along ``wind_direction``
    (degrees), for water of index ``eta`` + i ``k`` (per channel) under ``ext_ior``, with
    ``whitecaps`` of that reflectance (None: none) and ``shadowing``."""

    def __init__(self, wind_speed=0.1, eta=1.33, k=0.0, ext_ior=1.000277, wind_direction=None,
                 whitecaps=None, shadowing=True):
        self.u = float(wind_speed)
        self.eta, self.k, self.ext = (np.atleast_1d(np.asarray(x, float))
                                      for x in (eta, k, ext_ior))
        self.phi_w = None if wind_direction is None else math.radians(wind_direction)
        self.whitecaps, self.shadowing = whitecaps, shadowing
        if self.phi_w is None:
            self.var_x = self.var_y = (0.003 + 0.00512 * self.u) / 2  # per axis
        else:
            self.var_x = max(0.00316 * self.u, AXIS_VARIANCE_MIN)
            self.var_y = max(0.003 + 0.00192 * self.u, AXIS_VARIANCE_MIN)

    def _along_wind(self, x, y):
        """Components along and across the wind of (x, y) in the local frame."""
        if self.phi_w is None:
            return x, y
        c, s = math.cos(self.phi_w), math.sin(self.phi_w)
        return c * x + s * y, c * y - s * x

    def slope_pdf(self, zx, zy) -> np.ndarray:
        """P(zx, zy): the density of the slopes (per unit area of slope space)."""
        zu, zc = self._along_wind(np.asarray(zx, float), np.asarray(zy, float))
        return np.exp(-0.5 * (zu ** 2 / self.var_x + zc ** 2 / self.var_y)) / \
            (2 * np.pi * math.sqrt(self.var_x * self.var_y))

    def ndf(self, m) -> np.ndarray:
        """D(m) = P(slopes of m)/cos⁴θm, per unit solid angle of normals (0 below)."""
        m = np.atleast_2d(np.asarray(m, float))
        up = m[:, 2] > 0
        mz = np.where(up, m[:, 2], 1.0)
        d = self.slope_pdf(-m[:, 0] / mz, -m[:, 1] / mz) / mz ** 4
        return np.where(up, d, 0.0)

    def lam(self, w) -> np.ndarray:
        """Mishchenko & Travis's Λ(μ), with s² the mean square slope in w's azimuth."""
        w = np.atleast_2d(np.asarray(w, float))
        mu = np.clip(w[:, 2], 1e-300, 1.0)
        sin2 = np.maximum(1.0 - mu ** 2, 0.0)
        rho = np.hypot(w[:, 0], w[:, 1])
        safe = np.where(rho > 0, rho, 1.0)
        cu, cc = self._along_wind(w[:, 0] / safe, w[:, 1] / safe)
        s = np.sqrt(2 * (self.var_x * cu ** 2 + self.var_y * cc ** 2))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            v = mu / (s * np.sqrt(sin2))
            out = 0.5 * (np.exp(-v ** 2) / (v * math.sqrt(math.pi)) - erfc(v))
        return np.where(sin2 > 0, out, 0.0)

    def glint(self, wi, wo) -> np.ndarray:
        """The glint's f (n, channels) without the whitecaps' share."""
        wi, wo = (np.atleast_2d(np.asarray(w, float)) for w in (wi, wo))
        h = wi + wo
        m = h / np.linalg.norm(h, axis=1, keepdims=True)
        cos_im = np.sum(wi * m, axis=1)
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0) & (cos_im > 0)
        s = 1 / (1 + self.lam(wi) + self.lam(wo)) if self.shadowing else 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            f = self.ndf(m) * s / (4 * wi[:, 2] * wo[:, 2])
        return np.where(ok[:, None], f[:, None] * fresnel(cos_im, self.eta, self.k, self.ext),
                        0.0)

    def brdf(self, wi, wo) -> np.ndarray:
        """f (n, channels): the glint, and the whitecaps' W ρ/π with the glint's 1 − W."""
        f = self.glint(wi, wo)
        if self.whitecaps is None:
            return f
        w = coverage(self.u)
        up = (np.atleast_2d(wi)[:, 2] > 0) & (np.atleast_2d(wo)[:, 2] > 0)
        return (1 - w) * f + np.where(up[:, None], w * np.asarray(self.whitecaps) / np.pi, 0.0)

    def albedo(self, theta: float, n: int = 400, extent: float = 7.0) -> np.ndarray:
        """
        E(θ) = ∫ f cosθo dωo per channel, for ωi at zenith θ in the xz plane: the glint's
        part over the slopes, where the narrow lobe is wide (dωo = 4 (ωo·m) dωm and
        dωm = cos³θm dzx dzy make f cosθo dωo = F P S (ωi·m)/(cosθi cosθm) dzx dzy; the
        midpoint rule on n² slopes within ``extent`` standard deviations of each axis), the
        whitecaps' exactly (W ρ).
        """
        t = (np.arange(n) + 0.5) / n * 2 - 1
        zu, zc = np.meshgrid(t * extent * math.sqrt(self.var_x),
                             t * extent * math.sqrt(self.var_y), indexing="ij")
        area = (2 * extent / n) ** 2 * math.sqrt(self.var_x * self.var_y)
        c, s = (1.0, 0.0) if self.phi_w is None else (math.cos(self.phi_w), math.sin(self.phi_w))
        zx, zy = (c * zu - s * zc).ravel(), (s * zu + c * zc).ravel()
        m = np.stack([-zx, -zy, np.ones_like(zx)], -1)
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        wi = np.broadcast_to([math.sin(theta), 0.0, math.cos(theta)], m.shape)
        cos_im = np.sum(wi * m, axis=1)
        wo = 2 * cos_im[:, None] * m - wi
        s_ = 1 / (1 + self.lam(wi) + self.lam(wo)) if self.shadowing else 1.0
        ok = (cos_im > 0) & (wo[:, 2] > 0)
        weight = np.where(ok, self.slope_pdf(zx, zy) * s_ * cos_im / (wi[:, 2] * m[:, 2]), 0.0)
        glint = area * weight @ fresnel(cos_im, self.eta, self.k, self.ext)
        if self.whitecaps is None:
            return glint
        w = coverage(self.u)
        return (1 - w) * glint + w * np.asarray(self.whitecaps, float)
