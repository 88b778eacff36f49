"""
Checks of microfacet terms on their own, before they become a BSDF:

* **NDF normalisation**: ∫ D(m) cosθm dωm = 1 over the hemisphere (the projected microfacet
  area equals the macro-surface area);
* **weak white furnace** (Heitz 2014, §3.5): ∫ G1(ωo, ωh) D(ωh) / (4 |cosθo|) dωi = 1 with
  ωh = normalize(ωo + ωi), over the *whole* sphere of ωi, below the horizon included. It holds
  exactly when D and G1 are consistent (the visible normals of ωo are normalised), for any
  physically based masking function, Smith and V-cavity alike.

Terms are given as callables on NumPy arrays of unit vectors, shape (n, 3): ``D(m)`` → (n,) and
``G1(v, m)`` → (n,). :func:`mitsuba_terms` wraps ``mi.MicrofacetDistribution`` and
:func:`package_terms` the package's own :mod:`mi_brdfs.scattering.microfacet` (JIT variants); the
float64 terms of :mod:`mi_brdfs.reference.cooktorrance` are such callables already.
Integrals use Gauss-Legendre in cosθ and the midpoint rule in φ, with more nodes for sharper
lobes (about 60/α per dimension). Every ``alpha`` may be a pair (αu, αv) for an anisotropic
distribution (its smaller value sets the nodes).
"""

from __future__ import annotations

import math

import numpy as np

from ..reference.quadrature import direction, sphere_grid
from .result import CheckResult

#: Tolerance of both integrals (the quadrature error is below 1e-5).
TOL = 1e-3


def _nodes(alpha) -> int:
    return int(np.clip(60.0 / max(float(np.min(alpha)), 1e-3), 256, 2048))


def ndf_normalization(D, alpha) -> float:
    """∫ D(m) cosθm dωm over the upper hemisphere (1 for a normalised NDF)."""
    m, w = sphere_grid(_nodes(alpha), 256, (0.0, 1.0))
    return float(np.sum(w * np.asarray(D(m), dtype=np.float64) * m[:, 2]))


def weak_white_furnace(D, G1, wo: np.ndarray, alpha) -> float:
    """
    Heitz's weak white furnace integral for one ``wo`` (upper hemisphere).

    The integral over the whole sphere of ωi is computed after the change of variables
    ωi = reflect(ωo, ωh), dωi = 4 |ωo·ωh| dωh, a bijection between the sphere of ωi and the
    hemisphere ωo·ωh > 0: ∫ G1(ωo, ωh) D(ωh) |ωo·ωh| / |cosθo| dωh. The integrand is then
    smooth, where in ωi it swings across all of D near ωi = −ωo, which a tensor grid in ωi does
    not resolve (errors of 1e-3 at α = 1). :func:`weak_white_furnace_wi` integrates in ωi.
    """
    wo = np.asarray(wo, dtype=np.float64)
    # near the pole D hardly depends on φ, and G1, ωo·ωh vary slowly with it: 256 suffice
    h, w = sphere_grid(_nodes(alpha), 256, (0.0, 1.0))  # D = 0 below the horizon
    cos_oh = h @ wo
    ok = cos_oh > 0
    value = np.where(ok, np.asarray(G1(np.broadcast_to(wo, h.shape), h), dtype=np.float64)
                     * np.asarray(D(h), dtype=np.float64) * cos_oh, 0.0) / abs(wo[2])
    return float(np.sum(w * value))


def weak_white_furnace_wi(D, G1, wo: np.ndarray, alpha) -> float:
    """The same integral as Heitz writes it, on a tensor grid over the sphere of ωi."""
    n = _nodes(alpha)
    wo = np.asarray(wo, dtype=np.float64)
    total = 0.0
    for mu_range in ((-1.0, 0.0), (0.0, 1.0)):
        wi, w = sphere_grid(n, n, mu_range)
        h = wi + wo[None, :]
        length = np.linalg.norm(h, axis=1)
        ok = length > 1e-9
        h = h / np.where(ok, length, 1.0)[:, None]
        value = np.where(ok, np.asarray(G1(np.broadcast_to(wo, h.shape), h), dtype=np.float64)
                         * np.asarray(D(h), dtype=np.float64), 0.0) / (4 * abs(wo[2]))
        total += float(np.sum(w * value))
    return total


