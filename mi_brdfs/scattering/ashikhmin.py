r"""
The anisotropic Phong model of Ashikhmin & Shirley (2000, "An Anisotropic Phong BRDF Model",
Journal of Graphics Tools 5(2)): its specular and diffuse terms, the sampler of its half vector
and the density that goes with it.

Directions are in the local frame (normal n = +z, tangent u = +x, bitangent v = +y), k1 = ωi
and k2 = ωo both pointing away from the surface, h = (k1 + k2)/|k1 + k2| and k·h = k1·h = k2·h.
With the density p_h of the paper's half-vector sampler (φh the azimuth of h)

.. math::

    p_h(h) = \frac{\sqrt{(n_u+1)(n_v+1)}}{2\pi}\,(n\cdot h)^{n_u\cos^2\phi_h + n_v\sin^2\phi_h}

the paper's specular term ρs (with Schlick's approximation F) and diffuse term ρd are

.. math::

    \rho_s = \frac{p_h(h)\,F(k\cdot h)}{4\,(k\cdot h)\max(n\cdot k_1, n\cdot k_2)}, \quad
    F = R_s + (1 - R_s)(1 - k\cdot h)^5, \quad
    \rho_d = \frac{28 R_d}{23\pi}(1 - R_s)\Big(1 - \big(1 - \tfrac{n\cdot k_1}{2}\big)^5\Big)
             \Big(1 - \big(1 - \tfrac{n\cdot k_2}{2}\big)^5\Big).

**Sampling**, as the paper samples: h with density p_h (φh and cosθh from two uniform numbers,
:func:`sample_half`), k2 the mirror image of k1 about h, whose density is p(k2) = p_h(h) /
(4 k·h). So ρs·cosθo = p(k2)·F·cosθo / max(cosθi, cosθo), the form :func:`specular` computes:
the sample weight of the lobe is F·cosθo/max(cosθi, cosθo) ≤ 1, whatever float32 makes of a
density at the edge of its range.

**Float32.** The exponent is written as the paper writes it without trigonometry, (nu hx² +
nv hy²)/(1 − hz²) = nu cos²φh + nv sin²φh, and taken from the components of the unnormalised
k1 + k2 (a ratio in [nu, nv]: no 0/0 except at h = n, where the lobe is 1 whatever the
exponent); (n·h)^e is the halfway Phong lobe of :func:`mi_brdfs.scattering.phong.halfway_lobe`,
exp(e·log1p(−(1 − cosθh))) with 1 − cosθh free of cancellation, and so is its density p(k2),
with the normalisation of p_h in place of (n+1)/(2π). The normalisation is √(nu+1)·√(nv+1),
which does not overflow for exponents up to :data:`EXPONENT_MAX`; 1 − (1 − x)⁵ is a polynomial
in x, accurate for small x.

**Energy.** For k2 above the surface, 2(k·h)(n·h) = n·k1 + n·k2 > n·k1 and n·h ≤ 1, so
k·h > (n·k1)/2 and F ≤ Rs + (1 − Rs)(1 − (n·k1)/2)⁵; as p_h integrates to 1 over the half
vectors and cosθo/max(…) ≤ 1, the specular albedo is at most that bound. 28/(23π) normalises
the diffuse factor of k2 exactly (2π ∫₀¹ (1 − (1 − μ/2)⁵) μ dμ = 23π/28), so the diffuse albedo
is Rd (1 − Rs)(1 − (1 − (n·k1)/2)⁵). The two bounds (:func:`albedo_bounds`) add up to at most 1
for Rs, Rd ∈ [0, 1]: the model conserves energy at every incidence, as the paper claims.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .fresnel import schlick_r0
from .phong import cos_power_theta, halfway_lobe

#: Largest exponent accepted (as the ``phong`` plugin's): the lobe is then far narrower than
#: float32 can resolve, and √(n+1) stays finite.
EXPONENT_MAX = 1e30

#: 28/(23π), the normalisation of the paper's diffuse term.
DIFFUSE_NORMALIZATION = 28.0 / (23.0 * dr.pi)

_TINY = 1e-30


def exponent(hx, hy, nu, nv):
    """nu cos²φh + nv sin²φh, the lobe's exponent, from the x and y components of any multiple of
    h; ``(nu + nv)/2`` at h = n, where the lobe does not depend on it."""
    t2 = hx * hx + hy * hy
    ok = t2 > 0.0
    w = dr.select(ok, hx * hx / dr.select(ok, t2, 1.0), 0.5)  # cos²φh
    return nu * w + nv * (1.0 - w)


def normalization(nu, nv):
    """√((nu+1)(nv+1))/(2π), the factor of p_h."""
    return dr.sqrt(nu + 1.0) * dr.sqrt(nv + 1.0) * dr.inv_two_pi


def lobe(wi, wo, nu, nv):
    """
    (p(ωo) = p_h(h)/(4 k·h), k·h): the density of ωi reflected about :func:`sample_half`'s
    half vector, and the cosine of F; for ``wi`` and ``wo`` above the surface.
    """
    e = exponent(wi.x + wo.x, wi.y + wo.y, nu, nv)
    _, density = halfway_lobe(wi, wo, e, normalization(nu, nv))
    # k·h = |k1 + k2|/2 for unit k1, k2: symmetric in them, as the model is
    k_dot_h = 0.5 * dr.norm(wi + wo)
    return density, k_dot_h


def fresnel(k_dot_h, rs):
    """Schlick's F(k·h) with Rs the reflectance at normal incidence, as the paper uses it."""
    return schlick_r0(k_dot_h, rs)


