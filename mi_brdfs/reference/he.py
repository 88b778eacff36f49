r"""
He, Torrance, Sillion & Greenberg's BRDF in float64 (1991, "A Comprehensive Physical Model for
Light Reflection", SIGGRAPH, §4 and its appendix; "HTSG"): Kirchhoff's scattering by a
Gaussian random surface of rms height σ0 and autocorrelation length τ (Beckmann & Spizzichino
1963, §5.3), per wavelength λ. Lengths in µm. f = ρ_sp + ρ_dd + ρ_ud with

* the specular (coherent) part, a delta (Eqs. 70, 73-74): ρ_sp = ρ_s Δ/(cosθi dωi), where
  Δ = 1 inside the cone of solid angle dωr = dωi about the mirror direction M(ωi), else 0, and
  ρ_s = |F(θi)|² e^(−g) S. As dωi → 0, Δ/dωi → δ(ωo − M(ωi)), the delta normalised in solid
  angle, so f_sp = ρ_s δ(ωo − M(ωi))/cosθo and ∫ f_sp cosθo dωo = ρ_s: :meth:`HTSG.specular`
  gives ρ_s, the weight of the delta lobe, what Mitsuba's delta lobes return as the sample
  weight (as ``conductor`` returns F); :meth:`HTSG.specular_cone` is the finite-cone form;
* the directional diffuse part (Eqs. 71, 76-79): ρ_dd = |F|² G S D/(π cosθi cosθo),
  D = (π²τ²/4λ²) Σ_{m≥1} g^m e^(−g)/(m!·m) · exp(−v_xy² τ²/(4m)). Written with k = 2π/λ the
  prefactor is |F|² S G/(cosθi cosθo) · k²τ²/(16π): the k² is there;
* the uniform diffuse part ρ_ud = a/π.

The terms, with v̂ = k̂r − k̂i = ωi + ωo (k̂i = −ωi, the incident propagation direction):

* |F|² (Eq. 75): the unpolarized Fresnel reflectance ½(|r_s|² + |r_p|²) of n = η + ik (the
  paper averages the two polarizations), at the local angle of incidence, cos = |v̂|/2 for ρ_dd
  and cosθi for ρ_s (:func:`mi_brdfs.reference.cooktorrance.fresnel_exact`);
* S (Eqs. 24-25): Smith's (1967) shadowing of the Gaussian surface, S = S(θi) S(θo),
  S(θ) = (1 − ½ erfc a)/(1 + Λ), a = τ cotθ/(2σ0), Λ = ½(E/(√π a) − erfc a), where E = e^(−a²)
  (the errata; then Λ is Beckmann's Smith Λ for α = 2σ0/τ) or E = 1 (Eq. 25 as printed);
* σ (Eqs. 80-83), the roughness left visible by shadowing: σ = σ0 (1 + z0²/σ0²)^(−1/2) with
  √(π/2) z0 = (σ0/4)(K_i + K_o) e^(−z0²/2σ0²), K = tanθ erfc(τ cotθ/(2σ0)); for x = z0/σ0 this
  is x e^(x²/2) = (K_i + K_o)/√(8π), solved by bisection to float64;
* g = (2πσ(cosθi + cosθo)/λ)² (Eq. 79), the phase variance;
* G (Eq. 76) = (v̂·v̂/v̂_z)² [(ŝr·k̂i)² + (p̂r·k̂i)²][(ŝi·k̂r)² + (p̂i·k̂r)²]/|k̂i × k̂r|⁴.
  As (ŝ, p̂, k̂) is orthonormal, each bracket is 1 − (k̂i·k̂r)² = |k̂i × k̂r|², so
  G = (v̂·v̂)²/v̂_z² exactly (no 0/0 at retro-reflection;
  tests/reference/test_he.py::test10_geometry_factor);
* v_xy (Eq. 84), the tangential part of v. Kirchhoff's phase needs wave numbers,
  v = k(k̂r − k̂i), |v_xy|² = k² |v̂_xy|², as Westin's code has it; bbm reads the equation as
  printed with the unit vectors, |v̂_xy|², which makes the exponent depend on the unit of τ:
  read so, ρ_dd tends to k² times the microfacet BRDF of a Beckmann α' = kα, and its albedo
  exceeds 1 by far for rough surfaces (46 for bbm's default σ0 = 0.18, τ = 3 µm at 0.5 µm).

Variants (:data:`VARIANTS`), as bbm's ``include/bsdfmodel/he.h`` documents the readings of the
paper (https://github.com/bsdfbenchmark/bbm; no code taken from it):

* ``paper``: the equations as printed: Eq. 25 without e^(−a²), v_xy from unit vectors, the
  series summed to convergence. The errata (Holzschuch & Pacanowski, "Demystifying the HTSG
  BRDF", https://manao.inria.fr/perso/~pac/hugo/posts/hedemystified/) add e^(−a²): that is
  ``holzschuch`` with ``terms=None``.
* ``westin``: Westin et al.'s reference code (Cornell, heBRDF.tar.gz): e^(−a²) in Eq. 25, v_xy
  in wave numbers, and for g > 18.5 Beckmann's rough-surface asymptote (1963, §5.3, Eq. 47)
  Σ ≈ e^(−v_xy²τ²/4g)/g in place of the series. Only this reading tends to a microfacet model
  with Beckmann's D of α = 2σ/τ (slope variance 2σ²/τ² per axis) as g grows:
  ρ_dd → |F|² S D/(4 cosθi cosθo).
* ``holzschuch``: Holzschuch & Pacanowski's reading: e^(−a²) in Eq. 25, v_xy from unit
  vectors, the series cut at 10 terms.

Where they differ, in numbers: tests/reference/test_he.py::test08_variant_differences.
Holzschuch & Pacanowski's later model (2017, "A physically accurate reflectance model
combining reflection and diffraction") is another BRDF, not a reading of this one.

The series (:func:`series`) is summed to convergence: its terms are log-concave in m from m = 2
on, so once they decrease, the tail after term m is at most t_m r/(1 − r) with r = t_m/t_{m−1}
(:func:`tail_bound`), and the sum stops where that is below 1e-16 of the sum (:data:`RTOL`);
terms below m = g − 12√g − 12 are skipped (Poisson's lower tail: below 1e-20 of the sum for
g ≤ 10⁶), and those below m = c/800, each under e^(−800), beyond float64's range.
``terms`` cuts it at a fixed count instead, :func:`terms_needed` gives the count a tolerance
needs. The equation numbers are those Westin's code and bbm cite; the printed paper
was not at hand to check them against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cooktorrance import fresnel_exact
from .quadrature import direction, gauss_legendre

_erfc = np.vectorize(math.erfc, otypes=[float])
_lgamma = np.vectorize(math.lgamma, otypes=[float])

#: The series' relative tolerance: it stops where the bound on its tail is below this.
RTOL = 1e-16
#: The most terms :func:`series` adds to converge (it needs about 21√g + 60 after the skip).
MAX_TERMS = 10**6


@dataclass(frozen=True)
class Variant:
    """One reading of the paper: e^(−a²) in Eq. 25 (``errata_shadowing``), v_xy in wave
    numbers (``wavenumber``), the series' length (``terms``, None: to convergence) and the g
    above which Beckmann's asymptote replaces the series (``rough_threshold``, None: never)."""
    errata_shadowing: bool
    wavenumber: bool
    terms: int | None
    rough_threshold: float | None


