"""
Gradients of any BSDF with respect to its parameters: for each parameter that ``mi.traverse``
marks differentiable, the derivative by automatic differentiation (forward mode) of ``eval``,
of ``pdf`` and of the ``sample()`` weight (fixed random numbers) against central finite
differences, in an AD variant.

The parameter is moved along all its entries at once (p + t·1, t a scalar). ``eval`` and
``pdf`` are compared pointwise at random pairs of directions over the sphere: central
differences at two steps h and 2h give the truncation error of the one at h, (D(2h) − D(h))/3
(Richardson), and float32 rounding of the values adds about 8 ε max|f|/h. An element where
the two differences disagree by a quarter or more (a kink or a jump between them: a lobe's
edge, Lafortune's max|C| at a tie, total internal reflection) is left out.

The sample weight is an estimator: with fixed random numbers a sample can change lobe (or,
for a dielectric, reflection for refraction) as the parameter moves, and a renderer may
differentiate the choice's probability instead (Mitsuba's ``roughdielectric``: the derivative
of the log of the probability of the chosen lobe). Both are right where their mean is: the
derivative of the albedo. So the weights are compared by their means over the samples of
each band of cosθi (8 bands), AD's against the differences' (at steps :data:`WEIGHT_STEPS`
times longer), within 5 standard errors of the paired differences plus the truncation and
rounding terms.

* ``ok``: every compared element (or band) agrees;
* ``detached``: automatic differentiation gives 0 everywhere where the differences are
  clearly not 0: the quantity's dependence on the parameter is cut (``dr.detach``), as
  renderers may do on purpose for sampling densities and weights; reported, and a failure
  only for ``eval``;
* ``mismatch``: some element disagrees (a wrong or missing term, a wrong sign);
* ``constant``: the quantity does not depend on the parameter at these points.

To keep the differences within the parameter's range, they are taken about p moved inwards by
four of the weights' steps (p·(1 − 16δ), or 16δ where p = 0), with h = δ·max(|p|, 0.1),
δ = 2e-3.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import MiBrdfsError, arguments, counts, valid_seed
from . import batch
from .consistency import STEP
from .result import CheckResult

QUANTITIES = ("eval", "pdf", "weight")

#: The relative step δ (h = δ·max(|p|, 0.1)): about the cube root of float32's ε, where the
#: truncation error of central differences and the rounding error meet.
DELTA = 2e-3

_EPS = 2.0 ** -24

#: The derivative by AD carries float32 rounding of its own, which cancellation between large
#: terms (a value over a density, the sum of lobes) makes absolute: 1e-5 of the largest
#: derivative (about 170 ε).
AD_FLOOR = 1e-5

#: How many times longer the steps of the weights' differences are: a sample that changes lobe
#: within ±h adds a jump to the mean's difference, so the mean over M samples carries a Poisson
#: noise of variance ∝ 1/(h M); longer steps average more of them (the mean is smooth).
WEIGHT_STEPS = 4

#: The share of compared elements that may exceed their tolerance: isolated ones, where a
#: kink sits so that both differences see it alike, or rounding adds up beyond the terms above.
OUTLIERS = 0.01


@dataclass
class Gradient:
    """One parameter's derivative of one quantity: ``status`` (see the module docstring), the
    largest ratio of |AD − FD| to its tolerance, the elements compared and those left out."""

    parameter: str
    quantity: str
    status: str
    worst: float
    compared: int
    kinks: int


#: Parameters left out: the wavelengths of a tabulated spectrum (Mitsuba's ``irregular``,
#: e.g. a named conductor's η and k in spectral variants) are the nodes of a piecewise-linear
#: interpolation, with a kink at each, which moving them all at once meets at every sample.
NODES = (".wavelengths",)


def differentiable(params) -> list[str]:
    """The keys of ``mi.traverse`` that are differentiable and hold floating-point values (not
    the nodes of a table: :data:`NODES`)."""
    keys = []
    for key in params.keys():
        if key.endswith(NODES):
            continue
        if params.flags(key) & int(mi.ParamFlags.NonDifferentiable):
            continue
        if params.properties[key][0] is None:  # an unset parameter (hair's sigma_a)
            continue
        value = params[key]
        if value is not None and dr.is_array_v(value) and \
                (dr.is_float_v(value) or dr.is_tensor_v(value)):
            keys.append(key)
    return keys


def _outputs(bsdf, ctx, points) -> dict:
    """eval and pdf at the pairs of ``points``, the sample weight at its samples, as drjit
    values."""
    (si, wo), (si_w, u1, u2) = points
    return {"eval": bsdf.eval(ctx, si, wo), "pdf": bsdf.pdf(ctx, si, wo),
            "weight": bsdf.sample(ctx, si_w, u1, u2)[1]}


def _numpy(values, lanes: dict) -> dict:
    """Each quantity as a float64 array (entries × lanes: the channels, or the elements of a
    Mueller matrix, by the lanes), a value of width 1 broadcast to ``lanes[quantity]``."""
    out = {}
    for q, v in values.items():
        a = np.array(v, dtype=np.float64)
        a = a.reshape(-1, a.shape[-1]) if a.ndim else a.reshape(1, 1)
        out[q] = np.broadcast_to(a, (a.shape[0], lanes[q])) if a.shape[1] == 1 else a
    return out


def _flat(value):
    """The entries of a parameter: a tensor's array, else the value itself."""
    return value.array if dr.is_tensor_v(value) else value


