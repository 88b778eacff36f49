r"""
Every order of scattering in Hanrahan & Krueger's slab (:mod:`mi_brdfs.reference.hk`: optical
depth τ, single-scattering albedo a, Henyey-Greenstein g, a smooth interface of relative index
η ≥ 1 on top; free-standing with the same interface below, or over a Lambertian base of
reflectance ρ in contact with the medium) in float64, by the discrete-ordinates
adding-doubling method with a Fourier expansion in azimuth (van de Hulst 1980, "Multiple Light
Scattering", ch. 4-5; Wiscombe 1976, "On initialization, error and flux conservation in the
doubling method", JQSRT 16, 637-658; Prahl 1995, "The adding-doubling method", in
"Optical-Thermal Response of Laser-Irradiated Tissue", ch. 5, for the Fresnel faces with the
quadrature split at the critical angle; Jakob et al. 2014, "A Comprehensive Framework for
Rendering Layered Materials", §4-5, for the Fourier-in-azimuth formulation).

**Azimuth.** ωi and ωo both point away from the surface, Δφ = φo − φi, and

.. math::  f(\mu_i, \mu_o, \Delta\phi) = \sum_{m \ge 0} c_m f_m(\mu_i, \mu_o) \cos(m\Delta\phi),
           \qquad c_0 = 1,\ c_{m \ge 1} = 2,

so f_m = (1/2π) ∫ f cos(mΔφ) dΔφ (f_0 is the azimuthal mean). The forward-scattering peak
(−ωi refracted, in transmission; the mirror side in reflection) is at Δφ = π. Inside, the
code labels directions by their azimuth of travel, where the forward peak is at 0: f_m there
is (−1)^m times the one returned.

**Discretisation.** Inside the slab, Gauss-Legendre on [0, μc] and [μc, 1], μc = √(1 − 1/η²)
(below μc the faces reflect totally; above it the nodes are Gauss-Legendre in the external
cosine, as Prahl's Radau nodes are, which 1 − F needs); at η = 1 one interval, graded to
grazing angles (:func:`_nodes`). The internal cosines μ'(μ) of the wanted external μ join the
set with weight 0 (they receive and send, but take no part in the integrals), so results come
exactly at those μ. Every operator (a layer's reflection or transmission, per mode) is a pair
(d, K): a delta part d (diagonal: the unscattered beam, a mirror reflection) and a diffuse
kernel K[out, in] acting on radiance as L_out = d L_in + 2π Σ_k K[:, k] μ_k w_k L_in[k];
products, sums and inverses of pairs are exact in this form, so a zero-weight column keeps
its diffuse response. The phase function's modes come from an FFT of HG over N_PHI azimuths,
mode 0 renormalised to conserve energy in the quadrature, symmetrically (Wiscombe 1976;
:func:`_renormalise`). A thin layer by the diamond (trapezoid) scheme, which conserves flux
exactly, of Δ ≤ THIN·μ' at the external directions, then doubling to τ_min and on, one level
per doubling; then the faces by the adding equations, with the n² law of radiance at the
crossings: f = T_i T_o K(μi', μo')/η² for K the inside kernel.

**Accuracy** (measured, ``tests/reference/test_hk_doubling.py``): f to ~1e-6 of its maximum
at |g| ≤ 0.7 with the default 24 nodes (against 128), ~1e-3 at g = 0.9 with 48; energy at
a = 1 to 1e-6 at every μi (g = 0.9: 1e-5); the walk of :func:`mi_brdfs.reference.hk.walk`
within its noise; the first-order term equal to the closed form to 1e-15 (64 modes).
The cost grows as albedos × modes × (nodes + K)² × nodes × (doublings + log2(τ_min/Δ)).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import ParameterError
from .hk import fresnel, hg, refracted
from .quadrature import gauss_legendre

#: Azimuths of the FFT of the phase function (modes above N_PHI/2 alias).
N_PHI = 256
#: Real nodes per hemisphere inside the slab (split at μc where η > 1), for |g| ≤ 0.7 and
#: above: measured against 128 nodes, f to ~1e-6 of its maximum at |g| ≤ 0.7 with 24 nodes;
#: at g = 0.9 the transmitted peak needs 48 (~1e-3; 24 nodes: ~4e-2).
DEFAULT_NODES = (24, 48)
#: The first layer's optical depth as a fraction of the smallest cosine (diamond scheme).
THIN = 0.1


@dataclasses.dataclass
class Tables:
    """The slab's Fourier coefficients on the external cosines ``mu`` (see :func:`tables`)."""

    tau: np.ndarray
    mu: np.ndarray
    reflect: np.ndarray
    transmit: np.ndarray
    single_reflect: np.ndarray
    single_transmit: np.ndarray
    E: np.ndarray | None = None
    U: np.ndarray | None = None
    S: np.ndarray | None = None
    E0: np.ndarray | None = None
    U0: np.ndarray | None = None