def specular(density, f, cos_theta_i, cos_theta_o):
    """
    ρs·cosθo from the density :func:`lobe` gives and F: p(ωo)·F·cosθo/max(cosθi,
    cosθo), for both directions above the surface.
    """
    return density * f * (cos_theta_o / dr.maximum(dr.maximum(cos_theta_i, cos_theta_o), _TINY))


def _one_minus_pow5(x):
    """1 − (1 − x)⁵ = x(5 − 10x + 10x² − 5x³ + x⁴), without the cancellation at small x."""
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))))


def diffuse(cos_theta_i, cos_theta_o):
    """ρd/(Rd (1 − Rs)) = 28/(23π)·(1 − (1 − cosθi/2)⁵)(1 − (1 − cosθo/2)⁵)."""
    return DIFFUSE_NORMALIZATION * (_one_minus_pow5(0.5 * cos_theta_i)
                                    * _one_minus_pow5(0.5 * cos_theta_o))


def albedo_bounds(rs, rd, cos_theta_i):
    """
    (bound of the specular albedo, diffuse albedo) at incidence cosθi: Rs + (1 − Rs)(1 −
    cosθi/2)⁵ and Rd (1 − Rs)(1 − (1 − cosθi/2)⁵) (module docstring, **Energy**); their sum
    is at most 1.
    """
    x = 0.5 * dr.clip(cos_theta_i, 0.0, 1.0)
    g = _one_minus_pow5(x)
    return rs + (1.0 - rs) * (1.0 - g), rd * (1.0 - rs) * g


def sample_half(u, nu, nv):
    """
    A half vector with density p_h from ``u`` ∈ [0, 1)², by the paper's formulas: φ =
    atan(√((nu+1)/(nv+1)) tan(πξ/2)) in the first quadrant, with ξ a quarter of ``u.x``
    mirrored into the quadrant that ``u.x`` picks (continuous in ``u.x``), and cosθ = (1 −
    u.y)^(1/(nu cos²φ + nv sin²φ + 1)).
    """
    q = 4.0 * u.x
    quadrant = dr.floor(q)
    xi = q - quadrant
    odd = (quadrant == 1.0) | (quadrant == 3.0)  # φ = π − φ₁ and 2π − φ₁: run ξ backwards
    s, c = dr.sincos(0.5 * dr.pi * dr.select(odd, 1.0 - xi, xi))
    # (cos φ, sin φ) ∝ (√(nv+1) cos(πξ/2), √(nu+1) sin(πξ/2)): no tan, so no pole at ξ → 1
    x, y = dr.sqrt(nv + 1.0) * c, dr.sqrt(nu + 1.0) * s
    inv = dr.rsqrt(dr.maximum(x * x + y * y, _TINY))
    cos_phi = dr.select((quadrant == 1.0) | (quadrant == 2.0), -x * inv, x * inv)
    sin_phi = dr.select(quadrant >= 2.0, -y * inv, y * inv)
    e = nu * cos_phi * cos_phi + nv * sin_phi * sin_phi
    cos_theta, sin_theta = cos_power_theta(1.0 - u.y, 1.0 / (e + 1.0))
    return mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
