r"""
Energy compensation of a single-scattering microfacet lobe (Kulla & Conty 2017, "Revisiting
Physically Based Shading at Imageworks", SIGGRAPH course "Physically Based Shading in Theory and
Practice", §"Energy compensation"; after Kelemen & Szirmay-Kalos 2001): the light that a
microfacet BRDF loses to the bounces between microfacets is given back by a second, reciprocal
lobe

.. math::

    f_\mathrm{ms}(\omega_i, \omega_o) = F_\mathrm{ms}\,
        \frac{(1 - E(\mu_i))\,(1 - E(\mu_o))}{\pi\,(1 - E_\mathrm{avg})}, \qquad
    E_\mathrm{avg} = 2\int_0^1 E(\mu)\,\mu\,d\mu,

where E(μ) is the directional albedo of the single-scattering lobe with F ≡ 1 at incidence
cosine μ. Then the albedo of f_ss + f_ms with F ≡ 1 is E(μi) + (1 − E(μi)) = 1 at every μi,
exactly when E is the lobe's own albedo. With a Fresnel term F ≠ 1, each bounce absorbs
1 − F: Kulla & Conty sum the series of bounces with the hemispherical average
F_avg = 2∫F(μ)μ dμ, which gives the colour of the compensation

.. math::

    F_\mathrm{ms} = \frac{F_\mathrm{avg}^2\, E_\mathrm{avg}}{1 - F_\mathrm{avg}\,(1 - E_\mathrm{avg})}.

**Tables.** E(μ, α) is tabulated per distribution and masking by ``mi-brdfs tables`` from the
``cooktorrance`` plugin's own single-scattering lobe (:mod:`mi_brdfs.albedo_tables`) and shipped
in ``mi_brdfs/data/microfacet_albedo.npz``. The nodes are uniform in x = sqrt(μ) and in
y = sqrt(α / α_max): the albedo changes fastest at grazing incidence and at small roughness.
:meth:`AlbedoTable.albedo` interpolates bilinearly in (x, y) in every variant (a NumPy lookup in
scalar variants; in JIT ones a gather from a ``mi.Float`` that stores each node beside the next,
so that one packet gather reads both ends of a cell instead of two gathers; the
``multiscatter`` bench pairs of ``make bench`` price the compensation),
and :meth:`AlbedoTable.average` linearly in y: E_avg of a node is the exact integral of the
interpolant in μ, so the two are consistent between the nodes too and the compensated albedo
is 1 up to the interpolation error of E alone. Beyond α_max the tables hold their last value
(the compensation then falls short: the lobe loses energy, it never creates it).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import drjit as dr
import mitsuba as mi
import numpy as np

from . import fresnel

#: The tables shipped with the package (written by ``mi-brdfs tables``).
TABLE_PATH = Path(__file__).resolve().parent.parent / "data" / "microfacet_albedo.npz"

#: Gauss-Legendre nodes and weights on [−1, 1] of F_avg (:func:`fresnel_average`).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)

_TINY = 1e-30


def table_key(kind: str, shadowing: str) -> str:
    """The name of a distribution's table in the file: e.g. 'ggx-smith'."""
    return f"{kind}-{shadowing}"


@lru_cache(maxsize=None)
def load_tables(path: str = str(TABLE_PATH)) -> dict:
    """The tables as float64 NumPy arrays: the conductor's ``E[key]`` (n_alpha, n_mu) and
    ``E_avg[key]`` (n_alpha,), the dielectric's ``ET[key]`` (n_eta, n_alpha, n_mu) and
    ``ET_avg[key]`` (n_eta, n_alpha), the scalars ``alpha_max`` and ``eta_max``."""
    with np.load(path) as data:
        out = {"alpha_max": float(data["alpha_max"]), "eta_max": float(data["eta_max"])}
        for name in ("E", "ET"):
            keys = [k[len(name) + 1:] for k in data.files if k.startswith(name + "_") and
                    not k.startswith(name + "_avg_")]
            out[name] = {k: np.asarray(data[f"{name}_{k}"], np.float64) for k in keys}
            out[name + "_avg"] = {k: np.asarray(data[f"{name}_avg_{k}"], np.float64)
                                  for k in keys}
        return out


