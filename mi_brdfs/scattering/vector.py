"""
Three-vector helpers for the terms, the same in every variant.

They take anything with ``.x``, ``.y``, ``.z`` (``mi.Vector3f``: arrays in JIT variants, Python
floats in scalar ones) and use the fused multiply-adds of ``dr.dot`` and ``dr.normalize``, so that
the terms round exactly as Mitsuba's C++ BSDFs do (``tests/scattering/test_vector.py`` checks the
results bit for bit against ``dr.dot``, ``dr.normalize`` and ``mi.reflect``).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi


def dot(a, b):
    """a·b, rounded as ``dr.dot`` rounds it."""
    return dr.fma(a.z, b.z, dr.fma(a.y, b.y, a.x * b.x))


def half_vector(wi, wo):
    """(ωi + ωo)/‖ωi + ωo‖ as ``dr.normalize`` computes it (NaN when ωo = −ωi, to be masked)."""
    hx, hy, hz = wi.x + wo.x, wi.y + wo.y, wi.z + wo.z
    inv = dr.rsqrt(dr.fma(hz, hz, dr.fma(hy, hy, hx * hx)))  # +inf for h = 0: then 0·inf = NaN
    return mi.Vector3f(hx * inv, hy * inv, hz * inv)


def reflect(wi, m):
    """The mirror image 2(ωi·m)m − ωi of ωi about m, as ``mi.reflect`` computes it."""
    k = 2.0 * dot(wi, m)
    return mi.Vector3f(dr.fma(k, m.x, -wi.x), dr.fma(k, m.y, -wi.y), dr.fma(k, m.z, -wi.z))


def refract(wi, m, cos_theta_t, eta_ti):
    """
    ωi refracted through a facet of normal m: (ωi·m η_ti + cosθt) m − η_ti ωi, with cosθt and
    η_ti from :func:`mi_brdfs.scattering.fresnel.dielectric` (Snell's law in vector form), as
    ``mi.refract`` computes it.
    """
    k = dr.fma(dot(wi, m), eta_ti, cos_theta_t)
    return mi.Vector3f(dr.fma(m.x, k, -(wi.x * eta_ti)), dr.fma(m.y, k, -(wi.y * eta_ti)),
                       dr.fma(m.z, k, -(wi.z * eta_ti)))


def generalized_half_vector(wi, wo, eta):
    """
    The generalised half vector (Walter et al. 2007, eq. 16): ωi + η ωo normalised and turned
    to the side of the normal, with η the relative index in the direction of travel for a
    refraction and 1 for a reflection (then :func:`half_vector`, turned up when both directions
    lie below the surface); NaN for ωi + η ωo = 0. Rounded as Mitsuba's ``roughdielectric``
    computes it (a product and a sum, not a fused multiply-add).
    """
    hx, hy, hz = wi.x + wo.x * eta, wi.y + wo.y * eta, wi.z + wo.z * eta
    inv = dr.rsqrt(dr.fma(hz, hz, dr.fma(hy, hy, hx * hx)))
    inv = dr.select(hz < 0.0, -inv, inv)
    return mi.Vector3f(hx * inv, hy * inv, hz * inv)
