r"""
Hapke's bidirectional reflectance of a particulate surface (Hapke 2012, "Theory of Reflectance
and Emittance Spectroscopy", 2nd ed., eq. 12.55 with K = 1; the macroscopic roughness of
Hapke 1984, Icarus 59, eqs. 45-51; the opposition effect of Hapke 1986, Icarus 67; the
H-function of Hapke 2002, Icarus 157, eq. 13) as a function of the directions in the local
frame: ωi towards the source, ωo towards the viewer, both above the surface. Per channel:

    f = r/cos i = (w/4π) μ0e/(μ0e + μe) [p(g)(1 + B(g)) + H(μ0e)H(μe) − 1] (μe/ηe)(1/η0e) χ/D,

the shadowing S = (μe/ηe)(cos i/η0e) χ/D with its cos i cancelled against f's 1/cos i (so that
grazing incidence divides by nothing), D = 1 − f(ψ) + f(ψ) χ cos s/η(s), s the smaller of i, e.

Written without angles where vectors give them safely: tan(g/2) = |ωi − ωo|/|ωi + ωo| (no
acos at the opposition peak, g = 0), and from the horizontal parts a = ωi_xy, b = ωo_xy:
cos ψ = a·b/(|a||b|), ψ = atan2(|a × b|, a·b), tan(ψ/2) = |a × b|/(|a||b| + a·b). Where
|a||b| = 0 (i = 0 or e = 0) ψ is taken as 0: the limits (:mod:`mi_brdfs.reference.hapke`).
cot θ̄ cot x is held at :data:`COT_MAX` or below (E1, E2 are 0 in float32 long before) and
1 − E is computed without cancellation (:func:`one_minus_exp`), so that the roughness's
denominators 2 − E1(e) − (ψ/π)E1(i) are sums of non-negative terms. The float64 counterpart,
with angles: :mod:`mi_brdfs.reference.hapke`.
"""

from __future__ import annotations

import drjit as dr

#: The smallest cosine the model uses (θ ≤ 89.99994°).
COS_MIN = 1e-6
#: The largest cot θ̄ cot x used: E1 = exp(−(2/π)·10⁴) and E2 are 0 in float32 beyond.
COT_MAX = 1e4
#: The largest macroscopic roughness θ̄ (degrees) the model uses: at 90° χ = 0 and tan θ̄ = ∞
#: (vertical facets; Eradiate's values are NaN or 10⁻¹⁸ there).
THETA_MAX = 89.0


def one_minus_exp(u):
    """1 − exp(−u) for u ≥ 0, without cancellation for small u (a Taylor polynomial below
    0.05, whose remainder u⁶/720 is below float32's rounding there)."""
    small = u * (1.0 - u * (0.5 - u * (1.0 / 6.0 - u * (1.0 / 24.0 - u * (1.0 / 120.0)))))
    return dr.select(u < 0.05, small, 1.0 - dr.exp(-u))


def h_function(w, x):
    """Hapke's (2002, eq. 13) H(x) = 1/(1 − w x [r0 + (1 − 2 r0 x)/2 ln((1 + x)/x)]),
    r0 = (1 − γ)/(1 + γ) = w/(1 + γ)², γ = √(1 − w); x > 0."""
    gamma = dr.sqrt(dr.maximum(1.0 - w, 0.0))
    r0 = w / dr.square(1.0 + gamma)
    x = dr.maximum(x, 1e-30)
    return dr.rcp(1.0 - w * x * (r0 + (0.5 - r0 * x) * dr.log(1.0 + dr.rcp(x))))


def phase(b, c, cos_g):
    """The double Henyey-Greenstein p(g) = (1 − c) HG(−b) + c HG(b), c the backward lobe's
    weight: (1 − b²)/(1 ± 2b cos g + b²)^{3/2}."""
    one, b2 = 1.0 - b * b, b * b

    def hg(denominator):  # b = 1: a delta at g = 0 or π, 0 elsewhere (0 there too)
        return one / dr.maximum(denominator * dr.sqrt(denominator), 1e-30)
    return (1.0 - c) * hg(1.0 + 2.0 * b * cos_g + b2) + c * hg(1.0 - 2.0 * b * cos_g + b2)


def opposition(B_0, h, tan_half_g):
    """B = B_0/(1 + tan(g/2)/h) = B_0 h/(h + tan(g/2)); B_0 at g = 0 for every h."""
    total = h + tan_half_g
    return dr.select(total > 0, B_0 * h / dr.maximum(total, 1e-30), B_0)


