"""
The choice: each measured candidate's bias bounds, time to the tolerance and speed-up
(:func:`_derive`), the cheapest candidate per material that is within the tolerance and
measurably faster (:func:`_choose`), and the simplified scene's numbers predicted from its
parts (:func:`_predict`).
"""

from __future__ import annotations

import math

from .candidates import NOT_OFFERED
from .report import Candidate, MaterialResult, _ratio


def _derive(c: Candidate, ref: dict, tolerance: float, original_time: float) -> None:
    """
    Bias, its bounds, time to the tolerance and speed-up of a measured candidate; the
    original's cost per spp and 1-spp variance (``ref``) are the same for all, each candidate
    has its ratios to them.
    """
    me = c.measured
    b2 = me["b2"]
    c.bias, c.bias_hi, c.bias_lo = me["bias"], me["bias_hi"], me["bias_lo"]
    variance = ref["variance_1spp_ref"] * me["variance_ratio"]
    cost = ref["ref_seconds_per_spp"] * me["cost_ratio"]
    room = tolerance ** 2 - max(b2, 0.0)
    c.within = c.bias_hi <= tolerance
    c.time_to_tolerance = variance * cost / room if c.within and room > 0 else math.inf
    c.speedup = original_time / c.time_to_tolerance
    c.speedup_se = math.sqrt(me["cost_ratio_se"] ** 2 + me["variance_ratio_se"] ** 2) \
        if math.isfinite(me["cost_ratio_se"]) else math.nan
    if me.get("nonfinite"):
        c.within, c.time_to_tolerance, c.speedup = False, math.inf, 0.0
        c.note = (c.note + "; " if c.note else "") + f"{me['nonfinite']} non-finite pixel values"


def _significant(c: Candidate, confidence: float) -> bool:
    if not c.speedup > 1:
        return False
    if confidence <= 0:
        return True
    if not math.isfinite(c.speedup_se):
        return False
    return math.log(c.speedup) > confidence * c.speedup_se


def _choose(r: MaterialResult, tolerance: float, confidence: float) -> None:
    original = r.candidates[0]
    original.verdict = "kept"
    best = None
    for c in r.candidates[1:]:
        if not c.ok:
            c.verdict = "not offered" if (c.error or "").startswith(NOT_OFFERED) else "failed"
            continue
        if c.measured.get("nonfinite"):
            c.verdict = "non-finite pixel values"
        elif c.bias_lo > tolerance:
            c.verdict = "over tolerance"
        elif not c.within:
            c.verdict = f"inconclusive: bias bound over tolerance after {c.measured['seeds']} seeds"
        elif not c.speedup > 1:
            c.verdict = "within, not faster"
        elif not _significant(c, confidence):
            c.verdict = "within, not measurably faster"
        else:
            c.verdict = "within, faster"
            if best is None or c.time_to_tolerance < best.time_to_tolerance:
                best = c
    if len(r.candidates) == 1:
        r.reason = r.reason or ("a wrapper: its nested BSDFs are listed apart"
                                if not r.material.leaf else "no cheaper candidate")
        return
    if best is None:
        within = [c for c in r.candidates[1:] if c.ok and c.within]
        r.reason = ("kept: no candidate within the tolerance" if not within else
                    "kept: no candidate within the tolerance is measurably faster")
        return
    r.chosen = r.candidates.index(best)
    best.verdict = "**chosen**"
    original.verdict = "replaced"
    r.reason = (f"{best.label}: bias {best.bias:.4f}, time to the tolerance "
                f"{_ratio(best.speedup, best.speedup_se)} faster")


def _predict(results, ref_numbers, tolerance, original_time) -> dict:
    """The simplified scene's bias, cost, variance and speed-up from its parts."""
    chosen = [r.candidates[r.chosen].measured for r in results if r.chosen]
    b2 = sum(max(me["b2"], 0.0) for me in chosen)
    cost = 1 + sum(me["cost_ratio"] - 1 for me in chosen)
    var = 1 + sum(me["variance_ratio"] - 1 for me in chosen)
    room = tolerance ** 2 - b2
    t = ref_numbers["variance_1spp_ref"] * var * ref_numbers["ref_seconds_per_spp"] * cost / room \
        if room > 0 else math.inf
    return {"bias": math.sqrt(b2), "cost_ratio": cost, "variance_ratio": var,
            "time_to_tolerance": t, "speedup": original_time / t}