def _like(value, flat):
    """``flat`` in the form of ``value`` (a tensor of its shape, else as it is)."""
    return type(value)(flat, value.shape) if dr.is_tensor_v(value) else flat


def _moved(value, t):
    """``value`` + t in every entry (t a Float of width 1, or a Python float)."""
    return _like(value, _flat(value) + t)


def _centre(value):
    """(the point p moved inwards by four of the weights' steps, the step h) (module
    docstring): one step for every entry, as t moves them alike, the smallest."""
    v, move = _flat(value), 4.0 * WEIGHT_STEPS * DELTA
    inward = dr.select(v != 0, v * (1.0 - move), move)
    scale = np.array(dr.maximum(dr.abs(v), 0.1), dtype=np.float64)
    return _like(value, inward), DELTA * float(scale.min())


@dataclass
class _Differences:
    """A quantity's AD derivative, its central differences at h and 2h and the largest |f|
    around, per element (float64 arrays of one shape), and the step h."""

    ad: np.ndarray
    fd: np.ndarray
    fd2: np.ndarray
    second: np.ndarray   # f(p + h) − 2 f(p) + f(p − h)
    second2: np.ndarray  # the same at 2h
    size: np.ndarray
    h: float

    #: how far the value moves when a coordinate of a direction moves by float32's rounding
    #: (:func:`_noise`): the differences' rounding where the computation is ill-conditioned
    noise: np.ndarray | float = 0.0

    def tolerance(self):
        """Truncation (Richardson) and float32 rounding of the differences, per element."""
        return 4.0 * np.abs(self.fd2 - self.fd) / 3.0 + 8.0 * _EPS * self.size / self.h + \
            2.0 * self.noise / self.h + AD_FLOOR * np.max(np.abs(self.fd), initial=0.0)

    def smooth(self):
        """
        The elements where f is smooth within ±2h: both differences finite and within a
        quarter of each other (no jump), and the second differences at 2h four times those
        at h, as a smooth f's are (a kink, such as a table's node, makes them twice),
        up to rounding.
        """
        rounding = 32.0 * (_EPS * self.size + self.noise)
        finite = np.isfinite(self.ad) & np.isfinite(self.fd) & np.isfinite(self.fd2)
        no_jump = np.abs(self.fd2 - self.fd) <= \
            0.25 * np.maximum(np.abs(self.fd), np.abs(self.fd2)) + rounding / self.h
        no_kink = np.abs(self.second2 - 4.0 * self.second) <= \
            0.2 * np.abs(self.second2) + rounding
        return finite & no_jump & no_kink


