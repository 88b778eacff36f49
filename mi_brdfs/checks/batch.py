"""
Calling a BSDF on many directions, in any variant, with NumPy arrays in and out: the layer the
checks, the plots, the campaign and the benchmark share (public API: :func:`evaluate`,
:func:`eval_and_pdf`, :func:`sample`, :func:`interaction`, :func:`random_directions`, :func:`direction`,
:func:`is_jit`).

JIT variants take all directions in one vectorised call; scalar variants call the BSDF once per
direction (keep ``n`` small there). Spectral variants get the fixed :data:`WAVELENGTHS`. Every
array that comes back has one row per direction: values ``(n, channels)``, pdfs ``(n,)``,
directions ``(n, 3)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..arrays import floats  # noqa: F401  (re-exported: the checks' NumPy → mi.Float)
from ..bsdfspec import load_bsdf
from ..reference.quadrature import direction  # noqa: F401  (re-exported for the checks)

#: Wavelengths (nm) given to spectral variants, where a BSDF may depend on them.
WAVELENGTHS = (450.0, 500.0, 550.0, 600.0)


def is_jit() -> bool:
    """Whether the current variant is a JIT one (llvm_*, cuda_*)."""
    return bool(dr.is_jit_v(mi.Float))


def random_directions(rng: np.random.Generator, n: int, sphere: bool = True) -> np.ndarray:
    """``n`` unit vectors, uniform on the sphere (or the upper hemisphere), as (n, 3) float64."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if not sphere:
        v[:, 2] = np.abs(v[:, 2])
    return v




def _rows(a, n: int) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    return np.broadcast_to(a, (n, 3)) if a.ndim == 1 else a


def vectors(a: np.ndarray):
    """(n, 3) directions as one ``mi.Vector3f`` of n lanes (JIT variants)."""
    a = np.asarray(a, dtype=np.float32)
    return mi.Vector3f(floats(a[:, 0]), floats(a[:, 1]), floats(a[:, 2]))


def interaction(wi, n: int | None = None, uv=(0.5, 0.5)):
    """
    Surface interaction(s) whose shading frame is the local frame, with ``si.wi`` = ``wi``.

    JIT: ``n`` lanes from ``wi`` of shape (n, 3), or one direction (3,) repeated ``n`` times,
    and ``uv`` one point or (n, 2). Scalar: ``wi`` and ``uv`` must be one each.
    """
    si = dr.zeros(mi.SurfaceInteraction3f, n or 1) if is_jit() else mi.SurfaceInteraction3f()
    if is_jit():
        si.wi = vectors(_rows(wi, n or len(wi)))
    else:
        si.wi = mi.Vector3f(*[float(x) for x in np.ravel(wi)[:3]])
    uv = np.asarray(uv, dtype=np.float32)
    si.uv = mi.Point2f(*(floats(c) if is_jit() else float(c) for c in uv.T))
    # the geometry of a flat surface at the origin, parametrised by uv along x and y: wrappers
    # that perturb the frame (bumpmap, normalmap) need the tangents, and a zero dp_du
    # degenerates their frame into NaN or zero vectors
    si.p = mi.Point3f(0, 0, 0)
    si.t = 1.0
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    si.dp_du, si.dp_dv = mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0)
    si.dn_du = si.dn_dv = mi.Vector3f(0, 0, 0)
    if mi.is_spectral:  # (UnpolarizedSpectrum: in polarized variants Spectrum is a Mueller matrix)
        si.wavelengths = mi.UnpolarizedSpectrum(WAVELENGTHS) if not is_jit() else \
            dr.zeros(mi.UnpolarizedSpectrum, n or 1) + mi.UnpolarizedSpectrum(WAVELENGTHS)
    return si


def _channels(x, spectrum: bool = True) -> np.ndarray:
    """A drjit spectrum or vector (channels × n in JIT, channels in scalar) → (n, channels)."""
    if spectrum:
        x = mi.unpolarized_spectrum(x)  # the identity outside polarized variants
    a = np.array(x, dtype=np.float64)
    if not is_jit():
        return a.reshape(1, -1)
    return a[:, None] if a.ndim == 1 else a.T


def _lanes(x, n: int, dtype=np.float64) -> np.ndarray:
    """Per-lane values, broadcast to ``n`` rows: a BSDF may return a width-1 constant."""
    a = np.asarray(x, dtype=dtype)
    if a.ndim <= 1:
        a = a.ravel()
        return np.broadcast_to(a, (n,)).copy() if a.size == 1 else a
    return np.broadcast_to(a, (n, a.shape[1])).copy() if a.shape[0] == 1 else a


