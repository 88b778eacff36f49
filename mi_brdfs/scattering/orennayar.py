r"""
Oren & Nayar's rough diffuse reflectance (Oren & Nayar 1994, "Generalization of Lambert's
Reflectance Model", SIGGRAPH '94, §4.4): V-groove facets, each a Lambertian reflector, with
slopes of standard deviation σ (radians), with masking, shadowing and interreflection.

With α = max(θi, θo), β = min(θi, θo) and Δφ = φi − φo, f = ρ/π · factor, where factor is

- ``qualitative`` (the paper's eq. 30, the widely used form):
  A + B·max(0, cos Δφ)·sin α·tan β, with A = 1 − 0.5 σ²/(σ² + 0.33), B = 0.45 σ²/(σ² + 0.09);
- ``full`` (eqs. 26 to 29, with the interreflection term):
  C1 + cos Δφ·C2·tan β + (1 − |cos Δφ|)·C3·tan((α + β)/2) + ρ·C4·(1 − cos Δφ·(2β/π)²), with
  C1 = A, C2 = 0.45 σ²/(σ² + 0.09)·(sin α, or sin α − (2β/π)³ where cos Δφ < 0),
  C3 = 0.125 σ²/(σ² + 0.09)·(4αβ/π²)², C4 = 0.17 σ²/(σ² + 0.13).

Without trigonometry where it can be avoided: cos Δφ·sin θi·sin θo = ωi,xy·ωo,xy (the
tangential parts' dot product), so cos Δφ·sin α·tan β = ωi,xy·ωo,xy / max(cosθi, cosθo), which
is the whole azimuthal term of the qualitative form, exact also where Δφ is undefined (a
direction along the normal: the term is then 0). The full form needs α and β themselves.

At σ = 0 every term but A = C1 = 1 vanishes: factor is exactly 1 and f is Lambert's ρ/π.

The ``full`` form, as the paper writes it, goes negative where both directions graze the
surface on opposite sides (cos Δφ = −1: the term cos Δφ·C2·tan β, with tan β → ∞, outweighs
the others): in float64, f/(ρ/π) reaches −0.27 + 0.32 ρ at 89.994° (σ = 1.57), negative for
ρ below about 0.85. :func:`factor` returns the paper's value; the ``orennayar`` plugin clamps
it at 0 (``tests/plugins/test_orennayar.py`` measures both).
"""

from __future__ import annotations

import drjit as dr

FORMS = ("qualitative", "full")

_TINY = 1e-30


def coefficients(sigma):
    """(A, B) of the qualitative form; A = C1 and B/0.45 = σ²/(σ² + 0.09) serve the full form."""
    s2 = dr.square(sigma)
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def factor(form: str, sigma, wi, wo, rho=None):
    """
    f/(ρ/π) for directions above the surface; ``rho`` (the reflectance, needed by the ``full``
    form's interreflection term only) may be a spectrum, and the result is then one.
    """
    a, b = coefficients(sigma)
    xy = dr.fma(wi.y, wo.y, wi.x * wo.x)     # cos Δφ sinθi sinθo
    cos_beta = dr.maximum(wi.z, wo.z)        # β: the direction nearer the normal
    if form == "qualitative":
        return a + b * dr.maximum(xy, 0.0) / dr.maximum(cos_beta, _TINY)
    cos_alpha = dr.minimum(wi.z, wo.z)
    sin_i = dr.sqrt(dr.fma(wi.x, wi.x, wi.y * wi.y))
    sin_o = dr.sqrt(dr.fma(wo.x, wo.x, wo.y * wo.y))
    sin_alpha, sin_beta = dr.select(wi.z < wo.z, sin_i, sin_o), dr.select(wi.z < wo.z, sin_o, sin_i)
    sines = sin_i * sin_o
    cos_phi = dr.select(sines > 0, dr.clip(xy / dr.maximum(sines, _TINY), -1.0, 1.0), 0.0)
    alpha, beta = dr.atan2(sin_alpha, cos_alpha), dr.atan2(sin_beta, cos_beta)
    ratio = b / 0.45                          # σ²/(σ² + 0.09)
    beta_2pi = 2.0 * dr.inv_pi * beta         # 2β/π
    c2 = b * dr.select(cos_phi >= 0, sin_alpha, sin_alpha - beta_2pi * dr.square(beta_2pi))
    c3 = 0.125 * ratio * dr.square(4.0 * dr.square(dr.inv_pi) * alpha * beta)
    tan_beta = sin_beta / dr.maximum(cos_beta, _TINY)
    # tan((α + β)/2) by the half-angle formula: both denominators' terms are ≥ 0
    tan_half = (sin_alpha + sin_beta) / dr.maximum(cos_alpha + cos_beta, _TINY)
    single = a + cos_phi * c2 * tan_beta + (1.0 - dr.abs(cos_phi)) * c3 * tan_half
    s2 = dr.square(sigma)
    c4 = 0.17 * s2 / (s2 + 0.13)
    # as the paper writes it: negative at grazing forward scattering for ρ ≲ 0.85 (docstring)
    return single + rho * (c4 * (1.0 - cos_phi * dr.square(beta_2pi)))
