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

What is interpolated, at each of the four cosine nodes around (μi, μo): mode 0 (positive: a
sum of paths) by its logarithm, linearly in τ — exact for the exponential attenuation of a
thick slab, where a linear interpolation of the value erred by up to 5 % of the largest
transmission — then geometrically in w (linearly from a = 0, where it is 0), and the other
modes as ratios to mode 0 (|c_m f_m| ≤ 2 f_0 for a non-negative f) linearly in τ and w; then
both bilinearly in the cosines (a logarithm across the cosines erred by 7 % at grazing
incidence, where f falls as T(μ) ∝ μ). The Fresnel transmittances of both crossings,
T(μi) T(μo), are divided out of the tables and multiplied back exactly (linear interpolation
of f itself erred by 5 % of the peak between the first two cosine nodes under an interface).
Below τ₀ the higher orders scale as τ/τ₀ (one scattering with internal reflections).

A medium that is one spectrum over the whole surface and carries no gradient (the usual case)
has its (a, τ) interpolation done once, on the host, at load (:meth:`Orders.fix`, the same
formulas in float64: the kernel then reads and interpolates the cosines alone; differentiated,
with the derivatives in a and τ by one-sided differences, carried as derivative × (x −
detach(x))); a textured medium interpolates in the kernel. Both are one function of (a, τ),
so derivatives match finite differences of either.

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
#: The step of the host's differences in albedo and optical depth.
DELTA = 1e-6
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
    out = {"tau": np.sort(np.concatenate([[0.0], chains[0].tau[1:], chains[1].tau[1:]]))}
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


def cell(albedo: float, tau: float, n_tau: int) -> tuple:
    """(albedo node, its fraction in w, τ node (τ = 0 counted), its fraction linear in τ) in
    float64: :meth:`Orders._cell`'s formulas."""
    w = (1.0 - np.cbrt(1.0 - min(max(albedo, 0.0), 1.0))) * (N_ALBEDO - 1)
    ia = min(int(w), N_ALBEDO - 2)
    t = min(max(tau, 0.0), TAU_MIN * 2.0 ** (0.5 * (n_tau - 2)))
    x = t / TAU_MIN if t < TAU_MIN else 1.0 + 2.0 * math.log2(t / TAU_MIN)
    it = min(int(min(max(x, 0.0), n_tau - 1.0)), n_tau - 2)
    lo = 0.0 if it == 0 else TAU_MIN * 2.0 ** (0.5 * (it - 1))
    hi = TAU_MIN * 2.0 ** (0.5 * it)
    return ia, w - ia, it, min(max((t - lo) / (hi - lo), 0.0), 1.0)


def _lerp(a, b, t):
    return a + (b - a) * t


def at_medium(t: dict, albedo: float, tau: float, base: bool) -> dict:
    """The grid ``t`` interpolated in (a, τ) at one medium, in float64, by the kernel's
    formulas (:meth:`Orders._corner`, :meth:`Orders._vector`, :meth:`Orders._scalar`):
    ``q`` f_0 (times τ/τ₀ below τ₀) and ``r`` the ratios per side and pair of cosine nodes;
    over a base ``E``, ``U``, ``E0``, ``U0`` per cosine node and ``S``."""
    n_tau = len(t["tau"])
    ia, fa, it, ft = cell(albedo, tau, n_tau)
    lo, fth = max(it, 1), (0.0 if it == 0 else ft)
    out = {}
    for q, r in (("q", "r"), ("qt", "rt")):
        if q not in t:
            continue
        logs = [_lerp(np.log(t[q][ia + d, lo]), np.log(t[q][ia + d, lo + 1]), fth)
                for d in (0, 1)]
        f0 = _lerp(np.exp(logs[0]), np.exp(logs[1]), fa) if ia == 0 else \
            np.exp(_lerp(logs[0], logs[1], fa))
        ratios = [_lerp(t[r][ia + d, lo], t[r][ia + d, lo + 1], fth) for d in (0, 1)]
        out[q] = f0 * min(tau / TAU_MIN, 1.0)
        out[r] = _lerp(ratios[0], ratios[1], fa)
    if base:
        for name in ("E", "U", "E0", "U0"):
            out[name] = sum(wa * np.exp(_lerp(np.log(t[name][ia + d, it]),
                                              np.log(t[name][ia + d, it + 1]), ft))
                            for d, wa in ((0, 1.0 - fa), (1, fa)))
        rows = [_lerp(t["S"][ia + d, it], t["S"][ia + d, it + 1], ft) for d in (0, 1)]
        out["S"] = _lerp(rows[0], rows[1], fa)
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


