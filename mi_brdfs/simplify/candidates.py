"""
The candidates of a material: what each of our plugins can be replaced by (switches of its
parameters, a lobe left out, the built-in that computes the same model, cheaper models fitted
with :func:`mi_brdfs.fit.fit`), as ``(label, kind, element or None, note)``; see
:mod:`mi_brdfs.simplify`.
"""

from __future__ import annotations

import copy
import math
import re
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from ..errors import MiBrdfsError, MiBrdfsWarning
from ..registry import PLUGINS
from .edit import (
    _as_dict, _diffuse_of, _drop, _from_spec, _params, _retyped, _set, _substituted, _zero,
)
from .measure import _key
from .scene import Material

#: Our plugins (:data:`mi_brdfs.registry.PLUGINS`): the materials simplify finds candidates for.
OURS = tuple(PLUGINS)

#: Our plugins for which no candidate applies in any configuration, and why.
NO_CANDIDATES = {
    "merl": "measured data, which no switch, lobe left out or built-in reproduces, and no "
            "model is fitted to it here",
    "he": "no switch, lobe left out or built-in is offered for He et al.'s model, and no "
          "model is fitted to it here",
}

#: A ``lafortune`` lobe property: its kind, "_", the lobe's index (as the plugin reads them).
_LOBE_PROPERTY = re.compile(r"^(cx|cy|cz|exponent|specular_reflectance)_(0|[1-9][0-9]*)$")


def _lafortune_terms(p: dict) -> list[str]:
    """
    The reflectances of a ``lafortune``'s terms that are not the constant 0, in component
    order: ``diffuse_reflectance``, then ``specular_reflectance_i`` of each lobe (one more lobe
    than the largest index of a lobe property, as the plugin counts them; one when none).
    """
    indices = [int(m.group(2)) for m in map(_LOBE_PROPERTY.match, p) if m]
    lobes = max(indices) + 1 if indices else 1
    names = ["diffuse_reflectance"] + [f"specular_reflectance_{i}" for i in range(lobes)]
    return [n for n in names if not _zero(p.get(n))]


def _terms(p: dict, kind: str) -> list[str]:
    """The reflectances of the terms of a model with several, but for those that are 0."""
    if kind == "lafortune":
        return _lafortune_terms(p)
    return [n for n in ("diffuse_reflectance", "specular_reflectance") if not _zero(p.get(n))]


#: Incident angles (degrees) at which a term's albedo is weighed: 45°, and for ``lafortune``,
#: whose off-specular lobes (|Cz| < max|C|) reflect little but towards grazing incidence and
#: whose retro-reflective ones (Cx, Cy > 0) most towards normal incidence, the mean of three.
_THETAS = {"lafortune": (15.0, 45.0, 75.0)}


def _albedo(element: ET.Element, thetas=(45.0,)) -> float | None:
    """The directional albedo of ``element``, mean over RGB and the incident angles ``thetas``
    (degrees); None where it does not load."""
    from ..bsdfspec import load_bsdf
    from ..checks.albedo import albedo_quadrature

    try:
        bsdf = load_bsdf(ET.tostring(element, encoding="unicode"))
        return float(np.mean([albedo_quadrature(bsdf, math.radians(t), 64, 64)
                              for t in thetas]))
    except (MiBrdfsError, RuntimeError):
        return None


def _term_albedos(element: ET.Element, kind: str) -> dict | None:
    """
    {reflectance: directional albedo of that term alone (at :data:`_THETAS`)} of each term of
    :func:`_terms` (each alone: the others' reflectances set to 0); None where an element does
    not load. ``ashikhmin``'s glossy lobe is never 0 (F reaches 1 at grazing angles) and its
    Rs weighs the diffuse term, so there the diffuse term's albedo is the whole's less that of
    the glossy lobe alone (Rd = 0).
    """
    if kind == "ashikhmin":
        whole = _albedo(element)
        glossy = _albedo(_set(copy.deepcopy(element), "float", "diffuse_reflectance", 0.0))
        if whole is None or glossy is None:
            return None
        return {"diffuse_reflectance": whole - glossy, "specular_reflectance": glossy}
    names, out = _terms(_params(element), kind), {}
    for keep in names:
        e = copy.deepcopy(element)
        for drop in names:
            if drop != keep:
                _set(e, "float", drop, 0.0)
        out[keep] = _albedo(e, _THETAS.get(kind, (45.0,)))
        if out[keep] is None:
            return None
    return out


