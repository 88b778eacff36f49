r"""
The generalized cosine lobe of Lafortune, Foo, Torrance & Greenberg (1997, "Non-Linear
Approximation of Reflectance Functions", SIGGRAPH '97): for directions u, v in the local frame
(normal +z, both pointing away from the surface) and a lobe with coefficients C = (Cx, Cy, Cz)
and exponent n,

    g(u, v) = Cx·ux·vx + Cy·uy·vy + Cz·uz·vz,        lobe = max(0, g)ⁿ,

0 wherever g ≤ 0 (for n = 0 as well). g is symmetric in u and v, so every lobe is reciprocal.
Cx = Cy = −Cz gives Phong's mirror lobe (g = |C|·cos α), Cx = Cy > 0 a retro-reflective one,
|Cz| < −Cx = −Cy one whose peak moves towards grazing (the paper's off-specular reflection).

**Written about the principal direction.** For fixed u, g(u, v) = (C∘u)·v, where C∘u is the
component-wise product: the lobe is a cosⁿ lobe about d = (C∘u)/|C∘u|, scaled. With
c = max(|Cx|, |Cy|, |Cz|) (c ≥ |C∘u| for unit u) and C' = C/c,

    (g/c)ⁿ = rⁿ·cosⁿβ,   r = |C'∘u| ∈ [0, 1],   cos β = d·v,

and r² = 1 − q with q = Σ (1 − C'k²) uk², which is exactly 0 for a lobe whose |Ck| are all
equal (Phong's): no rounding of |C∘u| reaches rⁿ there, which n = 10⁶ would amplify a
millionfold. cosⁿβ is evaluated from 1 − cos β = |v − d|²/2, as
:func:`mi_brdfs.scattering.phong.cos_power` does for Phong's lobe; for the mirror lobe d is
exactly Phong's R. The two normalisations of the plugin put a factor K in front:

* ``normalize`` = true: f = ρs·(n+2)/(2π)·(g/c)ⁿ. The mirror lobe is then the modified Phong lobe
  of Lafortune & Willems (1994), ρs·(n+2)/(2π)·cosⁿα, whatever the scale of C, and no lobe
  reflects more than ρs at any incidence (see :func:`albedo_scale`);
* ``normalize`` = false: f = ρs·gⁿ, the paper's form, where C carries the lobe's magnitude cⁿ
  (the paper writes Phong's lobe as −Cx = −Cy = Cz = ((n+2)/(2π))^(1/n)).

**Sampling** draws cosⁿβ about d (density (n+1)/(2π)·cosⁿβ, as
:func:`mi_brdfs.scattering.phong.sample_cos_power`), which is proportional to the lobe for the
given u; the lobes and a cosine-weighted diffuse term are mixed in proportion to weights
(:mod:`mi_brdfs.scattering.mixture`: Veach 1997, §9.2.4, with more than two strategies).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

from .phong import cos_power, pdf_normalization, sample_cos_power
from .stable import log1p

#: Largest exponent accepted: as :data:`mi_brdfs.plugins.phong.EXPONENT_MAX`, it keeps n and
#: (n+2)/(2π) finite in float32.
EXPONENT_MAX = 1e30

#: Largest magnitude K of a lobe accepted (the factor in front of rⁿcosⁿβ): ``normalize`` =
#: false gives K = cⁿ, which leaves float32's range (3.4e38) for c > 1 and large n, where the
#: model itself is not finite. The plugin refuses such lobes at load; values set later through
#: ``mi.traverse`` are clamped to it.
MAGNITUDE_MAX = 1e30


class Lobe:
    """
    The constants of one lobe, computed once per parameter change: C' = C/c, 1 − C'², n,
    1/(n+1), the magnitude K, the sampling density factor (n+1)/(2π) and K·2π/(n+2), the
    lobe's albedo if its principal direction were the normal and r = 1.
    """

    def __init__(self, cx, cy, cz, n, normalize: bool):
        # values set through mi.traverse are not validated: clamp them into the accepted range
        n = dr.clip(n, 0.0, EXPONENT_MAX)
        c = dr.maximum(dr.maximum(dr.abs(cx), dr.abs(cy)), dr.abs(cz))
        inv_c = dr.select(c > 0, 1.0 / dr.select(c > 0, c, 1.0), 0.0)
        self.c = tuple(ck * inv_c for ck in (cx, cy, cz))   # C' ∈ [−1, 1]³, 0 for C = 0
        self.e = tuple(1.0 - ck * ck for ck in self.c)      # 1 − C'k², exactly 0 where |Ck| = c
        self.n, self.inv_n1 = n, 1.0 / (n + 1.0)
        self.magnitude = magnitude(c, n, normalize)
        self.pdf_norm = pdf_normalization(n)
        self.albedo_scale = albedo_scale(self.magnitude, n)

    def arrays(self) -> list:
        """Every constant, for ``dr.make_opaque``."""
        return [*self.c, *self.e, self.n, self.inv_n1, self.magnitude, self.pdf_norm,
                self.albedo_scale]


def magnitude(c, n, normalize: bool):
    """K: (n+2)/(2π) (``normalize``) or cⁿ (the paper's form, capped at MAGNITUDE_MAX)."""
    if normalize:
        return (n + 2.0) * dr.inv_two_pi
    # cⁿ = exp(n log c); c = 0 gives 0 (no lobe at all), also for n = 0
    log_c = dr.log(dr.maximum(c, 1e-30))
    return dr.select(c > 0, dr.exp(dr.minimum(n * log_c, math.log(MAGNITUDE_MAX))), 0.0)


def albedo_scale(k, n):
    """
    K·2π/(n+2): the albedo of the lobe K·cosⁿβ about the normal (∫ cosⁿβ cosθ dω = 2π/(n+2)).
    No lobe direction does better: ∫ cosⁿβ max(0, cosθ) dω over the sphere is largest when
    the lobe's axis is the normal, by the rearrangement inequality on the sphere (Baernstein &
    Taylor 1976: both factors fall with the angle to their axis). With r ≤ 1, a lobe's albedo
    is at most ρs·K·2π/(n+2), which is ρs when normalised.
    """
    return k * (dr.two_pi / (n + 2.0))


def axis(wi, lobe: Lobe):
    """
    (d, rⁿ) of ``lobe`` for incident ``wi``: the principal direction d = C'∘ωi / r (|d| = |ωi|,
    so d = R, Phong's mirror direction, for Cx = Cy = −Cz) and the scale rⁿ = |C'∘ωi|ⁿ, 0 where
    C∘ωi = 0 (there g = 0: no lobe, d is then the normal).
    """
    cx, cy, cz = lobe.c
    ex, ey, ez = lobe.e
    x2, y2, z2 = wi.x * wi.x, wi.y * wi.y, wi.z * wi.z
    norm2 = x2 + y2 + z2
    inv_norm2 = 1.0 / dr.select(norm2 > 0, norm2, 1.0)
    # r² and 1 − r² as sums of non-negative terms, each accurate where it is small: r² gives
    # d (r → 0 at grazing, for Cz alone), 1 − r² gives rⁿ near r = 1 (1 exactly for Phong's)
    r2 = (cx * cx * x2 + cy * cy * y2 + cz * cz * z2) * inv_norm2
    q = dr.minimum((ex * x2 + ey * y2 + ez * z2) * inv_norm2, 1.0)
    ok = r2 > 0
    log_r2 = dr.select(q < 0.5, log1p(-q), dr.log(dr.select(ok, r2, 1.0)))
    inv_r = dr.select(ok, 1.0 / dr.sqrt(dr.select(ok, r2, 1.0)), 0.0)
    d = mi.Vector3f(cx * wi.x * inv_r, cy * wi.y * inv_r, dr.select(ok, cz * wi.z * inv_r, 1.0))
    return d, dr.select(ok, dr.exp(0.5 * lobe.n * log_r2), 0.0)


def lobe_value(wo, d, scale, lobe: Lobe):
    """
    (K·rⁿ·cosⁿβ, the sampling density (n+1)/(2π)·cosⁿβ) at ``wo``, β the angle between ``wo``
    and the principal direction ``d`` of :func:`axis` (``scale`` = its rⁿ).
    """
    dx, dy, dz = wo.x - d.x, wo.y - d.y, wo.z - d.z
    cos_n = cos_power(0.5 * (dx * dx + dy * dy + dz * dz), lobe.n)
    return lobe.magnitude * scale * cos_n, lobe.pdf_norm * cos_n


def sample(d, u, inv_n1):
    """``wo`` drawn with density (n+1)/(2π)·cosⁿβ about the principal direction ``d``, from
    ``u`` ∈ [0, 1)² and 1/(n+1)."""
    return mi.Frame3f(d).to_world(sample_cos_power(u, inv_n1))
