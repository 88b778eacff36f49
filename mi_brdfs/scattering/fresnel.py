r"""
Fresnel reflectance of unpolarised light at a smooth interface with relative complex index of
refraction η + ik, per channel: η and k may be spectra (RGB, wavelengths) or plain floats,
``cos_theta_i`` is a Float. k = 0 is a dielectric (with total internal reflection for η < 1),
η = 0 with k = 1 a perfect mirror.

:func:`exact` is the full formula (Born & Wolf; Cook & Torrance 1982 use its dielectric case,
F = ½ (g−c)²/(g+c)² [1 + (c(g+c)−1)²/(c(g−c)+1)²] with g² = η² + c² − 1). With
a² + b² = sqrt((η² − k² − sin²θ)² + 4η²k²) and 2a² = (a² + b²) + (η² − k² − sin²θ):

.. math::

    R_s = \frac{(a - \cos\theta)^2 + b^2}{(a + \cos\theta)^2 + b^2}, \qquad
    R_p = R_s \, \frac{(a\cos\theta - \sin^2\theta)^2 + b^2\cos^2\theta}
                      {(a\cos\theta + \sin^2\theta)^2 + b^2\cos^2\theta}, \qquad
    F = \tfrac12 (R_s + R_p).

These are the usual expressions (pbrt-v3 ``FrConductor``, Mitsuba's ``fresnel_conductor``) with
each numerator and denominator written as a sum of squares: never negative, and free of the
cancellation that makes the expanded form (a² + b² − 2a cosθ + cos²θ) round below 0 as η → 1.

:func:`schlick` is Schlick's approximation R0 + (1 − R0)(1 − cosθ)⁵ with the normal-incidence
reflectance R0 = ((η − 1)² + k²) / ((η + 1)² + k²) of the same η, k (:func:`r0`).

:func:`polarized_reflection` is the Mueller matrix of specular reflection at a facet, for
Mitsuba's polarized variants: F above is its first element.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .vector import dot

#: Largest η and k the terms take (and the widest ratio of two indices): beyond about 1e9 the
#: squares in them leave float32's range (η⁴ > 3.4e38) and F is NaN; no material comes near
#: (metals' η and k stay below 100).
IOR_MAX = 1e6

# Floor of denominators that vanish only in degenerate cases (grazing light on η = 1, k = 0):
# there the numerator vanishes too, and F = 0 is the limit.
_TINY = 1e-30


def exact(cos_theta_i, eta, k):
    """Unpolarised Fresnel reflectance at incidence cosθi ∈ [0, 1], exact, per channel."""
    c = dr.minimum(dr.maximum(cos_theta_i, 0.0), 1.0)
    c2 = c * c
    s2 = 1.0 - c2
    ek = eta * k
    t0 = eta * eta - k * k - s2
    # a² + b², and a; safe_sqrt: the same values, and a derivative of 0 (not ∞·0 = NaN) where
    # the argument is 0, as a is for a perfect mirror (η = 0)
    ab = dr.safe_sqrt(t0 * t0 + 4.0 * ek * ek)
    a = dr.safe_sqrt(0.5 * (ab + t0))
    b2 = dr.maximum(0.5 * (ab - t0), 0.0)
    am, ap = a - c, a + c
    rs = (am * am + b2) / dr.maximum(ap * ap + b2, _TINY)
    ac = a * c
    pm, pp = ac - s2, ac + s2
    b2c2 = b2 * c2
    rp = rs * (pm * pm + b2c2) / dr.maximum(pp * pp + b2c2, _TINY)
    return 0.5 * (rs + rp)


def r0(eta, k):
    """Reflectance at normal incidence: ((η − 1)² + k²) / ((η + 1)² + k²)."""
    k2 = dr.square(k)
    return (dr.square(eta - 1.0) + k2) / (dr.square(eta + 1.0) + k2)


def schlick(cos_theta_i, eta, k):
    """Schlick's approximation R0 + (1 − R0)(1 − cosθi)⁵, with R0 from η and k."""
    return schlick_r0(cos_theta_i, r0(eta, k))


def schlick_r0(cos_theta_i, f0):
    """Schlick's approximation R0 + (1 − R0)(1 − cosθi)⁵ for a given R0 = ``f0``."""
    x = 1.0 - dr.minimum(dr.maximum(cos_theta_i, 0.0), 1.0)
    x2 = x * x
    return f0 + (1.0 - f0) * (x2 * x2 * x)