def _term_label(name: str) -> str:
    """A term of :func:`_terms` in words: diffuse, glossy, lobe i."""
    if name == "diffuse_reflectance":
        return "diffuse"
    return "glossy" if name == "specular_reflectance" else f"lobe {name.rsplit('_', 1)[1]}"


#: The diffuse reflectance of each model where the element gives none.
_DIFFUSE_DEFAULTS = {"phong": 0.5, "ward": 0.5, "cooktorrance": 0.0, "ashikhmin": 0.5,
                     "lafortune": 0.5}


def _two_lobes(element, values, kind: str) -> list:
    """
    The weakest term left out: of a phong, ward, cooktorrance (with a diffuse base) or
    lafortune (its diffuse term or a lobe), and of an ashikhmin its diffuse term only (the
    glossy lobe cannot be left out: F reaches 1 at grazing angles whatever Rs).
    """
    p = _params(values)
    if kind == "cooktorrance" and (p.get("transmission") or "diffuse_reflectance" not in p
                                   or _zero(p.get("diffuse_reflectance"))):
        return []
    terms = _terms(p, kind)
    if len(terms) < 2:
        return []  # one lobe already
    albedos = _term_albedos(values, kind)
    if albedos is None:
        return []
    thetas = _THETAS.get(kind, (45.0,))
    shares = (f"albedo at {thetas[0]:g}°: " if len(thetas) == 1 else
              f"mean albedo at {', '.join(f'{t:g}°' for t in thetas)}: ") + ", ".join(
        f"{_term_label(n)} {e:.3g}" for n, e in albedos.items())
    weakest = min(albedos, key=albedos.get)  # the first of equals: the diffuse term
    if weakest == "diffuse_reflectance":
        term = "term" if kind in ("ashikhmin", "lafortune") else "lobe"
        return [(f"{kind}, diffuse {term} left out", "lobe left out",
                 _set(copy.deepcopy(element), "float", "diffuse_reflectance", 0.0), shares)]
    if kind == "ashikhmin":
        return []
    if terms == ["diffuse_reflectance", weakest]:
        return [("diffuse: the glossy lobe left out", "lobe left out",
                 _diffuse_of(element, "diffuse_reflectance", _DIFFUSE_DEFAULTS[kind]), shares)]
    return [(f"lafortune, {_term_label(weakest)} left out", "lobe left out",
             _set(copy.deepcopy(element), "float", weakest, 0.0), shares)]


def _to_phong(element, p) -> tuple | None:
    """
    A normalized ``lafortune`` with one lobe, Phong's mirror lobe (-Cx = -Cy = Cz > 0, or no
    coefficient: the default), → ``phong`` (mirror lobe, normalized form): the same model, as
    the plugin computes it (Lafortune et al. 1997 after Lafortune & Willems 1994).
    """
    if p.get("normalize", True) is not True or "specular_reflectance_0" not in _terms(
            p, "lafortune") or any(_LOBE_PROPERTY.match(n) and not n.endswith("_0") for n in p):
        return None  # the paper's form, no lobe or more than one
    c = [p.get(f"c{axis}_0", default) for axis, default in zip("xyz", (-1.0, -1.0, 1.0))]
    if not all(isinstance(v, float) for v in c) or not (-c[0] == -c[1] == c[2] > 0):
        return None
    out = _drop(_retyped(element, "phong"), "normalize", "cx_0", "cy_0", "cz_0")
    for child in out:
        if child.get("name") in ("exponent_0", "specular_reflectance_0"):
            child.set("name", child.get("name")[:-2])
    return ("phong", "switch", out, "the same model (Phong's normalized mirror lobe)")


def _to_roughconductor(element, p) -> tuple | None:
    """cooktorrance (reflection) → roughconductor with the same α, distribution and IOR."""
    if p.get("transmission") or not _zero(p.get("diffuse_reflectance", 0.0)) \
            or p.get("fresnel", "exact") == "schlick":
        return None
    out = _drop(_retyped(element, "roughconductor"), "shadowing", "fresnel", "diffuse_reflectance",
                "multiscatter")
    if p.get("fresnel") == "none":
        _drop(out, "material", "eta", "k")
        _set(out, "string", "material", "none")
    elif "material" not in p and "eta" not in p:
        _set(out, "string", "material", "Cu")  # cooktorrance's default metal
    elif "eta" in p and "k" not in p:
        _set(out, "float", "k", 0.0)  # cooktorrance's k defaults to 0, roughconductor's to 1
    smith = p.get("shadowing", "vcavity") == "smith"
    note = "the same model (Smith masking)" if smith else \
        "Smith's masking in place of the V-cavity's"
    if p.get("multiscatter") is True:
        note = ("single scattering (no energy compensation), "
                + ("Smith masking" if smith else note))
    return ("roughconductor", "built-in", out, note)


