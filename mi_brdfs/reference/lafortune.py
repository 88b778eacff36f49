r"""
Lafortune's generalized cosine lobes in float64, as the paper writes them (Lafortune, Foo,
Torrance & Greenberg 1997, "Non-Linear Approximation of Reflectance Functions"):

    f(u, v) = ρd/π + Σᵢ ρs,i·Kᵢ·max(0, gᵢ(u, v)/cᵢ)ⁿⁱ,   gᵢ = Cx,i ux vx + Cy,i uy vy + Cz,i uz vz,

with cᵢ = max(|Cx,i|, |Cy,i|, |Cz,i|) and Kᵢ = (nᵢ+2)/(2π) (``normalize``, the modified Phong
normalisation of Lafortune & Willems 1994) or Kᵢ = cᵢⁿⁱ (the paper's own form, f = ρs·gⁿ), both
directions above the surface, 0 where g ≤ 0. Independent of :mod:`mi_brdfs.scattering.lafortune`:
g from the dot products as written, powers with ``**``.

Albedo. For fixed u, g(u, v) = (C∘u)·v: the lobe is cosⁿ of the angle β to the axis
a = (C∘u)/|C∘u|, times (|C∘u|/c)ⁿ. E(θ) is then integrated in the lobe's own coordinates, as
:mod:`mi_brdfs.reference.phong` does for Phong's mirror lobe but for an axis anywhere on the
sphere (below the horizon too): rings of constant β with u = cos^(n+1)β as the variable, the
φ-integral of max(0, cosθo) over each ring exact (an arc), Gauss-Legendre in u split where rings
start crossing the horizon. Checked against brute-force quadrature of :meth:`Lafortune.brdf` in
``tests/scattering/test_lafortune_lobes.py``.
"""

from __future__ import annotations

import math
import re

import numpy as np

from .quadrature import cosine_power_integral, direction

#: Lobe properties and their defaults: Phong's mirror lobe, as the ``phong`` plugin's defaults.
LOBE_DEFAULTS = {"cx": -1.0, "cy": -1.0, "cz": 1.0, "exponent": 30.0,
                 "specular_reflectance": 0.2}
_INDEXED = re.compile(r"^(cx|cy|cz|exponent|specular_reflectance)_(\d+)$")

#: Gauss-Legendre nodes per piece of the u-integral (as the Phong reference).
NODES = 400


def _unit(v) -> np.ndarray:
    v = np.atleast_2d(np.asarray(v, dtype=np.float64))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


