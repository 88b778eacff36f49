"""
The sampler's map of measured data (mi_brdfs.measured.warp): the float64 map the density is
built with and the drjit map the plugin samples with are one map, the drjit inverse inverts it,
and its Jacobian J, in closed form in both, equals |∂ωo/∂u × ∂ωo/∂v| by central differences.
"""

import mitsuba as mi
import numpy as np

from mi_brdfs.measured import warp


def _points(n, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(0, 1.5, n), rng.uniform(0.05, 0.95, n), rng.uniform(0.02, 0.98, n)


def test01_jacobian_by_finite_differences():
    """J of :func:`warp.forward` against the area of the parallelogram the map makes of a
    (du, dv) step (float64 central differences). A J without its πu or its 4(ωi·h) fails."""
    theta, u, v = _points(2000)
    _, wo, jac = warp.forward(theta, u, v)
    h = 1e-6
    du = (warp.forward(theta, u + h, v)[1] - warp.forward(theta, u - h, v)[1]) / (2 * h)
    dv = (warp.forward(theta, u, v + h)[1] - warp.forward(theta, u, v - h)[1]) / (2 * h)
    area = np.linalg.norm(np.cross(du, dv), axis=1)
    valid = jac > 0
    assert valid.mean() > 0.5
    np.testing.assert_allclose(jac[valid], area[valid], rtol=1e-5)


def test02_the_drjit_map_is_the_float64_one(variant_llvm_ad_rgb):
    """:func:`warp.to_direction` gives the ωo and J of :func:`warp.forward` (ωi turned to a
    random azimuth, which the map follows), and :func:`warp.to_square` takes ωo back to
    (u, v) with the same J."""
    theta, u, v = _points(2000, seed=1)
    wi, wo, jac = warp.forward(theta, u, v)
    phi = np.random.default_rng(2).uniform(-np.pi, np.pi, len(theta))
    c, s = np.cos(phi), np.sin(phi)

    def turn(w):
        return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], 1)

    wi, wo = turn(wi), turn(wo)
    as_vec = lambda a: mi.Vector3f(*[mi.Float(a[:, k].astype(np.float32)) for k in range(3)])
    uv = mi.Point2f(mi.Float(u.astype(np.float32)), mi.Float(v.astype(np.float32)))
    got_wo, got_jac, valid = warp.to_direction(as_vec(wi), uv)
    ok = np.array(valid, dtype=bool) & (jac > 0)
    assert ok.mean() > 0.5
    np.testing.assert_allclose(np.array(got_wo).T[ok], wo[ok], atol=2e-6)
    np.testing.assert_allclose(np.array(got_jac)[ok], jac[ok], rtol=2e-5)
    back, back_jac = warp.to_square(as_vec(wi), as_vec(wo))
    np.testing.assert_allclose(np.array(back).T[ok], np.stack([u, v], 1)[ok], atol=2e-5)
    np.testing.assert_allclose(np.array(back_jac)[ok], jac[ok], rtol=1e-4)