def _to_roughdielectric(element, p) -> tuple | None:
    """cooktorrance transmission=true → roughdielectric (same α, distribution, indices)."""
    if p.get("fresnel", "exact") != "exact":
        return None
    out = _drop(_retyped(element, "roughdielectric"), "transmission", "shadowing", "fresnel",
                "multiscatter")
    if "eta" in p:
        if not isinstance(p["eta"], float):
            return None
        _drop(out, "eta", "k")
        _set(out, "float", "int_ior", p["eta"])
        _set(out, "float", "ext_ior", 1.0)
    note = "single scattering (no energy compensation), Walter et al. 2007" \
        if p.get("multiscatter") is True else "the same model (Walter et al. 2007)"
    return ("roughdielectric", "built-in", out, note)


def _switches(element, p, kind) -> list:
    out = []
    if kind == "cooktorrance":
        if p.get("fresnel", "exact") == "exact" and not p.get("transmission"):
            out.append(("fresnel=schlick", "switch",
                        _set(copy.deepcopy(element), "string", "fresnel", "schlick"),
                        "Schlick's approximation of F (R0 from η, k)"))
        other = "ggx" if p.get("distribution", "beckmann") == "beckmann" else "beckmann"
        out.append((f"distribution={other}", "switch",
                    _set(copy.deepcopy(element), "string", "distribution", other),
                    "the same α"))
        if p.get("multiscatter") is True:
            out.append(("multiscatter=false", "switch",
                        _set(copy.deepcopy(element), "boolean", "multiscatter", False),
                        "single scattering: the energy compensation left out"))
        visible = p.get("sample_visible", True)
        out.append((f"sample_visible={str(not visible).lower()}", "switch",
                    _set(copy.deepcopy(element), "boolean", "sample_visible", not visible),
                    "the same model, another sampler"))
    if kind == "orennayar" and p.get("form", "qualitative") == "full":
        out.append(("form=qualitative", "switch",
                    _set(copy.deepcopy(element), "string", "form", "qualitative"),
                    "without the interreflection and C2, C3 terms"))
    return out


def _fit_candidates(element, values, kind, fit_fn) -> list:
    """Fitted cheaper models: (label, kind, element, note), or a note where none fits."""
    spec = _as_dict(values)
    p = _params(values)
    jobs = []
    if kind == "orennayar":
        if spec is None:
            return [("diffuse, σ → 0", "switch", _diffuse_of(element, "reflectance", 0.5),
                     "the same ρ (a texture: not fitted)")]
        rho = spec.get("reflectance", 0.5)
        jobs.append(({"type": "lambert", "reflectance": rho}, None))
    elif kind in ("phong", "ward", "ashikhmin", "lafortune") and spec is not None \
            and not _zero(p.get("diffuse_reflectance")):
        albedos = _term_albedos(values, kind)  # a fitted lambert where the glossy part is weaker
        diffuse = (albedos or {}).pop("diffuse_reflectance", None)
        if diffuse is not None and sum(albedos.values()) < diffuse:
            jobs.append(({"type": "lambert", "reflectance": spec.get("diffuse_reflectance", 0.5)},
                         None))
    elif kind == "cooktorrance" and spec is not None and not p.get("transmission") \
            and "alpha_u" not in p:
        rho = spec.get("diffuse_reflectance", 0.0)
        model = {"type": "phong", "lobe": "halfway", "diffuse_reflectance": rho,
                 "specular_reflectance": 1.0, "exponent": 30.0}
        free = "specular_reflectance,exponent" + ("" if _zero(rho) else ",diffuse_reflectance")
        jobs.append((model, free))
    out = []
    for model, free in jobs:
        fitted = fit_fn(spec, model, free)
        if isinstance(fitted, str):
            out.append((f"{model['type']} (fit)", "fit", None, fitted))
            continue
        result_spec, residual, albedo_error = fitted
        if result_spec["type"] == "lambert":
            result_spec = dict(result_spec, type="diffuse")  # lambert computes what diffuse does
            label = "diffuse (fitted lambert)"
        else:
            label = "phong halfway (fitted)"
        note = (f"fit residual {residual:.3g}, max |ΔE(θ)| {albedo_error:.3g}: "
                + " ".join(f"{k}={_short(v)}" for k, v in result_spec.items() if k != "type"))
        out.append((label, "fit", _from_spec(result_spec, element), note))
    return out


