r"""
The Ross-Thick Li-Sparse-Reciprocal kernel model of the MODIS BRDF/albedo product in float64,
as the papers write it, with angles (θ, φ from arccos and arctan2), independent of
:mod:`mi_brdfs.scattering.rtls`, which works with vectors.

The bidirectional reflectance factor is linear in three kernels (Lucht, Schaaf & Strahler
2000, "An Algorithm for the Retrieval of Albedo from Space Using Semiempirical BRDF Models",
IEEE TGRS 38(2), eqs. 37-39; Wanner, Li & Strahler 1995, "On the derivation of kernels for
kernel-driven models of bidirectional reflectance", JGR 100(D10), §3):

    BRF = f_iso + f_vol K_vol + f_geo K_geo,    f = BRF/π,

with θi the solar zenith (ωi, towards the sun), θo the view zenith (ωo, towards the viewer),
φ their relative azimuth (0 when the viewer looks back along the sun's azimuth: the hot spot
is at ωo = ωi) and the phase angle cos ξ = cosθi cosθo + sinθi sinθo cos φ:

- Ross-Thick (Roujean, Leroy & Deschamps 1992, JGR 97(D18), normalised to 0 at nadir by
  Wanner et al. 1995, eq. 13): K_vol = ((π/2 − ξ) cos ξ + sin ξ)/(cosθi + cosθo) − π/4;
- Li-Sparse-Reciprocal (Lucht et al. 2000, eqs. 39-44; Wanner et al. 1995, eqs. 32, 40-44),
  on angles made equivalent to spheroids' of vertical over horizontal radius b/r,
  θ' = atan((b/r) tanθ), ξ' the phase angle of the primed angles:
  D = √(tan²θi' + tan²θo' − 2 tanθi' tanθo' cos φ),
  cos t = (h/b) √(D² + (tanθi' tanθo' sin φ)²)/(secθi' + secθo'), clipped to [−1, 1],
  O = (1/π)(t − sin t cos t)(secθi' + secθo'),
  K_geo = O − secθi' − secθo' + ½(1 + cos ξ') secθi' secθo'.

Both kernels are 0 at θi = θo = 0. The model is a linear fit and goes below 0: at normal
incidence K_geo = O − ½ − ½ secθo', and O = 0 once cos t reaches 1, so K_geo → −∞ as the view
grazes (likewise away from the hot spot at any θi), and every f_geo > 0 makes the BRF negative
near the horizon; at the hot spot K_geo = sec²θ' − secθ' → +∞ instead.
:meth:`RTLS.brf` returns the model's value; :meth:`RTLS.brdf` max(BRF, 0)/π, as the ``rtls``
plugin evaluates it.

The albedos MODIS reports from the kernels' integrals (:func:`black_sky_polynomial`,
:func:`white_sky_polynomial`, and their float64 quadratures :func:`kernel_black_sky`,
:func:`kernel_white_sky`) and its linear inversion of the weights (:func:`invert`) follow the
class.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .quadrature import gauss_legendre, hemisphere_albedo

#: The MODIS product's shape parameters (Lucht et al. 2000, §IV: h/b = 2, b/r = 1).
H, R, B = 2.0, 1.0, 1.0
#: The published integrals of the kernels for h/b = 2, b/r = 1 (Lucht et al. 2000, Table 1):
#: the white-sky albedo ∫∫ K cosθi cosθo dωi dωo/π² of each kernel, and the coefficients of
#: the black-sky albedo's fit g0 + g1 θ² + g2 θ³ in the solar zenith θ (radians).
WHITE_SKY = {"vol": 0.189184, "geo": -1.377622}
BLACK_SKY = {"vol": (-0.007574, -0.070987, 0.307588), "geo": (-1.284909, -0.166314, 0.041840)}


def angles(w) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of unit vectors (n, 3)."""
    w = np.atleast_2d(np.asarray(w, dtype=np.float64))
    return np.arccos(np.clip(w[:, 2], -1.0, 1.0)), np.arctan2(w[:, 1], w[:, 0])