def conductor_table(kind: str, shadowing: str, alpha=None) -> "AlbedoTable":
    """The shipped :class:`AlbedoTable` of a reflecting lobe's distribution and masking, at
    the uniform roughness ``alpha`` (None: any roughness)."""
    tables = load_tables()
    key = table_key(kind, shadowing)
    return AlbedoTable(tables["E"][key], tables["E_avg"][key], tables["alpha_max"], alpha)


def dielectric_tables(kind: str, eta, alpha=None) -> tuple["AlbedoTable", ...]:
    """
    The :class:`AlbedoTable` pair of :func:`dielectric_arrays` (lit from above, from below),
    at the uniform roughness ``alpha`` (None: any roughness). ``eta``: a number, or a Float
    whose derivative, where AD tracks it, flows into the tables through the slope of their
    interpolation in η (:func:`dielectric_slopes`: the tables are linear in η within a cell).
    """
    value = float(np.asarray(eta, np.float64).ravel()[0])
    offset = eta - dr.detach(eta) if dr.is_diff_v(mi.Float) and dr.grad_enabled(eta) else None
    alpha_max = load_tables()["alpha_max"]
    return tuple(AlbedoTable(E, E_avg, alpha_max, alpha,
                             None if offset is None else (*slope, offset))
                 for (E, E_avg), slope in zip(dielectric_arrays(kind, value),
                                              dielectric_slopes(kind, value)))


def _eta_cell(relative: float, n: int, eta_max: float):
    """(node below, fraction to the next, d(position)/d(relative) or 0 beyond the table) of a
    relative index on the n nodes uniform in log η over [1/η_max, η_max]."""
    x = (np.log(relative) / np.log(eta_max) + 1.0) / 2.0
    s = np.clip(x, 0.0, 1.0) * (n - 1)
    j = min(int(s), n - 2)
    inside = 0.0 < x < 1.0
    return j, s - j, ((n - 1) / (2.0 * np.log(eta_max) * relative) if inside else 0.0)


def dielectric_slopes(kind: str, eta: float) -> tuple[tuple, tuple]:
    """d/dη of :func:`dielectric_arrays`' (E, E_avg) lit from above and from below (at 1/η:
    the chain rule's −1/η²), as NumPy arrays: constant within a cell of the η nodes."""
    tables = load_tables()
    key, eta_max = table_key(kind, "smith"), tables["eta_max"]
    E, E_avg = tables["ET"][key], tables["ET_avg"][key]
    out = []
    for relative, chain in ((eta, 1.0), (1.0 / eta, -1.0 / (eta * eta))):
        j, _, ds = _eta_cell(relative, len(E), eta_max)
        out.append(((E[j + 1] - E[j]) * ds * chain, (E_avg[j + 1] - E_avg[j]) * ds * chain))
    return tuple(out)


def dielectric_arrays(kind: str, eta: float) -> tuple[tuple, tuple]:
    """
    The albedo tables E_R+T(μ, α) of the rough dielectric (Smith masking) with relative index
    ``eta`` = η_int/η_ext and their averages E_avg(α), as NumPy arrays: ((E, E_avg) lit from
    above, (E, E_avg) lit from below), the file's E(μ, α, η) at η and at 1/η (from below the
    relative index inverts), linear in log η, once per material. Beyond [1/η_max, η_max]
    the tables hold their last value.
    """
    tables = load_tables()
    key, eta_max = table_key(kind, "smith"), tables["eta_max"]
    E, E_avg = tables["ET"][key], tables["ET_avg"][key]

    def at(relative):
        j, t, _ = _eta_cell(relative, len(E), eta_max)
        return ((1.0 - t) * E[j] + t * E[j + 1], (1.0 - t) * E_avg[j] + t * E_avg[j + 1])

    return at(eta), at(1.0 / eta)


