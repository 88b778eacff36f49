"""Helpers shared by the tests: the library's batch layer, under the names the tests use."""

import numpy as np

from mi_brdfs.checks._batch import evaluate, random_directions as _random_directions
from mi_brdfs.checks._batch import sample as _sample


def random_directions(rng, n, lower=True):
    """n unit vectors, uniform on the sphere (``lower``) or the upper hemisphere, as (n, 3)."""
    return _random_directions(rng, n, sphere=lower)


def eval_pdf(bsdf, wi, wo, ctx=None):
    """(f·cos (n, channels), pdf (n,), eval_pdf value, eval_pdf pdf) for pairs (wi, wo)."""
    e = evaluate(bsdf, wi, wo, ctx)
    return e.value, e.pdf, e.eval_pdf_value, e.eval_pdf_pdf


def sample(bsdf, wi, s1, s2, ctx=None):
    """dict(wo (n,3), pdf, weight (n,channels), type, component) for samples (s1, s2) at wi."""
    s = _sample(bsdf, np.atleast_2d(wi), s1, s2, ctx)
    return dict(wo=s.wo, pdf=s.pdf, weight=s.weight, type=s.sampled_type,
                component=s.sampled_component)
