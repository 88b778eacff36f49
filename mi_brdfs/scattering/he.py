r"""
He, Torrance, Sillion & Greenberg's BRDF (1991, "A Comprehensive Physical Model for Light
Reflection", SIGGRAPH, §4 and its appendix; "HTSG") in drjit, for every variant: the terms of
the future ``he`` plugin, per channel of wavelength λ (µm), rms roughness σ0 and
autocorrelation length τ (µm), index η + ik. The float64 counterpart, with the derivations and
the three readings of the paper, is :mod:`mi_brdfs.reference.he`; the equations:

* S(θ) = (1 − ½ erfc a)/(1 + Λ), a = τ cotθ/(2σ0), Λ = ½(E/(√π a) − erfc a), E = e^(−a²)
  with the errata, 1 as printed (Eqs. 24-25);
* σ = σ0/√(1 + x²), x e^(x²/2) = (K_i + K_o)/√(8π), K = tanθ erfc(τ cotθ/(2σ0)) (Eqs. 80-83),
  solved by Newton's method on ln x + x²/2 (:func:`solve_x`);
* g = (2πσ(cosθi + cosθo)/λ)² (Eq. 79);
* ρ_dd = |F|² G S D/(π cosθi cosθo), G = (v̂·v̂)²/v̂_z², v̂ = ωi + ωo (Eq. 76 reduced),
  D = (πτ/2λ)² Σ_{m≥1} g^m e^(−g)/(m!·m)·e^(−c/m), c = v_xy²τ²/4 (Eqs. 71, 78), v_xy in wave
  numbers (k v̂_xy, Westin's code) or unit vectors (as printed);
* ρ_s = |F(θi)|² e^(−g) S, the weight of the specular delta (Eqs. 73-74).

The series is summed over a window of ``terms`` consecutive m (:func:`series`), each term in
logarithms (e^(−g) alone underflows float32 from g ≈ 88), from m = 1, or centred on m ≈ g where
the Poisson weights g^m e^(−g)/m! concentrate. Against the converged float64 series, the part
a window leaves is below 10⁻⁶ up to g = 22 for 48 terms from m = 1 (``westin`` needs g ≤ 18.5,
beyond which it takes Beckmann's asymptote), and up to g = 163 for 128 terms centred (the
``paper`` reading's default; raise ``terms`` for rougher surfaces):
``tests/scattering/test_he_terms.py::test02_the_paper_reading_and_where_its_window_stops``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr

from .fresnel import exact as fresnel_exact
from .stable import log1p

#: The wavelengths (µm) RGB variants evaluate the wave-optical terms at, red, green, blue: those
#: of bsdfbenchmark/bbm's RGB configuration (backbone/*/include/backbone.h,
#: https://github.com/bsdfbenchmark/bbm), with which Ngan et al.'s He fits it ships are used.
RGB_WAVELENGTHS = (0.645, 0.526, 0.444)
#: The wavelength (µm) of monochrome variants: the middle of the visible range.
MONO_WAVELENGTH = 0.55
#: bbm's default surface (σ0, τ) in µm, the ``he`` plugin's.
DEFAULT_SIGMA0, DEFAULT_TAU = 0.18, 3.0

#: Newton steps of :func:`solve_x` (float32 converges in at most 5 from its starts).
NEWTON_STEPS = 8


@dataclass(frozen=True)
class Reading:
    """One reading of the paper (:data:`READINGS`): e^(−a²) in Eq. 25, v_xy in wave numbers,
    the series' default length and start, and the g above which Beckmann's asymptote replaces
    the series (None: never)."""
    errata_shadowing: bool
    wavenumber: bool
    terms: int
    centred: bool
    rough_threshold: float | None


#: The three readings of :mod:`mi_brdfs.reference.he`: ``paper`` (as printed; the series to
#: convergence, here a centred window), ``westin`` (Westin et al.'s code) and ``holzschuch``
#: (Holzschuch & Pacanowski's reading: ten terms).
READINGS = {"paper": Reading(False, False, 128, True, None),
            "westin": Reading(True, True, 48, False, 18.5),
            "holzschuch": Reading(True, False, 10, False, None)}


def _erfc(x):
    return 1.0 - dr.erf(x)


def shadowing(cos_theta, sigma0, tau, errata: bool):
    """S(θ) (Eqs. 24-25): 1 at normal incidence or σ0 = 0, 0 at and below the horizon."""
    c = dr.minimum(cos_theta, 1.0)
    s = dr.safe_sqrt(1.0 - c * c)
    ok = (c > 0) & (s > 0) & (sigma0 > 0)
    a = dr.select(ok, tau * c / dr.select(ok, 2.0 * sigma0 * s, 1.0), 1.0)
    e = _erfc(a)
    damp = dr.exp(-a * a) if errata else 1.0
    # a → 0 (τ → 0): Λ → ∞ and S → 0; the floor keeps Python floats from dividing by 0
    lam = 0.5 * (damp / (math.sqrt(math.pi) * dr.maximum(a, 1e-30)) - e)
    value = (1.0 - 0.5 * e) / (1.0 + lam)
    return dr.select(c > 0, dr.select(ok, value, 1.0), 0.0)


def _k(cos_theta, sigma0, tau):
    """K = tanθ erfc(τ cotθ/(2σ0)) (Eqs. 82-83): 0 at normal incidence and for σ0 = 0
    (erfc(∞) = 0)."""
    c = dr.maximum(cos_theta, 1e-12)
    t = dr.safe_sqrt(1.0 - c * c) / c
    ok = (t > 0) & (sigma0 > 0)  # both factors: Python floats divide before the select
    return dr.select(ok, t * _erfc(tau / dr.select(ok, 2.0 * sigma0 * t, 1.0)), 0.0)


def solve_x(f0):
    """x ≥ 0 with x e^(x²/2) = f0: Newton's method on h = ln x + x²/2 − ln f0 from above
    (f0 ≤ √e: x = f0; else √(2 ln f0)); where h is concave the first step lands below the root
    and the next ones climb to it, where convex they descend to it."""
    log_f0 = dr.log(dr.maximum(f0, 1e-30))
    x = dr.select(f0 <= math.exp(0.5), f0, dr.safe_sqrt(2.0 * log_f0))
    x = dr.maximum(x, 1e-30)
    for _ in range(NEWTON_STEPS):
        h = dr.log(x) + 0.5 * x * x - log_f0
        x = dr.maximum(x - x * h / (1.0 + x * x), 1e-30)
    return dr.select(f0 > 0, x, 0.0)


def effective_roughness(cos_i, cos_o, sigma0, tau):
    """σ = σ0/√(1 + x²) (Eqs. 80-83): the roughness shadowing leaves visible."""
    f0 = (_k(cos_i, sigma0, tau) + _k(cos_o, sigma0, tau)) * (1.0 / math.sqrt(8.0 * math.pi))
    x = solve_x(f0)
    return sigma0 * dr.rsqrt(1.0 + x * x)


def log_poisson(m, g, log_g):
    """
    ln(g^m e^(−g)/m!) for m ≥ 1. Where m > 16, by Stirling's series for ln m! with the large
    terms cancelled analytically, (m − g) − m ln(1 + (m − g)/g) − ½ ln(2πm) − 1/(12m) +
    1/(360m³) (its error below 1/(1260m⁵)): the direct m ln g − g − ln Γ(m + 1) subtracts
    numbers of size g ln g, which float32 holds to g ln g · 6·10⁻⁸ — 5·10⁻⁵ at g = 160 and
    beyond e^88, an infinite term, at g = 10⁸ (σ0 ≈ 500 µm).
    """
    direct = m * log_g - g - dr.lgamma(m + 1.0)
    d = m - g
    stirling = d - m * log1p(d / dr.maximum(g, 1e-30)) - 0.5 * dr.log(2.0 * math.pi * m) - \
        1.0 / (12.0 * m) + 1.0 / (360.0 * m * m * m)
    return dr.select(m > 16.0, stirling, direct)


def series(g, c, terms: int, centred: bool):
    """Σ g^m e^(−g)/(m!·m)·e^(−c/m) over ``terms`` consecutive m: from m = 1, or from
    max(1, ⌊g − terms/2⌋) (``centred``); 0 where g = 0."""
    log_g = dr.log(dr.maximum(g, 1e-30))
    start = dr.maximum(dr.floor(g - 0.5 * terms), 1.0) if centred else 1.0
    # ln of Poisson's g^m e^(−g)/m! at m = start, then by its ratio g/(m + 1)
    log_p = log_poisson(start, g, log_g) if centred else log_g - g
    total = 0.0
    for j in range(terms):
        m = start + j
        total = total + dr.exp(log_p - dr.log(m) - c / m)
        log_p = log_p + log_g - dr.log(m + 1.0)
    return dr.select(g > 0, total, 0.0)


def rough_asymptote(g, c):
    """Σ for g ≫ 1: e^(−c/g)/g (Beckmann & Spizzichino 1963, §5.3, Eq. 47)."""
    ok = g > 0
    gs = dr.select(ok, g, 1.0)
    return dr.select(ok, dr.exp(-c / gs) / gs, 0.0)


def phase_variance(sigma, cos_i, cos_o, wavelength):
    """g = (2πσ(cosθi + cosθo)/λ)² (Eq. 79), per channel of λ."""
    return dr.square((2.0 * math.pi) * sigma * (cos_i + cos_o) / wavelength)


def directional_diffuse(wi, wo, sigma0, tau, wavelength, eta, k, reading: Reading,
                        terms: int | None = None):
    """ρ_dd (Eq. 71) per channel, 0 unless both directions are above the surface."""
    ci, co = wi.z, wo.z
    above = (ci > 0) & (co > 0)
    v = wi + wo
    vv = dr.dot(v, v)
    vz = dr.select(above, v.z, 1.0)
    geometry = vv * vv / (vz * vz)
    s = shadowing(ci, sigma0, tau, reading.errata_shadowing) * \
        shadowing(co, sigma0, tau, reading.errata_shadowing)
    sigma = effective_roughness(ci, co, sigma0, tau)
    g = phase_variance(sigma, dr.maximum(ci, 0.0), dr.maximum(co, 0.0), wavelength)
    c = (v.x * v.x + v.y * v.y) * (tau * tau * 0.25)
    if reading.wavenumber:
        c = c * dr.square(2.0 * math.pi / wavelength)
    total = series(g, c, terms or reading.terms, reading.centred)
    if reading.rough_threshold is not None:
        total = dr.select(g > reading.rough_threshold, rough_asymptote(g, c), total)
    d = dr.square(math.pi * tau / (2.0 * wavelength)) * total
    f = fresnel_exact(0.5 * dr.sqrt(vv), eta, k)
    denom = dr.select(above, math.pi * ci * co, 1.0)
    # 0 where the series is (σ0 = 0): at grazing angles G/(cosθi cosθo) overflows float32
    return dr.select(above & (total > 0), f * (s * geometry / denom) * d, 0.0)


def specular_weight(cos_i, sigma0, tau, wavelength, eta, k, reading: Reading):
    """ρ_s = |F(θi)|² e^(−g) S (Eqs. 73-74): the weight of the delta at the mirror direction,
    per channel; 0 below the surface."""
    ci = dr.maximum(cos_i, 0.0)
    s = dr.square(shadowing(ci, sigma0, tau, reading.errata_shadowing))
    sigma = effective_roughness(ci, ci, sigma0, tau)
    g = phase_variance(sigma, ci, ci, wavelength)
    return dr.select(cos_i > 0, fresnel_exact(ci, eta, k) * dr.exp(-g) * s, 0.0)


__all__ = ["DEFAULT_SIGMA0", "DEFAULT_TAU", "MONO_WAVELENGTH", "NEWTON_STEPS", "READINGS",
           "RGB_WAVELENGTHS", "Reading", "directional_diffuse", "effective_roughness",
           "log_poisson", "phase_variance", "rough_asymptote", "series", "shadowing", "solve_x",
           "specular_weight"]
