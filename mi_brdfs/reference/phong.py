r"""
Phong in the lecture's three forms and two lobes, float64: f(L, V) as the formulas are written
(``pow``, dot products, no stabilisation: float64 keeps them accurate to n ≈ 1e12), and the
directional albedo by a lobe-aligned quadrature that resolves any exponent.

Albedo. E(θ) = ∫ f cosθo dωo in radiance transport (V = ωi at angle θ, L = ωo). The specular
part is integrated in the lobe's own coordinates: rings of constant angle to the lobe's axis (R
for the mirror lobe; the normal, for H, with the halfway lobe), with u = cos^(n+1) of that angle
as the variable, so that ∫ cosⁿ g dω = 1/(n+1) ∫₀¹ du ∫ g dφ at any n. On each ring the part of
the ring that reflects above the horizon is an arc |φ| < φ0 and the integrand a polynomial in
cos φ, so the φ-integral is exact; the u-integral is Gauss-Legendre on the pieces between the
angles where rings start and stop crossing the horizon (where it has a square-root kink). Checked
against brute-force quadrature of :meth:`Phong.brdf` and the closed forms at normal incidence in
``tests/reference/test_phong_reference.py``.
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import cosine_power_integral

FORMS = ("normalized", "lecture", "original")
LOBES = ("mirror", "halfway")

#: Gauss-Legendre nodes per piece of the u-integral: doubling them moves the integral far below
#: the tolerances of any check that uses it.
NODES = 400


def _unit(v) -> np.ndarray:
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


class Phong:
    """
    f(L, V) = ρd/π + ks·c·cosⁿα [/ (N·L) for ``original``], both directions above the surface
    (one-sided, like Mitsuba), with c = (n+2)/(2π) (normalized mirror), Giesen's
    (n+2)(n+4)/(8π(n + 2^(−n/2))) (normalized halfway), or 1.
    """

    def __init__(self, diffuse=0.5, specular=0.2, exponent=30.0, form="normalized",
                 lobe="mirror"):
        if form not in FORMS or lobe not in LOBES:
            raise ValueError(f"form must be one of {FORMS} and lobe one of {LOBES}")
        self.rho_d = np.atleast_1d(np.asarray(diffuse, dtype=np.float64))
        self.k_s = np.atleast_1d(np.asarray(specular, dtype=np.float64))
        self.n, self.form, self.lobe = float(exponent), form, lobe

    @property
    def normalization(self) -> float:
        n = self.n
        if self.form != "normalized":
            return 1.0
        if self.lobe == "mirror":
            return (n + 2) / (2 * math.pi)
        return (n + 2) * (n + 4) / (8 * math.pi * (n + 2.0 ** (-n / 2)))

    def specular_lobe(self, light, view) -> np.ndarray:
        """cosⁿα · c [/ N·L] for ks = 1: the specular part of f, (n,)."""
        L, V = _unit(light), _unit(view)
        if self.lobe == "mirror":
            R = 2 * L[:, 2:3] * np.array([0.0, 0.0, 1.0]) - L
            cos = np.sum(R * V, axis=1)
        else:
            cos = _unit(L + V)[:, 2]
        # cos ≤ 1 up to rounding, which cos^n would blow up for n ≳ 1e16
        value = np.where(cos > 0, np.clip(cos, 0.0, 1.0) ** self.n, 0.0) * self.normalization
        if self.form == "original":
            value = value / np.where(L[:, 2] > 0, L[:, 2], 1.0)
        return value

    def brdf(self, wi, wo, mode: str = "radiance") -> np.ndarray:
        """
        f(wi, wo), (n, channels). Mitsuba's convention: ``wi`` is the viewer in ``radiance``
        transport (L = wo) and the light in ``importance`` transport (L = wi).
        """
        wi, wo = _unit(wi), _unit(wo)
        light, view = (wo, wi) if mode == "radiance" else (wi, wo)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        f = self.rho_d[None, :] / np.pi + \
            self.k_s[None, :] * self.specular_lobe(light, view)[:, None]
        return np.where(above[:, None], f, 0.0)

    # -- albedo -----------------------------------------------------------------------------------

    def _ring_integral(self, cos_a, sin_a, theta):
        """
        ∫ g dφ over one ring at angle a to the lobe's axis (arrays), where the specular part of
        E is c/(n+1) ∫₀¹ (ring integral) du. g = cosθo (or 1 for ``original``) where ωo is above
        the surface, times the Jacobian 4 ωo·H of the halfway lobe.
        """
        ci, si = math.cos(theta), math.sin(theta)
        projected = self.form != "original"  # original: f cosθo = ks cosⁿα (L = ωo)
        if self.lobe == "mirror":
            # cosθo = a + b cos φ about R (R at angle θ)
            a, b = cos_a * ci, sin_a * si
            phi0 = _arc(a, b)
            return 2 * (a * phi0 + b * np.sin(phi0)) if projected else 2 * phi0
        # H at angle a to N: ωi·H = a + b cos φ, cosθo = 2(ωi·H) cos a − cos θ > 0 on the arc
        a, b = ci * cos_a, si * sin_a
        phi0 = _arc(2 * cos_a * a - ci, 2 * cos_a * b)
        s, c = np.sin(phi0), np.cos(phi0)
        first = 2 * a * phi0 + 2 * b * s                                   # ∫ (a + b cos φ)
        if not projected:
            return 4 * first
        second = 2 * a * a * phi0 + 4 * a * b * s + b * b * (phi0 + s * c)  # ∫ (a + b cos φ)²
        return 4 * (2 * cos_a * second - ci * first)

    def _kinks(self, theta: float) -> list[float]:
        """Angles to the lobe's axis where rings start or stop crossing the horizon."""
        if self.lobe == "mirror":
            return [math.pi / 2 - theta]
        return [(math.pi / 2 - theta) / 2, (math.pi / 2 + theta) / 2]

    def specular_albedo(self, theta: float) -> float:
        """E(θ) of the specular part with ks = 1."""
        if math.cos(theta) <= 0:
            return 0.0
        # u = cos^(n+1)(angle): the kinks in u, ascending (large angles give small u)
        cuts = sorted({min(max(math.cos(a), 0.0) ** (self.n + 1.0), 1.0)
                       for a in self._kinks(theta) if 0 < a < math.pi / 2})
        return self.normalization * cosine_power_integral(
            self.n, cuts, lambda cos_a, sin_a: self._ring_integral(cos_a, sin_a, theta), NODES)

    def albedo(self, theta: float) -> np.ndarray:
        """E(θ) per channel: ρd + ks·(specular albedo) above the surface, 0 below."""
        if math.cos(theta) <= 0:
            return np.zeros(max(len(self.rho_d), len(self.k_s)))
        return self.rho_d + self.k_s * self.specular_albedo(theta)


def _arc(a, b):
    """φ0 ∈ [0, π] with a + b cos φ > 0 exactly for |φ| < φ0 (b ≥ 0)."""
    b = np.asarray(b, dtype=np.float64)
    ratio = np.where(b > 0, -a / np.where(b > 0, b, 1.0), np.where(a > 0, -np.inf, np.inf))
    return np.arccos(np.clip(ratio, -1.0, 1.0))
