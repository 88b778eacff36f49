r"""
The Phong lobes: cosⁿ of the angle to the mirror direction (Phong 1975; Lafortune & Willems 1994)
or of the half-vector's angle to the normal (Blinn 1977), their importance sampling, and the
normalisations of the lecture's three forms.

Directions are in the local frame (normal N = +z), both pointing away from the surface; the
lobes are symmetric in their two directions, so it does not matter which of them is the light:

* mirror lobe: cos α = R·ωo with R = (−ωi.x, −ωi.y, ωi.z), the mirror image of ωi;
* halfway lobe: cos θh = N·H with H = (ωi + ωo)/|ωi + ωo|.

**Evaluation without cancellation.** max(0, cos)ⁿ is evaluated as exp(n·log1p(−(1 − cos))) from
1 − cos computed without subtracting two numbers close to 1:

* mirror: 1 − cos α = |ωo − R|²/2. Near the lobe the differences ωo − R are exact in float32
  (Sterbenz's lemma), and the result barely depends on the norm error ε of float32 "unit"
  vectors: for |a| = 1 + εa, |b| = 1 + εb, |a − b|²/2 = (1 − cos α)(1 + εa)(1 + εb) + (εa − εb)²/2.
  The textbook pow(R·ωo, n) instead rounds R·ωo to a multiple of 6e-8 (one float32 ulp below 1),
  a relative error of up to about n·6e-8 in cosⁿ (``validation/phong_float32.py`` measures it);
* halfway: with h = ωi + ωo, 1 − cos θh = (hx² + hy²) / (|h|(|h| + hz)).

**Sampling** draws the cosⁿ lobe about an axis with cos θ = u^(1/(n+1)), as cos θ = exp(t),
sin²θ = −expm1(2t), t = ln(u)/(n+1): for large n the naive sin θ = sqrt(1 − cos²θ) cancels in
float32, and returns exactly 0 (the sample collapses onto the axis) for a large share of the
samples (``validation/phong_float32.py`` measures both).
Density about the axis: (n+1)/(2π)·cosⁿθ. The mirror lobe is drawn about R; the halfway lobe draws
H about N and reflects ωi on it, which multiplies the density by the Jacobian 1/(4 ωo·H) = 1/(2|h|)
(capped at :data:`PDF_MAX` where it leaves float32's range, at the horizon for huge n).

**Normalisations**: the factor c in front of cosⁿ in f, and the directional albedo at normal
incidence of the specular lobe with ks = 1, E(0) = ∫ f cosθo dωo (in radiance transport, the
convention of ``eval``; for ``original``, f also holds 1/(N·L)):

==========  ========  =========================  ========  =========================
form        mirror c  halfway c                  mirror    halfway E(0)
                                                 E(0)
==========  ========  =========================  ========  =========================
normalized  (n+2)/2π  (n+2)(n+4)/(8π(n+2^−n/2))  1         1
lecture     1         1                          2π/(n+2)  8π(n+2^−n/2)/((n+2)(n+4))
original    1         1                          2π/(n+1)  8π(1−2^−(n+2)/2)/(n+2)
==========  ========  =========================  ========  =========================

The halfway normalisation (Giesen 2009, "Derivation of Phong and Blinn-Phong BRDF normalization
factors") follows from ωi = N, θh = θo/2: ∫ cosⁿ(θo/2) cosθo dωo = 8π ∫_{1/√2}^1 u^(n+1)(2u² − 1) du
= 8π(n + 2^(−n/2)) / ((n+2)(n+4)). ``tests/reference/test_phong_reference.py`` checks every
entry of the table by quadrature.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .stable import expm1, log1p

FORMS = ("normalized", "lecture", "original")
LOBES = ("mirror", "halfway")

#: Cap of the halfway lobe's sampling density (float32 overflows at 3.4e38).
PDF_MAX = 1e38


# -------------------------------------------------------------------------------------------------
# Evaluation
# -------------------------------------------------------------------------------------------------


def cos_power(one_minus_cos, n):
    """
    max(0, cos θ)ⁿ from 1 − cos θ ∈ [0, 2]: exp(n·log1p(−(1 − cos θ))), and 0 where cos θ ≤ 0
    (for n = 0 too: that lobe is the uniform hemisphere about its axis).
    """
    inside = one_minus_cos < 1.0
    # log1p's argument stays in (−1, 0] on discarded lanes as well: no NaN for AD to see there
    x = dr.select(inside, one_minus_cos, 0.0)
    return dr.select(inside, dr.exp(n * log1p(-x)), 0.0)


def mirror_lobe(wi, wo, n, pdf_norm):
    """
    (cosⁿα, density of :func:`sample_mirror` at ``wo``): α is the angle between ``wo`` and R,
    the mirror image of ``wi``; ``pdf_norm`` = :func:`pdf_normalization` (n).
    """
    dx, dy, dz = wo.x + wi.x, wo.y + wi.y, wo.z - wi.z  # wo − R
    value = cos_power(0.5 * (dx * dx + dy * dy + dz * dz), n)
    return value, pdf_norm * value


def halfway_lobe(wi, wo, n, pdf_norm):
    """
    (cosⁿθh, density of :func:`sample_halfway` at ``wo``): θh is the angle between N and H.
    Meant for ``wi`` and ``wo`` above the surface (hz > 0); ωo = −ωi (h = 0) gives 0.
    """
    hx, hy, hz = wi.x + wo.x, wi.y + wo.y, wi.z + wo.z
    t2 = hx * hx + hy * hy
    length = dr.sqrt(t2 + hz * hz)
    den = length * (length + hz)
    ok = den > 0  # h = 0 or H = −N: no lobe there (1 − cos θh := 2)
    value = cos_power(dr.select(ok, t2 / dr.select(ok, den, 1.0), 2.0), n)
    # Jacobian 1/(4 ωo·H) = 1/(2|h|) for unit ωi, ωo. The density is finite but exceeds
    # float32's range where ωo·H → 0 (both directions within 1e-32 of the horizon at n = 1e8,
    # 1e-10 at n = 1e30): capped at PDF_MAX there, which sample() and pdf() share.
    density = (pdf_norm * value) / dr.maximum(2.0 * length, 1e-30)
    return value, dr.minimum(density, PDF_MAX)


# -------------------------------------------------------------------------------------------------
# Sampling
# -------------------------------------------------------------------------------------------------


def cos_power_theta(u, inv_n1):
    """
    (cos θ, sin θ) with density (n+1)·cosⁿθ in cos θ, from ``u`` ∈ [0, 1] and 1/(n+1):
    cos θ = u^(1/(n+1)), with sin θ from expm1 (no collapse onto the axis for large n).
    """
    t = dr.log(u) * inv_n1  # ≤ 0; u = 0 gives −∞: cos θ = 0, sin θ = 1
    return dr.exp(t), dr.sqrt(-expm1(2.0 * t))


def sample_cos_power(u, inv_n1):
    """
    A direction about +z with density (n+1)/(2π)·cosⁿθ, from ``u`` ∈ [0, 1)² and 1/(n+1):
    cos θ = u.x^(1/(n+1)) (:func:`cos_power_theta`) and φ = 2π u.y.
    """
    cos_theta, sin_theta = cos_power_theta(u.x, inv_n1)
    sin_phi, cos_phi = dr.sincos(dr.two_pi * u.y)
    return mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)


def sample_mirror(wi, u, inv_n1):
    """``wo`` drawn from the mirror lobe about R = (−ωi.x, −ωi.y, ωi.z)."""
    return mi.Frame3f(mi.Vector3f(-wi.x, -wi.y, wi.z)).to_world(sample_cos_power(u, inv_n1))


def sample_halfway(wi, u, inv_n1):
    """``wo`` = ``wi`` reflected on H, H drawn from the cosⁿ lobe about the normal."""
    return mi.reflect(wi, sample_cos_power(u, inv_n1))


# -------------------------------------------------------------------------------------------------
# Normalisations
# -------------------------------------------------------------------------------------------------


def pdf_normalization(n):
    """(n+1)/(2π): the sampling density of the cosⁿ lobe per unit cosⁿ."""
    return (n + 1.0) * dr.inv_two_pi


def specular_normalization(form: str, lobe: str, n):
    """The factor in front of cosⁿ (table above); 1 for the unnormalized forms."""
    if form != "normalized":
        return n * 0.0 + 1.0  # 1, of n's type (a Python float, or a JIT array of n's width)
    if lobe == "mirror":
        return (n + 2.0) * dr.inv_two_pi
    # (n+2)(n+4)/(8π(n + 2^−n/2)), arranged so that no intermediate overflows for n up to 1e38
    return (n + 2.0) * (0.125 * dr.inv_pi) * ((n + 4.0) / (n + dr.exp2(-0.5 * n)))


def specular_albedo(form: str, lobe: str, n):
    """E(0) of the specular lobe with ks = 1 (table above): the lobe's share of the energy."""
    if form == "normalized":
        return n * 0.0 + 1.0
    if lobe == "mirror":
        return dr.two_pi / (n + (2.0 if form == "lecture" else 1.0))
    if form == "lecture":  # no product (n+2)(n+4): it would overflow float32 from n = 2e19
        return 8.0 * dr.pi / (n + 2.0) * ((n + dr.exp2(-0.5 * n)) / (n + 4.0))
    return 8.0 * dr.pi * (1.0 - dr.exp2(-0.5 * n - 1.0)) / (n + 2.0)
