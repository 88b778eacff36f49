r"""
Thin-film interference in drjit: a film of real index n₂ and thickness d between an incident
medium n₁ (real) and a base n₃ = η + iκ (a conductor, or a dielectric with κ = 0), by the Airy
summation of the waves reflected back and forth in the film (Born & Wolf, "Principles of
Optics", §7.6.1; Belcour & Barla 2017, "A Practical Extension to Microfacet Theory for the
Modeling of Varying Iridescence", ACM TOG 36(4), §4). Phases run as e^(−iωt) (Born & Wolf);
the float64 transfer-matrix reference is :mod:`mi_brdfs.reference.thinfilm`.

With q_j = n_j cosθ_j = sqrt(n_j² − n₁² sin²θ₁) (Im q ≥ 0), the Fresnel amplitudes of the
two interfaces i → j, r_s = (q_i − q_j)/(q_i + q_j), r_p = (n_j² q_i − n_i² q_j)/(n_j² q_i +
n_i² q_j), and z = exp(2πi x/λ) with the optical path difference x = 2 d q₂, the film reflects

.. math::

    r = \frac{r_{12} + r_{23}\,z}{1 + r_{12}\,r_{23}\,z}

for each polarization: :func:`amplitudes`, exact at a wavelength (spectral variants). With no
film (d = 0) r is the Fresnel amplitude of the bare base, r₁₃.

**Colour (RGB and mono variants).** Expanding 1/(1 + r₁₂r₂₃z) in powers of z, with a = r₁₂,
b = r₂₃, ρ = −ab and B = b(1 − a²),

.. math::

    |r|^2 = A_0 + 2\,\mathrm{Re}\sum_{k\ge 1} A_k z^k,\quad
    A_0 = |a|^2 + \frac{|B|^2}{1 - |\rho|^2},\quad
    A_1 = \bar a B + \frac{|B|^2\rho}{1 - |\rho|^2},\quad A_k = \rho^{k-1}A_1,

so that, the indices being constant over a channel (as an RGB variant gives them), the
reflectance integrated against a channel's sensitivity w_c(λ) is
A₀ + 2 Re Σ A_k W_c(k x), with W_c(x) = ∫ w_c(λ) e^(2πix/λ) dλ / ∫ w_c(λ) dλ: Belcour &
Barla's Fourier-space integration. Instead of their Gaussian fits of the colour-matching
functions, W_c is tabulated (:class:`Sensitivity`) from Mitsuba's own CIE 1931 table and D65
illuminant, through the linear sRGB matrix: w_c = D65·(M·x̄ȳz̄)_c, what Mitsuba's spectral
variants compute for a surface lit by a white ``<rgb>`` emitter and developed to sRGB. The
series is summed to :data:`ORDERS` = K terms, and the rest in closed form with W_c(kx) for
k > K extrapolated geometrically from the last two, W_c(Kx)·g^(k−K), g = W_c(Kx)/W_c((K−1)x)
(|g| ≤ 1): exact for a vanishing film (W ≡ 1) and for a thick one (W → 0), and within
0.015 of the exact integral for microfacet cosines above 0.1 (0.05 at grazing incidence on a
strongly absorbing base, where the film is a Fabry-Pérot cavity of high finesse: its sharp
spectral dips need many terms; ``tests/scattering/test_thinfilm.py``).
Where the wave in the film is evanescent (n₁ sinθ₁ > n₂: frustrated total reflection) z is
real and nothing oscillates: the exact formula at the channel's mean wavelength stands for it.
A colour outside sRGB's gamut (a negative channel) is clipped into [0, 1]. Where a material's
indices are constants, :mod:`mi_brdfs.scattering.thinfilm_table` tabulates :func:`colour` once
instead (the series in the kernel costs about 200 ns per evaluation).
"""

from __future__ import annotations

from functools import lru_cache

import drjit as dr
import mitsuba as mi
import numpy as np

#: Terms of the Fourier series summed one by one in colour variants (the rest in one).
ORDERS = 8

#: The tabulated W_c: optical path differences from 0 to X_MAX nm by X_STEP nm (beyond: 0).
X_STEP, X_MAX = 2.0, 30000.0

_TINY = 1e-30


# --- complex numbers as (re, im) pairs of any drjit type -------------------------------------

def _mul(a, b):
    return (a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])


def _div(a, b):
    d = dr.maximum(b[0] * b[0] + b[1] * b[1], _TINY)
    return ((a[0] * b[0] + a[1] * b[1]) / d, (a[1] * b[0] - a[0] * b[1]) / d)


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1])


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def _abs2(a):
    return a[0] * a[0] + a[1] * a[1]


