r"""
The kernels of the Ross-Thick Li-Sparse-Reciprocal model (Lucht, Schaaf & Strahler 2000, IEEE
TGRS 38(2), eqs. 37-44; Wanner, Li & Strahler 1995, JGR 100(D10), eqs. 13, 32, 40-44), as
functions of the directions in the local frame: ωi towards the sun, ωo towards the viewer,
both above the surface, the phase angle ξ between them (the hot spot at ωo = ωi):

    K_vol = ((π/2 − ξ) cos ξ + sin ξ)/(cosθi + cosθo) − π/4,
    K_geo = O − secθi' − secθo' + ½(1 + cos ξ') secθi' secθo',

O the overlap of the crowns' shadows from D and t (:func:`li_sparse_r`), the primed angles
those of the directions stretched horizontally by b/r (tanθ' = (b/r) tanθ, the azimuth kept).

Written without angles where vectors give them safely: sin ξ = |ωi × ωo| and
ξ = atan2(sin ξ, cos ξ) (no acos or √(1 − cos²) at the hot spot, ξ = 0); the tangent vector
p = ω'_xy/cosθ' (|p| = tanθ'), so that D = |pi − po|, tanθi' tanθo' sin φ = pi × po and
cos ξ' secθi' secθo' = 1 + pi·po; t = atan2(√(1 − cos²t), cos t). The cosines are held at
:data:`COS_MIN` or above, so that sec ≤ 10⁶, sec² ≤ 10¹² and every term stays finite in
float32 up to the horizon (the model itself is ±∞ there); the float64 counterpart, with
angles: :mod:`mi_brdfs.reference.rtls`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

#: The smallest cosine the kernels use (θ ≤ 89.99994°): sec θ ≤ 10⁶.
COS_MIN = 1e-6


def ross_thick(wi, wo):
    """K_vol at ωi, ωo (above the surface)."""
    cos_xi = dr.clip(dr.dot(wi, wo), -1.0, 1.0)
    sin_xi = dr.norm(dr.cross(wi, wo))
    xi = dr.atan2(sin_xi, cos_xi)
    cos_sum = dr.maximum(wi.z, COS_MIN) + dr.maximum(wo.z, COS_MIN)
    return ((0.5 * dr.pi - xi) * cos_xi + sin_xi) / cos_sum - 0.25 * dr.pi


def _primed(w, b_over_r):
    """(p, sec θ') of ω stretched horizontally by b/r: p = ω'_xy/cosθ'."""
    v = dr.normalize(mi.Vector3f(b_over_r * w.x, b_over_r * w.y, w.z))
    cos = dr.maximum(v.z, COS_MIN)
    sec = dr.rcp(cos)
    return mi.Vector2f(v.x * sec, v.y * sec), sec


def li_sparse_r(wi, wo, h_over_b, b_over_r):
    """K_geo at ωi, ωo (above the surface) for crowns of shape h/b, b/r."""
    pi, sec_i = _primed(wi, b_over_r)
    po, sec_o = _primed(wo, b_over_r)
    sec_sum = sec_i + sec_o
    d2 = dr.squared_norm(pi - po)
    cross = pi.x * po.y - pi.y * po.x
    cos_t = dr.clip(h_over_b * dr.sqrt(d2 + cross * cross) / sec_sum, -1.0, 1.0)
    sin_t = dr.safe_sqrt(1.0 - cos_t * cos_t)
    t = dr.atan2(sin_t, cos_t)
    overlap = (t - sin_t * cos_t) * sec_sum * dr.inv_pi
    return overlap - sec_sum + 0.5 * (sec_i * sec_o + 1.0 + dr.dot(pi, po))


def brf(f_iso, f_vol, f_geo, wi, wo, h_over_b, b_over_r):
    """The model's BRF f_iso + f_vol K_vol + f_geo K_geo (negative where the fit is)."""
    return f_iso + f_vol * ross_thick(wi, wo) + f_geo * li_sparse_r(wi, wo, h_over_b, b_over_r)