def ross_thick(theta_i, theta_o, cos_xi) -> np.ndarray:
    """K_vol from the zenith angles and the phase angle's cosine."""
    xi = np.arccos(np.clip(cos_xi, -1.0, 1.0))
    return ((np.pi / 2 - xi) * np.cos(xi) + np.sin(xi)) / (np.cos(theta_i) + np.cos(theta_o)) \
        - np.pi / 4


def li_sparse_r(theta_i, theta_o, phi, h=H, r=R, b=B) -> np.ndarray:
    """K_geo from the zenith angles and the relative azimuth φ (0 at the hot spot)."""
    ti, to = (b / r) * np.tan(theta_i), (b / r) * np.tan(theta_o)
    pi_, po = np.arctan(ti), np.arctan(to)  # θ'
    sec_i, sec_o = 1.0 / np.cos(pi_), 1.0 / np.cos(po)
    d = np.sqrt(np.maximum(ti ** 2 + to ** 2 - 2.0 * ti * to * np.cos(phi), 0.0))
    cos_t = np.clip((h / b) * np.sqrt(d ** 2 + (ti * to * np.sin(phi)) ** 2) / (sec_i + sec_o),
                    -1.0, 1.0)
    t = np.arccos(cos_t)
    overlap = (t - np.sin(t) * cos_t) * (sec_i + sec_o) / np.pi
    cos_xi = np.cos(pi_) * np.cos(po) + np.sin(pi_) * np.sin(po) * np.cos(phi)
    return overlap - sec_i - sec_o + 0.5 * (1.0 + cos_xi) * sec_i * sec_o


