"""
What makes a fit useless or unphysical, said in words on the result (:attr:`FitResult.flags`):
a parameter at a bound of its range, a fit no better than the zero model (the BSDF that returns
0 everywhere), a start whose objective is not finite, and reflectances or an albedo above 1.
``simplify`` offers no flagged fit as a candidate.
"""

from __future__ import annotations

import math

import numpy as np

from .optimise import objective_np
from .parameters import Parameter, base_name

#: How close to a bound (a fraction of the width of the transformed range) counts as at it.
AT_BOUND = 1e-5

#: A fit whose residual (of f·cosθi·cosθo) is below this reproduces its target: a bound it
#: sits at is where the target is, not a limit that binds.
EXACT = 1e-3


def _natural_lower(name: str) -> bool:
    """Whether the lower bound of ``name`` is a physical value, not a limit of the model: k = 0
    (a dielectric), a reflectance of 0 (no such lobe), σ at its floor (Lambert), ``hapke``'s
    B_0 = 0 or h = 0 (no opposition surge) and θ̄ = 0 (a smooth surface), a calm sea."""
    return name in ("k", "sigma", "B_0", "h", "theta", "wind_speed") \
        or base_name(name).endswith(("reflectance", "transmittance"))


#: Models whose albedo at normal incidence is about ρd + ks (phong in its normalized form), or
#: ρd + Σ ρs,i over the lobes (lafortune in its normalized form, Lafortune et al. 1997 with
#: Phong's normalisation per lobe). Not ``ashikhmin``: its diffuse term is weighed by 1 − Rs
#: and its specular albedo is at most Rs + (1 − Rs)(1 − cosθi/2)⁵, so it conserves energy for
#: every Rs, Rd in [0, 1] (Ashikhmin & Shirley 2000, their diffuse term).
_SUMMED = ("phong", "ward", "cooktorrance", "lafortune")

#: The models of :data:`_SUMMED` whose sum holds in one form only: (parameter, that form).
_SUMMED_FORM = {"phong": ("form", "normalized"), "lafortune": ("normalize", True)}


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


def _zero_model(figures: dict, wi, wo, target_values, loss: float, metric: str) -> list[str]:
    """
    Flags of a fit no better than the zero model, by the residual of f·cosθi·cosθo (the light
    each pair carries under uniform illumination), the albedo and the objective. Not by the
    residual of f·cosθo: a few grazing pairs, where f·cosθo of a glossy target or of ward
    (1/√(cosθi cosθo)) and ashikhmin (1/max(cosθi, cosθo)) grows without bound, rule it, and it
    passes 1 for fits that carry the target's light well (`mi-brdfs fit roughconductor --model
    ashikhmin`: 4.1, against 0.098 weighted by cosθi).
    """
    out = []
    for name in ("residual", "residual_projected"):
        value = figures[name]
        if not math.isfinite(value):
            out.append(f"{name} is {value}: the fitted BSDF's values are not finite")
    if figures["residual_projected"] >= 1.0:
        out.append(f"residual of f·cosθi·cosθo {figures['residual_projected']:.4g} ≥ 1, the "
                   f"zero model's (a BSDF that returns 0 everywhere): the fit is no better than "
                   f"no reflection at all")
    zero_albedo = float(np.max(np.abs(figures["albedo_target"])))
    if not math.isfinite(figures["albedo_error"]):
        out.append(f"albedo error is {figures['albedo_error']}")
    elif figures["albedo_error"] >= zero_albedo > 0:
        out.append(f"albedo error {figures['albedo_error']:.4g} ≥ the zero model's "
                   f"{zero_albedo:.4g}")
    zero_loss = objective_np(metric, np.zeros_like(target_values), np.asarray(wi),
                             np.asarray(wo), target_values)
    if math.isfinite(loss) and loss >= zero_loss:
        out.append(f"objective {loss:.4g} ≥ the zero model's {zero_loss:.4g}")
    return out


def _summed(spec: dict) -> list[str]:
    """The reflectances whose sum is about the albedo of ``spec`` at normal incidence
    (:data:`_SUMMED`), when the spec gives the diffuse one and a specular one; else []."""
    kind = spec["type"]
    form = _SUMMED_FORM.get(kind)
    if kind not in _SUMMED or (form and spec.get(form[0], form[1]) != form[1]) \
            or "diffuse_reflectance" not in spec:
        return []
    specular = [k for k in spec if base_name(k) == "specular_reflectance" and _at_normal(spec, k)]
    return ["diffuse_reflectance"] + specular if specular else []


def _at_normal(spec: dict, name: str) -> bool:
    """Whether the lobe of reflectance ``name`` reflects about its ρs at normal incidence: every
    lobe but a ``lafortune`` lobe whose |Cz| is below max(|Cx|, |Cy|), which leans towards
    grazing angles (Lafortune et al. 1997's off-specular lobe: (|Cz|/max|C|)ⁿ ρs there)."""
    index = name[len("specular_reflectance_"):]
    if not index:
        return True
    c = [abs(float(spec.get(f"c{axis}_{index}", default)))
         for axis, default in zip("xyz", (-1.0, -1.0, 1.0))]  # the plugin's mirror lobe
    return c[2] >= max(c)


def _energy(spec: dict, figures: dict) -> list[str]:
    """Flags of an unphysical fitted BSDF: ρd + ks (+ ...) > 1, an albedo above 1."""
    out = []
    names = _summed(spec)
    if names:
        channels = [np.broadcast_to(np.asarray(spec[n]["value"] if isinstance(spec[n], dict)
                                               else spec[n], dtype=np.float64), 3)
                    for n in names]
        total = float(np.max(np.sum(channels, axis=0)))
        if total > 1.0 + 1e-3:
            out.append(f"{' + '.join(names)} = {total:.4g} > 1: the fitted {spec['type']} "
                       f"reflects more light than it receives")
    albedo = np.asarray(figures["albedo_fit"], dtype=np.float64)
    if albedo.size and float(np.nanmax(albedo)) > 1.0 + 1e-3:
        i = np.unravel_index(int(np.nanargmax(albedo)), albedo.shape)[0]
        out.append(f"the fitted albedo E(θ) reaches {float(np.nanmax(albedo)):.4g} > 1 (at "
                   f"θ = {figures['thetas_deg'][i]:g}°): unphysical")
    return out


def fit_flags(params: list[Parameter], written: dict, spec: dict, runs: dict, best: str,
              figures: dict, wi, wo, target_values, metric: str = "cuberoot") -> list[str]:
    """
    Every flag of a fit, one line each (empty: none): parameters at a bound
    (:data:`AT_BOUND`; unless the fit reproduces its target, :data:`EXACT`), residuals, albedo error or objective no better than the zero model's,
    starts whose objective is not finite, and an unphysical fitted BSDF.
    """
    out = _at_bounds(params, written) if not figures["residual_projected"] < EXACT else []
    out += _zero_model(figures, wi, wo, target_values, runs[best][1], metric)
    out += [f"the start '{label}' diverged (objective {loss})"
            for label, (_, loss) in runs.items() if not math.isfinite(loss)]
    out += _energy(spec, figures)
    return out
