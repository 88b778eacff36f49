"""
Consistency of a BSDF's methods with each other: what ``mi.chi2`` does not see (it checks only
the directions ``sample()`` draws against ``pdf()``, not ``eval`` nor the sample weight).

For samples drawn at random incident directions:

* ``bs.pdf == pdf(bs.wo)`` (the path integrator uses ``bs.pdf`` for MIS);
* weight == ``eval(bs.wo) / pdf(bs.wo)`` (the weight is f·cosθo/pdf);
* ``eval_pdf`` == (``eval``, ``pdf``) at random direction pairs;
* ``bs.sampled_type`` is one of the BSDF's flags, and those of ``bs.sampled_component``;
* weights and pdfs are finite and not negative.

Delta lobes (``eval`` = ``pdf`` = 0 by convention) are excluded from the first two and counted.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import arguments, counts, nonnegative, valid_seed
from . import batch
from .result import CheckResult

#: Relative tolerance of the comparisons: float32 arithmetic in a few dozen operations. Our
#: plugins compute sample, eval and pdf from the same terms and agree to float32 rounding;
#: Mitsuba's roughconductor differs somewhat more (its sample() and pdf() evaluate D and G1
#: separately), still far below this tolerance.
RTOL = 1e-3


def _rel(a: np.ndarray, b: np.ndarray, floor: float = 1e-7) -> np.ndarray:
    """|a − b| / max(|a|, |b|), 0 where both are below ``floor`` (equal for float32 purposes)."""
    scale = np.maximum(np.abs(a), np.abs(b))
    return np.where(scale < floor, 0.0, np.abs(a - b) / np.maximum(scale, floor))


def _incident(rng, n: int, both_sides: bool = False) -> np.ndarray:
    """Incident directions: uniform over the upper hemisphere, plus normal and grazing ones;
    with ``both_sides`` (a BSDF that declares ``BackSide``: two-sided, or transmissive) every
    other one mirrored below the surface, so that its back is checked too."""
    wi = batch.random_directions(rng, n, sphere=False)
    special = [batch.direction(np.radians(t)) for t in (0.0, 84.26, 89.0, 89.9)]
    wi[: len(special)] = special
    if both_sides:
        wi[1::2, 2] *= -1.0
    return wi


def back_side(bsdf) -> bool:
    """Whether ``bsdf`` scatters light that arrives from below its surface."""
    return bool(int(bsdf.flags()) & int(mi.BSDFFlags.BackSide))


#: A mismatch within this many times the float32 conditioning of its directions
#: (:func:`conditioning`) is rounding, not a defect.
CONDITIONING_FACTOR = 8.0

#: The absolute step of :func:`conditioning`: 8 units of float32's last place at 1.
STEP = 8.0 * 2.0 ** -24


def conditioning(bsdf, wi: np.ndarray, wo: np.ndarray, ctx=None, seed: int = 0) -> np.ndarray:
    """
    How much ``pdf`` and ``eval/pdf`` move when one coordinate of ``wi`` or ``wo`` moves by
    :data:`STEP` (absolute, not renormalised; 12 evaluations per pair): the largest change of
    their logarithms. ``sample()`` computes ``bs.pdf`` from the direction it meant, then stores
    it rounded to float32, whose components carry absolute errors of about 2⁻²⁴ (a unit vector's
    length then differs from 1 by ~1e-8). Where the geometry is ill-conditioned (grazing
    directions, ωi + ωo near cancellation in a half vector) that alone moves the exact pdf by
    up to a few 1e-3, however the BSDF is written (a float64 evaluation of Mitsuba's formulas at
    the two directions differs as much: ``validation/audit/conditioning_microfacet_pdf.py``).
    A relative jitter would not show it: a small z component moves by far less than 2⁻²⁴.
    ``seed`` is unused (the steps are deterministic); kept for the callers' signature.
    """
    base = batch.evaluate(bsdf, wi, wo, ctx)

    def logs(e):
        pdf = np.where(e.pdf > 0, e.pdf, np.nan)
        return np.log(pdf), np.log(np.where(e.value[:, 0] > 0, e.value[:, 0], np.nan) / pdf)

    p0, r0 = logs(base)
    spread = np.zeros(len(wi))
    for which in range(2):
        for axis in range(3):
            for sign in (-1.0, 1.0):
                a, b = wi.copy(), wo.copy()
                (a if which == 0 else b)[:, axis] += sign * STEP
                p, r = logs(batch.evaluate(bsdf, a, b, ctx))
                change = np.fmax(np.abs(p - p0), np.abs(r - r0))
                spread = np.fmax(spread, np.nan_to_num(change, nan=0.0))
    return spread


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, rtol=nonnegative)
def check_consistency(spec, n: int | None = None, seed: int = 0, rtol: float = RTOL,
                      ctx=None) -> CheckResult:
    """
    Sample weight == eval/pdf, bs.pdf == pdf(bs.wo), eval_pdf == (eval, pdf), sampled flags
    valid, everything finite and non-negative: at ``n`` random incident directions (from both
    sides where the BSDF declares ``BackSide``; default
    100 000 in JIT variants, 400 in scalar ones). Works in every variant.
    """
    bsdf = load_bsdf(spec)
    n = n or (100_000 if batch.is_jit() else 400)
    rng = np.random.default_rng(seed)
    wi = _incident(rng, n, back_side(bsdf))
    s = batch.sample(bsdf, wi, rng.random(n), rng.random((n, 2)), ctx)
    e = batch.evaluate(bsdf, wi, s.wo, ctx)
    problems, details = [], {"samples": n}

    delta = (s.sampled_type & int(mi.BSDFFlags.Delta)) != 0
    produced = np.any(s.weight != 0, axis=1)
    valid = produced & ~delta
    details.update(produced=int(produced.sum()), delta=int((produced & delta).sum()))
    finite = valid & ~_invalid_samples(s, wi, n, produced, problems)
    worst = _sample_mismatch(bsdf, s, e, wi, finite, rtol, ctx, seed, problems, details)

    positive_pdf_zero = finite & (s.pdf <= 0)
    if positive_pdf_zero.any():
        problems.append(f"{int(positive_pdf_zero.sum())} samples with a weight but bs.pdf = 0")
    worst = max(worst, _eval_pdf_mismatch(bsdf, rng, wi, n, rtol, ctx, problems, details))
    _check_sampled_flags(bsdf, s, produced, problems)

    passed = not problems
    summary = (f"{int(finite.sum())} weighted samples, max relative error {worst:.2g}"
               + (f" ({details['conditioned']} within the float32 conditioning of their "
                  f"directions)" if details["conditioned"] else "")
               + (f", {details['delta']} delta samples skipped" if details["delta"] else ""))
    msg = f"consistency: {describe(spec)}: " + (summary if passed else "; ".join(problems))
    return CheckResult("consistency", passed, worst, rtol, msg, details)


def _invalid_samples(s, wi: np.ndarray, n: int, produced: np.ndarray,
                     problems: list) -> np.ndarray:
    """The samples that succeeded with a NaN, Inf or negative weight or pdf (a problem each,
    and one when no sample succeeded)."""
    # Only samples that succeeded are judged: a failed one (weight 0) leaves bs.wo and bs.pdf
    # undefined by the API (Mitsuba's samplers return e.g. negative pdfs there).
    bad_value = produced & (~np.isfinite(s.weight).all(axis=1) | ~np.isfinite(s.pdf) |
                            (s.pdf < 0) | (s.weight < 0).any(axis=1))
    if not produced.any():
        problems.append(f"no sample of {n} succeeded (every weight is 0): every other check "
                        f"would pass vacuously")
    if bad_value.any():
        i = int(np.argmax(bad_value))
        problems.append(f"{int(bad_value.sum())} samples with a NaN/Inf/negative weight or pdf "
                        f"(first: wi={np.round(wi[i], 4).tolist()}, weight={s.weight[i].tolist()}, "
                        f"pdf={s.pdf[i]:g})")
    return bad_value


def _sample_mismatch(bsdf, s, e, wi: np.ndarray, finite: np.ndarray, rtol: float, ctx,
                     seed: int, problems: list, details: dict) -> float:
    """
    bs.pdf against pdf(bs.wo) and the weight against eval/pdf at the ``finite`` samples, each
    within ``rtol`` or, where larger, the float32 conditioning of the directions: the largest
    relative error (problems and details filled in).
    """
    n = len(wi)
    pdf_err = np.where(finite, _rel(s.pdf, e.pdf), 0.0)
    ratio = e.value / np.where(e.pdf > 0, e.pdf, np.inf)[:, None]
    weight_err = np.where(finite[:, None], _rel(s.weight, ratio), 0.0).max(axis=1)
    # where either exceeds rtol, the tolerance follows the float32 conditioning there
    suspect = (pdf_err > rtol) | (weight_err > rtol)
    spread = np.zeros(n)
    if suspect.any():
        spread[suspect] = conditioning(bsdf, wi[suspect], s.wo[suspect], ctx, seed)
    tol = np.maximum(rtol, CONDITIONING_FACTOR * spread)
    details["conditioned"] = int((suspect & (pdf_err <= tol) & (weight_err <= tol)).sum())
    worst = 0.0
    for name, err, what in (("bs.pdf vs pdf(bs.wo)", pdf_err, "pdf"),
                            ("weight vs eval/pdf", weight_err, "weight")):
        i = int(np.argmax(err))
        details[f"max_rel_{what}"] = float(err[i])
        worst = max(worst, float(err[i]))
        over = err > tol
        if over.any():
            i = int(np.argmax(np.where(over, err / tol, 0.0)))
            problems.append(
                f"{name}: relative error {err[i]:.3g} > {tol[i]:.3g} (float32 conditioning "
                f"there: {spread[i]:.2g}) in {int(over.sum())} of "
                f"{int(finite.sum())} samples (worst: wi={np.round(wi[i], 4).tolist()}, "
                f"wo={np.round(s.wo[i], 4).tolist()}, weight={s.weight[i, 0]:.6g}, "
                f"eval/pdf={ratio[i, 0]:.6g}, bs.pdf={s.pdf[i]:.6g}, pdf={e.pdf[i]:.6g})")
    return worst


def _eval_pdf_mismatch(bsdf, rng, wi: np.ndarray, n: int, rtol: float, ctx, problems: list,
                       details: dict) -> float:
    """eval_pdf against eval and pdf, at pairs covering the whole sphere (below the horizon
    too): the largest relative difference."""
    wo = batch.random_directions(rng, n, sphere=True)
    pairs = batch.evaluate(bsdf, wi, wo, ctx)
    ep = max(float(_rel(pairs.value, pairs.eval_pdf_value).max(initial=0)),
             float(_rel(pairs.pdf, pairs.eval_pdf_pdf).max(initial=0)))
    details["max_rel_eval_pdf"] = ep
    if ep > rtol:
        problems.append(f"eval_pdf() differs from (eval(), pdf()) by {ep:.3g} relative")
    return ep


def _check_sampled_flags(bsdf, s, produced: np.ndarray, problems: list) -> None:
    """bs.sampled_type among the BSDF's flags and those of bs.sampled_component (a problem
    when not)."""
    flags = int(bsdf.flags())
    kinds = s.sampled_type[produced]
    comps = s.sampled_component[produced]
    foreign = (kinds & ~flags) != 0
    empty = kinds == 0
    out_of_range = comps >= max(bsdf.component_count(), 1)
    wrong_comp = np.array([(int(k) & ~int(bsdf.flags(int(c)))) != 0 if c < bsdf.component_count()
                           else True for k, c in zip(kinds, comps)], dtype=bool)
    if foreign.any() or empty.any() or out_of_range.any() or wrong_comp.any():
        problems.append(f"sampled_type/sampled_component inconsistent with the BSDF's flags "
                        f"({int(empty.sum())} empty, {int(foreign.sum())} not in flags(), "
                        f"{int(out_of_range.sum())} components out of range, "
                        f"{int(wrong_comp.sum())} not in flags(component))")