def transmitted_shares(t_above, eta, e_avg_above, e_avg_below):
    r"""
    (x_above, x_below): the share of the dielectric's compensation lobe that crosses the
    interface, lit from above and from below. Kulla & Conty 2017 split the missing energy
    1 − E(μi) between reflection and refraction so that the pair stays reciprocal across the
    interface; here detailed balance between the sides (radiance η² times larger below, for
    η = η_below/η_above) asks for x_above (1 − E_avg,above) = η² x_below (1 − E_avg,below).
    The shares are x = T_avg·K/(1 − E_avg) with the interface's average transmittance seen
    from each side, T_avg,above = 1 − F_avg(η) (``t_above``) and T_avg,below = T_avg,above/η²
    (the same balance for a smooth interface, so exact here by construction), and
    K = min(1 − E_avg,above, 1 − E_avg,below): then both x ≤ T_avg ≤ 1.
    """
    missing_above = dr.maximum(1.0 - e_avg_above, 1e-7)
    missing_below = dr.maximum(1.0 - e_avg_below, 1e-7)
    k = dr.minimum(missing_above, missing_below)
    return t_above * k / missing_above, t_above / dr.square(eta) * k / missing_below


def _gather(table, index):
    """``table[index]``: a gather from a ``mi.Float`` in JIT variants, a NumPy lookup else."""
    if dr.is_jit_v(mi.Float):
        return dr.gather(mi.Float, table, index)
    return float(table[int(index)])


def _pair(table, index):
    """(E at a node, E at the next node): entries 2·index and 2·index + 1 of a table of
    :func:`_node_pairs`, one packet gather (``JitFlag.PacketOps``) in JIT variants."""
    if dr.is_jit_v(mi.Float):
        pair = dr.gather(mi.Point2f, table, index)
        return pair.x, pair.y
    k = 2 * int(index)
    return float(table[k]), float(table[k + 1])


def _node_pairs(E):
    """E(..., μ) with each node stored beside the next, flat: [E₀, E₁, E₁, E₂, ...] per row
    (n_μ − 1 pairs), so that a linear lookup reads one pair, not two separate values."""
    return np.stack((E[..., :-1], E[..., 1:]), axis=-1).ravel()


def _upload(values):
    """A float64 NumPy table in the variant's form: a ``mi.Float`` in JIT variants (float32),
    the array itself in scalar ones."""
    return mi.Float(values.astype(np.float32)) if dr.is_jit_v(mi.Float) else values


def _cell(t, n):
    """(index of the node below, fraction to the next) of t ∈ [0, 1] on n uniform nodes."""
    s = dr.clip(t, 0.0, 1.0) * (n - 1)
    i = dr.minimum(mi.UInt32(dr.floor(s)), n - 2)
    return i, s - mi.Float(i)


