"""
A mixture of two sampling strategies, one per lobe (Veach 1997, "Robust Monte Carlo Methods for
Light Transport Simulation", §9.2.4, the one-sample model): a lobe is picked with probability
p₁ (else the other), its sampler draws ωo, and the density of ωo is the mixture of both lobes'
densities; the sample weight is then f·cosθo over that mixture density.
"""

from __future__ import annotations

import drjit as dr


def probability(w1, w2, default=0.5):
    """p₁ = w₁/(w₁ + w₂) from the lobes' weights (e.g. albedos); ``default`` where both are 0."""
    total = w1 + w2
    ok = total > 0
    return dr.select(ok, w1 / dr.select(ok, total, 1.0), default)


def pdf(p1, pdf1, pdf2):
    """The mixture density p₁·pdf₁ + (1 − p₁)·pdf₂."""
    return p1 * pdf1 + (1.0 - p1) * pdf2


def rescale(u, p1):
    """A uniform number in [0, 1) that chose lobe 1 (u < p₁), rescaled to [0, 1) again so that
    the chosen lobe's sampler can use it too (u/p₁)."""
    return u / dr.maximum(p1, 1e-30)