VARIANTS = {"paper": Variant(False, False, None, None),
            "westin": Variant(True, True, None, 18.5),
            "holzschuch": Variant(True, False, 10, None)}


def shadowing(cos_theta, sigma0: float, tau: float, errata: bool = True) -> np.ndarray:
    """S(θ) = (1 − ½erfc a)/(1 + Λ), a = τ cotθ/(2σ0), Λ = ½(E/(√π a) − erfc a), E = e^(−a²)
    with the errata, 1 as printed (Eqs. 24-25); 1 at normal incidence or σ0 = 0, 0 at and
    below the horizon."""
    c = np.clip(np.asarray(cos_theta, dtype=np.float64), -1.0, 1.0)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a = tau * c / (2.0 * sigma0 * s)
        e = _erfc(a)
        damp = np.exp(-a * a) if errata else 1.0
        lam = 0.5 * (damp / (math.sqrt(math.pi) * a) - e)
        value = (1.0 - 0.5 * e) / (1.0 + lam)
    return np.where(c > 0, np.where(np.isinf(a), 1.0, value), 0.0)


def _k(cos_theta, sigma0: float, tau: float) -> np.ndarray:
    """K = tanθ erfc(τ cotθ/(2σ0)) (Eqs. 82-83): 0 at normal incidence, ∞ at the horizon."""
    c = np.asarray(cos_theta, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.sqrt(np.maximum(1.0 - c * c, 0.0)) / c
        k = t * _erfc(tau / (2.0 * sigma0 * t))
    return np.where(t > 0, k, 0.0)


def solve_z0(f0) -> np.ndarray:
    """x = z0/σ0 with x e^(x²/2) = f0 (Eq. 81 divided by σ0), by bisection on
    ln x + x²/2 = ln f0 over [0, f0] (f0 ≤ √e) or [0, √(2 ln f0)]: to the last bit; ∞ for
    f0 = ∞."""
    f0 = np.asarray(f0, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_f0 = np.log(f0)
        lo = np.zeros_like(f0)
        hi = np.where(f0 <= math.exp(0.5), f0, np.sqrt(2.0 * np.maximum(log_f0, 0.5)))
        for _ in range(110):
            mid = 0.5 * (lo + hi)
            below = np.log(mid) + 0.5 * mid * mid < log_f0
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return np.where(np.isfinite(f0), 0.5 * (lo + hi), np.inf)


def effective_roughness(cos_i, cos_o, sigma0: float, tau: float) -> np.ndarray:
    """σ = σ0/√(1 + x²), x = z0/σ0 from x e^(x²/2) = (K_i + K_o)/√(8π) (Eqs. 80-83)."""
    if sigma0 <= 0:
        return np.zeros(np.broadcast_shapes(np.shape(cos_i), np.shape(cos_o)))
    f0 = (_k(cos_i, sigma0, tau) + _k(cos_o, sigma0, tau)) / math.sqrt(8.0 * math.pi)
    x = solve_z0(f0)
    with np.errstate(over="ignore"):
        return sigma0 / np.sqrt(1.0 + x * x)


def phase_variance(sigma, cos_i, cos_o, wavelength) -> np.ndarray:
    """g = (2πσ(cosθi + cosθo)/λ)² (Eq. 79); λ per channel → (..., channels)."""
    lam = np.atleast_1d(np.asarray(wavelength, dtype=np.float64))
    x = np.asarray(sigma) * (np.asarray(cos_i) + np.asarray(cos_o))
    return (2.0 * math.pi * x[..., None] / lam) ** 2


def geometry(wi, wo) -> np.ndarray:
    """G = (v̂·v̂)²/v̂_z², v̂ = ωi + ωo: Eq. 76 with its polarization brackets, which equal
    |k̂i × k̂r|⁴ and cancel (module docstring)."""
    v = np.atleast_2d(wi) + np.atleast_2d(wo)
    vv = np.sum(v * v, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return vv * vv / (v[:, 2] * v[:, 2])


def log_terms(g: float, c: float, m) -> np.ndarray:
    """ln t_m of the series' terms t_m = g^m e^(−g)/(m!·m) · e^(−c/m), for integers m ≥ 1."""
    m = np.asarray(m, dtype=np.float64)
    return m * math.log(g) - g - _lgamma(m + 1.0) - np.log(m) - c / m


def rough_asymptote(g, c) -> np.ndarray:
    """Σ for g ≫ 1: e^(−c/g)/g (Beckmann & Spizzichino 1963, §5.3, Eq. 47), c = v_xy²τ²/4."""
    g = np.asarray(g, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(g > 0, np.exp(-np.asarray(c) / g) / g, 0.0)


def series(g, c, terms: int | None = None, rtol: float = RTOL) -> np.ndarray:
    """
    Σ_{m≥1} g^m e^(−g)/(m!·m) · e^(−c/m) elementwise (c = v_xy²τ²/4, Eq. 78), to convergence
    (``terms`` None: the tail bound below ``rtol`` of the sum, terms below g − 12√g − 12
    skipped), or its first ``terms`` terms. Summed in logarithms, rescaled to the largest
    term, so that neither e^(−g) nor g^m/m! over- or underflows. 0 where g = 0.
    """
    g, c = np.broadcast_arrays(np.asarray(g, dtype=np.float64), np.asarray(c, dtype=np.float64))
    shape, g, c = g.shape, g.ravel(), c.ravel()
    out = np.zeros(g.size)
    idx = np.flatnonzero(g > 0)
    if idx.size == 0 or terms == 0:
        return out.reshape(shape)
    g, c = g[idx], c[idx]
    converge = terms is None
    # skipped: Poisson's lower tail, and the terms under e^(−c/m) < e^(−800), below float64's
    # range (with τ = 10⁴ µm, c reaches 10⁹ and the terms would rise for 10⁴ orders)
    m0 = np.maximum(np.maximum(1.0, np.floor(g - 12.0 * np.sqrt(g) - 12.0)),
                    np.floor(c / 800.0)) if converge else np.ones_like(g)
    log_g = np.log(g)
    log_p = m0 * log_g - g - _lgamma(m0 + 1.0)  # ln of Poisson's pmf at m
    scale = np.full(g.size, -np.inf)  # ln of the largest term so far
    total = np.zeros(g.size)  # the sum over e^scale
    prev = np.full(g.size, -np.inf)
    log_m = np.log(m0)
    # the elements still summing (their index in ``act``), compacted as they converge
    act, done_total, done_scale = np.arange(g.size), np.zeros(g.size), np.zeros(g.size)
    live = np.ones(g.size, dtype=bool)  # not converged yet
    for j in range(MAX_TERMS if converge else int(terms)):
        m = m0 + j
        log_t = log_p - log_m - c / m
        new = np.maximum(scale, log_t)
        term = np.exp(log_t - new)  # the term over the largest so far
        total = total * np.exp(scale - new) + term
        scale = new
        log_m = np.log(m + 1.0)
        log_p = log_p + (log_g - log_m)
        if converge:
            log_r = log_t - prev
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                r = np.exp(np.minimum(log_r, 0.0))
                tail = term * r / (1.0 - r)
            done = live & (m >= 2) & (log_r < 0) & (tail <= rtol * total)
            prev = log_t
            if done.any():
                done_total[act[done]], done_scale[act[done]] = total[done], scale[done]
                live &= ~done
                count = np.count_nonzero(live)
                if count == 0:
                    break
                if count < 0.75 * live.size:  # summing on past convergence costs less
                    act, m0, c, log_g, log_p, log_m, scale, total, prev = (
                        a[live] for a in (act, m0, c, log_g, log_p, log_m, scale, total,
                                          prev))
                    live = np.ones(count, dtype=bool)
    if converge and live.any():
        raise ValueError(f"series: not converged in {MAX_TERMS} terms (g up to {g.max():.3g})")
    if not converge:
        done_total, done_scale = total, scale
    out[idx] = done_total * np.exp(done_scale)
    return out.reshape(shape)


def tail_bound(g: float, c: float, count: int) -> float:
    """A bound on Σ_{m>count} t_m: t_M r/(1 − r), r = t_M/t_{M−1}, M = ``count``, where the
    terms decrease there (r < 1, M ≥ 2; the terms are log-concave in m from m = 2 on), else
    ∞."""
    if count < 2:
        return math.inf
    log_t = log_terms(g, c, [count - 1, count])
    r = math.exp(log_t[1] - log_t[0])
    return math.exp(log_t[1]) * r / (1.0 - r) if r < 1 else math.inf


def terms_needed(g: float, c: float, rtol: float) -> int:
    """The smallest M with Σ_{m>M} t_m ≤ ``rtol``·Σ t_m: the terms to keep for a relative
    truncation error below ``rtol`` (0 where g = 0)."""
    if g <= 0:
        return 0
    top = int(g + 20.0 * math.sqrt(g) + 64.0)
    while True:
        log_t = log_terms(g, c, np.arange(1, top + 1))
        t = np.exp(log_t - log_t.max())
        r = math.exp(min(log_t[-1] - log_t[-2], 0.0))
        if r < 1 and t[-1] * r / (1 - r) <= 1e-3 * rtol * t.sum():
            break
        if top > MAX_TERMS:
            raise ValueError(f"terms_needed: not converged in {MAX_TERMS} terms (g = {g:.3g})")
        top *= 2
    total = t.sum()
    tails = np.concatenate([np.cumsum(t[::-1])[::-1][1:], [0.0]])  # Σ_{m>M}, M = 1..top
    return int(np.argmax(tails <= rtol * total)) + 1


def _prefactor(wavelength, tau: float) -> np.ndarray:
    """π²τ²/(4λ²), D's factor (Eq. 78)."""
    return (math.pi * tau / (2.0 * np.asarray(wavelength))) ** 2


def _channels(*values) -> list[np.ndarray]:
    arrays = [np.atleast_1d(np.asarray(v, dtype=np.float64)) for v in values]
    return [np.array(a) for a in np.broadcast_arrays(*arrays)]


class HTSG:
    """
    f(ωi, ωo) of He et al. (module docstring) for rms roughness ``sigma0`` and autocorrelation
    length ``tau`` (µm), per channel: ``wavelength`` λ (µm), the index ``eta`` + i``k``, the
    uniform diffuse albedo ``albedo`` a. ``variant``: a name in :data:`VARIANTS` or a
    :class:`Variant`; by default ``westin``, the one reading that tends to its Beckmann limit
    and keeps the albedo below 1 (and the one Ngan et al.'s fits used, as bbm's ``nganhe``
    says). ``terms``: "variant" (the variant's), None (to convergence) or a count.
    """

    def __init__(self, sigma0: float, tau: float, wavelength=0.55, eta=1.5, k=0.0, albedo=0.0,
                 variant="westin", terms="variant"):
        if sigma0 < 0 or tau <= 0:
            raise ValueError("he: sigma0 must be >= 0 and tau > 0 (µm)")
        self.variant = VARIANTS[variant] if isinstance(variant, str) else variant
        self.sigma0, self.tau = float(sigma0), float(tau)
        self.wavelength, self.eta, self.k, self.a = _channels(wavelength, eta, k, albedo)
        self.terms = self.variant.terms if terms == "variant" else terms

    def _pair(self, wi, wo) -> dict:
        """The quantities of a pair of directions: cosines, S, σ, g and c = v_xy²τ²/4."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        ci, co = wi[:, 2], wo[:, 2]
        above = (ci > 0) & (co > 0)
        errata = self.variant.errata_shadowing
        s = shadowing(ci, self.sigma0, self.tau, errata) * \
            shadowing(co, self.sigma0, self.tau, errata)
        sigma = effective_roughness(np.where(above, ci, 1), np.where(above, co, 1),
                                    self.sigma0, self.tau)
        v = wi + wo
        vxy2 = v[:, 0] ** 2 + v[:, 1] ** 2
        c = vxy2[:, None] * self.tau**2 / 4.0 * np.ones_like(self.wavelength)
        if self.variant.wavenumber:
            c = c * (2.0 * math.pi / self.wavelength) ** 2
        return {"ci": ci, "co": co, "above": above, "S": s, "c": c,
                "g": phase_variance(sigma, np.maximum(ci, 0), np.maximum(co, 0), self.wavelength),
                "cos_d": 0.5 * np.sqrt(np.sum(v * v, axis=1)), "G": geometry(wi, wo)}

    def _sum(self, g, c) -> np.ndarray:
        """Σ of Eq. 78 as the variant takes it (the series, or the asymptote above g*)."""
        thr = self.variant.rough_threshold
        rough = (g > thr) if thr is not None else np.zeros(g.shape, dtype=bool)
        out = np.zeros_like(g)
        out[rough] = rough_asymptote(g[rough], c[rough])
        out[~rough] = series(g[~rough], c[~rough], self.terms)
        return out

    def directional_diffuse(self, wi, wo) -> np.ndarray:
        """ρ_dd = |F|² G S D/(π cosθi cosθo) (Eq. 71), (n, channels); 0 unless both are above."""
        p = self._pair(wi, wo)
        above = p["above"]
        f = fresnel_exact(p["cos_d"], self.eta, self.k)
        with np.errstate(divide="ignore", invalid="ignore"):
            spatial = np.where(above, p["S"] * p["G"] / (math.pi * p["ci"] * p["co"]), 0.0)
        d = _prefactor(self.wavelength, self.tau) * self._sum(p["g"], p["c"])
        return np.where(above[:, None], f * spatial[:, None] * d, 0.0)

    def specular(self, wi, wo=None) -> np.ndarray:
        """
        ρ_s = |F|² e^(−g) S (Eqs. 73-74), (n, channels): the weight of the delta at
        ωo = M(ωi), f_sp = ρ_s δ(ωo − M(ωi))/cosθo (solid-angle delta). With ``wo`` (meant to be
        M(ωi)) σ, g, S and F take the pair's angles, which at the mirror are θi's; without, ωo
        is M(ωi).
        """
        wi = np.atleast_2d(wi).astype(np.float64)
        wo = wi * np.array([-1.0, -1.0, 1.0]) if wo is None else wo
        p = self._pair(wi, wo)
        f = fresnel_exact(p["cos_d"], self.eta, self.k)
        rho = f * np.exp(-p["g"]) * p["S"][:, None]
        return np.where(p["above"][:, None], rho, 0.0)

    def specular_cone(self, wi, wo, d_omega: float) -> np.ndarray:
        """ρ_sp = ρ_s Δ/(cosθi dωi) (Eq. 70): Δ = 1 where ωo is inside the cone of solid angle
        ``d_omega`` about M(ωi), 2π(1 − cosψ) for its half-angle ψ, else 0."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        mirror = wi * np.array([-1.0, -1.0, 1.0])
        inside = np.sum(mirror * wo, axis=1) >= 1.0 - d_omega / (2.0 * math.pi)
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = self.specular(wi) / (wi[:, 2:3] * d_omega)
        return np.where(inside[:, None] & (wi[:, 2:3] > 0), rho, 0.0)

    def uniform_diffuse(self, wi, wo) -> np.ndarray:
        """ρ_ud = a/π, (n, channels); 0 unless both directions are above."""
        above = (np.atleast_2d(wi)[:, 2] > 0) & (np.atleast_2d(wo)[:, 2] > 0)
        return np.where(above[:, None], self.a / math.pi, 0.0)

    def brdf(self, wi, wo) -> np.ndarray:
        """f without its delta: ρ_dd + ρ_ud, (n, channels) (the delta: :meth:`specular`)."""
        return self.directional_diffuse(wi, wo) + self.uniform_diffuse(wi, wo)

    def directional_diffuse_albedo(self, theta: float, n_r: int = 48,
                                   n_phi: int = 128) -> np.ndarray:
        """∫ ρ_dd cosθo dωo for ωi at polar angle θ (xz plane), per channel: over the
        projected disk, cosθo dωo = dx dy, in polar coordinates about the lobe's centre −ωi_xy
        (:func:`disk_rule`)."""
        wi = direction(theta)
        wo, weights = disk_rule(-wi[:2], n_r, n_phi)
        f = self.directional_diffuse(np.broadcast_to(wi, wo.shape), wo)
        return np.einsum("n,nc->c", weights, f)

    def albedo(self, theta: float, n_r: int = 48, n_phi: int = 128) -> np.ndarray:
        """E(θ) = ρ_s + ∫ ρ_dd cosθo dωo + a per channel (the delta's weight included)."""
        if math.cos(theta) <= 0:
            return np.zeros_like(self.a)
        wi = direction(theta)[None, :]
        return self.specular(wi)[0] + self.directional_diffuse_albedo(theta, n_r, n_phi) + self.a


#: Radii (in the projected disk) where :func:`disk_rule` splits its panels: lobes from the
#: smooth regime's λ/(πτ) to the rough one's 2α cosθ.
DISK_CUTS = (0.002, 0.006, 0.02, 0.06, 0.2, 0.5)


def disk_rule(center, n_r: int = 48, n_phi: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """
    Nodes and weights for ∫ g(ωo) cosθo dωo over the upper hemisphere as ∫ g dx dy over the
    unit disk of ωo's (x, y), in polar coordinates (r, φ) about ``center``: the midpoint rule
    in φ, Gauss-Legendre in r on panels split at :data:`DISK_CUTS`, the last one mapped by
    r = R − (R − r₀)(1 − u)² so that √(R − r) (cosθo near the rim) is smooth in u.

    Returns → (directions (N, 3), weights (N,)).
    """
    x, w = gauss_legendre(n_r)
    u, w = 0.5 * (x + 1.0), 0.5 * w
    cx, cy = float(center[0]), float(center[1])
    radii, weights, angles = [], [], []
    for p in (np.arange(n_phi) + 0.5) * (2.0 * math.pi / n_phi):
        b = cx * math.cos(p) + cy * math.sin(p)
        rim = -b + math.sqrt(b * b - (cx * cx + cy * cy) + 1.0)  # |center + rim·(cos, sin)| = 1
        edges = [0.0] + [e for e in DISK_CUTS if e < rim] + [rim]
        for lo, hi in zip(edges[:-2], edges[1:-1]):
            r = lo + (hi - lo) * u
            radii.append(r), weights.append(w * (hi - lo) * r)
        r = rim - (rim - edges[-2]) * (1.0 - u) ** 2
        radii.append(r), weights.append(w * 2.0 * (rim - edges[-2]) * (1.0 - u) * r)
        angles.append(np.full(n_r * (len(edges) - 1), p))
    r, phi = np.concatenate(radii), np.concatenate(angles)
    px, py = cx + r * np.cos(phi), cy + r * np.sin(phi)
    pz = np.sqrt(np.maximum(1.0 - px * px - py * py, 0.0))
    return np.stack([px, py, pz], axis=1), np.concatenate(weights) * (2.0 * math.pi / n_phi)