class RTLS:
    """
    BRF = f_iso + f_vol K_vol + f_geo K_geo per channel (each f a scalar or per-channel
    array); ``h``, ``r``, ``b`` the Li-Sparse crowns' shape (only h/b and b/r matter).
    """

    def __init__(self, f_iso=0.209741, f_vol=0.081384, f_geo=0.004140, h=H, r=R, b=B):
        arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=np.float64))
                                       for x in (f_iso, f_vol, f_geo)))
        self.f_iso, self.f_vol, self.f_geo = (np.array(a) for a in arrays)
        self.h, self.r, self.b = float(h), float(r), float(b)

    def kernels(self, wi, wo) -> tuple[np.ndarray, np.ndarray]:
        """(K_vol, K_geo) at pairs of directions above the surface, (n,) each; NaN where one
        is not above (the kernels are defined for cosθ > 0 only)."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        (theta_i, phi_i), (theta_o, phi_o) = angles(wi), angles(wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        theta_i, theta_o = np.where(above, theta_i, 0.0), np.where(above, theta_o, 0.0)
        cos_xi = np.sum(wi * wo, axis=1)  # the phase angle: ωi·ωo
        k_vol = ross_thick(theta_i, theta_o, cos_xi)
        k_geo = li_sparse_r(theta_i, theta_o, phi_i - phi_o, self.h, self.r, self.b)
        return np.where(above, k_vol, np.nan), np.where(above, k_geo, np.nan)

    def brf(self, wi, wo) -> np.ndarray:
        """The model's BRF, (n, channels), negative where the fit is; 0 unless both
        directions are above the surface."""
        k_vol, k_geo = self.kernels(wi, wo)
        above = np.isfinite(k_vol)[:, None]
        value = self.f_iso[None, :] + self.f_vol[None, :] * np.nan_to_num(k_vol)[:, None] + \
            self.f_geo[None, :] * np.nan_to_num(k_geo)[:, None]
        return np.where(above, value, 0.0)

    def brdf(self, wi, wo) -> np.ndarray:
        """f = max(BRF, 0)/π, (n, channels): what the ``rtls`` plugin evaluates."""
        return np.maximum(self.brf(wi, wo), 0.0) / math.pi

    def albedo(self, theta: float, n_mu: int = 256, n_phi: int = 256) -> np.ndarray:
        """E(θ) = ∫ f cosθo dωo per channel (the clamped f), by quadrature."""
        if math.cos(theta) <= 0:
            return np.zeros_like(self.f_iso)
        return hemisphere_albedo(self.brdf, theta, n_mu, n_phi)

    def negative_share(self, n_mu: int = 48, n_phi: int = 48) -> tuple[float, float, tuple]:
        """
        Where the model's BRF is below 0 on a grid of direction pairs: (its share of the
        pairs weighted by cosθi cosθo dωi dωo/π², the white-sky measure, which sums to 1;
        the lowest BRF over the channels; (θi, θo, φ) in degrees of that lowest value).
        Gauss-Legendre in cosθ (the last node within 10⁻³ of the horizon for ``n_mu`` = 48)
        and the midpoint rule in φ, for both directions' relative azimuth.
        """
        x, w = gauss_legendre(n_mu)
        mu, w_mu = 0.5 * (x + 1.0), 0.5 * w
        phi = (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi)
        mi_, mo, ph = (a.ravel() for a in np.meshgrid(mu, mu, phi, indexing="ij"))
        weight = (np.outer(np.outer(w_mu * mu, w_mu * mu), np.full(n_phi, 2.0 / n_phi))).ravel()
        si, so = np.sqrt(1.0 - mi_ ** 2), np.sqrt(1.0 - mo ** 2)
        wi = np.stack([si, np.zeros_like(si), mi_], axis=1)
        wo = np.stack([so * np.cos(ph), so * np.sin(ph), mo], axis=1)
        low = self.brf(wi, wo).min(axis=1)
        k = int(np.argmin(low))
        where = tuple(float(np.degrees(a)) for a in (np.arccos(mi_[k]), np.arccos(mo[k]), ph[k]))
        return float(weight[low < 0].sum() / weight.sum()), float(low[k]), where

    def modis_shape(self) -> bool:
        """Whether the crowns are MODIS's (h/b = 2, b/r = 1), those of Lucht et al.'s
        published integrals."""
        return math.isclose(self.h / self.b, H / B) and math.isclose(self.b / self.r, B / R)

    def white_sky(self) -> np.ndarray:
        """The model's white-sky albedo, unclamped, per channel: the published integrals
        (:func:`white_sky_polynomial`) for MODIS's crowns, else the kernels' quadrature
        (:func:`kernel_white_sky`)."""
        if self.modis_shape():
            return white_sky_polynomial(self.f_iso, self.f_vol, self.f_geo)
        vol, geo = kernel_white_sky(self.h, self.r, self.b, 32, 128, 128)
        return self.f_iso + self.f_vol * vol + self.f_geo * geo


# -- albedos and the linear inversion (MODIS's) ----------------------------------------------

def black_sky_polynomial(theta, f_iso, f_vol, f_geo) -> np.ndarray:
    """
    The black-sky albedo (the directional-hemispherical reflectance at solar zenith θ, in
    radians) of the model, unclamped, by Lucht et al.'s (2000, eqs. 49-52, Table 1) fit of each
    kernel's integral ∫ K cosθo dωo/π, g0 + g1 θ² + g2 θ³, for h/b = 2, b/r = 1 only:
    f_iso + f_vol (g0 + g1 θ² + g2 θ³)_vol + f_geo (...)_geo. Shape: θ's broadcast with
    the weights'.
    """
    t = np.asarray(theta, dtype=np.float64)

    def g(k):
        g0, g1, g2 = BLACK_SKY[k]
        return g0 + g1 * t ** 2 + g2 * t ** 3
    return np.asarray(f_iso) + np.asarray(f_vol) * g("vol") + np.asarray(f_geo) * g("geo")


def white_sky_polynomial(f_iso, f_vol, f_geo) -> np.ndarray:
    """The white-sky albedo (bihemispherical reflectance under isotropic illumination) of the
    model, unclamped: f_iso + 0.189184 f_vol − 1.377622 f_geo (Lucht et al. 2000, eqs.
    49-52, Table 1; h/b = 2, b/r = 1 only)."""
    return np.asarray(f_iso) + WHITE_SKY["vol"] * np.asarray(f_vol) + \
        WHITE_SKY["geo"] * np.asarray(f_geo)


def kernel_black_sky(theta: float, h=H, r=R, b=B, n_mu: int = 512,
                     n_phi: int = 512) -> tuple[float, float]:
    """(∫ K_vol cosθo dωo/π, ∫ K_geo cosθo dωo/π) at solar zenith θ (radians) by float64
    quadrature (Gauss-Legendre in cosθo, the midpoint rule in φ): the exact counterpart of
    :func:`black_sky_polynomial`'s fits, for any crowns."""
    model = RTLS(h=h, r=r, b=b)
    both = hemisphere_albedo(lambda wi, wo: np.stack(model.kernels(wi, wo), axis=1) / math.pi,
                             theta, n_mu, n_phi)
    return float(both[0]), float(both[1])


