"""The three-vector helpers of mi_brdfs.scattering.vector: bit for bit what Mitsuba computes."""

import drjit as dr
import mitsuba as mi
import numpy as np
from helpers import random_directions

from mi_brdfs.scattering import vector


def test01_bit_identical_to_mitsuba(variant_llvm_ad_rgb, np_rng):
    """dot, half_vector and reflect round exactly as dr.dot, dr.normalize(ωi + ωo) and
    mi.reflect: the reason cooktorrance renders bit-identical to roughconductor."""
    a = random_directions(np_rng, 20_000).astype(np.float32)
    b = random_directions(np_rng, 20_000).astype(np.float32)
    u, v = mi.Vector3f(a.T), mi.Vector3f(b.T)
    for ours, theirs in ((vector.dot(u, v), dr.dot(u, v)),
                         (vector.half_vector(u, v), dr.normalize(u + v)),
                         (vector.reflect(u, v), mi.reflect(u, v))):
        np.testing.assert_array_equal(np.array(ours), np.array(theirs))


def test02_scalar_values(variant_scalar_rgb, np_rng):
    """On scalar variants' Python floats: the float64 values to float32 storage, and NaN (not
    an exception) for the half vector of opposite directions."""
    for a, b in zip(random_directions(np_rng, 200), random_directions(np_rng, 200)):
        u, v = mi.Vector3f(*map(float, a)), mi.Vector3f(*map(float, b))
        a, b = np.array([u.x, u.y, u.z]), np.array([v.x, v.y, v.z])
        assert vector.dot(u, v) == np.float64(a @ b) or abs(vector.dot(u, v) - a @ b) < 1e-15
        h = vector.half_vector(u, v)
        np.testing.assert_allclose([h.x, h.y, h.z], (a + b) / np.linalg.norm(a + b), atol=2e-7)
        r = vector.reflect(u, v)
        np.testing.assert_allclose([r.x, r.y, r.z], 2 * (a @ b) * b - a, atol=5e-7)
    h = vector.half_vector(mi.Vector3f(0.6, 0, 0.8), mi.Vector3f(-0.6, 0, -0.8))
    assert np.isnan(h.z)