class AlbedoTable:
    """
    E(μ, α) and E_avg(α) of one single-scattering lobe (``E``: n_α × n_μ nodes, ``E_avg``: n_α,
    float64 NumPy arrays; ``alpha_max``: the last α node), looked up in the current variant
    (the arrays are built with the lobe, so each variant gets its own types). With ``alpha``,
    a uniform roughness (a float or a width-1 Float), the table is interpolated in α once,
    here, so that a lookup reads one pair of values, not two; gradients through ``alpha``
    still flow into that row. ``slope`` = (dE, dE_avg, Δ): the tables' derivatives in a
    parameter and Δ, a Float of value 0 whose derivative is the parameter's (AD variants).
    """

    def __init__(self, E, E_avg, alpha_max: float, alpha=None, slope=None):
        E, E_avg = np.asarray(E, np.float64), np.asarray(E_avg, np.float64)
        self.n_alpha, self.n_mu = E.shape
        self.alpha_max = alpha_max
        self._E, self._E_avg = _upload(_node_pairs(E)), _upload(E_avg)
        if slope is not None:  # (dE, dE_avg, Δ): a value 0 whose derivative AD tracks
            dE, dE_avg, delta = slope
            self._E = self._E + delta * _upload(_node_pairs(np.asarray(dE, np.float64)))
            self._E_avg = self._E_avg + delta * _upload(np.asarray(dE_avg, np.float64))
        #: E(μ) on the μ nodes (pairs, as _node_pairs) and E_avg at ``alpha``, or None
        self.row = self.row_average = None
        if alpha is not None:
            self.row, self.row_average = self._row(alpha), self._average(alpha)

    def __call__(self, mu, alpha=None):
        """(E(μ), E_avg), linear in sqrt μ, at the table's uniform roughness or else at
        ``alpha`` (a value, or a callable that gives it: only called when α varies)."""
        if self.row is not None:
            i, t = _cell(dr.sqrt(dr.maximum(mu, 0.0)), self.n_mu)
            return dr.lerp(*_pair(self.row, i), t), self.row_average
        alpha = alpha() if callable(alpha) else alpha
        return self.albedo(mu, alpha), self._average(alpha)

    def albedo(self, mu, alpha):
        """E(μ, α), bilinear in (sqrt μ, sqrt(α/α_max))."""
        i, tx = _cell(dr.sqrt(dr.maximum(mu, 0.0)), self.n_mu)
        j, ty = _cell(dr.sqrt(dr.maximum(alpha, 0.0) / self.alpha_max), self.n_alpha)
        pairs = self.n_mu - 1  # per row of α
        e0 = dr.lerp(*_pair(self._E, j * pairs + i), tx)
        e1 = dr.lerp(*_pair(self._E, (j + 1) * pairs + i), tx)
        return dr.lerp(e0, e1, ty)

    def average(self, alpha=None):
        """E_avg at the table's uniform roughness, or else at ``alpha`` (as :meth:`__call__`)."""
        if self.row is not None:
            return self.row_average
        return self._average(alpha() if callable(alpha) else alpha)

    def _average(self, alpha):
        """E_avg(α), linear in sqrt(α/α_max)."""
        j, ty = _cell(dr.sqrt(dr.maximum(alpha, 0.0) / self.alpha_max), self.n_alpha)
        return dr.lerp(_gather(self._E_avg, j), _gather(self._E_avg, j + 1), ty)

    def _row(self, alpha):
        """E on the μ nodes at one roughness, as pairs, interpolated in α."""
        j, ty = _cell(dr.sqrt(dr.maximum(alpha, 0.0) / self.alpha_max), self.n_alpha)
        size = 2 * (self.n_mu - 1)  # a row of pairs
        if dr.is_jit_v(mi.Float):
            k = dr.arange(mi.UInt32, size)
            return dr.lerp(dr.gather(mi.Float, self._E, j * size + k),
                           dr.gather(mi.Float, self._E, (j + 1) * size + k), ty)
        start = int(j) * size
        return (1.0 - ty) * self._E[start:start + size] + \
            ty * self._E[start + size:start + 2 * size]


def uniform_alpha(alpha_u, alpha_v):
    """The tables' isotropic roughness of a surface whose roughness textures are the same
    everywhere (:func:`equivalent_alpha` of their values), else None."""
    from .microfacet import ALPHA_MIN

    if alpha_u.is_spatially_varying() or alpha_v.is_spatially_varying():
        return None
    au = dr.maximum(alpha_u.mean(), ALPHA_MIN)
    return au if alpha_v is alpha_u else dr.sqrt(au * dr.maximum(alpha_v.mean(), ALPHA_MIN))


def equivalent_alpha(distr):
    """The isotropic roughness of the albedo tables: α, or sqrt(αu·αv) when anisotropic (the
    roughness of the same D(0); its error is measured in the validation report)."""
    return dr.sqrt(distr.alpha_u * distr.alpha_v) if distr.anisotropic else distr.alpha_u


def lobe(e_i, e_o, e_avg):
    """(1 − E(μi))(1 − E(μo)) / (π (1 − E_avg)): f_ms without F_ms, and without the cosine."""
    missing = dr.maximum(1.0 - e_i, 0.0) * dr.maximum(1.0 - e_o, 0.0)
    return missing * dr.inv_pi / dr.maximum(1.0 - e_avg, 1e-7)


