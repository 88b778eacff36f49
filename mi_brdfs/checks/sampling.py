"""
Sampling checks: Pearson's χ² test of ``sample()`` against ``pdf()``, through ``mitsuba.chi2``.

``mitsuba.chi2`` needs a JIT variant (it uses wide arrays and scatter-adds), so these checks
raise :class:`mi_brdfs.MiBrdfsError` in scalar variants.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import MiBrdfsError, arguments, counts, fraction, valid_direction, valid_seed
from . import batch
from .result import CheckResult


def rotation_to_equator(d) -> np.ndarray:
    """
    A rotation matrix (3×3) taking the unit vector ``d`` to (1, 0, 0), a point on the equator
    of ``mitsuba.chi2.SphericalDomain``, whose cells are uniform in (φ, cosθ): finest in θ at the
    equator (Δθ = 2/res), coarsest at the poles (Δθ ≈ 2/sqrt(res)).
    """
    d = np.asarray(d, dtype=np.float64)
    d = d / np.linalg.norm(d)
    x = np.array([1.0, 0.0, 0.0])
    axis = np.cross(d, x)
    s, c = np.linalg.norm(axis), float(d @ x)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([-1.0, -1.0, 1.0])  # d = ±x
    k = axis / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K  # Rodrigues


def _apply(R, v):
    """R·v for a wide mi.Vector3f and a constant 3×3 matrix."""
    r = [[float(x) for x in row] for row in R]
    return mi.Vector3f(r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z,
                       r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
                       r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z)


def bsdf_adapter(bsdf, wi, ctx=None, rotation=None, delta_failed=False):
    """
    ``(sample_func, pdf_func)`` for ``mi.chi2.ChiSquareTest`` on a loaded BSDF.

    Like ``mi.chi2.BSDFAdapter``, but takes the BSDF object (so a plugin is built once, not per
    call), sets the wavelengths in spectral variants, and marks samples with zero weight as
    failed: they are not counted, and their direction, which the contract leaves undefined, is
    replaced by the normal (Mitsuba's GGX visible-normal sampler returns NaN for some failed
    samples at exactly normal incidence, which ``mitsuba.chi2`` rejects as "outside the domain").

    Parameter ``rotation`` (3×3 | None): the histogram is made of R·ωo and the pdf evaluated at
    Rᵀ·ω; a rotation preserves solid angle, so the densities are unchanged (see
    :func:`rotation_to_equator`).

    Parameter ``delta_failed`` (bool): count samples of a Dirac lobe as failed. With every lobe
    enabled, the histogram then holds the smooth lobes' samples, whose mass is the probability
    of choosing them, and ``pdf()`` (which reports the smooth lobes times that probability)
    must match it: the lobe-selection weights are tested too.
    """
    ctx = ctx or mi.BSDFContext()
    R = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)

    def sample_func(sample):
        si = batch.interaction(wi, dr.width(sample))
        bs, weight = bsdf.sample(ctx, si, sample[0], mi.Point2f(sample[1], sample[2]))
        ok = dr.any(mi.unpolarized_spectrum(weight) != 0)
        if delta_failed:
            ok &= (bs.sampled_type & mi.UInt32(int(mi.BSDFFlags.Delta))) == 0
        wo = dr.select(ok, bs.wo, mi.Vector3f(0, 0, 1))
        return _apply(R, wo), dr.select(ok, mi.Float(1.0), mi.Float(0.0))

    def pdf_func(wo):
        return bsdf.pdf(ctx, batch.interaction(wi, dr.width(wo)), _apply(R.T, wo))

    return sample_func, pdf_func


#: A sharp lobe whose mean direction lies within this many degrees of a pole is rotated onto the
#: equator by :func:`chi2_bsdf`.
POLAR_DEG = 45.0

#: (largest pdf below which, θ resolution ``res``, per-cell integration ``ires``) for the
#: automatic choice of :func:`chi2_settings`.
RESOLUTIONS = ((5.0, 101, 8), (50.0, 201, 16), (500.0, 301, 32), (float("inf"), 401, 32))


def _elongation(wo: np.ndarray) -> float:
    """
    How much narrower than wide a lobe is: sqrt(λmax/λmin) of the covariance of its directions
    projected on the plane perpendicular to their mean (1 for a round lobe, αv/αu for an
    anisotropic microfacet lobe), clipped to [1, 100].
    """
    mean = wo.mean(axis=0)
    norm = np.linalg.norm(mean)
    if len(wo) < 10 or norm < 1e-6:
        return 1.0
    mean = mean / norm
    a = np.cross(mean, [1.0, 0.0, 0.0] if abs(mean[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(mean, a)
    lam = np.linalg.eigvalsh(np.cov(np.stack([wo @ a, wo @ b])))
    return float(np.clip(np.sqrt(lam[1] / max(lam[0], 1e-30)), 1.0, 100.0))


def _pilot(bsdf, wi, ctx, n: int):
    """
    (sharpness, mean direction) of ``n`` pilot samples, or None if none succeeded. The
    sharpness is the largest pdf, times the elongation of the lobe's core (the samples with at
    least a tenth of that pdf): a lobe of widths w₁ ≤ w₂ has its largest pdf ∝ 1/(w₁ w₂), but
    needs the resolution of a round lobe of width w₁, whose pdf ∝ 1/w₁².
    """
    rng = np.random.default_rng(12345)
    s = batch.sample(bsdf, wi, rng.random(n), rng.random((n, 2)), ctx)
    ok = np.any(s.weight != 0, axis=1) & np.isfinite(s.pdf) & np.isfinite(s.wo).all(axis=1)
    if not ok.any():
        return None
    pdf_max = float(np.max(s.pdf[ok]))
    core = s.wo[ok & (s.pdf >= 0.1 * pdf_max)]
    return pdf_max * _elongation(core), s.wo[ok].mean(axis=0)


@counts("n")
@arguments(wi=valid_direction)
def chi2_settings(bsdf, wi, ctx=None, n: int = 20_000):
    """
    ``(res, ires, pdf_max, lobe)`` for a χ² test of ``bsdf`` at ``wi``, from pilot samples of
    its sharpest lobe: ``pdf_max`` its largest ``bs.pdf`` (sampled alone, through
    ``ctx.component``, so that a sharp lobe mixed with a diffuse one is not hidden by the
    mixture's weights) times the elongation of an anisotropic lobe (:func:`_pilot`), ``lobe``
    its mean direction, and the resolution from ``pdf_max``.

    The histogram cells of ``mitsuba.chi2`` are uniform in (φ, cosθ): near a pole a lobe of
    angular width w spans only w²/2 in cosθ, and the pdf integral over its cell is poor (a
    Phong lobe with n = 1000 at normal incidence integrates to visibly more than 1 at res 301,
    ires 32, and is rejected with a correct pdf). So :func:`chi2_bsdf` rotates such a lobe onto the
    equator, where the cells are finest, and uses these resolutions there.
    """
    contexts = [ctx]
    if ctx is None and bsdf.component_count() > 1:
        contexts = []
        for c in range(bsdf.component_count()):
            if not int(bsdf.flags(c)) & int(mi.BSDFFlags.Delta):
                one = mi.BSDFContext()
                one.component = c
                contexts.append(one)
    pilots = [p for p in (_pilot(bsdf, wi, c, n) for c in contexts) if p is not None]
    pdf_max, lobe = max(pilots, key=lambda p: p[0]) if pilots else (0.0, np.array([0, 0, 1.0]))
    if np.linalg.norm(lobe) < 1e-6:
        lobe = np.array([0.0, 0.0, 1.0])
    for limit, res, ires in RESOLUTIONS:
        if pdf_max < limit:
            return res, ires, pdf_max, lobe
    raise AssertionError("unreachable")


@loaded_once()
@counts("res", "ires", "sample_count", "test_count")
@arguments(wi=valid_direction, seed=valid_seed, significance=fraction)
def chi2_bsdf(bsdf, wi=(0.0, 0.0, 1.0), ctx=None, res: int | None = 101, ires: int | None = 4,
              sample_count: int = 1_000_000, seed: int = 0, significance: float = 0.01,
              test_count: int = 1, rotate: bool = True) -> CheckResult:
    """
    Pearson's χ² test: does ``sample()`` draw directions with the density that ``pdf()`` reports?

    Parameter ``bsdf`` (dict | str | mi.BSDF): the BSDF (see :mod:`mi_brdfs.bsdfspec`).

    Parameter ``wi`` (3 floats): the incident direction in the local frame (normalised here).

    Parameter ``ctx`` (mi.BSDFContext | None): e.g. to test one lobe (``ctx.component = i``).

    Parameter ``res``, ``ires`` (int | None): histogram resolution in θ (odd, so no cell edge lies
    on the horizon: Mitsuba's default 101) and the per-cell integration resolution of the pdf.
    Raise them for sharp lobes (α ≤ 0.05), as Mitsuba's own tests do; ``None`` chooses both
    from the lobe's sharpness (:func:`chi2_settings`).

    Parameter ``rotate`` (bool): for a sharp lobe (largest pilot pdf ≥ 5) whose mean direction
    lies within :data:`POLAR_DEG` of a pole, histogram the directions in a frame where it lies
    on the equator (:func:`rotation_to_equator`), where the cells are finest; rotations
    preserve solid angle, so this changes the resolution, not the test.

    Parameter ``significance`` (float), ``test_count`` (int): the test rejects at
    ``significance`` after Šidák correction for ``test_count`` tests run together.

    Returns → CheckResult: value = p-value; passes when the hypothesis is not rejected.
    """
    if not dr.is_jit_v(mi.Float):
        raise MiBrdfsError(f"the χ² test needs a JIT variant (llvm_* or cuda_*), "
                           f"not {mi.variant()}")
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    obj = load_bsdf(bsdf)
    wi = np.asarray(wi, dtype=np.float64)
    wi = wi / np.linalg.norm(wi)
    where = f"{describe(bsdf)} at wi=({wi[0]:.3f}, {wi[1]:.3f}, {wi[2]:.3f})"
    flags, delta = int(obj.flags()), int(mi.BSDFFlags.Delta)
    note, delta_failed = "", False
    if ctx is None and flags & delta:
        # Dirac lobes have pdf() = 0 by convention: χ² judges the other lobes, sampled with
        # every lobe enabled and Dirac samples counted as failed, so that the probability of
        # choosing the smooth lobes is tested too (restricting the context to them would not).
        smooth = flags & int(mi.BSDFFlags.All) & ~delta
        if not smooth & int(mi.BSDFFlags.Smooth):
            return CheckResult("chi2", True, float("nan"), "n/a",
                               f"χ²: {where}: not applicable (only Dirac delta lobes)",
                               skipped=True)
        delta_failed = True
        note = " (Dirac samples counted as failed)"
    if rotate or res is None or ires is None:  # the pilot samples are needed
        auto_res, auto_ires, pdf_max, lobe = chi2_settings(obj, wi, ctx)
        res, ires = res or auto_res, ires or auto_ires
    else:
        pdf_max, lobe = 0.0, np.array([0.0, 0.0, 1.0])
    # Only a sharp lobe near a pole is moved: a wide one reaches the horizon, where the pdf
    # jumps to 0, and that edge is best left on the equator, aligned with the cells (rotated,
    # α = 1 at normal incidence is rejected; unrotated it passes).
    lobe_dir = lobe / np.linalg.norm(lobe)
    rotate = rotate and pdf_max >= RESOLUTIONS[0][0] and abs(lobe_dir[2]) > math.cos(
        math.radians(POLAR_DEG))
    rotation = rotation_to_equator(lobe) if rotate else None
    sample_func, pdf_func = bsdf_adapter(obj, wi, ctx, rotation, delta_failed)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=sample_count, res=res, ires=ires, seed=seed)
    passed = bool(test.run(significance_level=significance, test_count=test_count, quiet=True))
    p = float(test.p_value) if test.p_value is not None else float("nan")
    if test.histogram is not None and not float(np.sum(np.asarray(test.histogram))) > 0:
        return CheckResult("chi2", False, p, significance,
                           f"χ²: {where}{note}: no sample succeeded (every weight is 0): the "
                           f"test would pass vacuously", details={"wi": wi.tolist()})
    level = 1.0 - (1.0 - significance) ** (1.0 / test_count)  # Šidák, as mitsuba.chi2 does
    log = " ".join(str(test.messages).split())
    log = log.replace(' Target density and histogram were written to "chi2_data.py".', "")
    log = log.replace(' Target density and histogram were written to "chi2_data.py', "")
    if passed:
        message = (f"χ²: {where}{note}: p = {p:.3g} ≥ {level:.3g} (sample() matches pdf(); "
                   f"res {res}, ires {ires}{', lobe on the equator' if rotate else ''})")
    elif test.fail:
        message = f"χ²: {where}{note}: the test could not run: {log[-300:]}"
    else:
        message = f"χ²: {where}{note}: rejected, p = {p:.3g} < {level:.3g}: {log[-300:]}"
    return CheckResult("chi2", passed, p, level, message,
                       details={"wi": wi.tolist(), "res": res, "ires": ires, "rotated": rotate,
                                "sample_count": sample_count, "histogram": test.histogram,
                                "pdf": test.pdf})
