"""
A mixture of sampling strategies, one per lobe (Veach 1997, "Robust Monte Carlo Methods for
Light Transport Simulation", §9.2.4, the one-sample model): strategy k is picked with
probability pₖ, its sampler draws ωo, and the density of ωo is the mixture Σₖ pₖ·pdfₖ of every
strategy's density; the sample weight is then f·cosθo over that mixture density.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi


def probabilities(weights):
    """wₖ/Σw for each strategy from their weights (e.g. albedos); equal where every weight is
    0."""
    total = weights[0]
    for w in weights[1:]:
        total = total + w
    ok = total > 0
    inv = dr.select(ok, 1.0 / dr.select(ok, total, 1.0), 0.0)
    return [dr.select(ok, w * inv, 1.0 / len(weights)) for w in weights]


def choose(probs, u):
    """
    (k, u'): the index k of the strategy that ``u`` ∈ [0, 1) picks, Σ_{j<k} pⱼ ≤ u <
    Σ_{j≤k} pⱼ (a strategy of probability 0 is never picked), and u rescaled to [0, 1) within
    that interval, so that the chosen strategy can use it too. k is a Python int in scalar
    variants, a UInt32 in JIT ones.
    """
    index, below, p_k, acc = mi.UInt32(0), 0.0, probs[0], 0.0
    for j, p in enumerate(probs[:-1]):
        acc = acc + p
        past = u >= acc
        index = dr.select(past, mi.UInt32(j + 1), index)
        below = dr.select(past, acc, below)
        p_k = dr.select(past, probs[j + 1], p_k)
    return index, (u - below) / dr.maximum(p_k, 1e-30)


def pdf(probs, pdfs):
    """Σₖ pₖ·pdfₖ: the density of the one-sample mixture."""
    total = probs[0] * pdfs[0]
    for p, density in zip(probs[1:], pdfs[1:]):
        total = total + p * density
    return total