class _Ops:
    """The algebra of pairs (d, K) on a node set whose first ``nr`` nodes have the weights
    2π μ w = ``m2`` (the others weight 0). K = None is a zero kernel."""

    def __init__(self, m2: np.ndarray, nr: int):
        self.m2, self.nr = m2[:nr], nr

    def mul(self, a, b, rows=slice(None), cols=slice(None)):
        """The operator a∘b (b acts first); ``rows``/``cols`` (slices of the nodes) keep a
        block of the kernel only (then d stays whole); b's kernel may already be cut to
        ``cols``."""
        (da, ka), (db, kb) = a, b
        if ka is None and kb is None:
            return da * db, None
        kbc = kb if kb is None or kb.shape[-1] != da.shape[-1] else kb[..., cols]
        if ka is None or kb is None:
            k = da[..., rows, None] * kbc[..., rows, :] if ka is None else \
                ka[..., rows, cols] * db[..., None, cols]
            return da * db, k
        k = ka[..., rows, :self.nr] @ (self.m2[:, None] * kbc[..., :self.nr, :])
        if np.any(da):
            k += da[..., rows, None] * kbc[..., rows, :]
        if np.any(db):
            k += ka[..., rows, cols] * db[..., None, cols]
        return da * db, k

    @staticmethod
    def add(a, b, sign=1.0):
        k = a[1] if b[1] is None else sign * b[1] if a[1] is None else a[1] + sign * b[1]
        return a[0] + sign * b[0], k

    def inv(self, a):
        """(D + 2πKM)⁻¹ = (1/d, Y/d), Y = −(I + 2πCM)⁻¹C, C = K/d: the real block by a
        solve, the zero-weight rows after it (their columns of 2πCM are zero)."""
        d, k = a
        if k is None:
            return 1.0 / d, None
        unit = bool(np.all(d == 1))
        c = k if unit else k / d[..., :, None]
        nr = self.nr
        y = np.empty(c.shape)
        y[..., :nr, :] = np.linalg.solve(np.eye(nr) + c[..., :nr, :nr] * self.m2,
                                         c[..., :nr, :])
        np.matmul(c[..., nr:, :nr] * self.m2, y[..., :nr, :], out=y[..., nr:, :])
        np.subtract(c[..., nr:, :], y[..., nr:, :], out=y[..., nr:, :])
        if not unit:
            y /= d[..., None, :]
        return 1.0 / d, np.negative(y, out=y)

    def solve(self, a, b, cols=slice(None)):
        """a⁻¹∘b without forming a⁻¹: d = d_b/d_a and (D_a + 2πK_a M)K = K_b − K_a d, the
        real rows by a solve, the zero-weight rows after them; only the kernel's columns
        ``cols`` (b's may already be cut to them)."""
        (da, ka), (db, kb) = a, b
        d, n = db / da, da.shape[-1]
        kbc = kb if kb is None or kb.shape[-1] != n else kb[..., cols]
        if ka is None:
            return d, (None if kb is None else kbc / da[..., :, None])
        rhs = -ka[..., :, cols] * d[..., None, cols]
        if kb is not None:
            rhs = rhs + kbc
        c = ka
        if not np.all(da == 1):
            rhs, c = rhs / da[..., :, None], ka / da[..., :, None]
        nr = self.nr
        y = np.empty(np.broadcast_shapes(rhs.shape, c.shape[:-1] + rhs.shape[-1:]))
        y[..., :nr, :] = np.linalg.solve(np.eye(nr) + c[..., :nr, :nr] * self.m2,
                                         rhs[..., :nr, :])
        np.matmul(c[..., nr:, :nr] * self.m2, y[..., :nr, :], out=y[..., nr:, :])
        np.subtract(rhs[..., nr:, :], y[..., nr:, :], out=y[..., nr:, :])
        return d, y

    def one_minus(self, a):
        """I − a."""
        return 1.0 - a[0], (None if a[1] is None else -a[1])