class Geometry:
    """The angles' functions of a pair that the model reads (every one a Float)."""

    def __init__(self, wi, wo):
        self.cos_i, self.cos_e = dr.maximum(wi.z, COS_MIN), dr.maximum(wo.z, COS_MIN)
        self.sin_i = dr.sqrt(dr.square(wi.x) + dr.square(wi.y))
        self.sin_e = dr.sqrt(dr.square(wo.x) + dr.square(wo.y))
        n = self.sin_i * self.sin_e
        dot = wi.x * wo.x + wi.y * wo.y
        cross = dr.abs(wi.x * wo.y - wi.y * wo.x)
        has = n > 0
        self.cos_psi = dr.select(has, dr.clip(dot / dr.maximum(n, 1e-30), -1.0, 1.0), 1.0)
        self.sin2_half = 0.5 * (1.0 - self.cos_psi)
        self.cos2_half = 0.5 * (1.0 + self.cos_psi)
        self.psi_over_pi = dr.select(has, dr.atan2(cross, dot), 0.0) * dr.inv_pi
        # f(ψ) = exp(−2 tan(ψ/2)): 0 in float32 once tan(ψ/2) > 140 (1 + cos ψ < 10⁻⁴)
        near_pi = (n + dot) <= 1e-4 * n
        tan_half = cross / dr.maximum(n + dot, 1e-4 * n + 1e-30)
        self.f = dr.select(has & near_pi, 0.0, dr.exp(-2.0 * tan_half))
        self.cos_g = dr.clip(dr.dot(wi, wo), -1.0, 1.0)
        self.tan_half_g = dr.norm(wi - wo) / dr.norm(wi + wo)
        self.smaller_i = wi.z >= wo.z  # i ≤ e


def _e_terms(cos_x, sin_x, cos_bar, sin_bar):
    """(1 − E1(x), E2(x), 1 − E2(x)) with E1 = exp(−(2/π) cot θ̄ cot x), E2 = exp(−(1/π)
    cot²θ̄ cot²x), cot θ̄ cot x held at COT_MAX or below."""
    q = cos_bar * cos_x
    k = q / dr.maximum(sin_bar * sin_x, q / COT_MAX)
    v = dr.square(k) * dr.inv_pi
    return one_minus_exp(2.0 * dr.inv_pi * k), dr.exp(-v), one_minus_exp(v)


def roughness(geo: Geometry, theta_bar):
    """
    (μ0e, μe, ηe·η0e·D/χ): Hapke's (1984) effective cosines and what divides the shadowing
    S·(1/cos i) = (μe/ηe)(1/η0e)χ/D, at the macroscopic roughness θ̄ (radians, per channel).
    """
    sin_bar, cos_bar = dr.sin(theta_bar), dr.cos(theta_bar)
    tan_bar = sin_bar / cos_bar
    chi = dr.rsqrt(1.0 + dr.pi * dr.square(tan_bar))
    om1_i, e2_i, om2_i = _e_terms(geo.cos_i, geo.sin_i, cos_bar, sin_bar)
    om1_e, e2_e, om2_e = _e_terms(geo.cos_e, geo.sin_e, cos_bar, sin_bar)
    eta_i = chi * (geo.cos_i + geo.sin_i * tan_bar * e2_i / (1.0 + om1_i))
    eta_e = chi * (geo.cos_e + geo.sin_e * tan_bar * e2_e / (1.0 + om1_e))
    s2, c2, p = geo.sin2_half, geo.cos2_half, geo.psi_over_pi
    first = geo.smaller_i
    # the larger angle L and the smaller s: 2 − E1(L) − (ψ/π)E1(s), E2(L) − E2(s) ≥ 0
    om1_l, om1_s = dr.select(first, om1_e, om1_i), dr.select(first, om1_i, om1_e)
    e2_l = dr.select(first, e2_e, e2_i)
    gap = dr.select(first, om2_i - om2_e, om2_e - om2_i)
    den = om1_l + (1.0 - p) + p * om1_s
    # the smaller angle's effective cosine: cos ψ E2(L) + sin²(ψ/2) E2(s); the larger's:
    # E2(L) − sin²(ψ/2) E2(s)
    small = (c2 * e2_l - s2 * gap) / den
    large = (c2 * e2_l + s2 * gap) / den
    mu0e = chi * (geo.cos_i + geo.sin_i * tan_bar * dr.select(first, small, large))
    mue = chi * (geo.cos_e + geo.sin_e * tan_bar * dr.select(first, large, small))
    ratio = dr.select(first, geo.cos_i / eta_i, geo.cos_e / eta_e)  # cos s/η(s)
    d = 1.0 - geo.f + geo.f * chi * ratio
    return mu0e, mue, eta_e * eta_i * d / chi


def brdf(w, b, c, theta_deg, B_0, h, wi, wo):
    """f per channel (spectra for the parameters, θ̄ in degrees, held at THETA_MAX)."""
    geo = Geometry(wi, wo)
    theta_bar = dr.deg2rad(dr.minimum(theta_deg, THETA_MAX))
    mu0e, mue, shadow_den = roughness(geo, theta_bar)
    mu0e, mue = dr.maximum(mu0e, 0.0), dr.maximum(mue, 0.0)
    single = phase(b, c, geo.cos_g) * (1.0 + opposition(B_0, h, geo.tan_half_g))
    multiple = h_function(w, mu0e) * h_function(w, mue) - 1.0
    return (w * (0.25 * dr.inv_pi)) * mu0e * mue / ((mu0e + mue) * shadow_den) * \
        (single + multiple)


