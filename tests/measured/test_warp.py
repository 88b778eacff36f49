"""
The sampler's map of measured data (mi_brdfs.measured.warp): the float64 map the density is
built with and the drjit map the plugin samples with are one map, the drjit inverse inverts it,
and its Jacobian J, in closed form in both, equals |∂ωo/∂u × ∂ωo/∂v| by central differences.
"""

import drjit as dr
import mitsuba as mi
import pytest
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


def _density_at(f_mean, theta, u, v):
    """The sampler's density p(u, v | θi) of :func:`warp.density` built from ``f_mean``."""
    sampler = warp.Sampler(*warp.density(f_mean))
    uv = mi.Point2f(mi.Float(u.astype(np.float32)), mi.Float(v.astype(np.float32)))
    t = mi.Float(theta.astype(np.float32))
    return np.array(sampler.density(mi.Vector3f(dr.sin(t), 0.0, dr.cos(t)), uv))


def test03_the_density_is_positive_wherever_f_is(variant_llvm_ad_rgb, monkeypatch):
    """f non-zero at one node of each θi's grid alone (a lobe the grid all but misses): the
    defensive share keeps the density positive at every valid (u, v), where f·cosθo/pdf stays bounded;
    with no defensive share it is 0 almost everywhere (rejected)."""
    def spike(wi, wo):  # 1 at the node (u, v) = (32/63, 16/31) of each θi, else 0
        target = warp.forward(np.arctan2(wi[:, 0], wi[:, 2]), 32 / 63, 16 / 31)[1]
        return np.where(np.all(np.isclose(wo, target, rtol=0, atol=1e-9), axis=1), 1.0, 0.0)

    theta, u, v = _points(4000, seed=3)
    valid = warp.forward(theta, u, v)[2] > 0
    p = _density_at(spike, theta[valid], u[valid], v[valid])
    assert p.min() > 0
    monkeypatch.setattr(warp, "DEFENSIVE_SHARE", 0.0)
    p = _density_at(spike, theta[valid], u[valid], v[valid])
    assert (p == 0).mean() > 0.9


def test04_the_tabulated_albedo(variant_llvm_ad_rgb):
    """The albedo :func:`warp.density` estimates (the weight of a tabulated lobe in a
    mixture) against closed forms: f = ρ/π reflects ρ at every incident angle, f = ρ·cosθo/π
    reflects 2ρ/3 (within 0.5 % to 80°: the trapezoidal rule over the grid; the plain mean
    of the nodes, measured 2-5 % low, is rejected); and :meth:`warp.Sampler.albedo`
    interpolates the nodes linearly in θi."""
    for f, want in ((lambda wi, wo: np.full(len(wo), 0.3 / np.pi), 0.3),
                    (lambda wi, wo: 0.6 / np.pi * wo[:, 2], 0.4)):
        data, thetas, albedo = warp.density(f)
        near = np.array(thetas) <= np.radians(80.0)
        np.testing.assert_allclose(albedo[near], want, rtol=0.005)
        t, v, u = np.meshgrid(np.minimum(thetas, np.pi / 2 - 1e-3), np.linspace(0, 1, warp.N_V),
                              np.linspace(0, 1, warp.N_U), indexing="ij")
        wi, wo, jac = warp.forward(t, u, v)
        plain = np.where(jac > 0, f(None, wo.reshape(-1, 3)).reshape(jac.shape), 0.0)
        plain = (plain * wo[..., 2] * jac).mean(axis=(1, 2))
        assert np.max(np.abs(plain[near] / want - 1.0)) > 0.005
    sampler = warp.Sampler(data, thetas, albedo)
    t = np.linspace(0.0, 1.5, 7)
    wi = mi.Vector3f(mi.Float(np.sin(t).astype(np.float32)), 0.0,
                     mi.Float(np.cos(t).astype(np.float32)))
    np.testing.assert_allclose(np.array(sampler.albedo(wi)), np.interp(t, thetas, albedo),
                               rtol=1e-5)


@pytest.mark.parametrize("kind", ["random", "one", "uniform", "zeros"])
def test05_alias_table(kind):
    """Walker's alias table draws each entry with its probability: prob[c]/n from its own
    column plus (1 − prob[c'])/n from each column c' whose alias it is, exactly (to float64
    rounding), for random, one-entry, uniform and sparse distributions. A table whose
    columns forget their alias (prob = 1 everywhere, uniform) fails on the others."""
    rng = np.random.default_rng(7)
    p = {"random": rng.random(1953) ** 4, "one": np.eye(1, 300, 17)[0],
         "uniform": np.ones(64), "zeros": np.where(rng.random(500) < 0.1, rng.random(500), 0)}[kind]
    p = p / p.sum()

    def drawn(prob, alias):
        n = len(prob)
        return (prob + np.bincount(alias, weights=1.0 - prob, minlength=n)) / n

    prob, alias = warp.alias_table(p)
    assert np.all((prob >= 0) & (prob <= 1)) and alias.min() >= 0 and alias.max() < len(p)
    np.testing.assert_allclose(drawn(prob, alias), p, rtol=0, atol=1e-12)
    if kind != "uniform":
        assert np.max(np.abs(drawn(np.ones(len(p)), alias) - p)) > 1e-3


def test06_sampler_density_integrates_to_one(variant_llvm_ad_rgb):
    """p(u, v | θi) of the sampler integrates to 1 over the square at θi between the nodes
    (midpoint rule on a fine grid; bilinear cells, linear in θi), for a density that varies
    by orders of magnitude; a sampler that forgot to normalise one node fails."""
    sampler = warp.Sampler(*warp.density(lambda wi, wo: np.exp(-20 * (1 - wo[:, 2]))))
    n = 512
    u, v = np.meshgrid((np.arange(n) + 0.5) / n, (np.arange(n) + 0.5) / n)
    uv = mi.Point2f(mi.Float(u.ravel().astype(np.float32)), mi.Float(v.ravel().astype(np.float32)))
    for t in np.radians([0.0, 3.0, 45.0, 71.0, 89.0]):
        wi = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
        assert np.mean(np.array(sampler.density(wi, uv))) == pytest.approx(1.0, rel=1e-3)