def _read4(table, index, count: int) -> list:
    """The ``count`` (a multiple of 4) numbers from ``index``·count on: packets of four
    adjacent numbers (one gather each in JIT variants)."""
    if dr.is_jit_v(mi.Float):
        out = []
        for k in range(count // 4):
            v = dr.gather(mi.Vector4f, table, index * (count // 4) + k)
            out += [v.x, v.y, v.z, v.w]
        return out
    start = int(index) * count
    return [float(x) for x in table[start:start + count]]


def _pack(t: dict, base: bool, modes: int) -> dict:
    """The tables in the current variant: per node f_0 and the ratios side by side, padded to
    packets of four, transmission's (no base) after reflection's: one lookup, either side."""
    stride = 4 * math.ceil(modes / 4)
    sides = [("q", "r")] + ([] if base else [("qt", "rt")])
    node = np.zeros((len(sides),) + t["q"].shape + (stride,))
    for k, (q, r) in enumerate(sides):
        node[k, ..., 0], node[k, ..., 1:modes] = t[q], t[r][..., :modes - 1]
    out = {k: _array(v) for k, v in t.items() if k not in ("tau", "q", "r", "qt", "rt")}
    out["node"] = _array(node)
    return out


class Orders:
    """The higher orders of one layer in the current variant: :meth:`value` per channel,
    interpolated in (albedo, depth) in the kernel, or once on the host for a medium that
    :meth:`fix` has been given."""

    def __init__(self, g: float, eta: float, base: bool):
        self.grid = grid(float(g), float(eta), bool(base))
        self.eta, self.base = float(eta), bool(base)
        self.n_tau = len(self.grid["tau"])
        self.tau_max = float(self.grid["tau"][-1])
        self.modes = self.grid["r"].shape[-1] + 1
        self.stride = 4 * math.ceil(self.modes / 4)
        self.tables, self.fixed = _pack(self.grid, base, self.modes), None

    def fix(self, channels, gradient: bool = False) -> None:
        """Interpolate the grid once, on the host, at each channel's (albedo, depth):
        ``channels`` a list of pairs; None: in the kernel again. With ``gradient``, also the
        derivatives in albedo and depth (one-sided differences of the same interpolation in
        float64, steps of :data:`DELTA`), which carry a derivative through the kernel's
        lookups as derivative × (x − detach(x)): zero in value."""
        if channels is None:
            self.fixed = None
            return
        pairs = sorted(set(channels))
        sets = [self._host([at_medium(self.grid, a, t, self.base) for a, t in pairs])]
        if gradient:  # a step inside [0, 1] in albedo, up in depth
            steps = [(-DELTA if a + DELTA > 1.0 else DELTA, DELTA) for a, _ in pairs]
            for axis in (0, 1):
                moved = self._host([at_medium(self.grid, a + h[0] * (axis == 0),
                                              t + h[1] * (axis == 1), self.base)
                                    for (a, t), h in zip(pairs, steps)])
                h = np.array([step[axis] for step in steps])
                sets.append({k: (v - sets[0][k]) / h.reshape((-1,) + (1,) * (v.ndim - 1))
                             for k, v in moved.items()})
        self.fixed = ([_pack(t, self.base, self.modes) for t in sets], len(pairs),
                      [pairs.index(c) for c in channels])

    @staticmethod
    def _host(media: list) -> dict:
        """The media of :func:`at_medium` stacked (pairs, 1, ...)."""
        return {k: np.stack([m[k] for m in media])[:, None] for k in media[0]}

    def _cell(self, albedo, tau):
        """(albedo node, its fraction in w; τ node (τ = 0 counted), its fraction linear in
        τ) of one channel (float64 on the host: :func:`cell`)."""
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

    def _corner(self, side, cell, i, o) -> list:
        """f_0 and the ratios at the cosine nodes (i, o), interpolated in (a, τ) (the
        formulas of :func:`at_medium`)."""
        ia, fa, it, ft = cell
        lo, ft = dr.maximum(it, 1), dr.select(it == 0, 0.0, ft)
        per_a = []
        for da in (0, 1):
            near, far = (_read4(self.tables["node"], (((ia + side * N_ALBEDO + da) * self.n_tau
                                                       + lo + dt) * N_MU + i) * N_MU + o,
                                self.stride) for dt in (0, 1))
            per_a.append([dr.lerp(dr.log(near[0]), dr.log(far[0]), ft)] +
                         [dr.lerp(near[m], far[m], ft) for m in range(1, self.modes)])
        (l0, *r0), (l1, *r1) = per_a
        f0 = dr.select(ia == 0, dr.lerp(dr.exp(l0), dr.exp(l1), fa),
                       dr.exp(dr.lerp(l0, l1, fa)))
        return [f0] + [dr.lerp(a, b, fa) for a, b in zip(r0, r1)]

    def _vector(self, name, cell, mu):
        """A base's vector at ``mu``: at each cosine node its logarithm linear in τ, the
        value linear in w; then linear in μ."""
        ia, fa, it, ft = cell
        i, f = self._mu(mu)
        t = self.tables[name]

        def node(k):
            return sum(wa * dr.exp(dr.lerp(dr.log(_read(t, n * N_MU + k)),
                                           dr.log(_read(t, (n + 1) * N_MU + k)), ft))
                       for n, wa in (((ia) * self.n_tau + it, 1.0 - fa),
                                     ((ia + 1) * self.n_tau + it, fa)))

        return dr.lerp(node(i), node(i + 1), f)

    def _scalar(self, name, cell):
        ia, fa, it, ft = cell
        t = self.tables[name]
        rows = [dr.lerp(_read(t, n), _read(t, n + 1), ft)
                for n in (ia * self.n_tau + it, (ia + 1) * self.n_tau + it)]
        return dr.lerp(rows[0], rows[1], fa)

    def _medium(self, side, c: int, albedo, tau, mu_i, mu_o):
        """Channel ``c``'s lookups: (f_0 and the ratios, bilinear in the cosines, and over a
        base (E(μi) U(μo), S, E₀(μi) U₀(μo))), from the grid or the fixed medium."""
        (i, fi), (o, fo) = self._mu(mu_i), self._mu(mu_o)
        if self.fixed is None:
            cell = self._cell(albedo, tau)
            corners = [self._corner(side, cell, i + di, o + do) for di in (0, 1)
                       for do in (0, 1)]
            small = dr.minimum(tau / TAU_MIN, 1.0)  # below τ₀ the higher orders scale as τ
            base = None if not self.base else (
                self._vector("E", cell, mu_i) * self._vector("U", cell, mu_o),
                self._scalar("S", cell),
                self._vector("E0", cell, mu_i) * self._vector("U0", cell, mu_o))
        else:
            sets, count, index = self.fixed
            p, shift = index[c], [1.0, albedo - dr.detach(albedo), tau - dr.detach(tau)]

            def read4(k):  # the value, plus the derivatives times zero-valued shifts
                parts = [_read4(t["node"], k, self.stride) for t in sets]
                return [sum(d * part[m] for d, part in zip(shift, parts))
                        for m in range(self.modes)]

            def read(name, k):
                return sum(d * _read(t[name], k) for d, t in zip(shift, sets))

            corners = [read4(((side * count + p) * N_MU + i + di) * N_MU + o + do)
                       for di in (0, 1) for do in (0, 1)]
            small = 1.0

            def vector(name, k, w):
                return dr.lerp(read(name, p * N_MU + k), read(name, p * N_MU + k + 1), w)

            base = None if not self.base else (
                vector("E", i, fi) * vector("U", o, fo), read("S", p),
                vector("E0", i, fi) * vector("U0", o, fo))
        v = [dr.lerp(dr.lerp(corners[0][k], corners[1][k], fo),
                     dr.lerp(corners[2][k], corners[3][k], fo), fi) for k in range(self.modes)]
        return v, small, base

    def value(self, wi, wo, albedo, tau, rho):
        """f (no cosine) of the higher orders, ωi above the surface; ``albedo``, ``tau``,
        ``rho``: spectra (channels of equal values are read once: drjit merges equal
        computations)."""
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
        side = 0 if self.base else dr.select(above, mi.UInt32(0), mi.UInt32(1))
        out = dr.zeros(mi.UnpolarizedSpectrum, dr.width(mu_i))
        for c in range(dr.size_v(mi.UnpolarizedSpectrum)):
            v, small, base = self._medium(side, c, albedo[c], tau[c], mu_i, mu_o)
            f = v[0] * (1.0 + sum(v[m] * cos_m[m] for m in range(1, self.modes))) * small
            if base is not None:  # the base's series, less its direct part
                eu, s, direct = base
                f = dr.select(above, f + rho[c] * (eu / (1.0 - rho[c] * s) - direct), 0.0)
            out[c] = f * t_i * t_o
        return out