def kernel_white_sky(h=H, r=R, b=B, n_theta: int = 64, n_mu: int = 256,
                     n_phi: int = 256) -> tuple[float, float]:
    """(∫ K_vol, ∫ K_geo) cosθi cosθo dωi dωo/π²: 2 ∫ of :func:`kernel_black_sky` cosθ sinθ dθ,
    Gauss-Legendre in cos²θ (which makes the weight cosθ sinθ dθ uniform)."""
    x, w = gauss_legendre(n_theta)
    s, w_s = 0.5 * (x + 1.0), 0.5 * w  # s = cos²θ on (0, 1): 2 cosθ sinθ dθ = ds
    rows = np.array([kernel_black_sky(math.acos(math.sqrt(si)), h, r, b, n_mu, n_phi)
                     for si in s])
    return float(w_s @ rows[:, 0]), float(w_s @ rows[:, 1])


def invert(wi, wo, brf, weights=None, bounds=(0.0, 1.0), h=H, r=R, b=B) -> np.ndarray:
    """
    The kernel weights (f_iso, f_vol, f_geo) that minimise Σ w (BRF_model − BRF)² over the
    direction pairs (wi, wo) (n, 3), ``brf`` (n,) the observed BRF, ``weights`` w (n,)
    (default 1), ``h``, ``r``, ``b`` the crowns': the linear inversion of the MODIS algorithm
    (Lucht et al. 2000: the model is linear in the weights), with each weight kept within
    ``bounds`` (the plugin's [0, 1]; None: unbounded). A least-squares
    problem with box bounds is convex, and its minimum is the unconstrained minimum on one
    face of the box (KKT: the free weights' gradient is 0 there): every face, 3³ of them, is
    solved and the best minimum inside the box kept.
    """
    k_vol, k_geo = RTLS(h=h, r=r, b=b).kernels(wi, wo)
    a = np.stack([np.ones_like(k_vol), k_vol, k_geo], axis=1)
    y = np.asarray(brf, dtype=np.float64).ravel()
    w = np.ones_like(y) if weights is None else np.asarray(weights, dtype=np.float64)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(y)) and len(y) >= 3):
        raise ValueError("invert: needs 3 or more pairs above the surface with finite BRFs")
    sw = np.sqrt(w)[:, None]
    if bounds is None:
        return np.linalg.lstsq(a * sw, y * sw[:, 0], rcond=None)[0]
    best, best_cost = None, np.inf
    for face in itertools.product((None, *bounds), repeat=3):  # None: free
        fixed = np.array([0.0 if v is None else v for v in face])
        free = [k for k, v in enumerate(face) if v is None]
        x = fixed.copy()
        if free:
            rest = y - a @ fixed
            x[free] = np.linalg.lstsq(a[:, free] * sw, rest * sw[:, 0], rcond=None)[0]
        if np.all(x >= bounds[0] - 1e-12) and np.all(x <= bounds[1] + 1e-12):
            cost = float(w @ (a @ x - y) ** 2)
            if cost < best_cost:
                best, best_cost = np.clip(x, *bounds), cost
    return best
