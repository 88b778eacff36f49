r"""
Hanrahan & Krueger's single-scattering layer in drjit, for every variant: the formulas of
:mod:`mi_brdfs.reference.hk` (Hanrahan & Krueger 1993, "Reflection from Layered Surfaces due to
Subsurface Scattering", §3-4; Chandrasekhar 1960, "Radiative Transfer", §46), ωi above the
surface (the plugin flips a pair from below), in float32-stable forms: 1 − e^{−x} by ``expm1``,
and the transmission's (e^{−τ/μo'} − e^{−τ/μi'})/(μo' − μi') as e^{−τ/μ₊} τ/(μ₋μ₊) ·
(1 − e^{−y})/y with μ₋ ≤ μ₊ the two cosines and y = τ(1/μ₋ − 1/μ₊) ≥ 0, finite at μo' = μi'
(the ratio's limit, 1) and at grazing angles (y → ∞: 0).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import fresnel
from .stable import expm1

#: The smallest refracted cosine used (η = 1 at grazing incidence: μ' = 0).
MU_MIN = 1e-6


def inside(w, eta: float):
    """(μ', T, the refracted direction inside the slab on w's side) of an outside direction w:
    Snell's law and the Fresnel transmittance 1 − F(|cosθ|, η)."""
    f, cos_t, _, _ = fresnel.dielectric(dr.abs(w.z), eta)
    mu = dr.maximum(dr.abs(cos_t), MU_MIN)
    d = mi.Vector3f(w.x / eta, w.y / eta, dr.sign(w.z) * mu)
    return mu, 1.0 - f, d


def hg(cos_theta, g: float):
    """Henyey-Greenstein's phase function, normalised to 1 over the sphere."""
    denom = dr.maximum(1.0 + g * g - 2.0 * g * cos_theta, 1e-12)
    return (1.0 - g * g) * dr.inv_four_pi * dr.rsqrt(denom) / denom


def sample_hg(axis, g: float, u):
    """A direction drawn from HG(g) about the unit vector ``axis`` (cosθ by inversion of its
    cumulative distribution, Henyey & Greenstein 1941), and its density."""
    if abs(g) < 1e-4:
        cos_t = 1.0 - 2.0 * u.x
    else:
        s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x)
        cos_t = (1.0 + g * g - s * s) / (2.0 * g)
    cos_t = dr.clip(cos_t, -1.0, 1.0)
    sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
    sin_p, cos_p = dr.sincos(dr.two_pi * u.y)
    local = mi.Vector3f(sin_t * cos_p, sin_t * sin_p, cos_t)
    return mi.Frame3f(axis).to_world(local), hg(cos_t, g)


def _one_minus_exp_over(y):
    """(1 − e^{−y})/y for y ≥ 0, 1 at y = 0."""
    small = y < 1e-4
    return dr.select(small, 1.0 - 0.5 * y, -expm1(-y) / dr.select(small, 1.0, y))


def single(wi, wo, albedo, tau, g: float, eta: float, rho, base: bool):
    """
    f·|cosθo| of the single model for ωi above the surface: reflection (with the base term
    ρ T_i T_o e^{−τ(1/μi' + 1/μo')}/(πη²) where ``base``), and, without a base, transmission
    for ωo below. ``albedo``, ``tau``, ``rho``: spectra.
    """
    mu_i, t_i, d_i = inside(wi, eta)
    mu_o, t_o, d_o = inside(wo, eta)
    cos_theta = -dr.dot(d_i, d_o)
    common = albedo * (hg(cos_theta, g) * t_i * t_o / (eta * eta))
    above = wo.z > 0
    sum_inv = dr.rcp(mu_i) + dr.rcp(mu_o)
    f_r = common * (-expm1(-tau * sum_inv)) / (mu_i + mu_o)
    if base:
        f_r = f_r + rho * (t_i * t_o * dr.inv_pi / (eta * eta)) * dr.exp(-tau * sum_inv)
        return dr.select(above, f_r, 0.0) * dr.abs(wo.z)
    lo, hi = dr.minimum(mu_i, mu_o), dr.maximum(mu_i, mu_o)
    y = tau * (dr.rcp(lo) - dr.rcp(hi))
    f_t = common * dr.exp(-tau / hi) * (tau / (lo * hi)) * _one_minus_exp_over(y)
    return dr.select(above, f_r, f_t) * dr.abs(wo.z)


def unscattered(wi, tau, eta: float):
    """The beam straight through the slab, T² e^{−τ/μi'} (a spectrum)."""
    mu, t, _ = inside(wi, eta)
    return t * t * dr.exp(-tau / mu)


def unscattered_all(wi, tau, eta: float):
    """The unscattered beams of every internal reflection where η > 1: (through the slab
    along −ωi, T² t/(1 − F² t²); back along the mirror, T² F t²/(1 − F² t²)), t = e^{−τ/μi'}
    the slab's transmittance and F the faces' reflectance at the beam's angle, the same
    inside and out (Stokes's relations): geometric series of the beam's round trips."""
    mu, t, _ = inside(wi, eta)
    f = 1.0 - t
    through = dr.exp(-tau / mu)
    rest = dr.rcp(1.0 - f * f * through * through)
    return t * t * through * rest, t * t * f * through * through * rest
