r"""
The higher orders of Hanrahan & Krueger's slab (``hk``, ``scattering = all``) in drjit: the
float64 adding-doubling tables of :mod:`mi_brdfs.reference.hk_doubling` (every order of
scattering and every internal reflection, less the first-order term, which the plugin keeps in
closed form) over a grid of albedo a, optical depth τ and the two cosines, as Fourier series in
the azimuth difference, looked up multilinearly at each channel's (a, τ).

The grid: albedo nodes uniform in w = 1 − (1 − a)^{1/3} (dense towards a = 1, where the
higher orders of a thick slab grow fastest: the last interval of 12 nodes uniform in
1 − √(1 − a) erred by 4 % of the largest value, 16 nodes in this w by 1.6 %); optical depths 0 and τ₀·2^{j/2}
(two doubling chains, half an octave apart; beyond the last, the last: a slab that thick is
semi-infinite to the table's accuracy); the external cosines at the midpoints of
:data:`N_MU` equal steps. The Fourier modes kept: computed :data:`CHUNK` at a time (modes are
independent) until one falls below :data:`MODE_TOLERANCE` of mode 0's peak (an isotropic
phase function needs one: the higher orders do not depend on the azimuth).

What is interpolated: mode 0 (positive: a sum of paths) linearly in the cosines, then its
logarithm linearly in τ — exact for the exponential attenuation of a thick slab, where a
linear interpolation of the value erred by up to 5 % of the largest transmission, while a
logarithm across the cosines erred by 7 % at grazing incidence, where f falls as T(μ) ∝ μ; the
Fresnel transmittances of both crossings, T(μi) T(μo), are divided out of the tables and
multiplied back exactly (T ∝ μ at grazing incidence under an interface: linear interpolation
of f itself erred by 5 % of the peak between the first two cosine nodes); the
other modes as ratios to mode 0 (|c_m f_m| ≤ 2 f_0 for a non-negative f); linearly in w
between albedo nodes.
Below τ₀ the higher orders scale as τ/τ₀ (one scattering with internal reflections).

A Lambertian base of reflectance ρ adds ρ E(μi) U(μo)/(1 − ρ S) (light reaching the base,
leaving the top from it, returning to it: the interreflection between the base and the layer
summed as a geometric series), less its direct part ρ E₀(μi) U₀(μo), which the closed form has.
"""

from __future__ import annotations

import math
from functools import lru_cache

import drjit as dr
import mitsuba as mi
import numpy as np

from . import fresnel

#: The grid: albedo nodes, cosine nodes, the first optical depth and doublings per chain.
N_ALBEDO, N_MU, TAU_MIN, DOUBLINGS = 16, 32, 1.0 / 32.0, 13
#: The most Fourier modes computed, how many at a time, and the relative size of the last
#: mode of a chunk below which no more are computed.
MAX_MODES, CHUNK, MODE_TOLERANCE = 16, 4, 1e-3
#: The smallest value whose logarithm is tabulated.
FLOOR = 1e-30
#: The error the tables promise: at most this fraction of f·cosθo's largest value at the
#: incidence, and in the median of each value (tests/scattering/test_hk_orders.py measures
#: it against the adding-doubling at the very albedo and depth, off the nodes).
PROMISE = 0.035


def albedo_nodes() -> np.ndarray:
    w = np.linspace(0.0, 1.0, N_ALBEDO)
    return 1.0 - (1.0 - w) ** 3


def mu_nodes() -> np.ndarray:
    return (np.arange(N_MU) + 0.5) / N_MU


