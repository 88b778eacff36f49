"""
The candidates of a material: what each of our plugins can be replaced by (switches of its
parameters, a lobe left out, the built-in that computes the same model, cheaper models fitted
with :func:`mi_brdfs.fit.fit`), as ``(label, kind, element or None, note)``; see
:mod:`mi_brdfs.simplify`.
"""

from __future__ import annotations

import copy
import math
import warnings
import xml.etree.ElementTree as ET

import numpy as np

from ..errors import MiBrdfsError, MiBrdfsWarning
from .edit import (
    _as_dict, _diffuse_of, _drop, _from_spec, _params, _retyped, _set, _substituted, _zero,
)
from .measure import _key
from .scene import Material

#: Our plugins: the materials with candidates.
OURS = ("lambert", "phong", "cooktorrance", "ward", "orennayar")


def _lobe_albedos(element: ET.Element, diffuse: str, glossy: str) -> tuple:
    """
    (E_diffuse, E_glossy): mean directional albedo at 45° of each lobe of a two-lobe model
    alone (the other lobe's reflectance set to 0); None where the element does not load.
    """
    from ..bsdfspec import load_bsdf
    from ..checks.albedo import albedo_quadrature

    out = []
    for keep, drop in ((diffuse, glossy), (glossy, diffuse)):
        e = _set(copy.deepcopy(element), "float", drop, 0.0)
        try:
            bsdf = load_bsdf(ET.tostring(e, encoding="unicode"))
            out.append(float(np.mean(albedo_quadrature(bsdf, math.radians(45.0), 64, 64))))
        except (MiBrdfsError, RuntimeError):
            return None, None
    return tuple(out)


def _two_lobes(element, values, kind: str) -> list:
    """The weaker lobe of a phong, ward or cooktorrance (with a diffuse base) left out."""
    defaults = {"phong": (0.5, 0.2), "ward": (0.5, 0.2), "cooktorrance": (0.0, 1.0)}[kind]
    p = _params(values)
    if kind == "cooktorrance" and (p.get("transmission") or "diffuse_reflectance" not in p
                                   or _zero(p.get("diffuse_reflectance"))):
        return []
    if _zero(p.get("diffuse_reflectance")) or _zero(p.get("specular_reflectance")):
        return []  # one lobe already
    e_d, e_s = _lobe_albedos(values, "diffuse_reflectance", "specular_reflectance")
    if e_d is None:
        return []
    shares = f"albedo at 45°: diffuse {e_d:.3g}, glossy {e_s:.3g}"
    if e_d <= e_s:
        return [(f"{kind}, diffuse lobe left out", "lobe left out",
                 _set(copy.deepcopy(element), "float", "diffuse_reflectance", 0.0), shares)]
    return [("diffuse: the glossy lobe left out", "lobe left out",
             _diffuse_of(element, "diffuse_reflectance", defaults[0]), shares)]


def _to_roughconductor(element, p) -> tuple | None:
    """cooktorrance (reflection) → roughconductor with the same α, distribution and IOR."""
    if p.get("transmission") or not _zero(p.get("diffuse_reflectance", 0.0)) \
            or p.get("fresnel", "exact") == "schlick":
        return None
    out = _drop(_retyped(element, "roughconductor"), "shadowing", "fresnel", "diffuse_reflectance")
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
    return ("roughconductor", "built-in", out, note)


def _to_roughdielectric(element, p) -> tuple | None:
    """cooktorrance transmission=true → roughdielectric (same α, distribution, indices)."""
    if p.get("fresnel", "exact") != "exact":
        return None
    out = _drop(_retyped(element, "roughdielectric"), "transmission", "shadowing", "fresnel")
    if "eta" in p:
        if not isinstance(p["eta"], float):
            return None
        _drop(out, "eta", "k")
        _set(out, "float", "int_ior", p["eta"])
        _set(out, "float", "ext_ior", 1.0)
    return ("roughdielectric", "built-in", out, "the same model (Walter et al. 2007)")


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
    elif kind in ("phong", "ward") and spec is not None and not _zero(p.get("diffuse_reflectance")):
        e_d, e_s = _lobe_albedos(values, "diffuse_reflectance", "specular_reflectance")
        if e_d is not None and e_s < e_d:
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
    out += _switches(element, p, kind)
    if kind in ("phong", "ward", "cooktorrance"):
        out += _two_lobes(element, subst, kind)
    if fit_fn is not None:
        out += _fit_candidates(element, subst, kind, fit_fn)
    return out


#: The start of the note of a fit that is not offered as a candidate (its flags follow).
NOT_OFFERED = "fit not offered"


def _fit(target: dict, model: dict, free, sizes: dict):
    """(fitted spec, residual, albedo error) of :func:`mi_brdfs.fit.fit`, in an AD variant; a
    note why not (a str) for a fit with flags (:mod:`mi_brdfs.fit.flags`): a fit at a bound,
    no better than the zero model or unphysical is no candidate."""
    import drjit as dr
    import mitsuba as mi

    import mi_brdfs
    from ..fit import fit

    ad = dr.is_diff_v(mi.Float) and mi.is_rgb and not mi.is_polarized
    if not ad and not mi_brdfs.llvm_usable():
        raise MiBrdfsError("fits need llvm_ad_rgb, which this machine lacks")
    # fit hands this variant back when it returns or raises; the plugins' warnings about the
    # models it loads on the way (a start whose ρd + ks exceeds 1) are no news to the user:
    # what matters about the fitted model is in its flags
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        result = fit(target, model, free, variant=None if ad else "llvm_ad_rgb", **sizes)
    if result.flags:
        return f"{NOT_OFFERED}: " + "; ".join(result.flags)
    return result.spec, result.residual, result.albedo_error


def _cached_fit(store, fit_sizes: dict):
    """
    The ``fit_fn(target, model, free)`` of :func:`candidates_for`: :func:`_fit` with
    ``fit_sizes`` (in llvm_ad_rgb where the current variant has no AD), its result (or the note why it failed) stored in ``store``.
    """
    from .. import __version__

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
