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


def eval_gradient(bsdf, key, value, step, wi, wo):
    """(d/dp by AD, central difference over ±``step``) of Σ eval over the pairs (wi, wo), where
    p is the parameter ``key`` of ``mi.traverse(bsdf)``, at ``value`` (an AD variant)."""
    import drjit as dr
    import mitsuba as mi

    from mi_brdfs.checks.batch import interaction, vectors

    params = mi.traverse(bsdf)
    si, w = interaction(wi, len(wi)), vectors(wo)

    def total(p, grad=False):
        params[key] = mi.Float(p)
        if grad:
            dr.enable_grad(params[key])
        params.update()
        return dr.sum(bsdf.eval(mi.BSDFContext(), si, w)[0])

    dr.backward(total(value, grad=True))
    grad = float(np.array(dr.grad(params[key]))[0])
    finite = (float(total(value + step)[0]) - float(total(value - step)[0])) / (2 * step)
    return grad, finite


def cli_one_line_error(args, message):
    """Run ``mi-brdfs args`` in-process: exit status 2 and one line ``mi-brdfs: error: ...``
    containing ``message``, no traceback; returns that line."""
    import sys
    from io import StringIO

    from mi_brdfs.cli import main

    err, saved = StringIO(), sys.stderr
    sys.stderr = err
    try:
        code = main(args)
    except SystemExit as e:  # argparse
        code = e.code
    finally:
        sys.stderr = saved
    text = err.getvalue()
    lines = [ln for ln in text.strip().splitlines() if ln]
    assert code == 2, (code, text)
    assert len(lines) == 1 and lines[0].startswith("mi-brdfs: error: "), text
    assert message in lines[0] and "Traceback" not in text, lines[0]
    return lines[0]
