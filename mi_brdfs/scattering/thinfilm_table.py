r"""
A film's colour tabulated once per material (RGB and mono variants): where the base's index,
the film's index and the range of its thickness are known at load, the reflectance integrated
against each channel's sensitivity (:mod:`mi_brdfs.scattering.thinfilm`) is tabulated over
the incidence cosine and the thickness, and looked up bilinearly: four reads of adjacent
numbers instead of the Fourier series in the kernel (about 200 ns per evaluation for a
conductor in ``llvm_ad_rgb``, which made a render twice as slow).

The table sums the series of :func:`~mi_brdfs.scattering.thinfilm.fourier` in float64 until
|ρ|^K < 1e-5 (at most :data:`MAX_ORDERS` terms, then the geometric rest), with W_c
interpolated from the 2 nm table: within 2e-5 of the exact integral at its nodes. Nodes:
:data:`N_COS` uniform in cosθ₁, and thickness steps of :data:`OPTICAL_STEP`/n₂ (a phase step
of at most 4π·3/380 ≈ 0.1 rad, whose linear interpolation errs by about 1e-3 of the
oscillation's amplitude). A film of one thickness everywhere (a constant ``film_thickness``)
takes a table of that thickness alone, looked up in the cosine only: two reads instead of four,
and no error from an interpolation in thickness.
"""

from __future__ import annotations

from functools import lru_cache

import drjit as dr
import mitsuba as mi
import numpy as np

from . import thinfilm

#: Cosine nodes, uniform in [0, 1].
N_COS = 128
#: The thickness step times the film's index (nm).
OPTICAL_STEP = 3.0
#: The most thickness nodes a table takes (beyond: the kernel sums the series itself).
MAX_NODES = 2048
#: The most terms of the series summed for a node.
MAX_ORDERS = 64


def _q(n, n1, cos1):
    q = np.sqrt(np.asarray(n, np.complex128) ** 2 - n1 * n1 * (1.0 - cos1 * cos1))
    return np.where(q.imag < 0.0, -q, q)


def _amplitudes(c, n1, n2, n3):
    """((r₁₂, r₂₃) for s, for p) and q₂ at cosine ``c`` (float64, complex)."""
    q1, q2, q3 = n1 * c + 0j, _q(n2, n1, c), _q(n3, n1, c)
    if abs(q2) < 1e-3:
        q2 = 1e-3 + 0j
    s = ((q1 - q2) / (q1 + q2), (q2 - q3) / (q2 + q3))
    n3_2 = complex(n3) ** 2
    p = ((n2 * n2 * q1 - n1 * n1 * q2) / (n2 * n2 * q1 + n1 * n1 * q2),
         (n3_2 * q2 - n2 * n2 * q3) / (n3_2 * q2 + n2 * n2 * q3))
    return s, p, q2


def _orders(rho) -> int:
    """Terms summed one by one: until |ρ|^K < 1e-5, at most MAX_ORDERS."""
    r = abs(rho)
    if r > 0.9:
        return MAX_ORDERS
    return int(min(MAX_ORDERS, max(2, np.ceil(np.log(1e-5) / np.log(max(r, 1e-30))))))


def _series(a, b, W):
    """|r|² against a channel's sensitivity, float64: ``W`` (orders + 1, thicknesses) holds
    W_c(k·x) for k = 1 … orders + 1."""
    rho, B = -a * b, b * (1.0 - a * a)
    inv = 1.0 / max(1.0 - abs(rho) ** 2, 1e-12)
    A = np.conj(a) * B + abs(B) ** 2 * rho * inv
    k = np.arange(1, W.shape[0] + 1)
    terms = A * rho ** (k - 1)
    # the rest, weighted by W at the next order (A = 0 where ρ = 1: both interfaces total)
    terms[-1] = terms[-1] / (1.0 - rho) if abs(1.0 - rho) > 1e-12 else 0.0
    return abs(a) ** 2 + abs(B) ** 2 * inv + 2.0 * (terms @ W).real