def _conj(a):
    return (a[0], -a[1])


def _sqrt(a):
    """The square root with Im ≥ 0, without cancellation."""
    x, y = a
    r = dr.sqrt(x * x + y * y)
    big = dr.sqrt(0.5 * (r + dr.abs(x)))
    small = dr.abs(y) / dr.maximum(2.0 * big, _TINY)
    re, im = dr.select(x >= 0.0, big, small), dr.select(x >= 0.0, small, big)
    return dr.select(y < 0.0, -re, re), im


def _expi(phase):
    s, c = dr.sincos(phase)
    return (c, s)


# --- the film --------------------------------------------------------------------------------

def interfaces(cos1, n1, n2, eta3, k3):
    """
    ((r₁₂, r₂₃) for s, (r₁₂, r₂₃) for p, q₂): the amplitudes of the film's two interfaces at
    incidence cosine ``cos1`` from the medium ``n1`` (real), the film ``n2`` (real) over the
    base ``eta3`` + i``k3``; complex numbers as (re, im) pairs.
    """
    film = upper(cos1, n1, n2)
    r23s, r23p = lower(film, n2, eta3, k3)
    return (film.r12s, r23s), (film.r12p, r23p), film.q2


class upper:  # noqa: N801 (a record, computed once for every channel)
    """The film's upper interface, the same for every channel: n₁² sin²θ₁, q₂ and r₁₂ for s
    and p light."""

    def __init__(self, cos1, n1, n2):
        self.n1sin2 = n1 * n1 * (1.0 - cos1 * cos1)
        zero = 0.0 * self.n1sin2
        q1 = (cos1 * n1 + zero, zero)
        q2 = _sqrt((n2 * n2 - self.n1sin2, zero))
        # at the film's critical angle (q₂ = 0) both interfaces reflect totally and r is 0/0:
        # q₂ kept from vanishing, r tends to the bare base's r₁₃ there (within about 1e-3)
        self.q2 = q2 = (dr.select(_abs2(q2) < 1e-6, 1e-3, q2[0]), q2[1])
        self.r12s = _div(_sub(q1, q2), _add(q1, q2))
        n1_2, n2_2 = n1 * n1, n2 * n2
        a, b = (n2_2 * q1[0], n2_2 * q1[1]), (n1_2 * q2[0], n1_2 * q2[1])
        self.r12p = _div(_sub(a, b), _add(a, b))


def lower(film: upper, n2, eta3, k3):
    """(r₂₃ for s, for p) of the film's lower interface over the base ``eta3`` + i``k3``."""
    e2 = (eta3 * eta3 - k3 * k3, 2.0 * eta3 * k3)  # n₃²
    q2, q3 = film.q2, _sqrt((e2[0] - film.n1sin2, e2[1]))
    s = _div(_sub(q2, q3), _add(q2, q3))
    n2_2 = n2 * n2
    a, b = _mul(e2, q2), (n2_2 * q3[0], n2_2 * q3[1])
    return s, _div(_sub(a, b), _add(a, b))


def reflect(r12, r23, z):
    """The Airy sum (r₁₂ + r₂₃z)/(1 + r₁₂r₂₃z)."""
    return _div(_add(r12, _mul(r23, z)), _add((1.0, 0.0), _mul(_mul(r12, r23), z)))


def amplitudes(cos1, n1, n2, eta3, k3, thickness, wavelength, evanescent: bool = True):
    """The film's complex reflection amplitudes (r_s, r_p) at ``wavelength`` (nm, per
    channel; ``thickness`` in nm), exact: spectral variants. ``evanescent``: whether n₁ sinθ₁
    may exceed n₂ (else q₂ is real, and the decay, 1, is left out of the kernel)."""
    s, p, q2 = interfaces(cos1, n1, n2, eta3, k3)
    # z = exp(2πi·2d·q₂/λ): its modulus decays where q₂ is imaginary (evanescent)
    # (a wavelength of 0, which an interaction Mitsuba did not sample carries, kept finite)
    x = 4.0 * dr.pi * thickness / dr.maximum(wavelength, 1.0)
    z = _expi(x * q2[0])
    if evanescent:
        decay = dr.exp(-x * q2[1])
        z = (z[0] * decay, z[1] * decay)
    return reflect(*s, z), reflect(*p, z)


