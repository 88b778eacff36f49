"""
The higher orders' tables of ``hk`` (mi_brdfs.scattering.hk_orders) against the float64
adding-doubling of mi_brdfs.reference.hk_doubling computed at the very albedo and optical
depth (no interpolation in either), at slabs off the tables' nodes: the plugin's whole f·cosθo
(closed-form first order + the interpolated rest) within the error its page promises
(:data:`~mi_brdfs.scattering.hk_orders.PROMISE` of the largest value at that incidence, and
in the median of each value).
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.checks import batch
from mi_brdfs.reference import hk as ref
from mi_brdfs.reference import hk_doubling
from mi_brdfs.scattering.hk_orders import PROMISE

K, MODES = 12, 16
#: (g, η, ρ of a base or None, albedo, optical depth): off the nodes in both.
SLABS = [(0.6, 1.5, None, 0.551, 5.15), (0.6, 1.5, None, 0.673, 0.173),
         (0.0, 1.0, None, 0.266, 1.685), (0.3, 1.33, 0.6, 0.879, 0.971)]


def _exact(g, eta, rho, a, tau, wi, wo, dphi, i, o, mu):
    """f·cosθo: the closed-form first order + the exact tables' higher orders."""
    t = hk_doubling.tables(np.array([a]), tau, 0, g, eta, rho is not None, mu, MODES)
    c_m = np.where(np.arange(MODES) == 0, 1.0, 2.0)[:, None]
    cos_m = np.cos(np.arange(MODES)[:, None] * dphi[None])
    params = {"sigma_s": a * tau, "sigma_a": (1 - a) * tau, "g": g, "eta": eta}
    if rho is not None:
        params["diffuse_reflectance"] = rho
    out = []
    for side, (total, single) in ((1.0, ("reflect", "single_reflect")),
                                  (-1.0, ("transmit", "single_transmit"))):
        h = getattr(t, total)[0, 1] - getattr(t, single)[0, 1]
        f = np.sum(c_m * h[:, i, o] * cos_m, axis=0)
        if rho is not None:
            f += rho * (t.E[0, 1, i] * t.U[0, 1, o] / (1 - rho * t.S[0, 1])
                        - t.E0[0, 1, i] * t.U0[0, 1, o])
        w = wo * [1.0, 1.0, side]
        out.append((f + ref.HK(**params).brdf(wi, w)[:, 0]) * mu[o])
        if rho is not None:
            break
    return params, out


def _textured(params: dict) -> dict:
    """The same medium as a texture that may vary over the surface (a checkerboard of one
    value): the plugin reads the grid, interpolating in albedo and depth."""
    return {**params, **{k: {"type": "checkerboard", "color0": params[k], "color1": params[k]}
                         for k in ("sigma_s", "sigma_a")}}


@pytest.mark.parametrize("slab", range(len(SLABS)))
@pytest.mark.parametrize("medium", ["grid", "constant"])
def test01_tables_within_their_promise(variant_llvm_ad_rgb, slab, medium):
    """The grid (a textured medium) and the tables at a constant medium's own (albedo,
    depth) (only the cosines interpolated) within the promise."""
    g, eta, rho, a, tau = SLABS[slab]
    mu = (np.arange(K) + 0.5) / K  # between the tables' cosine nodes
    i, o = (x.ravel() for x in np.meshgrid(np.arange(K), np.arange(K), indexing="ij"))
    dphi = np.random.default_rng(slab).uniform(0, 2 * np.pi, i.size)
    s_i, s_o = np.sqrt(1 - mu[i] ** 2), np.sqrt(1 - mu[o] ** 2)
    wi = np.stack([s_i, 0 * s_i, mu[i]], axis=1)
    wo = np.stack([s_o * np.cos(dphi), s_o * np.sin(dphi), mu[o]], axis=1)
    params, exact = _exact(g, eta, rho, a, tau, wi, wo, dphi, i, o, mu)
    bsdf = mi.load_dict({"type": "hk", "scattering": "all",
                         **(_textured(params) if medium == "grid" else params)})
    for side, want in zip((1.0, -1.0), exact):
        si = batch.interaction(wi[0], len(wi))
        si.wi = mi.Vector3f(*(batch.floats(x) for x in wi.T))
        got = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(
            *(batch.floats(x) for x in (wo * [1.0, 1.0, side]).T))))[0]
        dr.eval()
        peak = np.max(want.reshape(K, K), axis=1)[i]
        assert np.max(np.abs(got - want) / peak) <= PROMISE, (side, np.max(np.abs(got - want)
                                                                             / peak))
        assert np.median(np.abs(got - want) / want) <= PROMISE, side


@pytest.mark.parametrize("slab", [0, 3])
def test02_a_constant_medium_is_the_grid_interpolated_once(variant_llvm_ad_rgb, slab):
    """The host's interpolation of a constant medium (float64) and the kernel's of a
    textured one are one function: equal to float32 rounding (so that a derivative by AD, the
    kernel's, matches finite differences of either)."""
    g, eta, rho, a, tau = SLABS[slab]
    params = {"sigma_s": a * tau, "sigma_a": (1 - a) * tau, "g": g, "eta": eta,
              "scattering": "all", **({} if rho is None else {"diffuse_reflectance": rho})}
    rng = np.random.default_rng(4)
    wi, wo = batch.random_directions(rng, 2000, False), batch.random_directions(rng, 2000)
    fixed = batch.evaluate({"type": "hk", **params}, wi, wo).value[:, 0]
    grid = batch.evaluate({"type": "hk", **_textured(params)}, wi, wo).value[:, 0]
    # float32: a logarithm carries |ln x|·2⁻²⁴ ≤ 4e-6 (x ≥ 1e-30), the lerps and sums a few ulps
    np.testing.assert_allclose(fixed, grid, rtol=2e-5, atol=1e-6 * fixed.max())
