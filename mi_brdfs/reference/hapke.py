r"""
Hapke's bidirectional reflectance of a particulate surface in float64, as the papers write it,
with angles (i, e, ψ, g from arccos and arctan2), independent of
:mod:`mi_brdfs.scattering.hapke`, which works with vectors.

The bidirectional reflectance (Hapke 2012, "Theory of Reflectance and Emittance Spectroscopy",
2nd ed., Cambridge University Press, eq. 12.55 with the porosity factor K = 1 and without the
coherent-backscatter term; Hapke 1984, "Bidirectional reflectance spectroscopy 3. Correction
for macroscopic roughness", Icarus 59, 41-59; Hapke 1986, Icarus 67, 264-280), i the angle of
incidence (ωi, towards the source), e of emergence (ωo, towards the viewer), g the phase
angle (cos g = ωi·ωo: g = 0 at ωo = ωi) and ψ the azimuth between them (0 at ωo = ωi):

    r = (w/4π) μ0e/(μ0e + μe) [p(g)(1 + B(g)) + H(μ0e) H(μe) − 1] S(i, e, ψ),   f = r/cos i,

- p(g): the double Henyey-Greenstein phase function, p = (1 − c) HG(−b) + c HG(b) with
  HG(±b) = (1 − b²)/(1 ∓ 2b cos g + b²)^{3/2}: c is the weight of the backward lobe (peaked
  at g = 0), 1 − c of the forward one (Hapke 2012 eq. 6.7b's form with c in [0, 1]; eq. 6.7a
  writes (1 + c')/2 for the backward lobe: c' = 2c − 1);
- B(g) = B_0/(1 + tan(g/2)/h): the shadow-hiding opposition effect (Hapke 1986, eq. 8;
  Hapke 2012 eq. 9.22), B(0) = B_0 at every h (h = 0: B_0 at g = 0 alone, 0 elsewhere);
- H(x) = 1/(1 − w x [r0 + (1 − 2 r0 x)/2 ln((1 + x)/x)]), r0 = (1 − γ)/(1 + γ), γ = √(1 − w):
  Hapke's (2002, "Bidirectional reflectance spectroscopy 5", Icarus 157, 523-534, eq. 13)
  approximation of Chandrasekhar's H-function of isotropic scattering (:func:`h_exact` is
  the exact one, for the tests);
- the macroscopic roughness θ̄ (Hapke 1984, eqs. 45-51; Hapke 2012 eqs. 12.45-12.54): the
  effective cosines μ0e, μe and the shadowing S (:func:`roughness`). At θ̄ = 0: μ0e = cos i,
  μe = cos e, S = 1.

Where i = 0 or e = 0 the azimuth ψ is undefined; every term that reads ψ is multiplied there by
sin i, E1(i) or E2(i) (sin e, E1(e), E2(e)), which are 0, and the shadowing's denominator is
1 − f(ψ) + f(ψ)·χ·cos i/η(i) with χ cos i/η(i) = 1 at i = 0: the limits are those of the
formulas with ψ = 0 (:func:`roughness` takes it), and so it evaluates them.
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import gauss_legendre, hemisphere_albedo

#: Eradiate's defaults (its C++ plugin, src/bsdfs/hapke.cpp of eradiate-mitsuba 0.5.0).
DEFAULTS = {"w": 0.5, "b": 0.2, "c": 0.5, "theta": 30.0, "B_0": 0.0, "h": 0.0}
#: Chandrasekhar's H(μ = 1) for conservative isotropic scattering (w = 1): Chandrasekhar 1960,
#: "Radiative Transfer", Dover, Table XI (the H-function for ϖ0 = 1).
H_CONSERVATIVE_1 = 2.90781


def h_function(w, x):
    """Hapke's (2002, eq. 13) approximation of the H-function at cosine ``x`` ≥ 0."""
    w, x = np.asarray(w, dtype=np.float64), np.asarray(x, dtype=np.float64)
    gamma = np.sqrt(1.0 - w)
    r0 = (1.0 - gamma) / (1.0 + gamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_term = np.where(x > 0, x * np.log((1.0 + x) / x), 0.0)  # x ln(1/x) → 0
    return 1.0 / (1.0 - w * (r0 * x + (1.0 - 2.0 * r0 * x) / 2.0 * log_term))


def h_exact(w: float, x, n: int = 4000):
    """
    Chandrasekhar's H-function of isotropic scattering of albedo ``w`` at cosines ``x``, from
    its explicit integral ln H(μ) = −(μ/π) ∫₀^{π/2} ln(1 − w t cot t)/(cos²t + μ² sin²t) dt
    (Chandrasekhar 1960, "Radiative Transfer", Dover, ch. V), by Gauss-Legendre quadrature on
    ``n`` nodes in t. Exact to about 10⁻⁸ for w = 1 (Chandrasekhar's H(1) = 2.90781), better
    below.
    """
    t, wt = gauss_legendre(n)
    t, wt = 0.25 * math.pi * (t + 1.0), 0.25 * math.pi * wt
    log_term = np.log(1.0 - w * t / np.tan(t))
    x = np.atleast_1d(np.asarray(x, dtype=np.float64))
    integral = (wt * log_term / (np.cos(t) ** 2 + np.outer(x ** 2, np.sin(t) ** 2))).sum(axis=1)
    return np.exp(-x / math.pi * integral)


def phase(b, c, cos_g):
    """The double Henyey-Greenstein p(g): c the backward lobe's weight (its mean over the
    sphere is 1: ∫ p dω/4π = 1)."""
    one = 1.0 - b * b
    forward = one / (1.0 + 2.0 * b * cos_g + b * b) ** 1.5
    backward = one / (1.0 - 2.0 * b * cos_g + b * b) ** 1.5
    return (1.0 - c) * forward + c * backward


def opposition(B_0, h, g):
    """B(g) = B_0/(1 + tan(g/2)/h); B_0 at g = 0 for every h (h = 0: 0 elsewhere)."""
    t = np.tan(np.asarray(g, dtype=np.float64) / 2.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        value = B_0 / (1.0 + t / h)
    return np.where(t == 0.0, B_0, np.where(h > 0, value, 0.0))


def _e1(tan_bar, x):
    """E1(x) = exp(−(2/π) cot θ̄ cot x) (Hapke 1984, eq. 45b)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.exp(-2.0 / math.pi / (tan_bar * np.tan(x)))


def _e2(tan_bar, x):
    """E2(x) = exp(−(1/π) cot²θ̄ cot²x) (Hapke 1984, eq. 45c)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.exp(-1.0 / math.pi / (tan_bar * np.tan(x)) ** 2)


def _eta(chi, tan_bar, x):
    """η(x) = χ[cos x + sin x tan θ̄ E2(x)/(2 − E1(x))], the effective cosine at ψ = 0
    without the other direction (Hapke 1984, eqs. 47, 48)."""
    return chi * (np.cos(x) + np.sin(x) * tan_bar * _e2(tan_bar, x) / (2.0 - _e1(tan_bar, x)))


def roughness(i, e, psi, theta_bar):
    """
    (μ0e, μe, S) of Hapke's (1984) macroscopic roughness θ̄ (radians) at the angles i, e and
    the azimuth ψ ∈ [0, π] (arrays): eqs. 46, 49 (i ≤ e) and 50, 51 (e ≤ i), with
    χ = 1/√(1 + π tan²θ̄) and f(ψ) = exp(−2 tan(ψ/2)). ψ is taken as 0 where i = 0 or e = 0
    (the limits: the module's docstring).
    """
    i, e, psi = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (i, e, psi)))
    if theta_bar == 0.0:
        return np.cos(i), np.cos(e), np.ones_like(i)
    psi = np.where((i == 0) | (e == 0), 0.0, psi)
    tan_bar = math.tan(theta_bar)
    chi = 1.0 / math.sqrt(1.0 + math.pi * tan_bar ** 2)
    s2 = np.sin(psi / 2.0) ** 2
    with np.errstate(over="ignore"):
        f = np.exp(-2.0 * np.tan(psi / 2.0))
    e1i, e1e, e2i, e2e = _e1(tan_bar, i), _e1(tan_bar, e), _e2(tan_bar, i), _e2(tan_bar, e)
    eta_i, eta_e = _eta(chi, tan_bar, i), _eta(chi, tan_bar, e)
    # i ≤ e (eqs. 46, 49)
    den = 2.0 - e1e - psi / math.pi * e1i
    mu0e_a = chi * (np.cos(i) + np.sin(i) * tan_bar * (np.cos(psi) * e2e + s2 * e2i) / den)
    mue_a = chi * (np.cos(e) + np.sin(e) * tan_bar * (e2e - s2 * e2i) / den)
    low_a = np.cos(i) / eta_i  # the smaller angle's μ/η
    # e ≤ i (eqs. 50, 51)
    den = 2.0 - e1i - psi / math.pi * e1e
    mu0e_b = chi * (np.cos(i) + np.sin(i) * tan_bar * (e2i - s2 * e2e) / den)
    mue_b = chi * (np.cos(e) + np.sin(e) * tan_bar * (np.cos(psi) * e2i + s2 * e2e) / den)
    low_b = np.cos(e) / eta_e
    first = i <= e
    mu0e, mue = np.where(first, mu0e_a, mu0e_b), np.where(first, mue_a, mue_b)
    low = np.where(first, low_a, low_b)
    shadow = (mue / eta_e) * (np.cos(i) / eta_i) * chi / (1.0 - f + f * chi * low)
    return mu0e, mue, shadow