def _short(value) -> str:
    if isinstance(value, dict):
        return ",".join(f"{v:.4g}" for v in value["value"])
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def kept_reason(material: Material, fits: bool) -> str:
    """Why a material has no candidate, in words (the table's "kept: ...")."""
    from ..registry import builtin_plugin_names

    kind = material.type
    if not material.leaf:
        refs = [ref for ref, _ in material.refs]
        return ("a wrapper: its nested BSDFs are listed apart" if not refs else
                f"a wrapper of {', '.join(refs)} (<ref>): the BSDFs it references are listed "
                f"apart (where they are defined in this file)")
    if "$" in kind:
        return (f"its type is {kind}, chosen by a <default> or -D: left alone (a replacement "
                f"measured for one plugin would be wrong for another)")
    if kind in builtin_plugin_names():
        return "a built-in of Mitsuba: no cheaper candidate"
    if kind not in OURS:
        return (f"{kind} is not a plugin of mi_brdfs ({', '.join(OURS)}): simplify has no "
                f"candidates for it")
    if kind in NO_CANDIDATES:
        return (f"simplify has no candidates for {kind} ({NO_CANDIDATES[kind]}): fit models "
                f"to it with mi-brdfs fit TARGET --models all and try the best in the scene")
    reason = "no cheaper candidate applies to this configuration" + ("" if fits else
                                                                       " (fits off)")
    named = [ref for ref, name in material.refs if name]
    if named:
        reason += (f"; the candidates that need its parameters' values (a lobe left out, a fit) "
                   f"cannot read {', '.join(named)} (a <ref> to an object defined apart)")
    return reason


def candidates_for(material: Material, values: dict, fit_fn) -> list:
    """
    The candidates of one material: ``(label, kind, element or None, note)`` each, without
    the original (see the module docstring). ``values``: the scene's defaults and defines, for
    the ``$name`` references of its parameters. ``fit_fn(target, model, free)`` → (spec,
    residual, albedo error) or a note why not.
    """
    if not material.leaf or material.type not in OURS:
        return []
    element = material.element()
    subst = _substituted(element, values)
    p = _params(subst)
    kind = material.type
    out = []
    if kind == "lambert":
        out.append(("diffuse", "built-in", _retyped(element, "diffuse"),
                    "the same model (lambert computes what diffuse computes)"))
    if kind == "cooktorrance":
        builtin = _to_roughdielectric(element, p) if p.get("transmission") else \
            _to_roughconductor(element, p)
        if builtin:
            out.append(builtin)
    if kind == "lafortune" and _to_phong(element, p):
        out.append(_to_phong(element, p))
    out += _switches(element, p, kind)
    if kind in ("phong", "ward", "cooktorrance", "ashikhmin", "lafortune"):
        out += _two_lobes(element, subst, kind)
    if fit_fn is not None:
        out += _fit_candidates(element, subst, kind, fit_fn)
    return out


#: The start of the note of a fit that is not offered as a candidate (its flags follow).
NOT_OFFERED = "fit not offered"


def _fit(target: dict, model: dict, free, sizes: dict):
    """(fitted spec, residual, albedo error) of :func:`mi_brdfs.fit.fit` (which fits in
    ``llvm_ad_rgb`` from a variant without AD, and hands this variant back); a note why not
    (a str) for a fit with flags (:mod:`mi_brdfs.fit.flags`): a fit at a bound, no better
    than the zero model or unphysical is no candidate."""
    from ..fit import fit

    # the plugins' warnings about the models it loads on the way (a start whose ρd + ks
    # exceeds 1) are no news to the user: what matters about the fitted model is in its flags
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        result = fit(target, model, free, **sizes)
    if result.flags:
        return f"{NOT_OFFERED}: " + "; ".join(result.flags)
    return result.spec, result.residual, result.albedo_error


def _cached_fit(store, fit_sizes: dict):
    """
    The ``fit_fn(target, model, free)`` of :func:`candidates_for`: :func:`_fit` with
    ``fit_sizes`` (in llvm_ad_rgb where the current variant has no AD), its result (or the
    note why it failed) stored in ``store``.
    """
    from .._version import __version__

    def fit_fn(target, model, free):
        key = _key("fit", target, model, free, fit_sizes, __version__, "flags")
        record = store.get(key)
        if record is not None:
            return record["result"] if "result" in record else record["note"]
        try:
            result = _fit(target, model, free, fit_sizes)
            stored = {"note": result} if isinstance(result, str) else {"result": result}
        except MiBrdfsError as e:
            result = f"fit failed: {e}"
            stored = {"note": result}
        store.put(key, stored)
        return result

    return fit_fn
