"""The three-vector helpers of mi_brdfs.scattering.vector: bit for bit what Mitsuba computes."""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
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


def test03_refraction_bit_identical_to_mitsuba(variant_llvm_ad_rgb, np_rng):
    """refract and the generalised half vector round as mi.refract (with mi.fresnel's cosθt and
    η_ti) and as roughdielectric's dr.normalize(ωi + ωo η) turned to the normal's side: the
    reason cooktorrance with transmission samples roughdielectric's directions bit for bit."""
    from mi_brdfs.scattering import fresnel
    a = random_directions(np_rng, 20_000).astype(np.float32)
    m = random_directions(np_rng, 20_000, lower=False).astype(np.float32)
    wi, mm = mi.Vector3f(a.T), mi.Vector3f(m.T)
    eta = mi.Float(1.5)
    _, cos_t, _, eta_ti = mi.fresnel(dr.dot(wi, mm), eta)
    np.testing.assert_array_equal(np.array(vector.refract(wi, mm, cos_t, eta_ti)),
                                  np.array(mi.refract(wi, mm, cos_t, eta_ti)))
    ours = fresnel.dielectric(dr.dot(wi, mm), eta)
    for x, y in zip(ours, mi.fresnel(dr.dot(wi, mm), eta)):
        np.testing.assert_array_equal(np.array(x), np.array(y))
    wo = mi.Vector3f(random_directions(np_rng, 20_000).astype(np.float32).T)
    scale = dr.select(wi.z * wo.z > 0, 1.0, dr.select(wi.z > 0, eta, 1 / eta))
    h = dr.normalize(wi + wo * scale)
    h = dr.mulsign(h, h.z)
    ok = np.array(h.z) != 0
    np.testing.assert_array_equal(np.array(vector.generalized_half_vector(wi, wo, scale))[:, ok],
                                  np.array(h)[:, ok])


def test04_refraction_obeys_snell(variant_scalar_rgb, np_rng):
    """On Python floats (stored as float32 in the vectors): the refracted direction is a unit
    vector on the other side, in the plane of ωi and m, with η_i sinθi = η_t sinθt about m."""
    from mi_brdfs.scattering import fresnel
    checked = 0
    for a, b in zip(random_directions(np_rng, 300), random_directions(np_rng, 300, lower=False)):
        wi, m = mi.Vector3f(*map(float, a)), mi.Vector3f(*map(float, b))
        c = vector.dot(wi, m)
        f, cos_t, eta_it, eta_ti = fresnel.dielectric(c, 1.5)
        if f == 1.0:  # total internal reflection
            continue
        t = vector.refract(wi, m, cos_t, eta_ti)
        t, wi_, m_ = (np.array([v.x, v.y, v.z]) for v in (t, wi, m))
        assert np.linalg.norm(t) == pytest.approx(1.0, abs=1e-6)
        assert np.sign(t @ m_) == -np.sign(c)
        sin_i, sin_t = np.linalg.norm(np.cross(wi_, m_)), np.linalg.norm(np.cross(t, m_))
        assert sin_t == pytest.approx(sin_i * eta_ti, abs=1e-6)
        assert abs(np.linalg.det(np.stack([wi_, m_, t]))) < 1e-6  # coplanar
        checked += 1
    assert checked > 150
