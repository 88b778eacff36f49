"""
Helmholtz reciprocity f(a, b) = f(b, a), and positivity (f ≥ 0, pdf ≥ 0), for any BSDF.

``eval`` returns f·cosθo, so f(a, b) = eval(wi=a, wo=b) / cosθ_b. Pairs with either cosine below
``min_cos`` are left out (the division amplifies float32 rounding there).
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf
from ..errors import counts
from . import batch
from .result import CheckResult

#: Relative asymmetry tolerated: float32 evaluation of the same expression with the two
#: directions swapped (measured ≤ 2e-6 for our reciprocal models and Mitsuba's microfacets).
RTOL = 1e-4


def _angles(v: np.ndarray) -> str:
    theta = np.degrees(np.arccos(np.clip(v[2], -1, 1)))
    phi = np.degrees(np.arctan2(v[1], v[0]))
    return f"(θ {theta:.1f}°, φ {phi:.1f}°)"


@counts("n")
def reciprocity(spec, n: int | None = None, seed: int = 0, min_cos: float = 1e-3):
    """
    f(a, b) and f(b, a) at ``n`` random pairs over the upper hemisphere.

    Returns → dict(a, b, f_ab, f_ba, asym): ``asym`` = |f_ab − f_ba| / max(f_ab, f_ba) per pair
    (max over channels; 0 where both are 0).
    """
    bsdf = load_bsdf(spec)
    n = n or (200_000 if batch.is_jit() else 400)
    rng = np.random.default_rng(seed)
    a = batch.random_directions(rng, n, sphere=False)
    b = batch.random_directions(rng, n, sphere=False)
    keep = (a[:, 2] > min_cos) & (b[:, 2] > min_cos)
    a, b = a[keep], b[keep]
    f_ab = batch.evaluate(bsdf, a, b).value / b[:, 2:3]
    f_ba = batch.evaluate(bsdf, b, a).value / a[:, 2:3]
    scale = np.maximum(np.abs(f_ab), np.abs(f_ba))
    asym = np.where(scale > 0, np.abs(f_ab - f_ba) / np.where(scale > 0, scale, 1), 0.0)
    return dict(a=a, b=b, f_ab=f_ab, f_ba=f_ba, asym=np.nan_to_num(asym, nan=np.inf).max(axis=1))


@counts("n")
def check_reciprocity(spec, n: int | None = None, seed: int = 0, rtol: float = RTOL) -> CheckResult:
    """
    Largest relative asymmetry |f(a,b) − f(b,a)| / max over random pairs, and where it occurs.
    A BSDF that declares ``NonSymmetric`` still fails (it is not reciprocal); the message says
    that it declares so.
    """
    bsdf = load_bsdf(spec)
    r = reciprocity(bsdf, n, seed)
    i = int(np.argmax(r["asym"]))
    worst = float(r["asym"][i])
    passed = worst <= rtol
    declared = bool(int(bsdf.flags()) & int(mi.BSDFFlags.NonSymmetric))
    where = (f"a = {_angles(r['a'][i])}, b = {_angles(r['b'][i])}: "
             f"f(a,b) = {r['f_ab'][i, 0]:.6g}, f(b,a) = {r['f_ba'][i, 0]:.6g}")
    msg = (f"reciprocity: {describe(spec)}: max relative asymmetry {worst:.3g} "
           f"({'≤' if passed else '>'} {rtol:g}) at {where}"
           + ("; the BSDF declares NonSymmetric" if declared else ""))
    return CheckResult("reciprocity", passed, worst, rtol, msg,
                       details={"declared_nonsymmetric": declared,
                                "fraction_above_tol": float((r["asym"] > rtol).mean())})


@counts("n")
def check_positivity(spec, n: int | None = None, seed: int = 1) -> CheckResult:
    """
    eval ≥ 0 and pdf ≥ 0 (and finite) at random pairs over the whole sphere and at the stress
    pairs of the stability sweep (normal, grazing, back-facing, mirror, V = −L).
    """
    from .stability import adversarial_pairs

    bsdf = load_bsdf(spec)
    n = n or (200_000 if batch.is_jit() else 400)
    rng = np.random.default_rng(seed)
    stress_wi, stress_wo, _ = adversarial_pairs()
    wi = np.concatenate([stress_wi, batch.random_directions(rng, n, sphere=True)])
    wo = np.concatenate([stress_wo, batch.random_directions(rng, n, sphere=True)])
    n = len(wi)
    e = batch.evaluate(bsdf, wi, wo)
    negative = (e.value < 0).any(axis=1) | (e.pdf < 0)
    nonfinite = ~np.isfinite(e.value).all(axis=1) | ~np.isfinite(e.pdf)
    bad = negative | nonfinite
    passed = not bad.any()
    msg = f"positivity: {describe(spec)}: "
    if passed:
        msg += f"eval and pdf finite and ≥ 0 at {n} stress and random pairs over the sphere"
    else:
        i = int(np.argmax(bad))
        msg += (f"{int(negative.sum())} negative and {int(nonfinite.sum())} non-finite of {n} "
                f"(first: wi = {_angles(wi[i])}, wo = {_angles(wo[i])}, "
                f"eval = {e.value[i].tolist()}, pdf = {e.pdf[i]:g})")
    return CheckResult("positivity", passed, float(bad.sum()), 0, msg,
                       details={"negative": int(negative.sum()), "nonfinite": int(nonfinite.sum())})