def dielectric(cos_theta_i, eta):
    r"""
    Fresnel reflectance of a smooth dielectric interface for light arriving from either side,
    and the refracted ray's cosine: ``(F, cos_theta_t, eta_it, eta_ti)``.

    ``eta`` is the relative index η = η_int/η_ext (a Float, the same for every wavelength, as
    refraction bends them all alike here); ``cos_theta_i`` is signed: > 0 from outside (the
    side the normal points to), < 0 from inside, where the relative index inverts. With
    η_it the relative index in the direction of travel and η_ti = 1/η_it, Snell's law gives
    cos²θt = 1 − η_ti² (1 − cos²θi); below 0 the light is totally reflected (F = 1). Else
    (Born & Wolf; Walter et al. 2007, eq. 22 in the form of the amplitude coefficients)

    .. math::

        r_s = \frac{|\cos\theta_i| - \eta_{it}|\cos\theta_t|}
                   {|\cos\theta_i| + \eta_{it}|\cos\theta_t|}, \quad
        r_p = \frac{|\cos\theta_t| - \eta_{it}|\cos\theta_i|}
                   {|\cos\theta_t| + \eta_{it}|\cos\theta_i|}, \quad
        F = \tfrac12 (r_s^2 + r_p^2),

    F = 0 for η = 1 and F = 1 at cosθi = 0. ``cos_theta_t`` has the sign opposite to
    ``cos_theta_i`` (the refracted ray leaves on the other side). Each product and sum is
    rounded as in ``mi.fresnel``, so the two agree bit for bit in JIT variants
    (``tests/scattering/test_fresnel.py``).
    """
    outside = cos_theta_i >= 0.0
    inv_eta = dr.rcp(eta)
    eta_it = dr.select(outside, eta, inv_eta)
    eta_ti = dr.select(outside, inv_eta, eta)
    # Snell's law: cos²θt = 1 − η_ti² sin²θi
    cos_t2 = dr.fma(-dr.fma(-cos_theta_i, cos_theta_i, 1.0), eta_ti * eta_ti, 1.0)
    cos_i = dr.abs(cos_theta_i)
    cos_t = dr.sqrt(dr.maximum(cos_t2, 0.0))  # 0 under total internal reflection: F = 1
    # (the floors only matter at cosθi = cosθt = 0, grazing under total reflection: F = 1)
    a_s = dr.fma(-eta_it, cos_t, cos_i) / dr.maximum(dr.fma(eta_it, cos_t, cos_i), _TINY)
    a_p = dr.fma(-eta_it, cos_i, cos_t) / dr.maximum(dr.fma(eta_it, cos_i, cos_t), _TINY)
    f = 0.5 * (dr.square(a_s) + dr.square(a_p))
    f = dr.select(eta == 1.0, 0.0, dr.select(cos_i == 0.0, 1.0, f))
    return f, dr.select(outside, -cos_t, cos_t), eta_it, eta_ti


def polarized_reflection(wi, wo, m, eta, k, radiance: bool):
    r"""
    The Mueller matrix (``mi.Spectrum`` of a polarized variant) of the specular reflection of
    light at a facet of normal ``m`` with relative index η + ik (per channel), in the Stokes
    frames Mitsuba attaches to the directions of travel (Mitsuba's ``mueller.h``: a Stokes
    vector travelling along d has its reference axis ``mueller.stokes_basis(d)``).

    Light arrives along −ω̂o and leaves along ω̂i, where (ω̂o, ω̂i) = (ωo, ωi) in radiance
    transport and (ωi, ωo) in importance transport. The matrix of reflection at the facet
    (``mueller.specular_reflection``, per channel at cosθ = ω̂o·m: its s axis is
    perpendicular to the plane of reflection, m × −ω̂o before and m × ω̂i after) is rotated
    from those axes into the Stokes bases of −ω̂o and ω̂i; where ω̂o, ω̂i and m are collinear
    (normal incidence) the plane of reflection is undefined and the x axis stands for it. These
    are the conventions of ``roughconductor`` (``src/bsdfs/roughconductor.cpp``), whose
    polarized values the plugin reproduces.
    """
    wo_hat = wo if radiance else wi
    cos_theta = dot(wo_hat, m)
    channels = [mi.mueller.specular_reflection(cos_theta, mi.Complex2f(eta[c], k[c]))
                for c in range(len(eta))]
    M = mi.Spectrum(0.0)
    for i in range(4):
        for j in range(4):
            M[i, j] = mi.UnpolarizedSpectrum(*(channel[i, j] for channel in channels))
    return rotate_reflection(M, wi, wo, m, radiance)


def rotate_reflection(M, wi, wo, m, radiance: bool):
    """The Mueller matrix ``M`` of a reflection at the facet ``m``, laid out as
    ``mi.mueller.specular_reflection`` (s axis perpendicular to the plane of reflection),
    rotated into the Stokes bases of the directions of travel, as
    :func:`polarized_reflection` describes."""
    wo_hat, wi_hat = (wo, wi) if radiance else (wi, wo)
    s_in, s_out = dr.cross(m, -wo_hat), dr.cross(m, wi_hat)
    collinear = dr.all(s_in == 0.0)
    x_axis = mi.Vector3f(1.0, 0.0, 0.0)
    s_in = dr.select(collinear, x_axis, dr.normalize(s_in))
    s_out = dr.select(collinear, x_axis, dr.normalize(s_out))
    return mi.mueller.rotate_mueller_basis(M, -wo_hat, s_in, mi.mueller.stokes_basis(-wo_hat),
                                           wi_hat, s_out, mi.mueller.stokes_basis(wi_hat))