def angles(wi, wo):
    """(i, e, ψ ∈ [0, π], g) of pairs of unit vectors (n, 3) above the surface."""
    wi, wo = (np.atleast_2d(np.asarray(w, dtype=np.float64)) for w in (wi, wo))
    i = np.arccos(np.clip(wi[:, 2], -1.0, 1.0))
    e = np.arccos(np.clip(wo[:, 2], -1.0, 1.0))
    psi = np.abs(np.arctan2(wi[:, 1], wi[:, 0]) - np.arctan2(wo[:, 1], wo[:, 0]))
    psi = np.where(psi > math.pi, 2.0 * math.pi - psi, psi)
    # cos g = cos i cos e + sin i sin e cos ψ as the haversine, exact at g = 0
    half = np.sin((i - e) / 2) ** 2 + np.sin(i) * np.sin(e) * np.sin(psi / 2) ** 2
    return i, e, psi, 2.0 * np.arcsin(np.sqrt(np.clip(half, 0.0, 1.0)))


class Hapke:
    """
    Hapke's model per channel: ``w``, ``b``, ``c``, ``B_0``, ``h`` scalars or per-channel
    arrays, ``theta`` θ̄ in degrees (Eradiate's unit); ``exact_h``: Chandrasekhar's exact
    H-function (:func:`h_exact`) instead of Hapke's approximation, for the tests.
    """

    NAMES = ("w", "b", "c", "theta", "B_0", "h")

    def __init__(self, w=0.5, b=0.2, c=0.5, theta=30.0, B_0=0.0, h=0.0, exact_h=False):
        #: the H-function: Hapke's approximation (the model), or Chandrasekhar's exact one
        self.h_function = (lambda w, x: h_exact(w, x.ravel()).reshape(x.shape)) if exact_h \
            else h_function
        arrays = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=np.float64))
                                       for x in (w, b, c, theta, B_0, h)))
        self.w, self.b, self.c, self.theta, self.B_0, self.h = (np.array(a) for a in arrays)

    def reflectance(self, wi, wo) -> np.ndarray:
        """Hapke's bidirectional reflectance r, (n, channels); 0 unless both directions are
        above the surface."""
        wi, wo = (np.atleast_2d(np.asarray(w, dtype=np.float64)) for w in (wi, wo))
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        i, e, psi, g = angles(np.where(above[:, None], wi, [0, 0, 1]),
                              np.where(above[:, None], wo, [0, 0, 1]))
        return np.where(above[:, None], self.reflectance_at(i, e, psi, g), 0.0)

    def reflectance_at(self, i, e, psi, g) -> np.ndarray:
        """r at the angles i, e, ψ ∈ [0, π], g (radians, (n,) each; g need not be the phase
        angle of the others: the tests move it alone), (n, channels)."""
        out = np.zeros((len(i), len(self.w)))
        for k in range(len(self.w)):
            w, b, c, b0, h = self.w[k], self.b[k], self.c[k], self.B_0[k], self.h[k]
            mu0e, mue, shadow = roughness(i, e, psi, math.radians(self.theta[k]))
            single = phase(b, c, np.cos(g)) * (1.0 + opposition(b0, h, g))
            multiple = self.h_function(w, mu0e) * self.h_function(w, mue) - 1.0
            out[:, k] = w / (4 * math.pi) * mu0e / (mu0e + mue) * (single + multiple) * shadow
        return out

    def brdf(self, wi, wo) -> np.ndarray:
        """f = r/cos i, (n, channels): what the ``hapke`` plugin evaluates."""
        wi = np.atleast_2d(np.asarray(wi, dtype=np.float64))
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(wi[:, 2:3] > 0, self.reflectance(wi, wo) / wi[:, 2:3], 0.0)

    def albedo(self, theta: float, n_mu: int = 256, n_phi: int = 256) -> np.ndarray:
        """E(θ) = ∫ f cosθo dωo per channel, by quadrature (θ in radians)."""
        if math.cos(theta) <= 0:
            return np.zeros_like(self.w)
        return hemisphere_albedo(self.brdf, theta, n_mu, n_phi)

    def max_albedo(self, n_theta: int = 16, n_mu: int = 48, n_phi: int = 48):
        """(the largest directional albedo over the channels, θi in degrees where it is) on
        θi = arccos of Gauss-Legendre nodes in cosθi."""
        x, _ = gauss_legendre(n_theta)
        thetas = np.arccos(0.5 * (x + 1.0))
        values = np.array([self.albedo(t, n_mu, n_phi).max() for t in thetas])
        k = int(np.argmax(values))
        return float(values[k]), float(np.degrees(thetas[k]))