class Lafortune:
    """
    f = ρd/π + Σ lobes. ``lobes``: a list of dict(cx, cy, cz, exponent, specular_reflectance)
    (missing keys take :data:`LOBE_DEFAULTS`); reflectances per channel.
    """

    def __init__(self, lobes=({},), diffuse=0.5, normalize=True):
        self.rho_d = np.atleast_1d(np.asarray(diffuse, dtype=np.float64))
        self.normalize = bool(normalize)
        self.lobes = []
        for lobe in lobes:
            p = dict(LOBE_DEFAULTS, **lobe)
            C = np.array([p["cx"], p["cy"], p["cz"]], dtype=np.float64)
            rho = np.atleast_1d(np.asarray(p["specular_reflectance"], dtype=np.float64))
            self.lobes.append((C, float(p["exponent"]), rho))

    @classmethod
    def from_spec(cls, spec: dict, color):
        """The reference of a ``lafortune`` dict (``color`` reads a reflectance, as
        :func:`mi_brdfs.reference.color`), or None where it cannot know a value."""
        indices = {int(m.group(2)) for m in map(_INDEXED.match, spec) if m}
        lobes = []
        for i in range(max(indices) + 1 if indices else 1):
            lobe = {k: spec[f"{k}_{i}"] for k in LOBE_DEFAULTS if f"{k}_{i}" in spec}
            lobe["specular_reflectance"] = color(lobe.get("specular_reflectance"), 0.2)
            numbers = [lobe.get(k, 0.0) for k in ("cx", "cy", "cz", "exponent")]
            if lobe["specular_reflectance"] is None or \
                    not all(isinstance(x, (int, float)) for x in numbers):
                return None
            lobes.append(lobe)
        rho_d = color(spec.get("diffuse_reflectance"), 0.5)
        return None if rho_d is None else cls(lobes, rho_d, spec.get("normalize", True))

    def magnitude(self, C, n) -> float:
        """K: (n+2)/(2π), or cⁿ in the paper's form."""
        c = float(np.max(np.abs(C)))
        return (n + 2) / (2 * math.pi) if self.normalize else (c ** n if c > 0 else 0.0)

    def lobe(self, i, wi, wo) -> np.ndarray:
        """K·max(0, g/c)ⁿ of lobe ``i`` for ρs = 1, (n,); 0 where g ≤ 0 (also for n = 0)."""
        C, n, _ = self.lobes[i]
        u, v = _unit(wi), _unit(wo)
        g = C[0] * u[:, 0] * v[:, 0] + C[1] * u[:, 1] * v[:, 1] + C[2] * u[:, 2] * v[:, 2]
        c = float(np.max(np.abs(C)))
        if c == 0:
            return np.zeros(len(u))
        ratio = np.clip(g / c, 0.0, 1.0)  # ≤ 1 up to rounding, which large n would amplify
        return np.where(g > 0, ratio ** n, 0.0) * self.magnitude(C, n)

    def brdf(self, wi, wo) -> np.ndarray:
        """f(wi, wo), (n, channels); 0 unless both directions are above the surface."""
        wi, wo = _unit(wi), _unit(wo)
        f = self.rho_d[None, :] / math.pi
        for i, (_, _, rho) in enumerate(self.lobes):
            f = f + rho[None, :] * self.lobe(i, wi, wo)[:, None]
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(above[:, None], f, 0.0)

    # -- sampling density -------------------------------------------------------------------------

    def _axis(self, i, wi):
        """(unit axis a = C∘u/|C∘u| (the normal where C∘u = 0), r = |C∘u|/c), per row."""
        C, _, _ = self.lobes[i]
        cu = C[None, :] * _unit(wi)
        s = np.linalg.norm(cu, axis=1)
        c = float(np.max(np.abs(C)))
        a = np.where(s[:, None] > 0, cu / np.where(s > 0, s, 1.0)[:, None], [0.0, 0.0, 1.0])
        return a, (s / c if c > 0 else np.zeros_like(s))

    def weights(self, wi) -> list[np.ndarray]:
        """The mixture's weights, (n,) each: mean(ρd) for the diffuse term (if ρd ≠ 0), and
        mean(ρs)·K·rⁿ·2π/(n+2) for each lobe with ρs ≠ 0 (the plugin leaves zero lobes out)."""
        out = [np.full(len(np.atleast_2d(wi)), np.mean(self.rho_d))] if np.any(self.rho_d) \
            else []
        for i, (C, n, rho) in enumerate(self.lobes):
            if np.any(rho):
                r = self._axis(i, wi)[1]
                out.append(np.mean(rho) * self.magnitude(C, n) * np.where(r > 0, r ** n, 0.0)
                           * 2 * math.pi / (n + 2))
        return out

    def sampling_pdf(self, wi, wo) -> np.ndarray:
        """The density of the plugin's sampler: Σ pₖ·pdfₖ, pₖ = wₖ/Σw (equal where Σw = 0),
        pdf = cosθo/π (diffuse) or (n+1)/(2π)·max(0, a·ωo)ⁿ (lobe); 0 below the surface."""
        wi, wo = _unit(wi), _unit(wo)
        weights = self.weights(wi)
        total = np.sum(weights, axis=0)
        pdfs = [wo[:, 2] / math.pi] if np.any(self.rho_d) else []
        for i, (_, n, rho) in enumerate(self.lobes):
            if np.any(rho):
                cos = np.sum(self._axis(i, wi)[0] * wo, axis=1)
                pdfs.append((n + 1) / (2 * math.pi) * np.where(cos > 0, np.maximum(cos, 0) ** n,
                                                               0.0))
        probs = [np.where(total > 0, w / np.where(total > 0, total, 1), 1 / len(weights))
                 for w in weights]
        pdf = np.sum([p * q for p, q in zip(probs, pdfs)], axis=0)
        return np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), pdf, 0.0)

    # -- albedo -----------------------------------------------------------------------------------

    def lobe_albedo(self, i, theta: float, phi: float = 0.0) -> float:
        """E(θ, φ) = ∫ f cosθo dωo of lobe ``i`` with ρs = 1."""
        wi = direction(theta, phi)
        if wi[2] <= 0:
            return 0.0
        C, n, _ = self.lobes[i]
        a, r = self._axis(i, wi)
        if r[0] <= 0:
            return 0.0
        theta_a = math.acos(float(np.clip(a[0, 2], -1.0, 1.0)))
        return self.magnitude(C, n) * float(r[0]) ** n * cosine_lobe_integral(theta_a, n)

    def albedo(self, theta: float, phi: float = 0.0) -> np.ndarray:
        """E(θ) per channel: ρd + Σ ρs,i·E_i(θ) above the surface, 0 below."""
        if math.cos(theta) <= 0:
            return np.zeros(np.broadcast_shapes(self.rho_d.shape,
                                                *(rho.shape for _, _, rho in self.lobes)))
        total = self.rho_d
        for i, (_, _, rho) in enumerate(self.lobes):
            total = total + rho * self.lobe_albedo(i, theta, phi)
        return total


def cosine_lobe_integral(theta_axis: float, n: float) -> float:
    """
    ∫ max(0, cos β)ⁿ max(0, cosθo) dωo over the sphere, β the angle to an axis at polar angle
    ``theta_axis`` ∈ [0, π]: 2π/(n+2) for the normal, less for any other axis.
    """
    ca, sa = math.cos(theta_axis), math.sin(theta_axis)

    def ring(cos_b, sin_b):
        # on the ring at angle β: cosθo = a + b cos φ, positive for |φ| < φ0
        a, b = cos_b * ca, sin_b * sa
        ratio = np.where(b > 0, -a / np.where(b > 0, b, 1.0), np.where(a > 0, -np.inf, np.inf))
        phi0 = np.arccos(np.clip(ratio, -1.0, 1.0))
        return 2 * (a * phi0 + b * np.sin(phi0))

    # rings cross the horizon for β > |π/2 − θa|: the kink, in u = cos^(n+1)β
    kink = abs(math.pi / 2 - theta_axis)
    cuts = [min(math.cos(kink) ** (n + 1.0), 1.0)] if 0 < kink < math.pi / 2 else []
    return cosine_power_integral(n, cuts, ring, NODES)