def _nodes(eta: float, nodes: int, mu_ext: np.ndarray):
    """(μ' (n,), w (n,), nr): the real nodes, then the zero-weight μ'(μ). At η = 1,
    Gauss-Legendre in u with μ' = u²: nodes crowd at grazing angles, where the light scattered
    from a grazing beam varies on the scale of its cosine. At η > 1 no outside direction is
    grazing inside (μ' ≥ μc): Gauss-Legendre in μ' on [0, μc], and above μc in the external
    cosine μ (Prahl 1995, §5.3.1), as 1 − F has a square-root branch at μc in μ' and none in
    μ; there dμ' = μ dμ/(η² μ')."""
    x, w = gauss_legendre(nodes if eta == 1 else nodes // 2)
    x, w = 0.5 * (x + 1), 0.5 * w
    if eta == 1:
        mu, wt = x * x, 2 * x * w
    else:
        mc, up = math.sqrt(1 - 1 / eta ** 2), refracted(x, eta)
        mu = np.concatenate([mc * x, up])
        wt = np.concatenate([mc * w, w * x / (eta * eta * up)])
    inner = refracted(mu_ext, eta)
    return (np.concatenate([mu, inner]), np.concatenate([wt, np.zeros(inner.size)]), mu.size)


def _phase(mu: np.ndarray, g: float, modes: range, n_phi: int = N_PHI):
    """HG's modes p_m(μ_out, μ_in) (M, n, n), m in ``modes``, with directions labelled by travel: same
    hemisphere (cosΘ = μμ' + ss' cosΔφ) and opposite (−μμ' + ss' cosΔφ)."""
    s = np.sqrt(np.maximum(1 - mu * mu, 0))
    phi = 2 * np.pi * np.arange(n_phi) / n_phi
    mm, ss = np.multiply.outer(mu, mu), np.multiply.outer(s, s)
    out = []
    for sign in (1.0, -1.0):
        p = hg(np.clip(sign * mm[..., None] + ss[..., None] * np.cos(phi), -1, 1), g)
        c = np.fft.rfft(p, axis=-1).real / n_phi
        out.append(np.moveaxis(c[..., modes.start:modes.stop], -1, 0))
    return out


def _renormalise(p_same, p_opp, w, nr):
    """Mode 0 conserves energy in the quadrature (Wiscombe 1976): a real column's deficit
    goes on the diagonal of the forward part; a zero-weight node's column (light from it
    into the real nodes) and row (into it) are divided by their sum over the real nodes,
    which is 1 for an isotropic field. Both keep the matrices symmetric (reciprocity); the
    block between zero-weight nodes (one scattering, no quadrature) stays exact."""
    p_same, p_opp = p_same.copy(), p_opp.copy()
    total = 2 * np.pi * (w[:nr] @ (p_same[0, :nr] + p_opp[0, :nr]))
    j = np.arange(nr)
    p_same[0, j, j] += (1 - total[:nr]) / (2 * np.pi * w[:nr])
    for p in (p_same, p_opp):
        p[0, :nr, nr:] /= total[nr:]
        p[0, nr:, :nr] /= total[nr:, None]
    return p_same, p_opp


def _thin_layer(ops, albedo, delta, mu, p_same, p_opp):
    """(R, T) of a layer of optical depth ``delta`` by the diamond scheme: with du/dτ =
    −αu + βv, dv/dτ = −βu + αv and the trapezoid rule over the layer,
    T = (I − HH)⁻¹(GC + HH), R = H(I + T), G = (I + Δα/2)⁻¹, C = I − Δα/2, H = GΔβ/2."""
    scale = 0.5 * delta * albedo[:, None, None, None] / np.multiply.outer(mu, mu)
    k_same, k_opp = scale * p_same, scale * p_opp
    half = 0.5 * delta / mu
    g = ops.inv((1 + half, -k_same))
    c = (1 - half, k_same)
    h = ops.mul(g, (np.zeros_like(mu), k_opp))
    hh = ops.mul(h, h)
    t = ops.mul(ops.inv(ops.one_minus(hh)), ops.add(ops.mul(g, c), hh))
    r = ops.mul(h, ops.add((np.ones_like(mu), None), t))
    return r, t


def _double(ops, r, t):
    """A layer on itself: R₂ = R + TR(I − RR)⁻¹T, T₂ = T(I − RR)⁻¹T ((I − RR)⁻¹ and R
    commute)."""
    y = ops.solve(ops.one_minus(ops.mul(r, r)), t)
    return ops.add(r, ops.mul(t, ops.mul(r, y))), ops.mul(t, y)


def _slabs(ops, albedo, tau_min, doublings, mu, p_same, p_opp):
    """[(R, T)] of the slab at τ_min·2^l, l = 0..doublings."""
    # Δ ≤ THIN·μ at the external directions; the diamond stays positive up to Δ = 2μ, and
    # the grazing real nodes below THIN·μ (weights ~μ²) are allowed Δ ≤ μ
    first = min(THIN * mu[ops.nr:].min(initial=1.0), mu.min())
    steps = max(0, math.ceil(math.log2(tau_min / first)))
    r, t = _thin_layer(ops, albedo, tau_min / 2 ** steps, mu, p_same, p_opp)
    for _ in range(steps):
        r, t = _double(ops, r, t)
    out = [(r, t)]
    for _ in range(doublings):
        r, t = _double(ops, r, t)
        out.append((r, t))
    return out


def _free_standing(ops, r, t, face):
    """Inside kernels between zero-weight nodes (reflected up at the top, transmitted down
    at the bottom) of the slab between two faces reflecting ``face`` (a delta, B = F):
    R' = R + T(I − BR)⁻¹BT with the bottom, the top's bounces by (I − F R')⁻¹, and
    (I − RB)⁻¹T(I − F R')⁻¹ down at the bottom."""
    z, one = slice(ops.nr, None), (np.ones_like(face[0]), None)
    bottom = ops.one_minus(ops.mul(face, r))
    r_tot = ops.add(r, ops.mul(t, ops.solve(bottom, ops.mul(face, t))))
    down = ops.solve(ops.one_minus(ops.mul(face, r_tot)), one, cols=z)
    up = ops.mul(r_tot, down, z, z)
    # (I − RB)⁻¹ = I + R(I − BR)⁻¹B, on the zero-weight columns only
    through = ops.mul(t, down, cols=z)
    bounced = ops.solve(bottom, ops.mul(face, through, cols=z), cols=z)
    return up[1], through[1][..., z, :] + ops.mul(r, bounced, z, z)[1]


def _over_base(ops, r, t, face, m2):
    """The slab under the top face over a black base: the inside reflection kernel, and
    for the base's series E (flux reaching the base per unit incident irradiance, per inside
    direction), U (inside radiance leaving up at the top face per unit flux sent up by the
    base, isotropically) and S (the flux coming back down to the base)."""
    z = slice(ops.nr, None)
    down = ops.solve(ops.one_minus(ops.mul(face, r)), (np.ones_like(face[0]), None), cols=z)
    up = ops.mul(r, down, z, z)
    # the base is Lambertian: mode 0 only
    r, t, down = ((d, None if k is None else k[..., :1, :, :]) for d, k in (r, t, down))
    x = ops.mul(t, down, cols=z)
    e = x[0][z] + (0 if x[1] is None else m2 @ x[1][..., 0, :, :])
    rise = ops.solve(ops.one_minus(ops.mul(r, face)), t)
    iso = np.full(m2.size, 1 / np.pi)
    u = rise[0] * iso + (0 if rise[1] is None else rise[1][..., 0, :, :] @ (m2 * iso))
    back = ops.add(r, ops.mul(ops.mul(t, face), rise))
    b = back[0] * iso + (0 if back[1] is None else back[1][..., 0, :, :] @ (m2 * iso))
    return up[1], e, u[..., z], np.sum(m2 * b, axis=-1)


def _single(albedo, tau, mu, p_same, p_opp, zero):
    """The first order in closed form (Chandrasekhar 1960, §46) with the same phase modes:
    inside kernels a p_m (1 − e^{−τ(1/μi + 1/μo)})/(μi + μo) reflected and
    a p_m (e^{−τ/μo} − e^{−τ/μi})/(μo − μi) transmitted, [.., τ, m, out, in]."""
    mo, mi_ = mu[zero][:, None], mu[zero][None, :]
    t = tau[:, None, None]
    fr = -np.expm1(-t * (1 / mi_ + 1 / mo)) / (mi_ + mo)
    lo, hi = np.minimum(mi_, mo), np.maximum(mi_, mo)
    y = t * (1 / lo - 1 / hi)
    ratio = np.where(y > 1e-8, -np.expm1(-y) / np.where(y > 0, y, 1), 1 - y / 2)
    ft = np.exp(-t / hi) * t / (lo * hi) * ratio
    a = albedo[:, None, None, None, None]
    sub = np.ix_(range(p_same.shape[0]), zero, zero)
    return (a * fr[:, None] * p_opp[sub], a * ft[:, None] * p_same[sub])


def unscattered_series(mu, tau, eta: float):
    """
    The free-standing slab's delta beams at external cosines ``mu`` (broadcast with ``tau``):
    (the total transmittance along −ωi, T² e^{−τ/μ'}/(1 − F²e^{−2τ/μ'}), and the extra
    reflectance in the mirror direction of the beams reflected inside, T² F e^{−2τ/μ'}/(1 −
    F²e^{−2τ/μ'})), the geometric series of the unscattered beam between the two faces.
    The mirror reflection F(μ) at the top itself is not included.
    """
    mu = np.asarray(mu, np.float64)
    f = fresnel(mu, eta)
    e = np.exp(-np.asarray(tau, np.float64) / np.maximum(refracted(mu, eta), 1e-300))
    t2, loop = (1 - f) ** 2, 1 - (f * e) ** 2
    return t2 * e / loop, t2 * f * e * e / loop


def tables(albedo, tau_min, doublings, g, eta, base, mu, modes, nodes=None,
           first_mode: int = 0) -> Tables:
    """
    The slab's Fourier coefficients f_m (BRDF per steradian, no cosine; c_m and Δφ as in the
    module's docstring) at the external cosines ``mu`` (K,) in (0, 1], for the albedos
    ``albedo`` (A,) and τ = ``tau`` = [0, τ_min·2^l for l = 0..``doublings``] (L + 1 values),
    modes m = ``first_mode``..``first_mode`` + ``modes`` − 1 (M). Free-standing (``base`` False: the same face below) or over
    a Lambertian base in contact with the medium.

    - ``reflect``, ``transmit`` (A, L+1, M, K, K) [.., i, o]: all the diffuse light, every
      order and the internal reflections, without the top's mirror reflection F(μi), the
      unscattered beams (deltas along −ωi and the mirror direction: the beam through the slab
      and its copies reflected between the faces, :func:`unscattered_series`) and, over a
      base, the base's part; ``transmit`` is 0 over a base.
    - ``single_reflect``, ``single_transmit``: the first order (one scattering, no internal
      reflection) in closed form with the same phase modes, so reflect − single_reflect is
      the higher orders and the internal reflections.
    - over a base only, mode 0: f_base(μi, μo) = ρ E[i] U[o]/(1 − ρ S), the base's whole part;
      ``E`` (A, L+1, K) the flux reaching the base per unit irradiance from μi, ``U`` (A,
      L+1, K) the radiance leaving at μo per unit flux the base sends up, ``S`` (A, L+1) the
      flux that comes back down to it; ``E0``, ``U0`` the direct part (no scattering, no
      internal reflection): ρ E0[i] U0[o] = ρ T_i T_o e^{−τ(1/μi' + 1/μo')}/(πη²).

    ``nodes``: real nodes per hemisphere inside, default :data:`DEFAULT_NODES` (24, or 48 for
    |g| > 0.7). Time: ~1-2.5 s for A = 12, L = 14, K = 32, M = 16 on one busy core.
    """
    albedo, mu = np.atleast_1d(np.asarray(albedo, np.float64)), np.asarray(mu, np.float64)
    _check(albedo, tau_min, doublings, eta, mu, modes)
    eta = float(eta)
    taus = np.concatenate([[0.0], tau_min * 2.0 ** np.arange(doublings + 1)])
    mu_in, w, nr = _nodes(eta, nodes or DEFAULT_NODES[abs(g) > 0.7], mu)
    zero = np.arange(nr, mu_in.size)
    orders = range(first_mode, first_mode + modes)
    p_same, p_opp = _phase(mu_in, g, orders)
    m2 = 2 * np.pi * mu_in * w
    ops = _Ops(m2, nr)
    face = (fresnel(mu_in, 1 / eta), None)
    if first_mode == 0:
        p_same, p_opp = _renormalise(p_same, p_opp, w, nr)
    slabs = _slabs(ops, albedo, tau_min, doublings, mu_in, p_same, p_opp)
    shape = (albedo.size, taus.size, modes, mu.size, mu.size)
    reflect, transmit = np.zeros(shape), np.zeros(shape)
    ext = _external(mu, eta, orders)
    out = {}
    if base:
        empty = (np.zeros(mu_in.size), None), (np.ones(mu_in.size), None)
        parts = [_over_base(ops, r, t, face, m2) for r, t in [empty] + slabs]
        for l, part in enumerate(parts[1:], 1):
            reflect[:, l] = np.swapaxes(part[0], -1, -2) * ext
        if first_mode == 0:  # the Lambertian base's series: mode 0 alone
            out = _base_series(parts, albedo.size, mu, taus, mu_in[zero], eta)
    else:
        for l, (r, t) in enumerate(slabs, 1):
            up, through = _free_standing(ops, r, t, face)
            reflect[:, l] = np.swapaxes(up, -1, -2) * ext
            transmit[:, l] = np.swapaxes(through, -1, -2) * ext
    sr, st = _single(albedo, taus, mu_in, p_same, p_opp, zero)
    single_t = np.swapaxes(st, -1, -2) * ext * (not base)
    return Tables(taus, mu, reflect, transmit, np.swapaxes(sr, -1, -2) * ext, single_t, **out)


def _check(albedo, tau_min, doublings, eta, mu, modes):
    """One-line errors for arguments out of range."""
    for name, value, ok, allowed in (
            ("albedo", albedo, np.all((albedo >= 0) & (albedo <= 1)), "in [0, 1]"),
            ("tau_min", tau_min, tau_min > 0, "> 0"),
            ("doublings", doublings, int(doublings) == doublings >= 0, "an integer >= 0"),
            ("eta", eta, eta >= 1, ">= 1"),
            ("mu", mu, mu.ndim == 1 and np.all((mu > 0) & (mu <= 1)), "1-D, in (0, 1]"),
            ("modes", modes, int(modes) == modes >= 1, "an integer >= 1")):
        if not ok:
            raise ParameterError("hk_doubling.tables", name, value, allowed)


def _base_series(parts, n_albedo, mu, taus, mu_inside, eta):
    """E, U, S at the external cosines (T_i at entry, T_o/η² at exit) and the direct E0, U0
    in closed form: T_i e^{−τ/μi'} and T_o e^{−τ/μo'}/(πη²)."""
    tr = 1 - fresnel(mu, eta)
    out = {
        "E": np.stack([np.broadcast_to(p[1], (n_albedo, mu.size)) for p in parts], 1) * tr,
        "U": np.stack([np.broadcast_to(p[2], (n_albedo, mu.size)) for p in parts], 1)
        * tr / eta ** 2,
        "S": np.stack([np.broadcast_to(p[3], (n_albedo,)) for p in parts], axis=1)}
    direct = tr * np.exp(-taus[:, None] / mu_inside)
    out["E0"] = np.broadcast_to(direct, (n_albedo,) + direct.shape).copy()
    out["U0"] = out["E0"] / (np.pi * eta * eta)
    return out


def _external(mu, eta, modes: range):
    """(−1)^m T_i T_o/η² (M, K, K): inside kernels to external f_m (n² law, Δφ shifted by π)."""
    tr = 1 - fresnel(mu, eta)
    sign = (-1.0) ** np.arange(modes.start, modes.stop)
    return sign[:, None, None] * np.multiply.outer(tr, tr)[None] / eta ** 2