def _noise(bsdf, ctx, wi, wo, lanes, wavelengths) -> dict:
    """
    For eval and pdf, per element: the largest change when one coordinate of ωi or ωo moves by
    a few float32 roundings (:data:`~mi_brdfs.checks.consistency.STEP`; 12 evaluations):
    float32 carries such errors in every direction and through every
    operation, and where the computation is ill-conditioned (a refraction near the critical
    angle, ωi·m + η ωo·m near cancellation) they move the value far more than its own
    rounding (the directions' conditioning, as :func:`~mi_brdfs.checks.consistency.
    conditioning` measures it for the consistency check); at the pairs' ``wavelengths``.
    """
    def at(a, b):
        si = batch.interaction(a, len(a))
        si.wavelengths = wavelengths
        return _numpy({"eval": bsdf.eval(ctx, si, batch.vectors(b)),
                       "pdf": bsdf.pdf(ctx, si, batch.vectors(b))}, lanes)

    base, spread = at(wi, wo), {"eval": 0.0, "pdf": 0.0}
    for which in range(2):
        for axis in range(3):
            for sign in (-1.0, 1.0):
                a, b = wi.copy(), wo.copy()
                (a if which == 0 else b)[:, axis] += sign * STEP
                moved = at(a, b)
                for q in spread:
                    spread[q] = np.fmax(spread[q], np.nan_to_num(np.abs(moved[q] - base[q])))
    return spread


def _derivatives(bsdf, params, key, ctx, points) -> dict:
    """{quantity: _Differences} of the derivatives with respect to t in p + t; the weights'
    differences at steps :data:`WEIGHT_STEPS` times longer (module docstring)."""
    original = type(params[key])(params[key])
    centre, h = _centre(original)
    lanes = {"eval": len(points[0][0]), "pdf": len(points[0][0]),
             "weight": dr.width(points[2][1])}
    params[key] = centre
    params.update()
    noise = _noise(bsdf, ctx, *points[0], lanes, points[1][0].wavelengths)
    points = points[1:]
    t = mi.Float(0.0)
    dr.enable_grad(t)
    params[key] = _moved(centre, t)
    params.update()
    values = _outputs(bsdf, ctx, points)
    dr.forward(t)
    ad = _numpy({q: dr.grad(v) for q, v in values.items()}, lanes)
    at = {}
    for k in (-2, -1, 0, 1, 2):
        for scale in {1, WEIGHT_STEPS}:
            params[key] = _moved(centre, scale * k * h)
            params.update()
            at[k, scale] = _numpy(_outputs(bsdf, ctx, points), lanes)
    params[key] = original
    params.update()
    out = {}
    for q in QUANTITIES:
        c = WEIGHT_STEPS if q == "weight" else 1
        f = {k: at[k, c][q] for k in (-2, -1, 0, 1, 2)}
        out[q] = _Differences(ad[q], (f[1] - f[-1]) / (2 * c * h), (f[2] - f[-2]) / (4 * c * h),
                              f[1] - 2.0 * f[0] + f[-1], f[2] - 2.0 * f[0] + f[-2],
                              np.max([np.abs(v) for v in f.values()], axis=0), c * h,
                              noise.get(q, 0.0))
    return out


def _status(ad_zero: bool, moving: bool, bad: bool) -> str:
    """ok, constant, mismatch or detached (module docstring)."""
    if bad and moving and ad_zero:
        return "detached"
    if bad:
        return "mismatch"
    return "ok" if moving else "constant"


def _pointwise(parameter, quantity, d: _Differences) -> Gradient:
    """eval and pdf: element by element, the smooth ones."""
    tolerance, smooth = d.tolerance(), d.smooth()
    ratio = np.abs(d.ad - d.fd)[smooth] / np.maximum(tolerance[smooth], 1e-30)
    moving = smooth & (np.abs(d.fd) > 4.0 * tolerance)
    bad = np.count_nonzero(ratio > 1.0) > max(2, OUTLIERS * ratio.size)
    status = _status(not np.any(d.ad[moving]), np.count_nonzero(moving) >= 8, bad)
    return Gradient(parameter, quantity, status, float(ratio.max(initial=0.0)),
                    int(np.count_nonzero(smooth)), int(np.count_nonzero(~smooth)))


