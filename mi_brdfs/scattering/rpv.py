r"""
The Rahman-Pinty-Verstraete model (Rahman, Pinty & Verstraete 1993, JGR 98(D11), eqs. 2-6)
as a function of the directions in the local frame: ωi towards the sun, ωo towards the
viewer, both above the surface,

    BRF = ρ0 M F H,    M = [cosθi cosθo (cosθi + cosθo)]^(k − 1),
    F = (1 − g²)/(1 + g² + 2g cos ξ)^(3/2),    H = 1 + (1 − ρc)/(1 + G),

ξ the phase angle (cos ξ = ωi·ωo: 0 at the hot spot ωo = ωi; the paper's cos(π − ξ) = −cos ξ)
and G = √(tan²θi + tan²θo − 2 tanθi tanθo cos φ) the distance between the tangent vectors
p = ω_xy/cosθ (|p| = tanθ): G = |pi − po|, which does not cancel at the hot spot.

F's denominator d = 1 + g² + 2g cos ξ is written without cancellation: with 1 ± cos ξ =
|ωi ± ωo|²/2, d = (1 − g)² + g|ωi + ωo|² for g ≥ 0 and (1 + g)² − g|ωi − ωo|² for g < 0, two
non-negative terms each (d ≥ (1 − |g|)², which float32's cos ξ near ±1 would otherwise lose
for |g| near 1), and 1 − g² as (1 − g)(1 + g). The cosines are held at :data:`COS_MIN` or
above, so that for k ≥ 0 M ≤ (2·10⁻¹⁸)^(−1) and G ≤ 2·10⁶: every value is finite in float32
up to the horizon, where the model itself is +∞ for k < 1. The float64 counterpart, with
angles: :mod:`mi_brdfs.reference.rpv`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

#: The smallest cosine the model uses (θ ≤ 89.99994°), as in :mod:`.rtls`.
COS_MIN = 1e-6


def minnaert(k, wi, wo):
    """M = [cosθi cosθo (cosθi + cosθo)]^(k − 1) (k per channel)."""
    ci, co = dr.maximum(wi.z, COS_MIN), dr.maximum(wo.z, COS_MIN)
    return dr.exp((k - 1.0) * dr.log(ci * co * (ci + co)))


def henyey_greenstein(g, wi, wo):
    """F = (1 − g)(1 + g)/d^(3/2), d = 1 + g² + 2g cos ξ, both without cancellation (g per
    channel)."""
    plus, minus = dr.squared_norm(wi + wo), dr.squared_norm(wi - wo)
    d = dr.select(g >= 0.0, dr.square(1.0 - g) + g * plus, dr.square(1.0 + g) - g * minus)
    return (1.0 - g) * (1.0 + g) / (d * dr.sqrt(d))


def _tangent(w):
    """p = ω_xy/cosθ, the cosine held at :data:`COS_MIN`: |p| = tanθ."""
    inv = dr.rcp(dr.maximum(w.z, COS_MIN))
    return mi.Vector2f(w.x * inv, w.y * inv)


def hot_spot(rho_c, wi, wo):
    """H = 1 + (1 − ρc)/(1 + G), G = |pi − po| (ρc per channel)."""
    big_g = dr.norm(_tangent(wi) - _tangent(wo))
    return 1.0 + (1.0 - rho_c) / (1.0 + big_g)


def brf(rho_0, k, g, rho_c, wi, wo):
    """The model's BRF ρ0 M F H (≥ 0 for ρ0 ≥ 0, |g| < 1, ρc ≤ 2)."""
    return rho_0 * minnaert(k, wi, wo) * henyey_greenstein(g, wi, wo) * hot_spot(rho_c, wi, wo)