def _jit_terms(D, G1):
    """NumPy callables (n, 3) → (n,) of DrJit terms ``D(m)``, ``G1(v, m)`` (JIT variants)."""
    import drjit as dr
    import mitsuba as mi

    if not dr.is_jit_v(mi.Float):
        raise RuntimeError("microfacet terms are evaluated on arrays: this needs a JIT variant")

    from .batch import vectors as vec

    return (lambda m: np.array(D(vec(m)), dtype=np.float64),
            lambda v, m: np.array(G1(vec(v), vec(m)), dtype=np.float64))


def mitsuba_terms(kind: str, alpha):
    """
    ``(D, G1)`` from ``mi.MicrofacetDistribution`` (``kind`` 'beckmann' or 'ggx'), evaluated in
    the current JIT variant: D = ``eval(m)``, G1 = ``smith_g1(v, m)``.
    """
    from ..scattering.microfacet import Distribution

    alphas = (alpha,) if np.ndim(alpha) == 0 else tuple(alpha)
    distr = Distribution(kind, *alphas).mitsuba()
    return _jit_terms(distr.eval, distr.smith_g1)


#: The masking functions of :mod:`mi_brdfs.scattering.microfacet`, by name.
MASKING = ("smith", "smith_mitsuba", "vcavity")


def package_terms(kind: str, alpha, masking: str = "smith"):
    """
    ``(D, G1)`` from the package's own terms (:mod:`mi_brdfs.scattering.microfacet`), evaluated
    in the current JIT variant: ``masking`` 'smith' (exact), 'smith_mitsuba' (Mitsuba's
    rational Beckmann approximation) or 'vcavity'.
    """
    import mitsuba as mi

    from ..scattering import microfacet as mf

    if masking not in MASKING:
        raise ValueError(f"masking must be one of {', '.join(MASKING)}, not {masking!r}")
    alphas = (alpha,) if np.ndim(alpha) == 0 else tuple(alpha)
    distr = mf.Distribution(kind, *(mi.Float(max(a, mf.ALPHA_MIN)) for a in alphas))
    g1 = {"smith": distr.smith_g1, "smith_mitsuba": distr.smith_g1_mitsuba,
          "vcavity": mf.vcavity_g1}[masking]
    return _jit_terms(distr.ndf, g1)


def check_ndf(D, alpha, label: str, tol: float = TOL) -> CheckResult:
    value = ndf_normalization(D, alpha)
    passed = abs(value - 1) <= tol
    msg = (f"NDF: {label}: ∫ D cosθm dω = {value:.6f} "
           f"({'within' if passed else 'outside'} 1 ± {tol:g})")
    return CheckResult("ndf", passed, value, tol, msg)


def check_weak_furnace(D, G1, alpha, label: str, thetas_deg=(0.0, 45.0, 70.0, 84.26),
                       tol: float = TOL, phi_deg: float = 0.0) -> CheckResult:
    """The weak white furnace at each θo of ``thetas_deg``, in the azimuth ``phi_deg`` (which
    matters for an anisotropic α)."""
    phi = math.radians(phi_deg)
    values = [weak_white_furnace(D, G1, direction(math.radians(t), phi), alpha)
              for t in thetas_deg]
    dev = [abs(v - 1) for v in values]
    i = int(np.argmax(dev))
    passed = dev[i] <= tol
    msg = (f"weak furnace: {label}: ∫ G1 D / (4|cosθo|) dωi = {values[i]:.6f} at θo = "
           f"{thetas_deg[i]:g}° (worst of {len(values)}; {'within' if passed else 'outside'} "
           f"1 ± {tol:g})")
    return CheckResult("weak_furnace", passed, values[i], tol, msg,
                       details={"theta_deg": list(thetas_deg), "values": values})

