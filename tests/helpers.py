"""
Helpers shared by the tests: call a BSDF on many direction pairs in any variant (vectorised in
JIT variants, one call per pair in scalar ones) and get NumPy arrays back.
"""

import drjit as dr
import mitsuba as mi
import numpy as np

WAVELENGTHS = [450.0, 500.0, 550.0, 600.0]


def random_directions(rng, n, lower=True):
    """n unit vectors, uniform on the sphere (``lower``) or the upper hemisphere, as (n, 3)."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if not lower:
        v[:, 2] = np.abs(v[:, 2])
    return v


def jit():
    return dr.is_jit_v(mi.Float)


def _vec(a):
    a = np.atleast_2d(np.asarray(a, dtype=np.float32))
    return mi.Vector3f(mi.Float(a[:, 0]), mi.Float(a[:, 1]), mi.Float(a[:, 2]))


def make_si(wi, uv=(0.5, 0.5)):
    """SurfaceInteraction(s) with the shading frame = the local frame and ``si.wi`` = wi."""
    wi = np.atleast_2d(np.asarray(wi, dtype=np.float32))
    if jit():
        si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
        si.wi = _vec(wi)
        si.uv = mi.Point2f(uv[0], uv[1])
        if mi.is_spectral:
            si.wavelengths = dr.zeros(mi.Spectrum, len(wi)) + mi.Spectrum(WAVELENGTHS)
    else:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*map(float, wi[0]))
        si.uv = mi.Point2f(*uv)
        if mi.is_spectral:
            si.wavelengths = mi.Spectrum(WAVELENGTHS)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.n = mi.Vector3f(0, 0, 1)
    return si


def _cols(x):
    """A wide drjit vector/spectrum (channels × n) → array (n, channels)."""
    a = np.array(x, dtype=np.float64)
    return a[:, None] if a.ndim == 1 else a.T


def _rows(values):
    """List of per-call results (scalar) → array (n, ...)."""
    return np.array([np.ravel(np.array(v, dtype=np.float64)) for v in values])


def eval_pdf(bsdf, wi, wo, ctx=None):
    """(f·cos (n, channels), pdf (n,), eval_pdf value, eval_pdf pdf) for pairs (wi, wo)."""
    ctx = ctx or mi.BSDFContext()
    wi, wo = np.atleast_2d(wi), np.atleast_2d(wo)
    if jit():
        si = make_si(wi)
        w = _vec(wo)
        f, p = bsdf.eval(ctx, si, w), bsdf.pdf(ctx, si, w)
        f2, p2 = bsdf.eval_pdf(ctx, si, w)
        return _cols(f), np.array(p).ravel(), _cols(f2), np.array(p2).ravel()
    out = [], [], [], []
    for a, b in zip(wi, wo):
        si = make_si(a)
        w = mi.Vector3f(*map(float, b))
        f2, p2 = bsdf.eval_pdf(ctx, si, w)
        for lst, v in zip(out, (bsdf.eval(ctx, si, w), bsdf.pdf(ctx, si, w), f2, p2)):
            lst.append(v)
    return _rows(out[0]), _rows(out[1]).ravel(), _rows(out[2]), _rows(out[3]).ravel()


def sample(bsdf, wi, s1, s2, ctx=None):
    """dict(wo (n,3), pdf, weight (n,channels), type, component) for samples (s1, s2) at wi."""
    ctx = ctx or mi.BSDFContext()
    wi = np.atleast_2d(wi)
    s1, s2 = np.asarray(s1, dtype=np.float32), np.atleast_2d(np.asarray(s2, dtype=np.float32))
    if jit():
        si = make_si(wi)
        u = mi.Point2f(mi.Float(s2[:, 0]), mi.Float(s2[:, 1]))
        bs, w = bsdf.sample(ctx, si, mi.Float(s1), u)
        return dict(wo=_cols(bs.wo), pdf=np.array(bs.pdf).ravel(),
                    weight=_cols(w), type=np.array(bs.sampled_type).ravel(),
                    component=np.array(bs.sampled_component).ravel())
    res = dict(wo=[], pdf=[], weight=[], type=[], component=[])
    for a, u, v in zip(wi, s1, s2):
        bs, w = bsdf.sample(ctx, make_si(a), float(u), mi.Point2f(float(v[0]), float(v[1])))
        res["wo"].append(bs.wo)
        res["pdf"].append(bs.pdf)
        res["weight"].append(w)
        res["type"].append(bs.sampled_type)
        res["component"].append(bs.sampled_component)
    return {k: _rows(v) if k in ("wo", "weight") else _rows(v).ravel() for k, v in res.items()}