def _in_mean(parameter, quantity, d: _Differences, bands) -> Gradient:
    """The sample weight: AD's mean against the differences' per band of cosθi and channel,
    within 5 standard errors of the paired differences plus the mean tolerance."""
    finite = np.isfinite(d.ad) & np.isfinite(d.fd)
    ad, fd, tolerance = np.where(finite, d.ad, 0.0), np.where(finite, d.fd, 0.0), d.tolerance()
    worst, bad, moving = 0.0, False, False
    for band in bands:
        a, f, m = ad[:, band], fd[:, band], len(band)
        diff = a.mean(axis=1) - f.mean(axis=1)
        limit = 5.0 * np.std(a - f, axis=1) / np.sqrt(m) + \
            np.where(finite[:, band], tolerance[:, band], 0.0).mean(axis=1)
        worst = max(worst, float(np.max(np.abs(diff) / np.maximum(limit, 1e-30))))
        bad |= bool(np.any(np.abs(diff) > limit))
        moving |= bool(np.any(np.abs(f.mean(axis=1)) > 5.0 * np.std(f, axis=1) / np.sqrt(m)))
    status = _status(not np.any(ad), moving, bad)
    return Gradient(parameter, quantity, status, worst, int(np.count_nonzero(finite)),
                    int(np.count_nonzero(~finite)))


def _interaction(wi, rng):
    """Interactions at ``wi``; in spectral variants at random visible wavelengths per lane, so
    that the nodes of a tabulated spectrum (a kink of its interpolation) are rarely hit."""
    si = batch.interaction(wi, len(wi))
    if mi.is_spectral:
        si.wavelengths = mi.UnpolarizedSpectrum(
            rng.uniform(mi.MI_CIE_MIN, mi.MI_CIE_MAX, (len(si.wavelengths), len(wi))))
    return si


@arguments(seed=valid_seed)
def gradient_rows(spec, n: int = 512, seed: int = 0, ctx=None) -> list:
    """
    Every differentiable parameter's derivatives of eval, pdf and the sample weight
    (:class:`Gradient` per parameter and quantity) at ``n`` random pairs over the sphere and
    64·``n`` samples, in the current variant, which must be an AD one. A parameter changed
    along the way is set back to its value.
    """
    if not dr.is_diff_v(mi.Float) or not batch.is_jit():
        raise MiBrdfsError(f"gradients need an AD variant (e.g. llvm_ad_rgb), not "
                           f"{mi.variant()}")
    bsdf, ctx = load_bsdf(spec), ctx or mi.BSDFContext()
    params = mi.traverse(bsdf)
    rng = np.random.default_rng(seed)
    wi, wo, wi_w = (batch.random_directions(rng, k) for k in (n, n, 64 * n))
    si, si_w = _interaction(wi, rng), _interaction(wi_w, rng)
    points = ((wi, wo), (si, batch.vectors(wo)),
              (si_w, mi.Float(rng.random(64 * n)), mi.Point2f(rng.random((2, 64 * n)))))
    edges = np.linspace(-1.0, 1.0, 9)
    bands = [np.flatnonzero((wi_w[:, 2] >= lo) & (wi_w[:, 2] < hi))
             for lo, hi in zip(edges[:-1], edges[1:])]
    out = []
    for key in differentiable(params):
        d = _derivatives(bsdf, params, key, ctx, points)
        out += [_pointwise(key, q, d[q]) for q in ("eval", "pdf")]
        out.append(_in_mean(key, "weight", d["weight"], bands))
    return out


@loaded_once()
@counts("n")
def check_gradients(spec, n: int = 512, seed: int = 0, ctx=None) -> CheckResult:
    """
    Automatic derivatives of eval, pdf and sample weights against finite differences for every
    differentiable parameter (:func:`gradient_rows`). Fails on a mismatch anywhere and on an
    ``eval`` whose dependence on a parameter is detached; a detached pdf or weight is
    reported, as renderers detach them on purpose.
    """
    rows = gradient_rows(spec, n=n, seed=seed, ctx=ctx)
    failed = [g for g in rows if g.status == "mismatch" or
              (g.status == "detached" and g.quantity == "eval")]
    detached = [f"{g.parameter} ({g.quantity})" for g in rows if g.status == "detached"]
    worst = max((g.worst for g in rows if g.status in ("ok", "mismatch")), default=0.0)
    if failed:
        what = "; ".join(f"{g.parameter}: {g.quantity} {g.status} (|AD − FD| up to "
                         f"{g.worst:.3g}× its tolerance)" for g in failed)
    else:
        what = (f"{len({g.parameter for g in rows})} parameter(s) × eval, pdf, weight agree "
                f"with finite differences" if rows else "no differentiable parameter")
    if detached:
        what += f"; detached: {', '.join(detached)}"
    msg = f"gradients: {describe(spec)}: {what}"
    return CheckResult("gradients", not failed, worst, 1.0, msg, details={"rows": rows})