def fourier(r12, r23, w_at):
    """|r|² integrated against a channel's sensitivity: the series of the module docstring,
    ``w_at(k)`` giving W_c(k·x) as a pair, summed to :data:`ORDERS` terms and the rest
    geometrically."""
    a, b = r12, r23
    rho = (-(a[0] * b[0] - a[1] * b[1]), -(a[0] * b[1] + a[1] * b[0]))
    B = _mul(b, _sub((1.0, 0.0), _mul(a, a)))
    inv = 1.0 / dr.maximum(1.0 - _abs2(rho), 1e-7)
    bb = _abs2(B) * inv
    total = _abs2(a) + bb
    A = _add(_mul(_conj(a), B), (bb * rho[0], bb * rho[1]))
    for k in range(1, ORDERS + 1):
        total = total + 2.0 * _mul(A, w_at(k))[0]
        A = _mul(A, rho)
    # the rest, W_c(k x) ≈ W_c(K x)·g^(k−K) with g = W_c(K x)/W_c((K−1) x), |g| ≤ 1
    last, before = w_at(ORDERS), w_at(ORDERS - 1)
    g = _div(last, before)
    shrink = dr.minimum(1.0, dr.rsqrt(dr.maximum(_abs2(g), _TINY)))
    g = dr.select(_abs2(before) > 1e-12, g[0] * shrink, 0.0), \
        dr.select(_abs2(before) > 1e-12, g[1] * shrink, 0.0)
    tail = _div(_mul(_mul(A, last), g), _sub((1.0, 0.0), _mul(rho, g)))
    return total + 2.0 * tail[0]


def colour(cos1, n1, n2, eta3, k3, thickness, sensitivity, evanescent: bool = True):
    """
    [(R_s, R_p) of each channel]: the film's reflectances integrated against the channels'
    sensitivities (:func:`fourier`). ``eta3``, ``k3``: per channel (a colour), or one value
    for every channel (a Float). ``evanescent``: whether n₁ sinθ₁ may exceed n₂ (else the
    branch for a film without oscillation is left out of the kernel).
    """
    film = upper(cos1, n1, n2)
    x = 2.0 * thickness * film.q2[0]
    rows = {}

    def w_at(k):  # W_c(k·x) of every channel, from one row of the table
        if k not in rows:
            rows[k] = sensitivity.row(k * x)
        return rows[k]
    per_channel = dr.depth_v(eta3) > dr.depth_v(mi.Float)
    shared = None if per_channel else lower(film, n2, eta3, k3)
    out = []
    for c in range(sensitivity.channels):
        r23s, r23p = lower(film, n2, eta3[c], k3[c]) if per_channel else shared
        rs2 = fourier(film.r12s, r23s, lambda k: w_at(k)[c])
        rp2 = fourier(film.r12p, r23p, lambda k: w_at(k)[c])
        if evanescent:  # nothing oscillates: the exact value at the mean wavelength
            inside = film.q2[1] > film.q2[0]
            wavelength = float(sensitivity.mean_wavelength[c])
            decay = dr.exp(-4.0 * dr.pi * thickness / wavelength * film.q2[1])
            z = (decay, 0.0 * decay)
            rs2 = dr.select(inside, _abs2(reflect(film.r12s, r23s, z)), rs2)
            rp2 = dr.select(inside, _abs2(reflect(film.r12p, r23p, z)), rp2)
        # a colour outside sRGB's gamut has a negative channel: clipped into [0, 1]
        out.append((dr.clip(rs2, 0.0, 1.0), dr.clip(rp2, 0.0, 1.0)))
    return out


def mueller(rs, rp):
    """The Mueller matrix of reflection (a ``mi.Spectrum`` of a polarized variant) from the
    amplitudes of each channel, laid out as ``mi.mueller.specular_reflection`` lays it out:
    Mitsuba's amplitudes are the complex conjugates of these (e^(+iωt))."""
    Rs, Rp = _abs2(rs), _abs2(rp)
    cross = _mul(rs, _conj(rp))  # c·cosδ = Re, c·sinδ = −Im (conjugated amplitudes)
    a, b, cc, cs = 0.5 * (Rs + Rp), 0.5 * (Rs - Rp), cross[0], -cross[1]
    M = mi.Spectrum(0.0)
    entries = {(0, 0): a, (0, 1): b, (1, 0): b, (1, 1): a, (2, 2): cc, (2, 3): cs,
               (3, 2): -cs, (3, 3): cc}
    for (i, j), v in entries.items():
        M[i, j] = mi.UnpolarizedSpectrum(v)
    return M


