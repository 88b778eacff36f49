"""
Three-vectors for the terms, cheap in every variant.

The terms take anything with ``.x``, ``.y``, ``.z``: ``mi.Vector3f`` (JIT variants: the
components are arrays, and these helpers trace the same operations as ``dr.dot`` and
``dr.normalize``) or a named tuple of Python floats. Scalar variants, where Mitsuba calls a
plugin once per ray and an operation on a ``mi.Vector3f`` costs 0.2–3 µs (``dr.normalize``
2.8 µs, ``dr.dot`` 0.7 µs, against 0.01 µs for a float product), use the flat float versions
of the terms (``microfacet.reflection_floats``) on (x, y, z) tuples, and :func:`reflect_f32`.
"""

from __future__ import annotations

import struct

import drjit as dr


def dot(a, b):
    """
    a·b from the components, with the fused multiply-adds of ``dr.dot``, so that the terms
    round as Mitsuba's C++ BSDFs do (with separate products and sums, cooktorrance differed from
    roughconductor by 2e-6 where it is bit-identical with these).
    """
    return dr.fma(a.z, b.z, dr.fma(a.y, b.y, a.x * b.x))


def half_vector(wi, wo, vec3):
    """(ωi + ωo)/‖ωi + ωo‖ as ``dr.normalize`` computes it, built with ``vec3`` (NaN when
    ωo = −ωi, to be masked)."""
    hx, hy, hz = wi.x + wo.x, wi.y + wo.y, wi.z + wo.z
    inv = dr.rsqrt(dr.fma(hz, hz, dr.fma(hy, hy, hx * hx)))
    return vec3(hx * inv, hy * inv, hz * inv)


_F32X3 = struct.Struct("3f")


def reflect_f32(wi, m) -> tuple:
    """
    The mirror image 2(ωi·m)m − ωi of ωi about m, for (x, y, z) sequences of Python floats,
    rounded to float32 as a scalar variant's ``mi.Vector3f`` stores it: the direction a
    ``BSDFSample3f`` records, so that a sample's terms can be evaluated at it (rounding by
    ``struct``: 0.13 µs, where building a ``mi.Vector3f`` and reading it back costs 0.5).
    """
    ix, iy, iz = wi
    mx, my, mz = m
    k = 2.0 * (ix * mx + iy * my + iz * mz)
    return _F32X3.unpack(_F32X3.pack(k * mx - ix, k * my - iy, k * mz - iz))