@dataclass
class Evaluation:
    """``eval`` (f·cosθo), ``pdf``, and ``eval_pdf``'s two values, one row per direction pair."""

    value: np.ndarray
    pdf: np.ndarray
    eval_pdf_value: np.ndarray
    eval_pdf_pdf: np.ndarray


@dataclass
class Samples:
    """What ``sample()`` returned, one row per sample."""

    wo: np.ndarray
    pdf: np.ndarray
    weight: np.ndarray
    sampled_type: np.ndarray
    sampled_component: np.ndarray


def evaluate(bsdf, wi, wo, ctx=None, uv=None) -> Evaluation:
    """``eval``, ``pdf`` and ``eval_pdf`` at the pairs (wi, wo); wi may be one direction, ``uv``
    (the texture coordinates, for textured parameters) one point or one per pair (default
    (0.5, 0.5)). The BSDF in any form of :mod:`mi_brdfs.bsdfspec`."""
    bsdf, ctx = load_bsdf(bsdf), ctx or mi.BSDFContext()
    wo = np.atleast_2d(np.asarray(wo, dtype=np.float64))
    n = len(wo)
    if is_jit():
        si, w = interaction(wi, n, (0.5, 0.5) if uv is None else uv), vectors(wo)
        value, pdf = bsdf.eval(ctx, si, w), bsdf.pdf(ctx, si, w)
        value2, pdf2 = bsdf.eval_pdf(ctx, si, w)
        return Evaluation(_lanes(_channels(value), n), _lanes(pdf, n),
                          _lanes(_channels(value2), n), _lanes(pdf2, n))
    wi = _rows(wi, n)
    uvs = np.broadcast_to((0.5, 0.5) if uv is None else uv, (n, 2))
    rows = []
    for a, b, c in zip(wi, wo, uvs):
        si, w = interaction(a, uv=c), mi.Vector3f(*map(float, b))
        value2, pdf2 = bsdf.eval_pdf(ctx, si, w)
        rows.append((_channels(bsdf.eval(ctx, si, w))[0], float(bsdf.pdf(ctx, si, w)),
                     _channels(value2)[0], float(pdf2)))
    value, pdf, value2, pdf2 = zip(*rows)
    return Evaluation(np.array(value), np.array(pdf), np.array(value2), np.array(pdf2))


def eval_and_pdf(bsdf, wi, wo, ctx=None) -> tuple[np.ndarray, np.ndarray]:
    """(``eval`` (n, channels), ``pdf`` (n,)) at the pairs (wi, wo): the two alone, traced
    together and evaluated in one launch in JIT variants (:func:`evaluate` also calls
    ``eval_pdf``, and launches each: three times the work where those two are all a caller
    needs, as the explorer's views)."""
    if not is_jit():
        e = evaluate(bsdf, wi, wo, ctx)
        return e.value, e.pdf
    bsdf, ctx = load_bsdf(bsdf), ctx or mi.BSDFContext()
    wo = np.atleast_2d(np.asarray(wo, dtype=np.float64))
    n = len(wo)
    si, w = interaction(wi, n), vectors(wo)
    value, pdf = bsdf.eval(ctx, si, w), bsdf.pdf(ctx, si, w)
    dr.eval(value, pdf)
    return _lanes(_channels(value), n), _lanes(pdf, n)


def sample(bsdf, wi, sample1, sample2, ctx=None) -> Samples:
    """``sample()`` with the given random numbers: ``sample1`` (n,), ``sample2`` (n, 2). The BSDF
    in any form of :mod:`mi_brdfs.bsdfspec`."""
    bsdf, ctx = load_bsdf(bsdf), ctx or mi.BSDFContext()
    sample1 = np.asarray(sample1, dtype=np.float32)
    sample2 = np.atleast_2d(np.asarray(sample2, dtype=np.float32))
    n = len(sample1)
    if is_jit():
        si = interaction(wi, n)
        u = mi.Point2f(floats(sample2[:, 0]), floats(sample2[:, 1]))
        bs, weight = bsdf.sample(ctx, si, floats(sample1), u)
        return Samples(_lanes(_channels(bs.wo, False), n), _lanes(bs.pdf, n),
                       _lanes(_channels(weight), n), _lanes(bs.sampled_type, n, np.int64),
                       _lanes(bs.sampled_component, n, np.int64))
    wi = _rows(wi, n)
    rows = []
    for a, u1, u2 in zip(wi, sample1, sample2):
        bs, weight = bsdf.sample(ctx, interaction(a), float(u1), mi.Point2f(*map(float, u2)))
        rows.append((np.array(bs.wo, dtype=np.float64), float(bs.pdf), _channels(weight)[0],
                     int(bs.sampled_type), int(bs.sampled_component)))
    wo, pdf, weight, kind, comp = zip(*rows)
    return Samples(np.array(wo), np.array(pdf), np.array(weight), np.array(kind), np.array(comp))