@lru_cache(maxsize=8)
def grid(g: float, eta: float, base: bool) -> dict:
    """The float64 tables of a layer (g, η, base), on the plugin's grid (a, τ, μi, μo[, m]):
    ``q``, ``r`` (and, without a base, ``qt``, ``rt`` for transmission): f_0 of the higher
    orders, and c_m f_m/f_0 for m ≥ 1; with a base ``E``, ``U``, ``E0``, ``U0`` (a, τ, μ) and
    ``S`` (a, τ); ``tau`` the depths."""
    from ..reference import hk_doubling
    from ..reference.hk import fresnel

    a, mu = albedo_nodes(), mu_nodes()
    tr = 1.0 - fresnel(mu, eta)  # the crossings' transmittance, divided out

    def chunk(first, count):
        chains = [hk_doubling.tables(a, t0, DOUBLINGS, g, eta, base, mu, count,
                                     first_mode=first)
                  for t0 in (TAU_MIN, TAU_MIN * math.sqrt(2.0))]
        return chains, lambda name: _merge(getattr(chains[0], name), getattr(chains[1], name))

    pairs = [("reflect", "single_reflect")] + ([] if base else [("transmit", "single_transmit")])
    chains, merge = chunk(0, 1 if g == 0 else CHUNK)
    higher = [merge(t) - merge(s) for t, s in pairs]  # (a, τ, m, μi, μo)
    peak = max(np.max(np.abs(h[:, :, 0])) for h in higher)
    while higher[0].shape[2] < MAX_MODES and g != 0 and \
            max(np.max(np.abs(h[:, :, -1])) for h in higher) > MODE_TOLERANCE * peak:
        _, more = chunk(higher[0].shape[2], CHUNK)
        higher = [np.concatenate([h, more(t) - more(s)], axis=2)
                  for h, (t, s) in zip(higher, pairs)]
    out = {"tau": np.concatenate([[0.0], chains[0].tau[1:], chains[1].tau[1:]])}
    out["tau"].sort()
    for (q, r), h in zip((("q", "r"), ("qt", "rt")), higher):
        f0 = h[:, :, 0]
        out[q] = np.maximum(f0 / np.multiply.outer(tr, tr), FLOOR)
        ratio = 2.0 * h[:, :, 1:] / np.where(f0 > FLOOR, f0, np.inf)[:, :, None]
        out[r] = np.moveaxis(np.clip(ratio, -2.0, 2.0), 2, -1)  # (a, τ, μi, μo, m − 1)
    if base:
        for name in ("E", "U", "E0", "U0"):
            out[name] = np.maximum(merge(name) / tr, FLOOR)
        out["S"] = merge("S")
    return out


def _merge(x, y):
    """The two chains' tables interleaved along τ (axis 1), τ = 0 first."""
    rest = np.stack([x[:, 1:], y[:, 1:]], axis=2).reshape(x.shape[0], -1, *x.shape[2:])
    return np.concatenate([x[:, :1], rest], axis=1)


def _array(x: np.ndarray):
    """A table in the current variant: a drjit array in JIT variants, NumPy in scalar ones."""
    if dr.is_jit_v(mi.Float):
        t = mi.Float(np.ravel(x).astype(np.float32))
        dr.make_opaque(t)
        return t
    return np.ravel(x).astype(np.float64)


def _read(table, index):
    if dr.is_jit_v(mi.Float):
        return dr.gather(mi.Float, table, index)
    return float(table[int(index)])