@lru_cache(maxsize=16)
def build(channels: int, n1: float, n2: float, base: tuple, d_max: float,
          uniform: bool = False) -> np.ndarray:
    """The table (N_COS, thickness nodes, channels) of the film's colour (the mean of s and p)
    for incidence from ``n1`` over ``base`` (a complex index per channel), thicknesses from 0
    by OPTICAL_STEP/n2 to ``d_max``; ``uniform``: the one thickness ``d_max`` alone."""
    W, mean = thinfilm.sensitivity_table(channels)
    W = W[..., 0] + 1j * W[..., 1]  # (channels, nodes)
    d = np.array([d_max]) if uniform else \
        np.arange(int(np.ceil(d_max * n2 / OPTICAL_STEP)) + 2) * (OPTICAL_STEP / n2)
    out = np.zeros((N_COS, d.size, channels))
    for i, cos1 in enumerate(np.linspace(0.0, 1.0, N_COS)):
        pairs = [_amplitudes(cos1, n1, n2, base[c]) for c in range(channels)]
        q2 = pairs[0][2]
        if q2.imag > q2.real:  # evanescent: at the mean wavelength, as the kernel
            for c, (s_pair, p_pair, _) in enumerate(pairs):
                z = np.exp(-4.0 * np.pi * d * q2.imag / mean[c])
                for a, b in (s_pair, p_pair):
                    out[i, :, c] += 0.5 * np.abs((a + b * z) / (1.0 + a * b * z)) ** 2
            continue
        orders = max(_orders(-a * b) for s_pair, p_pair, _ in pairs
                     for a, b in (s_pair, p_pair))
        # W_c(k x) for k = 1 … orders + 1, interpolated linearly (0 beyond the table)
        u = np.outer(np.arange(1, orders + 2), 2.0 * d * q2.real) / thinfilm.X_STEP
        j = np.minimum(u.astype(np.int64), W.shape[1] - 2)
        t = u - j
        Wk = np.where(u < W.shape[1] - 1, W[:, j] * (1.0 - t) + W[:, j + 1] * t, 0.0)
        for c, (s_pair, p_pair, _) in enumerate(pairs):
            for a, b in (s_pair, p_pair):
                out[i, :, c] += 0.5 * _series(a, b, Wk[c])
    return np.clip(out, 0.0, 1.0)  # as the kernel's series (thinfilm.colour)


class ColourTable:
    """A table of :func:`build` in the current variant, looked up bilinearly:
    ``table(cos1, d)`` → [R_c per channel]; linearly in the cosine alone where it holds one
    thickness (:attr:`uniform`: ``d`` is then not read)."""

    def __init__(self, table: np.ndarray, n2: float):
        self.step = OPTICAL_STEP / n2
        self.n_d, self.channels = table.shape[1], table.shape[2]
        self.uniform = self.n_d == 1
        flat = np.zeros((N_COS, self.n_d, 4))
        flat[..., :self.channels] = table
        flat[..., 3] = table.mean(axis=-1)  # the channels' mean, read alone
        if dr.is_jit_v(mi.Float):
            self.table = mi.Float(flat.ravel().astype(np.float32))
            dr.make_opaque(self.table)
        else:
            self.table = flat.reshape(-1, 4)

    def __call__(self, cos1, d=None):
        return self._lookup(cos1, d, None)

    def mean(self, cos1, d=None):
        """The channels' mean alone (a quarter of the reads): what a choice between
        reflection and refraction needs."""
        return self._lookup(cos1, d, 3)

    def _lookup(self, cos1, d, slot):
        """[R_c per channel], or the number ``slot`` of the nodes alone."""
        base, tu, tv = self._cell(cos1, d)
        rows = (0, self.n_d) if self.uniform else (0, 1, self.n_d, self.n_d + 1)
        g = [self._at(base + o, slot) for o in rows]
        if slot is not None:
            g = [[v] for v in g]
        if self.uniform:
            out = [dr.lerp(g[0][c], g[1][c], tu) for c in range(len(g[0]))]
        else:
            out = [dr.lerp(dr.lerp(g[0][c], g[1][c], tv), dr.lerp(g[2][c], g[3][c], tv), tu)
                   for c in range(len(g[0]))]
        return out[0] if slot is not None else out[:self.channels]

    def _cell(self, cos1, d):
        """(the first node's index, the fractions in cosθ and in thickness)."""
        u = dr.clip(cos1, 0.0, 1.0) * (N_COS - 1)
        i = dr.minimum(mi.UInt32(u), N_COS - 2)
        tu = u - mi.Float(i)
        if self.uniform:
            return i, tu, None
        v = dr.clip(d / self.step, 0.0, self.n_d - 1.0)
        j = dr.minimum(mi.UInt32(v), self.n_d - 2)
        tv = v - mi.Float(j)
        return i * self.n_d + j, tu, tv

    def _at(self, index, slot=None):
        """A node's four numbers, or its number ``slot`` alone."""
        if dr.is_jit_v(mi.Float):
            if slot is not None:
                return dr.gather(mi.Float, self.table, index * 4 + slot)
            return dr.gather(mi.Vector4f, self.table, index)
        row = [float(x) for x in self.table[int(index)]]
        return row if slot is None else row[slot]
