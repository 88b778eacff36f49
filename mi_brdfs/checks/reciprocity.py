"""
Helmholtz reciprocity f(a, b) = f(b, a), and positivity (f ≥ 0, pdf ≥ 0), for any BSDF.

``eval`` returns f·cosθo, so f(a, b) = eval(wi=a, wo=b) / cosθ_b. Pairs with either cosine below
``min_cos`` are left out (the division amplifies float32 rounding there).
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import arguments, counts, nonnegative, valid_seed
from . import batch
from .result import CheckResult

#: Relative asymmetry tolerated: float32 evaluation of the same expression with the two
#: directions swapped (for our reciprocal models and Mitsuba's microfacets, rounding far below
#: this).
RTOL = 1e-4

#: ... plus CONDITIONING·ε₃₂/min(cosθa, cosθb)² near grazing, where a BSDF that computes an
#: internal quantity from one direction only (e.g. pplastic's exit transmittance from the
#: refracted cosine) loses that much in float32, in one order of the pair and not the other;
#: perturbing the inputs by an ulp does not reveal it, the rounding being internal.
CONDITIONING = 4.0
EPS32 = 2.0 ** -23


def _angles(v: np.ndarray) -> str:
    theta = np.degrees(np.arccos(np.clip(v[2], -1, 1)))
    phi = np.degrees(np.arctan2(v[1], v[0]))
    return f"(θ {theta:.1f}°, φ {phi:.1f}°)"


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, min_cos=nonnegative)
def reciprocity(spec, n: int | None = None, seed: int = 0, min_cos: float = 1e-3):
    """
    f(a, b) and f(b, a) at ``n`` random pairs over the upper hemisphere (every other pair
    over the lower one where the BSDF declares ``BackSide``).

    Returns → dict(a, b, f_ab, f_ba, asym, tol): ``asym`` = |f_ab − f_ba| / max(f_ab, f_ba) per
    pair (max over channels; 0 where both are 0), ``tol`` the pair's tolerance (:data:`RTOL`
    plus the float32 conditioning at its smaller cosine).
    """
    bsdf = load_bsdf(spec)
    n = n or (200_000 if batch.is_jit() else 400)
    rng = np.random.default_rng(seed)
    a = batch.random_directions(rng, n, sphere=False)
    b = batch.random_directions(rng, n, sphere=False)
    keep = (a[:, 2] > min_cos) & (b[:, 2] > min_cos)
    a, b = a[keep], b[keep]
    if int(bsdf.flags()) & int(mi.BSDFFlags.BackSide):
        # its back too: every other pair below the surface (reflection there is reciprocal as
        # above; a pair across a refracting interface is not, by η², and is not drawn)
        a[1::2, 2] *= -1.0
        b[1::2, 2] *= -1.0
    f_ab = batch.evaluate(bsdf, a, b).value / np.abs(b[:, 2:3])
    f_ba = batch.evaluate(bsdf, b, a).value / np.abs(a[:, 2:3])
    scale = np.maximum(np.abs(f_ab), np.abs(f_ba))
    asym = np.where(scale > 0, np.abs(f_ab - f_ba) / np.where(scale > 0, scale, 1), 0.0)
    tol = RTOL + CONDITIONING * EPS32 / np.minimum(np.abs(a[:, 2]), np.abs(b[:, 2])) ** 2
    return dict(a=a, b=b, f_ab=f_ab, f_ba=f_ba, asym=np.nan_to_num(asym, nan=np.inf).max(axis=1),
                tol=tol)


#: Wrappers that replace the shading frame (a normal or bump map): Veach (1997, §5.3) shows
#: that shading normals make any BSDF non-reciprocal, so their asymmetry is expected.
FRAME_WRAPPERS = ("NormalMap", "BumpMap")


def expected_asymmetry(bsdf) -> str | None:
    """Why ``bsdf`` is not expected to be reciprocal (it declares ``NonSymmetric``, or it
    replaces the shading frame), else None."""
    if int(bsdf.flags()) & int(mi.BSDFFlags.NonSymmetric):
        return "the BSDF declares NonSymmetric"
    name = bsdf.class_name() if hasattr(bsdf, "class_name") else type(bsdf).__name__
    if name in FRAME_WRAPPERS:
        return f"{name} replaces the shading frame (shading normals: Veach 1997, §5.3)"
    return None


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, rtol=nonnegative)
def check_reciprocity(spec, n: int | None = None, seed: int = 0, rtol: float = RTOL) -> CheckResult:
    """
    Largest relative asymmetry |f(a,b) − f(b,a)| / max over random pairs, and where it occurs.
    A BSDF that declares ``NonSymmetric`` or replaces the shading frame
    (:func:`expected_asymmetry`) is not expected to be reciprocal: its asymmetry is measured
    and reported, and the check passes as "not reciprocal, as expected".
    """
    bsdf = load_bsdf(spec)
    r = reciprocity(bsdf, n, seed)
    tol = r["tol"] - RTOL + rtol
    i = int(np.argmax(r["asym"] / tol))
    worst = float(r["asym"][i])
    reciprocal = bool((r["asym"] <= tol).all())
    why = expected_asymmetry(bsdf)
    where = (f"a = {_angles(r['a'][i])}, b = {_angles(r['b'][i])}: "
             f"f(a,b) = {r['f_ab'][i, 0]:.6g}, f(b,a) = {r['f_ba'][i, 0]:.6g}")
    msg = (f"reciprocity: {describe(spec)}: {'largest' if reciprocal else 'worst'} relative "
           f"asymmetry {worst:.3g} against its tolerance {tol[i]:.3g} ({rtol:g} + float32 "
           f"conditioning at the smaller cosine) at {where}")
    if why:
        msg += f"; not expected to be reciprocal: {why}"
    return CheckResult("reciprocity", reciprocal or why is not None, worst, rtol, msg,
                       details={"declared_nonsymmetric": bool(
                                    int(bsdf.flags()) & int(mi.BSDFFlags.NonSymmetric)),
                                "expected_asymmetry": why, "reciprocal": reciprocal,
                                "fraction_above_tol": float((r["asym"] > tol).mean())})


@loaded_once()
@counts("n")
@arguments(seed=valid_seed)
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
    # A BSDF that does not transmit scatters nothing, and samples nothing, across the surface:
    # eval and pdf are exactly 0 where cosθi·cosθo ≤ 0 (a wrapper that replaces the shading
    # frame judges the sides in its own frame, and is left out)
    across = np.zeros(n, dtype=bool)
    if not int(bsdf.flags()) & int(mi.BSDFFlags.Transmission) and \
            not (expected_asymmetry(bsdf) or "").endswith("§5.3)"):
        across = (wi[:, 2] * wo[:, 2] <= 0) & ((e.value != 0).any(axis=1) | (e.pdf != 0)) & \
            ~nonfinite
    bad = negative | nonfinite | across
    passed = not bad.any()
    msg = f"positivity: {describe(spec)}: "
    if passed:
        msg += (f"eval and pdf finite and ≥ 0 at {n} stress and random pairs over the sphere"
                + ("" if int(bsdf.flags()) & int(mi.BSDFFlags.Transmission) else
                   ", and 0 across the surface"))
    else:
        i = int(np.argmax(bad))
        msg += (f"{int(negative.sum())} negative, {int(nonfinite.sum())} non-finite and "
                f"{int(across.sum())} non-zero across the surface (a BSDF without transmission) "
                f"of {n} (first: wi = {_angles(wi[i])}, wo = {_angles(wo[i])}, "
                f"eval = {e.value[i].tolist()}, pdf = {e.pdf[i]:g})")
    return CheckResult("positivity", passed, float(bad.sum()), 0, msg,
                       details={"negative": int(negative.sum()), "nonfinite": int(nonfinite.sum()),
                                "across": int(across.sum())})
