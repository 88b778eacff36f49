"""
What makes a fit useless or unphysical, said in words on the result (:attr:`FitResult.flags`):
a parameter at a bound of its range, a fit no better than the zero model (the BSDF that returns
0 everywhere), a start whose objective is not finite, and reflectances or an albedo above 1.
``simplify`` offers no flagged fit as a candidate.
"""

from __future__ import annotations

import math

import numpy as np

from .optimise import EPSILON
from .parameters import Parameter

#: How close to a bound (a fraction of the width of the transformed range) counts as at it.
AT_BOUND = 1e-5

#: A fit whose residual (of f·cosθi·cosθo) is below this reproduces its target: a bound it
#: sits at is where the target is, not a limit that binds.
EXACT = 1e-3


def _natural_lower(name: str) -> bool:
    """Whether the lower bound of ``name`` is a physical value, not a limit of the model: k = 0
    (a dielectric), a reflectance of 0 (no such lobe), σ at its floor (Lambert)."""
    return name in ("k", "sigma") or name.endswith(("reflectance", "transmittance"))

#: Models whose albedo at normal incidence is about ρd + ks (phong in its normalized form).
_SUMMED = ("phong", "ward", "cooktorrance")


def _show(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(f"{v:.6g}" for v in value) + "]"
    return f"{value:.6g}"


def _at_bounds(params: list[Parameter], written: dict) -> list[str]:
    """A flag for each parameter with a channel at a bound of its range."""
    out = []
    for p in params:
        x_lo, x_hi = p.x_range()
        if not (math.isfinite(x_lo) and math.isfinite(x_hi)):
            continue
        near = AT_BOUND * (x_hi - x_lo)
        x = p.encode(np.asarray(written[p.name], dtype=np.float64).ravel())
        for end, bound, x_bound in (("upper", p.hi, x_hi), ("lower", p.lo, x_lo)):
            if end == "lower" and _natural_lower(p.name):
                continue
            if np.any(np.abs(x - x_bound) <= near):
                out.append(f"{p.name} = {_show(written[p.name])} is at the {end} bound "
                           f"{bound:g} of its range: the best fit lies at or beyond what the "
                           f"model allows")
                break
    return out


def _zero_model(figures: dict, wi, target_values, loss: float) -> list[str]:
    """Flags of a fit no better than the zero model, by each figure and the objective."""
    out = []
    for name in ("residual", "residual_projected"):
        value = figures[name]
        if not math.isfinite(value):
            out.append(f"{name} is {value}: the fitted BSDF's values are not finite")
        elif value >= 1.0:
            out.append(f"{name} {value:.4g} ≥ 1, the zero model's (a BSDF that returns 0 "
                       f"everywhere): the fit is no better than no reflection at all")
    zero_albedo = float(np.max(np.abs(figures["albedo_target"])))
    if not math.isfinite(figures["albedo_error"]):
        out.append(f"albedo error is {figures['albedo_error']}")
    elif figures["albedo_error"] >= zero_albedo > 0:
        out.append(f"albedo error {figures['albedo_error']:.4g} ≥ the zero model's "
                   f"{zero_albedo:.4g}")
    projected = np.asarray(target_values) * np.asarray(wi)[:, 2:3]
    zero_loss = float(np.mean((EPSILON ** (1 / 3) - np.cbrt(projected + EPSILON)) ** 2))
    if math.isfinite(loss) and loss >= zero_loss:
        out.append(f"objective {loss:.4g} ≥ the zero model's {zero_loss:.4g}")
    return out


def _energy(spec: dict, figures: dict) -> list[str]:
    """Flags of an unphysical fitted BSDF: ρd + ks > 1, an albedo above 1."""
    out = []
    summed = spec["type"] in _SUMMED and (spec["type"] != "phong"
                                          or spec.get("form", "normalized") == "normalized")
    if summed and "diffuse_reflectance" in spec and "specular_reflectance" in spec:
        channels = [np.broadcast_to(np.asarray(v["value"] if isinstance(v, dict) else v,
                                               dtype=np.float64), 3)
                    for v in (spec["diffuse_reflectance"], spec["specular_reflectance"])]
        total = float(np.max(channels[0] + channels[1]))
        if total > 1.0 + 1e-3:
            out.append(f"diffuse_reflectance + specular_reflectance = {total:.4g} > 1: the "
                       f"fitted {spec['type']} reflects more light than it receives")
    albedo = np.asarray(figures["albedo_fit"], dtype=np.float64)
    if albedo.size and float(np.nanmax(albedo)) > 1.0 + 1e-3:
        i = np.unravel_index(int(np.nanargmax(albedo)), albedo.shape)[0]
        out.append(f"the fitted albedo E(θ) reaches {float(np.nanmax(albedo)):.4g} > 1 (at "
                   f"θ = {figures['thetas_deg'][i]:g}°): unphysical")
    return out


def fit_flags(params: list[Parameter], written: dict, spec: dict, runs: dict, best: str,
              figures: dict, wi, target_values) -> list[str]:
    """
    Every flag of a fit, one line each (empty: none): parameters at a bound
    (:data:`AT_BOUND`; unless the fit reproduces its target, :data:`EXACT`), residuals, albedo error or objective no better than the zero model's,
    starts whose objective is not finite, and an unphysical fitted BSDF.
    """
    out = _at_bounds(params, written) if not figures["residual_projected"] < EXACT else []
    out += _zero_model(figures, wi, target_values, runs[best][1])
    out += [f"the start '{label}' diverged (objective {loss})"
            for label, (_, loss) in runs.items() if not math.isfinite(loss)]
    out += _energy(spec, figures)
    return out
