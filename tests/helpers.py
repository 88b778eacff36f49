"""Helpers shared by the tests: the library's batch layer, under the names the tests use."""

import math

import numpy as np

from mi_brdfs.checks.batch import evaluate
from mi_brdfs.checks.batch import random_directions as _random_directions
from mi_brdfs.checks.batch import sample as _sample


def random_directions(rng, n, lower=True):
    """n unit vectors, uniform on the sphere (``lower``) or the upper hemisphere, as (n, 3)."""
    return _random_directions(rng, n, sphere=lower)


def eval_pdf(bsdf, wi, wo, ctx=None, uv=None):
    """(f·cos (n, channels), pdf (n,), eval_pdf value, eval_pdf pdf) for pairs (wi, wo), at
    texture coordinates ``uv`` (one or (n, 2))."""
    e = evaluate(bsdf, wi, wo, ctx, uv)
    return e.value, e.pdf, e.eval_pdf_value, e.eval_pdf_pdf


def sample(bsdf, wi, s1, s2, ctx=None):
    """dict(wo (n,3), pdf, weight (n,channels), type, component) for samples (s1, s2) at wi."""
    s = _sample(bsdf, np.atleast_2d(wi), s1, s2, ctx)
    return dict(wo=s.wo, pdf=s.pdf, weight=s.weight, type=s.sampled_type,
                component=s.sampled_component)


def closed_form(form, lobe, n):
    """E(0) of the specular lobe with ks = 1 (Lafortune & Willems 1994; Giesen 2009 for the
    halfway lobe)."""
    if form == "normalized":
        return 1.0
    if lobe == "mirror":
        return 2 * math.pi / (n + 2) if form == "lecture" else 2 * math.pi / (n + 1)
    if form == "lecture":
        return 8 * math.pi * (n + 2 ** (-n / 2)) / ((n + 2) * (n + 4))
    return 8 * math.pi * (1 - 2 ** (-(n + 2) / 2)) / (n + 2)