class Orders:
    """The higher orders of one layer in the current variant: :meth:`value` per channel."""

    def __init__(self, g: float, eta: float, base: bool):
        t = grid(float(g), float(eta), bool(base))
        self.eta = float(eta)
        self.base, self.n_tau, self.tau_max = base, len(t["tau"]), float(t["tau"][-1])
        self.modes = t["r"].shape[-1] + 1
        self.tables = {k: _array(v) for k, v in t.items() if k != "tau"}

    def _cell(self, albedo, tau):
        """(albedo node, its fraction in w; τ node (τ = 0 counted), its fraction linear in
        τ) of one channel."""
        w = (1.0 - dr.cbrt(1.0 - dr.clip(albedo, 0.0, 1.0))) * (N_ALBEDO - 1)
        ia = dr.minimum(mi.UInt32(w), N_ALBEDO - 2)
        t = dr.clip(tau, 0.0, self.tau_max)
        x = dr.select(t < TAU_MIN, t / TAU_MIN, 1.0 + 2.0 * dr.log2(dr.maximum(t, TAU_MIN)
                                                                   / TAU_MIN))
        it = dr.minimum(mi.UInt32(dr.clip(x, 0.0, self.n_tau - 1.0)), self.n_tau - 2)
        lo = dr.select(it == 0, 0.0, TAU_MIN * dr.exp2(0.5 * (mi.Float(it) - 1.0)))
        hi = TAU_MIN * dr.exp2(0.5 * mi.Float(it))
        return ia, w - mi.Float(ia), it, dr.clip((t - lo) / (hi - lo), 0.0, 1.0)

    @staticmethod
    def _mu(mu):
        x = dr.clip(mu * N_MU - 0.5, 0.0, N_MU - 1.0)
        i = dr.minimum(mi.UInt32(x), N_MU - 2)
        return i, x - mi.Float(i)

    def _bilinear(self, name, node, i, fi, o, fo, count=1, slot=0):
        """Bilinear in (μi, μo) of entry ``slot`` of ``count`` per node of table ``name``."""
        t = self.tables[name]

        def at(di, do):
            return _read(t, ((node * N_MU + i + di) * N_MU + o + do) * count + slot)

        return dr.lerp(dr.lerp(at(0, 0), at(0, 1), fo), dr.lerp(at(1, 0), at(1, 1), fo), fi)

    def _series(self, names, cell, mu_i, mu_o, cos_m):
        """The higher orders' f at one channel: f_0 (1 + Σ ratio_m cos(mΔφ)), interpolated
        at each albedo node in the cosines, then in τ (f_0's logarithm), then in albedo."""
        ia, fa, it, ft = cell
        q, r = names
        (i, fi), (o, fo) = self._mu(mu_i), self._mu(mu_o)
        lo = dr.maximum(it, 1)
        ft = dr.select(it == 0, 0.0, ft)
        logs, shapes = [], []
        for da in (0, 1):
            nodes = [(ia + da) * self.n_tau + lo + dt for dt in (0, 1)]
            logs.append(dr.lerp(*(dr.log(self._bilinear(q, n, i, fi, o, fo)) for n in nodes),
                                ft))
            shape = 1.0
            for m in range(1, self.modes):
                ratio = dr.lerp(*(self._bilinear(r, n, i, fi, o, fo, self.modes - 1, m - 1)
                                  for n in nodes), ft)
                shape = shape + ratio * cos_m[m]
            shapes.append(shape)
        # geometric in albedo (a thick slab's transmission falls exponentially with the
        # diffusion length), linear from a = 0 (f_0 = 0 there) to the first node
        f0 = dr.select(ia == 0, dr.lerp(dr.exp(logs[0]), dr.exp(logs[1]), fa),
                       dr.exp(dr.lerp(logs[0], logs[1], fa)))
        return f0 * dr.lerp(shapes[0], shapes[1], fa)

    def _vector(self, name, cell, mu):
        """A base's vector at ``mu``: linear in μ, its logarithm linear in τ, linear in w."""
        ia, fa, it, ft = cell
        i, f = self._mu(mu)
        total = 0.0
        for da, wa in ((0, 1.0 - fa), (1, fa)):
            node = (ia + da) * self.n_tau + it
            t = self.tables[name]
            at = [dr.lerp(_read(t, n * N_MU + i), _read(t, n * N_MU + i + 1), f)
                  for n in (node, node + 1)]
            total = total + wa * dr.exp(dr.lerp(dr.log(at[0]), dr.log(at[1]), ft))
        return total

    def _scalar(self, name, cell):
        ia, fa, it, ft = cell
        t = self.tables[name]
        rows = [dr.lerp(_read(t, n), _read(t, n + 1), ft)
                for n in (ia * self.n_tau + it, (ia + 1) * self.n_tau + it)]
        return dr.lerp(rows[0], rows[1], fa)

    def value(self, wi, wo, albedo, tau, rho):
        """f (no cosine) of the higher orders, ωi above the surface; ``albedo``, ``tau``,
        ``rho``: spectra."""
        mu_i, mu_o = dr.abs(wi.z), dr.abs(wo.z)
        sin2 = (1.0 - mu_i * mu_i) * (1.0 - mu_o * mu_o)
        cos_phi = dr.select(sin2 > 1e-12, (wi.x * wo.x + wi.y * wo.y)
                            * dr.rsqrt(dr.maximum(sin2, 1e-12)), 1.0)
        cos_m = [1.0, dr.clip(cos_phi, -1.0, 1.0)]
        for _ in range(2, self.modes):
            cos_m.append(2.0 * cos_m[1] * cos_m[-1] - cos_m[-2])
        above = wo.z > 0
        t_i = 1.0 - fresnel.dielectric(mu_i, self.eta)[0] if self.eta != 1.0 else 1.0
        t_o = 1.0 - fresnel.dielectric(mu_o, self.eta)[0] if self.eta != 1.0 else 1.0
        out = dr.zeros(mi.UnpolarizedSpectrum, dr.width(mu_i))
        for c in range(dr.size_v(mi.UnpolarizedSpectrum)):
            cell = self._cell(albedo[c], tau[c])
            small = dr.minimum(tau[c] / TAU_MIN, 1.0)  # below τ₀: ∝ τ
            f = self._series(("q", "r"), cell, mu_i, mu_o, cos_m) * small * t_i * t_o
            if self.base:
                r = rho[c]
                e, u = self._vector("E", cell, mu_i), self._vector("U", cell, mu_o)
                e0, u0 = self._vector("E0", cell, mu_i), self._vector("U0", cell, mu_o)
                f = f + r * t_i * t_o * (e * u / (1.0 - r * self._scalar("S", cell)) - e0 * u0)
                out[c] = dr.select(above, f, 0.0)
            else:
                ft = self._series(("qt", "rt"), cell, mu_i, mu_o, cos_m) * small * t_i * t_o
                out[c] = dr.select(above, f, ft)
        return out
