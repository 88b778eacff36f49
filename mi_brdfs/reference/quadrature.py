"""
Float64 quadrature over the (hemi)sphere, shared by the reference models and the checks:
Gauss-Legendre in μ = cosθ (exact for polynomials of degree < 2n in μ) and the midpoint rule in
φ (exact for trigonometric polynomials of degree < n_φ, so spectrally accurate for the periodic
φ-dependence of a BRDF).
"""

from __future__ import annotations

import functools
import math

import numpy as np


def direction(theta: float, phi: float = 0.0) -> np.ndarray:
    """The unit vector at polar angle ``theta`` and azimuth ``phi`` (radians)."""
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                     math.cos(theta)])


@functools.lru_cache(maxsize=16)
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """
    Gauss-Legendre nodes and weights on [−1, 1], ascending, cached. Up to 100 nodes NumPy's
    (the eigenvalues of an n×n matrix, O(n³): seconds for thousands of nodes); beyond, Newton's
    iteration on P_n from Tricomi's initial guesses cos(π(k − 1/4)/(n + 1/2)), vectorised over
    the nodes (Press et al., "Numerical Recipes", 3rd ed., §4.6.1: gauleg), with the weights
    2/((1 − x²) P_n'(x)²).
    """
    if n <= 100:
        x, w = np.polynomial.legendre.leggauss(n)
    else:
        x = np.cos(np.pi * (np.arange(n, 0, -1) - 0.25) / (n + 0.5))
        for _ in range(100):
            p, dp = _legendre(n, x)
            step = p / dp
            x = x - step
            if np.max(np.abs(step)) < 1e-15:
                break
        dp = _legendre(n, x)[1]
        w = 2.0 / ((1.0 - x * x) * dp * dp)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def _legendre(n: int, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P_n(x), P_n'(x)) by the three-term recurrence."""
    p0, p1 = np.ones_like(x), x.copy()
    for k in range(2, n + 1):
        p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
    return p1, n * (x * p1 - p0) / (x * x - 1.0)


def sphere_grid(n_mu: int, n_phi: int, mu_range=(0.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """
    Nodes and weights for ∫ g(ω) dω over the part of the sphere with μ = cosθ in ``mu_range``.

    Returns → (directions (n_mu·n_phi, 3), weights (n_mu·n_phi,)), μ varying slowest.
    """
    x, w = gauss_legendre(n_mu)
    a, b = mu_range
    mu, w_mu = 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w
    phi = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
    M, P = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(np.maximum(1 - M * M, 0.0))
    v = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    weights = np.repeat(w_mu, n_phi) * (2 * math.pi / n_phi)
    return v, weights


def hemisphere_albedo(brdf, theta: float, n_mu: int = 512, n_phi: int = 512,
                      mu_range=(0.0, 1.0)) -> np.ndarray:
    """
    E(θ) = ∫ f(wi, wo) cosθo dωo over the upper hemisphere, for ``wi`` at polar angle ``theta``
    in the xz plane.

    Parameter ``brdf`` (callable): ``brdf(wi (n, 3), wo (n, 3))`` → f, shape (n, channels).
    """
    wo, weights = sphere_grid(n_mu, n_phi, mu_range)
    wi = np.broadcast_to(direction(theta), wo.shape)
    f = np.asarray(brdf(wi, wo), dtype=np.float64).reshape(len(wo), -1)
    return np.einsum("n,nc->c", weights * wo[:, 2], f)


def cosine_power_integral(n: float, cuts, ring, nodes: int = 400) -> float:
    """
    ∫ cosⁿβ g(ω) dω over the directions with cos β > 0, β the angle to some axis and φ the
    angle about it: with u = cos^(n+1)β, cosⁿβ dω = du dφ/(n+1), so the integral is
    1/(n+1) ∫₀¹ (∫ g dφ) du at any n. Gauss-Legendre in u, split at ``cuts`` (the values of u
    in (0, 1) where the ring integral has a kink, e.g. where rings start crossing the
    horizon), with u = lo + (hi − lo)·x²(3 − 2x) on each piece: du/dx vanishes at both ends,
    which smooths the kinks and the u^(1/(n+1)) behaviour at u = 0.

    Parameter ``ring`` (callable): ``ring(cos β, sin β)`` (arrays) → ∫ g dφ over each ring.
    """
    x, w = gauss_legendre(nodes)
    x, w = 0.5 * (x + 1), 0.5 * w
    s, ds = x * x * (3 - 2 * x), 6 * x * (1 - x)
    n1 = n + 1.0
    total = 0.0
    for lo, hi in zip([0.0] + list(cuts), list(cuts) + [1.0]):
        if hi <= lo:
            continue
        t = np.log(lo + (hi - lo) * s) / n1  # cos β = e^t, sin²β = −expm1(2t): exact for n = 1e12
        total += (hi - lo) * np.dot(w * ds, ring(np.exp(t), np.sqrt(-np.expm1(2 * t))))
    return total / n1
