"""
The choice: each measured candidate's bias bounds, time to the tolerance and speed-up
(:func:`_derive`), per material the fastest candidate within the tolerance that is simpler and
not measurably slower (or, with the objective ``speed``, measurably faster) (:func:`_choose`),
and the simplified scene's numbers predicted from its parts (:func:`_predict`), with a standard
error, so that the verification can say whether the measured speed-up agrees
(:func:`~mi_brdfs.simplify.report.agreement`).
"""

from __future__ import annotations

import math

from .candidates import NOT_OFFERED
from .report import Candidate, MaterialResult, _ratio

#: The objectives of the choice: ``simplicity`` (the package's principle, model only what the
#: scene requires) replaces a material by a simpler candidate within the tolerance that is not
#: measurably slower; ``speed`` only by a candidate measurably faster.
OBJECTIVES = ("simplicity", "speed")

#: What makes a candidate simpler than the original, by kind, in this order of simplicity.
SIMPLER_KINDS = {
    "built-in": "Mitsuba's built-in of the same model (compiled, no Python plugin)",
    "lobe left out": "a lobe fewer",
    "fit": "a model of fewer lobes or parameters, fitted",
}
#: ... and by switch: a feature left out (a switch that swaps one feature for another, such as
#: the distribution or the sampler, is not simpler).
SIMPLER_SWITCHES = {
    "multiscatter=false": "no energy compensation",
    "form=qualitative": "Oren-Nayar's qualitative form (fewer terms)",
    "fresnel=schlick": "Schlick's approximation of F (a polynomial for the exact formula)",
    "diffuse, σ → 0": "Mitsuba's diffuse (the rough diffuse factor left out)",
}


def simpler(c: Candidate) -> str | None:
    """Why ``c`` is simpler than the original (:data:`SIMPLER_KINDS`,
    :data:`SIMPLER_SWITCHES`), or None where it is not."""
    if c.kind == "switch":
        return SIMPLER_SWITCHES.get(c.label)
    return SIMPLER_KINDS.get(c.kind)


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


def _slower(c: Candidate, confidence: float) -> bool:
    """Whether ``c`` is measurably slower: its speed-up below 1 by ``confidence`` standard
    errors (without a standard error, any speed-up below 1)."""
    if not c.speedup > 0:
        return True
    if not math.isfinite(c.speedup_se) or confidence <= 0:
        return c.speedup < 1
    return math.log(c.speedup) < -confidence * c.speedup_se


def _eligible(c: Candidate, tolerance: float, confidence: float, objective: str) -> bool:
    """Set ``c``'s verdict; whether it may replace the original (within the tolerance, and
    simpler and not measurably slower, or measurably faster, by the ``objective``)."""
    if c.measured.get("nonfinite"):
        c.verdict = "non-finite pixel values"
    elif c.bias_lo > tolerance:
        c.verdict = "over tolerance"
    elif not c.within:
        c.verdict = f"inconclusive: bias bound over tolerance after {c.measured['seeds']} seeds"
    elif objective == "simplicity":
        if simpler(c) is None:
            c.verdict = "within, not simpler"
        elif _slower(c, confidence):
            c.verdict = "within, simpler, measurably slower"
        else:
            c.verdict = "within, simpler, not measurably slower"
            return True
    elif not c.speedup > 1:
        c.verdict = "within, not faster"
    elif not _significant(c, confidence):
        c.verdict = "within, not measurably faster"
    else:
        c.verdict = "within, faster"
        return True
    return False


def _choose(r: MaterialResult, tolerance: float, confidence: float,
            objective: str = "simplicity") -> None:
    """The fastest eligible candidate (:func:`_eligible`) replaces the original, and the
    reason says why; else the original is kept, and the reason says why."""
    original = r.candidates[0]
    original.verdict = "kept"
    best = None
    for c in r.candidates[1:]:
        if not c.ok:
            c.verdict = "not offered" if (c.error or "").startswith(NOT_OFFERED) else "failed"
            continue
        if _eligible(c, tolerance, confidence, objective) and \
                (best is None or c.time_to_tolerance < best.time_to_tolerance):
            best = c
    if len(r.candidates) == 1:
        r.reason = r.reason or ("a wrapper: its nested BSDFs are listed apart"
                                if not r.material.leaf else "no cheaper candidate")
        return
    if best is None:
        within = [c for c in r.candidates[1:] if c.ok and c.within]
        r.reason = ("kept: no candidate within the tolerance" if not within else
                    "kept: no candidate within the tolerance is measurably faster"
                    if objective == "speed" else
                    "kept: no candidate within the tolerance is simpler and not measurably "
                    "slower")
        return
    r.chosen = r.candidates.index(best)
    best.verdict = "**chosen**"
    original.verdict = "replaced"
    why = f"simpler: {simpler(best)}; " if objective == "simplicity" else ""
    r.reason = (f"{best.label}: {why}bias {best.bias:.4f}, time to the tolerance "
                f"{_ratio(best.speedup, best.speedup_se)} the original's"
                + (" (the fastest of the simpler candidates)" if objective == "simplicity"
                   else " faster"))


def _predict(results, ref_numbers, tolerance, original_time) -> dict:
    """The simplified scene's bias, cost, variance and speed-up from its parts."""
    chosen = [r.candidates[r.chosen].measured for r in results if r.chosen]
    b2 = sum(max(me["b2"], 0.0) for me in chosen)
    cost = 1 + sum(me["cost_ratio"] - 1 for me in chosen)
    var = 1 + sum(me["variance_ratio"] - 1 for me in chosen)
    room = tolerance ** 2 - b2
    t = ref_numbers["variance_1spp_ref"] * var * ref_numbers["ref_seconds_per_spp"] * cost / room \
        if room > 0 else math.inf
    # the parts' log-ratio standard errors, independent measurements, add in quadrature
    se = math.sqrt(sum(me["cost_ratio_se"] ** 2 + me["variance_ratio_se"] ** 2
                       for me in chosen)) if chosen else 0.0
    return {"bias": math.sqrt(b2), "cost_ratio": cost, "variance_ratio": var,
            "time_to_tolerance": t, "speedup": original_time / t, "speedup_se": se}