def multiple_fresnel(f_avg, e_avg):
    """F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)), per channel: 1 where F ≡ 1."""
    return dr.square(f_avg) * e_avg / dr.maximum(1.0 - f_avg * (1.0 - e_avg), _TINY)


def fresnel_average(eta, k, nodes: int = 5):
    r"""
    F_avg = 2∫₀¹ F(μ) μ dμ of :func:`mi_brdfs.scattering.fresnel.exact`, per channel, by a
    5-node Gauss-Legendre rule: within 7e-5 of 3000 nodes for conductors and dielectrics, which
    moves F_ms, and the compensated albedo, by about as much (8 nodes would give 2e-6, at 8
    Fresnel terms per channel and call instead of 5). Where k = 0 and η < 1, F = 1 below the
    critical cosine μc = sqrt(1 − η²) (total internal reflection), which gives μc² in closed
    form, and F falls like sqrt(μ − μc) above it: the rule runs there in t with
    μ = μc + (1 − μc) t³, which makes the integrand smooth. ``nodes`` > 5 where it is computed
    once per material (the dielectric's η is one number): 32 give 1e-7.
    """
    tir = (k == 0.0) & (eta < 1.0)
    mu_c2 = dr.select(tir, dr.maximum(1.0 - dr.square(eta), 0.0), 0.0)
    mu_c = dr.sqrt(mu_c2)
    total = mu_c2
    gl_x, gl_w = (_GL_X, _GL_W) if nodes == 5 else np.polynomial.legendre.leggauss(nodes)
    for x, w in zip(gl_x, gl_w):
        t = 0.5 * (float(x) + 1.0)
        mu = mu_c + (1.0 - mu_c) * dr.select(tir, t * t * t, t)
        jacobian = (1.0 - mu_c) * dr.select(tir, 3.0 * t * t, 1.0)
        total = total + float(w) * jacobian * mu * fresnel.exact(mu, eta, k)
    return total


def schlick_average(f0):
    """F_avg of Schlick's approximation in closed form: R0 + (1 − R0)/21 (2∫(1−μ)⁵μ dμ = 1/21)."""
    return f0 + (1.0 - f0) / 21.0


# -- the tables' nodes (mi-brdfs tables builds on them, the film's shift too) ---------------

#: The incidence cosine at which the node μ = 0 is computed (a lobe at μ = 0 exactly is
#: undefined: ωi lies in the surface); it stands for μ < 2.5e-4 (θ > 89.99°).
MU_GRAZING = 1e-4

def mu_nodes(n_mu: int) -> np.ndarray:
    """The incidence cosines of the nodes: x² on x uniform in [0, 1], the first MU_GRAZING."""
    mu = np.linspace(0.0, 1.0, n_mu) ** 2
    mu[0] = MU_GRAZING
    return mu


def alpha_nodes(n_alpha: int, alpha_max: float) -> np.ndarray:
    """The roughnesses of the nodes: α_max·y² on y uniform in [0, 1], the first (0) at the
    plugin's smallest α (:data:`~mi_brdfs.scattering.microfacet.ALPHA_MIN`)."""
    from .microfacet import ALPHA_MIN

    alpha = alpha_max * np.linspace(0.0, 1.0, n_alpha) ** 2
    alpha[0] = ALPHA_MIN
    return alpha


def average(E: np.ndarray) -> np.ndarray:
    """
    E_avg = 2∫E(μ)μ dμ = 4∫E(x)x³dx of rows of E that are piecewise linear in x = sqrt μ on
    uniform nodes (exact: a cubic per segment, 3 Gauss-Legendre nodes each).
    """
    E = np.atleast_2d(E)
    n = E.shape[1]
    x, w = np.polynomial.legendre.leggauss(3)
    t, w = (x + 1.0) / 2.0, w / 2.0  # on [0, 1]
    h = 1.0 / (n - 1)
    total = np.zeros(E.shape[0])
    for tk, wk in zip(t, w):
        xs = (np.arange(n - 1) + tk) * h
        values = E[:, :-1] * (1.0 - tk) + E[:, 1:] * tk
        total += 4.0 * h * wk * (values * xs ** 3).sum(axis=1)
    return total
