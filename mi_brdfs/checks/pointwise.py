"""
Pointwise equality of two BSDFs: ``eval``, ``pdf`` and (optionally) ``sample()`` with the same
random numbers, at random direction pairs over the sphere. This is how a plugin is shown to
reproduce a built-in (lambert = diffuse, cooktorrance with Smith G = roughconductor).
"""

from __future__ import annotations

import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import arguments, counts, nonnegative, valid_seed
from . import batch
from .result import CheckResult


def _rel(a: np.ndarray, b: np.ndarray, atol: float) -> np.ndarray:
    scale = np.maximum(np.abs(a), np.abs(b))
    err = np.abs(a - b) / np.maximum(scale, 1e-30)
    return np.where(np.abs(a - b) <= atol, 0.0, err)


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, rtol=nonnegative, atol=nonnegative)
def check_equal(spec_a, spec_b, n: int | None = None, seed: int = 0, rtol: float = 1e-5,
                atol: float = 1e-7, sample: bool = True, upper: bool = False,
                ctx=None, pdf: bool = True) -> CheckResult:
    """
    Largest relative difference of eval, pdf (unless ``pdf`` is false) and, with ``sample``,
    of sample() (direction, pdf, weight) between two BSDFs over ``n`` random pairs (upper
    hemisphere only with ``upper``). Differences below ``atol`` absolute count as equal (float32
    values near 0). ``details['max']`` holds every quantity's largest difference, compared or not.
    """
    a, b = load_bsdf(spec_a), load_bsdf(spec_b)
    n = n or (100_000 if batch.is_jit() else 500)
    rng = np.random.default_rng(seed)
    wi = batch.random_directions(rng, n, sphere=not upper)
    wo = batch.random_directions(rng, n, sphere=not upper)
    ea, eb = batch.evaluate(a, wi, wo, ctx), batch.evaluate(b, wi, wo, ctx)
    errors = {"eval": _rel(ea.value, eb.value, atol).max(axis=1),
              "pdf": _rel(ea.pdf, eb.pdf, atol)}
    if sample:
        u1, u2 = rng.random(n), rng.random((n, 2))
        sa, sb = batch.sample(a, wi, u1, u2, ctx), batch.sample(b, wi, u1, u2, ctx)
        produced = np.any(sa.weight != 0, axis=1) | np.any(sb.weight != 0, axis=1)
        weight_err = _rel(sa.weight, sb.weight, atol).max(axis=1)
        errors["sample weight"] = np.where(produced, weight_err, 0)
        errors["sample pdf"] = np.where(produced, _rel(sa.pdf, sb.pdf, atol), 0)
        # unit vectors: the absolute difference is the relative one
        errors["sample wo"] = np.where(produced, np.abs(sa.wo - sb.wo).max(axis=1), 0)
    worst = {k: float(np.max(v)) for k, v in errors.items()}
    judged = {k: v for k, v in worst.items() if pdf or k != "pdf"}
    name, value = max(judged.items(), key=lambda kv: kv[1])
    i = int(np.argmax(errors[name]))
    passed = value <= rtol
    msg = (f"equal: {describe(spec_a)} vs {describe(spec_b)}: largest relative difference "
           f"{value:.3g} ({name}) over {n} pairs ({'≤' if passed else '>'} {rtol:g}; compared: "
           f"{', '.join(judged)})")
    if not passed:
        msg += f" at wi={np.round(wi[i], 4).tolist()}, wo={np.round(wo[i], 4).tolist()}"
    return CheckResult("equal", passed, value, rtol, msg, details={"max": worst})
