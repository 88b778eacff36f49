"""
What a BSDF promises about its lobes, which neither χ² nor the energy checks see:

* **context selection** — with ``ctx.component = c``, ``sample()`` draws from lobe c only: each
  sample that succeeds reports ``sampled_component == c`` and a ``sampled_type`` within
  ``flags(c)`` (Mitsuba's ``BSDFContext::is_enabled``; integrators and ``mi.chi2`` select lobes
  this way);
* **lobe additivity** — ``eval`` of all lobes equals the sum over the lobes selected one by one,
  pointwise, and the albedo E(θ) from ``sample()`` of all lobes equals the sum of the lobes'
  albedos (Dirac lobes included: only ``sample()`` sees them);
* **pdf normalisation** — ∫ pdf(ωo) dωo over the sphere equals the fraction of samples that
  succeed on the non-Dirac lobes. A pdf that integrates to more than what ``sample()`` draws
  overstates the density somewhere (multiple importance sampling then misweights), one that
  integrates to less is a sampler that produces directions ``pdf()`` denies.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import arguments, counts, positive, valid_seed
from . import batch
from .albedo import sphere_quadrature
from .result import CheckResult

#: Incident angles (degrees) of the lobe checks.
THETAS = (0.0, 45.0, 80.0)

#: Relative tolerance of the pointwise additivity of eval (float32 sums of a few lobes).
EVAL_RTOL = 1e-4


def _component_context(c: int, mode=None) -> mi.BSDFContext:
    ctx = mi.BSDFContext() if mode is None else mi.BSDFContext(mode)
    ctx.component = c
    return ctx


def _sampled_albedo(bsdf, theta: float, n: int, seed: int, ctx):
    rng = np.random.default_rng(seed)
    s = batch.sample(bsdf, batch.direction(math.radians(theta)), rng.random(n),
                     rng.random((n, 2)), ctx)
    w = np.nan_to_num(s.weight, nan=0.0, posinf=0.0)
    return w.mean(axis=0), w.std(axis=0, ddof=1) / math.sqrt(n), s


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, sigmas=positive)
def check_lobes(spec, n: int | None = None, seed: int = 0, sigmas: float = 5.0) -> CheckResult:
    """
    Context selection and lobe additivity (module docstring) at :data:`THETAS`, for a BSDF of
    two or more components; one component passes as "one lobe".
    """
    bsdf = load_bsdf(spec)
    count = bsdf.component_count()
    where = describe(spec)
    if count < 2:
        return CheckResult("lobes", True, 0.0, "n/a", f"lobes: {where}: one lobe",
                           skipped=True)
    n = n or (200_000 if batch.is_jit() else 2_000)
    problems, worst = [], 0.0
    rng = np.random.default_rng(seed + 3)
    wo = batch.random_directions(rng, min(n, 50_000), sphere=True)
    for theta in THETAS:
        wi = batch.direction(math.radians(theta))
        whole = batch.evaluate(bsdf, wi, wo).value
        parts = sum(batch.evaluate(bsdf, wi, wo, _component_context(c)).value
                    for c in range(count))
        scale = np.maximum(np.abs(whole), np.abs(parts))
        err = np.where(scale > 1e-7, np.abs(whole - parts) / np.maximum(scale, 1e-7), 0.0)
        if np.nanmax(err) > EVAL_RTOL or not np.isfinite(err).all():
            i = int(np.nanargmax(err))
            problems.append(f"eval of all lobes ≠ sum of the lobes one by one at θ = {theta:g}° "
                            f"(relative {err.flat[i]:.3g}, wo = "
                            f"{np.round(wo[i // err.shape[1]], 4).tolist()})")
        e_all, s_all, _ = _sampled_albedo(bsdf, theta, n, seed, None)
        e_sum, var = np.zeros_like(e_all), s_all ** 2
        for c in range(count):
            e_c, s_c, smp = _sampled_albedo(bsdf, theta, n, seed + 1 + c,
                                            _component_context(c))
            e_sum, var = e_sum + e_c, var + s_c ** 2
            ok = np.any(smp.weight != 0, axis=1)
            wrong_c = ok & (smp.sampled_component != c)
            wrong_t = ok & ((smp.sampled_type & ~int(bsdf.flags(c))) != 0)
            if wrong_c.any() or wrong_t.any():
                problems.append(
                    f"ctx.component = {c} at θ = {theta:g}°: {int(wrong_c.sum())} of "
                    f"{int(ok.sum())} samples report another sampled_component (e.g. "
                    f"{int(smp.sampled_component[wrong_c][0]) if wrong_c.any() else c}), "
                    f"{int(wrong_t.sum())} a sampled_type outside flags({c})")
        gap = np.abs(e_all - e_sum)
        bound = sigmas * np.sqrt(var) + 1e-3 * np.maximum(e_all, 1e-3)
        worst = max(worst, float(np.max(gap)))
        if (gap > bound).any():
            k = int(np.argmax(gap - bound))
            problems.append(f"E({theta:g}°) of all lobes {e_all[k]:.5f} ≠ sum of the lobes "
                            f"one by one {e_sum[k]:.5f} (> {sigmas:g}σ)")
    passed = not problems
    msg = (f"lobes: {where}: {count} lobes" + (
        ": selected one by one, each samples only itself and they add up to the whole "
        "(eval pointwise, albedo within its error)" if passed else ": " + "; ".join(problems)))
    return CheckResult("lobes", passed, worst, f"{sigmas:g}σ", msg,
                       details={"components": count})


def pdf_integral(bsdf, theta: float, n_mu: int = 256, n_phi: int = 256, ctx=None) -> float:
    """∫ pdf(ωo) dωo over the whole sphere at incident angle ``theta`` (radians)
    (:func:`~mi_brdfs.checks.albedo.sphere_quadrature`)."""
    return sphere_quadrature(bsdf, theta, n_mu, n_phi, ctx, whole_sphere=True)[1]


#: Largest sampled pdf at which the quadrature (384² nodes per hemisphere, spacing ≈ 0.016 rad
#: in φ) is trusted: a lobe with pdf ≈ 1/(π w²) has width w ≈ 0.08 rad there, five nodes
#: across. Sharper lobes can fall between the nodes, and both resolutions then agree on 0.
PDF_MAX_JUDGED = 50.0


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, sigmas=positive)
def check_pdf_integral(spec, n: int | None = None, seed: int = 0,
                       sigmas: float = 5.0) -> CheckResult:
    """
    ∫ pdf dω over the sphere (quadrature at two resolutions) against the fraction of
    ``sample()`` calls that succeed on a non-Dirac lobe, at :data:`THETAS`. An angle whose
    largest sampled pdf exceeds :data:`PDF_MAX_JUDGED`, or where the two quadratures differ by
    more than 0.5 %, holds a lobe too sharp for them: not judged there.
    """
    bsdf = load_bsdf(spec)
    n = n or (400_000 if batch.is_jit() else 4_000)
    delta = int(mi.BSDFFlags.Delta)
    problems, judged, worst, rows = [], 0, 0.0, []
    for theta in THETAS:
        t = math.radians(theta)
        coarse, fine = pdf_integral(bsdf, t, 128, 128), pdf_integral(bsdf, t, 384, 384)
        rng = np.random.default_rng(seed)
        s = batch.sample(bsdf, batch.direction(t), rng.random(n), rng.random((n, 2)))
        ok = np.any(s.weight != 0, axis=1) & ((s.sampled_type & delta) == 0)
        frac = float(ok.mean())
        err = sigmas * math.sqrt(max(frac * (1 - frac), 1.0 / n) / n) + 0.002
        pdf_max = float(np.max(s.pdf[ok & np.isfinite(s.pdf)], initial=0.0))
        rows.append((theta, fine, frac, pdf_max))
        if pdf_max > PDF_MAX_JUDGED or abs(fine - coarse) > 0.005 * max(fine, 1e-3):
            continue  # a lobe the quadrature does not resolve (or may miss): no verdict
        judged += 1
        worst = max(worst, abs(fine - frac))
        if abs(fine - frac) > err:
            problems.append(f"θ = {theta:g}°: ∫ pdf = {fine:.4f} but {frac:.4f} of the samples "
                            f"succeed on non-Dirac lobes")
    where = describe(spec)
    if not judged:
        return CheckResult("pdf integral", True, math.nan, "n/a",
                           f"pdf integral: {where}: lobes too sharp for the quadrature at every "
                           f"angle: not judged", skipped=True, details={"rows": rows})
    passed = not problems
    msg = (f"pdf integral: {where}: " + ("∫ pdf dω = the fraction of samples that succeed "
                                         f"(within {sigmas:g}σ + 0.002) at {judged} angle(s)"
                                         if passed else "; ".join(problems)))
    return CheckResult("pdf integral", passed, worst, f"{sigmas:g}σ + 0.002", msg,
                       details={"rows": rows})