@lru_cache(maxsize=None)
def sensitivity_table(channels: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    (W, mean wavelengths): W_c(x) at x = 0, X_STEP, … X_MAX as a float64 array (channels,
    nodes, 2) (real and imaginary parts), from Mitsuba's CIE 1931 table and D65 (1 nm rule
    over [MI_CIE_MIN, MI_CIE_MAX]); 3 channels: linear sRGB, 1: luminance (ȳ); and each
    channel's mean wavelength ∫λ w_c / ∫w_c.
    """
    lam = np.arange(mi.MI_CIE_MIN, mi.MI_CIE_MAX + 0.5, 1.0)
    if dr.is_jit_v(mi.Float):
        xyz = np.array(mi.cie1931_xyz(mi.Float(lam))).reshape(3, -1)
        d65 = np.array(mi.cie_d65(mi.Float(lam))).ravel()
    else:
        xyz = np.array([[float(v) for v in mi.cie1931_xyz(float(x))] for x in lam]).T
        d65 = np.array([float(mi.cie_d65(float(x))) for x in lam])
    w = (SRGB @ xyz if channels == 3 else xyz[1:2]) * d65
    w = w / w.sum(axis=1, keepdims=True)  # trapezoid and sum agree: w vanishes at both ends
    # e^(2πi x/λ) at x = (start + j)·X_STEP: the block's first row exactly, then powers
    n, block = int(round(X_MAX / X_STEP)) + 1, 64
    steps = np.exp(2j * np.pi * X_STEP * np.outer(np.arange(block), 1.0 / lam))
    table = np.empty((channels, n, 2))
    for start in range(0, n, block):
        rows = min(block, n - start)
        first = np.exp(2j * np.pi * start * X_STEP / lam)
        phases = steps[:rows] * first
        table[:, start:start + rows, 0] = w @ np.ascontiguousarray(phases.real).T
        table[:, start:start + rows, 1] = w @ np.ascontiguousarray(phases.imag).T
    return table, (w * lam).sum(axis=1)


#: CIE XYZ to linear sRGB (D65), as ``mi.xyz_to_srgb``.
SRGB = np.array([[3.240479, -1.537150, -0.498535],
                 [-0.969256, 1.875991, 0.041556],
                 [0.055648, -0.204043, 1.057311]])


class Sensitivity:
    """W_c(x) of each channel of the current variant (RGB: 3, mono: 1), looked up linearly
    in x (0 beyond X_MAX), and each channel's mean wavelength. A cell of the table stores what
    its lookup needs for every channel (both ends, real and imaginary parts): x is the same for
    every channel (the film's index is), and one row of adjacent numbers is read."""

    def __init__(self):
        channels = 1 if mi.is_monochromatic else 3
        table, self.mean_wavelength = sensitivity_table(channels)
        self.cells = table.shape[1] - 1
        self.channels = channels
        # (cells, 2 ends, channels, 2 parts), padded to a multiple of 4 numbers per cell
        cells = np.stack([table[:, :-1], table[:, 1:]], axis=0).transpose(2, 0, 1, 3)
        self.width = -(-4 * channels // 4) * 4
        flat = np.zeros((self.cells, self.width))
        flat[:, :4 * channels] = cells.reshape(self.cells, -1)
        if dr.is_jit_v(mi.Float):
            self.table = mi.Float(flat.ravel().astype(np.float32))
            dr.make_opaque(self.table)
        else:
            self.table = flat

    def row(self, x):
        """[W_c(x) as a pair, for each channel] (x ≥ 0, nm)."""
        u = x * (1.0 / X_STEP)
        inside = u < self.cells
        u = dr.clip(u, 0.0, self.cells)
        i = dr.minimum(mi.UInt32(u), self.cells - 1)
        t = u - mi.Float(i)
        if dr.is_jit_v(mi.Float):
            quads = self.width // 4
            v = [x for j in range(quads)
                 for x in dr.gather(mi.Vector4f, self.table, i * quads + j)]
        else:
            v = [float(x) for x in self.table[int(i)]]
        n = 2 * self.channels  # the numbers of one end: (re, im) per channel
        return [(dr.select(inside, dr.lerp(v[2 * c], v[n + 2 * c], t), 0.0),
                 dr.select(inside, dr.lerp(v[2 * c + 1], v[n + 2 * c + 1], t), 0.0))
                for c in range(self.channels)]

    def __call__(self, channel: int, x):
        """W_c(x) of one channel as a pair."""
        return self.row(x)[channel]
