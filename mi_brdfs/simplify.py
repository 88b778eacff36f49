"""
Simplify a scene's materials: for every BSDF, cheaper candidates that render the same image
within a tolerance, measured in the user's own scene, and the scene rewritten with the cheapest.

    from mi_brdfs.simplify import simplify
    result = simplify("scenes/showcase.xml", tolerance=0.01, output="simplified.xml")
    print(result.summary())

and ``mi-brdfs simplify SCENE.xml [--tolerance 0.01] [-o simplified.xml] [--report DIR]
[--quick] [--spp N] [-D name=value]``.

**Candidates.** For each ``<bsdf>`` of the scene that is no wrapper (those inside ``twosided``,
``blendbsdf``, ``mask``, ... are found too):

* switches of the plugins: ``cooktorrance`` with ``fresnel=schlick`` (Schlick 1994, "An
  Inexpensive BRDF Model for Physically-based Rendering", CGF 13(3)), the other ``distribution``
  (``beckmann``/``ggx``), the other ``sample_visible``; ``orennayar`` ``form=qualitative``;
* the weaker lobe of a two-lobe model left out (``phong``, ``ward``, ``cooktorrance`` with a
  diffuse base; weaker by directional albedo at 45°): a glossy-only model, or ``diffuse`` with
  the diffuse lobe's reflectance;
* the built-in that computes the same model: ``lambert`` → ``diffuse``; reflecting
  ``cooktorrance`` → ``roughconductor`` (the same α, distribution, material or η/k: exact with
  ``shadowing=smith``, Smith's masking in place of the V-cavity's otherwise);
  ``cooktorrance transmission=true`` → ``roughdielectric``;
* cheaper models fitted with :func:`mi_brdfs.fit.fit`: ``diffuse`` (a fitted ``lambert``) for
  ``orennayar`` and for a ``phong``/``ward`` whose glossy lobe is the weaker, a Blinn-Phong
  ``phong`` for an isotropic ``cooktorrance``.

Built-ins (``diffuse``, ``roughconductor``, ...) get no candidates: they are listed as kept.

**What is measured, per candidate.** The scene is rendered with only that material replaced
(the rest of the XML byte for byte) at k seeds, as is the original scene. With common random
numbers (the same seed for both scenes: a JIT render draws the same random numbers per pixel
and sample, so paths that never meet the replaced material are identical and their difference
is exactly 0), the difference images D_s = C_s − R_s carry only the material's effect and its
own noise; with D̄ their mean and s² their sample variance per pixel,

    bias² = mean(D̄² − s²/k) / mean(R̄)²,

an unbiased estimate of the squared relative RMSE between the converged candidate and the
converged original (s²/k estimates the variance of D̄; on common random numbers: Law & Kelton
2000, "Simulation Modeling and Analysis", 3rd ed., §11.2). Its standard error is estimated
per pixel and channel from the same numbers (for Gaussian noise of variance σ² per seed,
Var = 4b²σ²/k + 2σ⁴/k² + 2σ⁴/((k−1)k²)), times √3 because a pixel's three channels come from
the same paths; the bounds are √(bias² ± 2·SE). k starts at 2 and doubles (4, 8, 16 =
:data:`MAX_SEEDS`) while the bounds straddle the tolerance: the convergence is measured, not
assumed, and a candidate whose bound stays above the tolerance after 16 seeds is
"inconclusive", i.e. not accepted. The **noise** reported beside it is √mean(s²/k)/mean(R̄),
the RMS noise of the bias image's estimate. **FLIP** (Andersson et al. 2020, "FLIP: A
Difference Evaluator for Alternating Images", HPG) is the mean HDR-FLIP of R̄ against C̄, when
``flip-evaluator`` is installed, evaluated on the box where the two differ (see
:func:`_flip_mean`).

The **variance** of a 1-spp image (relative to mean(R̄)²) is N times the per-pixel sample
variance of the k renders of N spp, its ratio to the original's measured at the same seeds.
The **cost per sample** is the time per spp of renders of the candidate interleaved with
renders of the original (R C C R R C ..., the
median of the ratios, after a warm-up render that holds the JIT compilation; see
:mod:`mi_brdfs.benchmark.timing`). As in :mod:`mi_brdfs.benchmark.error_time`, the error of
a render of t seconds is then error² = bias² + V/t with V = variance × cost per spp, so the
**time to reach the tolerance** τ is

    T = V / (τ² − bias²)        (infinite when bias ≥ τ),

and the speed-up of a candidate is T(original)/T(candidate), with a standard error from the
spread of the timing ratios and of the per-pixel variance differences.

**Choice.** Per material, the candidate with the least T among those with bias_hi ≤ τ, and
only when its speed-up exceeds 1 by ``confidence`` standard errors (default 2): a candidate
that is not measurably faster leaves the original in place. The combined bias² is predicted
as the sum of the chosen ones' (replacements whose bias² add up beyond τ² are dropped, the
largest first); then the **simplified scene** (each chosen material's ``<bsdf>...</bsdf>``
text replaced, every other byte of the file kept) is measured as one more candidate, at other
seeds (101, 102, ...) and with its own timing: the verification, with its measured bias and
its predicted and measured speed-up. Should its bias_hi exceed τ, the replacement with the
largest bias is dropped and the scene measured again.

**Cache.** Every measurement is stored (JSON; the original's renders and each candidate's
difference images D_s as compressed .npz, so that a rerun can add seeds), and every fit, under
a key of the
scene file's content hash, the defines, the variant, the spp and timing settings, and the
candidate's text: in ``--report DIR/cache`` or ``~/.cache/mi_brdfs/simplify``
(``$XDG_CACHE_HOME``). The tolerance enters only the choice and the number of seeds, so a
rerun with another tolerance renders only where a bias's bounds straddle the new tolerance
and, where the choice changed, the simplified scene.

**Cost.** In ``llvm_ad_rgb`` a candidate costs one JIT compilation (about 0.5 s for the
showcase), 2 to 16 renders at N spp and the timing renders: the showcase took 138 s (33 s with
``--quick``) on two shared cores. Scalar variants render through :func:`mi_brdfs.render.render`
(processes for Python plugins), and are far slower; but there a Python plugin costs several
times its built-in, which JIT variants trace into the same kernel at about the same cost.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import re
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat
from xml.sax.saxutils import quoteattr

import numpy as np

from .errors import MiBrdfsError, counts, mitsuba_error_line

#: The most seeds rendered per scene while its bias is inconclusive (2, 4, 8, 16).
MAX_SEEDS = 16

#: Our plugins: the materials with candidates.
OURS = ("lambert", "phong", "cooktorrance", "ward", "orennayar")

#: Settings (full, quick): spp per seed, timing repeats, seconds per timing render, resolution
#: of ``--quick`` (through ``-D res=`` where the scene declares that default).
SPP = (64, 16)
REPEATS = (7, 3)
TIMING_S = (0.15, 0.04)
QUICK_RES = 128

#: Fit sizes (full, quick).
FIT_SIZES = ({}, {"pairs": 4096, "steps": 200, "thetas_deg": (0.0, 45.0, 80.0)})

#: Bump when what is measured or how changes: old cache entries are then ignored.
CACHE_VERSION = 1


# -------------------------------------------------------------------------------------------------
# The scene's BSDF elements, with their byte spans
# -------------------------------------------------------------------------------------------------


@dataclass
class Material:
    """A ``<bsdf>`` element of the scene file: its byte span, text, and what it contains."""

    label: str
    type: str
    start: int
    end: int
    line: int
    indent: str
    text: str
    leaf: bool
    parent: str | None = None

    def element(self) -> ET.Element:
        return ET.fromstring(self.text)


def _tag_end(data: bytes, start: int) -> int:
    """The index just past the ``>`` that ends the start tag at ``start`` (quotes respected)."""
    quote = None
    for i in range(start + 1, len(data)):
        c = data[i:i + 1]
        if quote:
            if c == quote:
                quote = None
        elif c in (b'"', b"'"):
            quote = c
        elif c == b">":
            return i + 1
    raise MiBrdfsError("unterminated tag in the scene file")


def scene_bsdfs(data: bytes) -> tuple[list[Material], dict]:
    """
    Every ``<bsdf>`` element of the scene file's bytes, in document order, with its exact byte
    span (comments are skipped: the parser does not report elements inside them), and the
    scene's ``<default>`` values. Raises MiBrdfsError for XML that does not parse.
    """
    parser = expat.ParserCreate()
    stack: list = []
    found: list[Material] = []
    defaults: dict[str, str] = {}

    def start(name, attrs):
        entry = {"name": name, "attrs": attrs, "start": parser.CurrentByteIndex,
                 "line": parser.CurrentLineNumber, "bsdf_children": 0, "label": None}
        parents = [e for e in stack if e["name"] == "bsdf"]
        if name == "bsdf":
            if parents:
                parents[-1]["bsdf_children"] += 1
            kind = attrs.get("type", "?")
            entry["label"] = attrs.get("id") or (
                f"{kind} in {parents[-1]['label']}" if parents else f"{kind} (line "
                f"{parser.CurrentLineNumber})")
            entry["parent"] = parents[-1]["label"] if parents else None
        if name == "default" and "name" in attrs:
            defaults[attrs["name"]] = attrs.get("value", "")
        stack.append(entry)

    def end(name):
        entry = stack.pop()
        if name != "bsdf":
            return
        begin, here = entry["start"], parser.CurrentByteIndex
        stop = _tag_end(data, begin)
        if data[stop - 2:stop] != b"/>":  # not self-closing: up to the end tag's '>'
            stop = data.index(b">", here) + 1
        line_start = data.rfind(b"\n", 0, begin) + 1
        prefix = data[line_start:begin].decode("utf-8")
        indent = prefix if not prefix.strip() else re.match(r"\s*", prefix).group(0)
        found.append(Material(label=entry["label"], type=entry["attrs"].get("type", "?"),
                              start=begin, end=stop, line=entry["line"], indent=indent,
                              text=data[begin:stop].decode("utf-8"),
                              leaf=entry["bsdf_children"] == 0, parent=entry["parent"]))

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise MiBrdfsError(f"the scene is not valid XML: {e}") from None
    found.sort(key=lambda m: m.start)
    return found, defaults


def splice(data: bytes, replacements: dict) -> bytes:
    """``data`` with each byte span ``(start, end)`` of ``replacements`` replaced by its text."""
    out, at = [], 0
    for (start, end), text in sorted(replacements.items()):
        if start < at:
            raise MiBrdfsError("overlapping replacements (a BSDF and one nested in it)")
        out += [data[at:start], text.encode("utf-8") if isinstance(text, str) else text]
        at = end
    out.append(data[at:])
    return b"".join(out)


def element_text(element: ET.Element, indent: str, step: str = "    ") -> str:
    """
    An element as XML text for the place of a material: its first line without indentation
    (it takes the place of the original ``<bsdf``), the others indented from ``indent``.
    Children only (Mitsuba's XML holds no text content); comments are not kept.
    """
    def attrs(e):
        keys = sorted(e.attrib, key=lambda k: ("type", "name", "id").index(k)
                      if k in ("type", "name", "id") else 3)
        return "".join(f" {k}={quoteattr(e.attrib[k])}" for k in keys)

    def write(e, level):
        children = list(e)
        if not children:
            return [f"<{e.tag}{attrs(e)}/>"]
        lines = [f"<{e.tag}{attrs(e)}>"]
        for child in children:
            sub = write(child, level + 1)
            lines.append(indent + step * (level + 1) + sub[0])
            lines += sub[1:]
        lines.append(indent + step * level + f"</{e.tag}>")
        return lines

    return "\n".join(write(element, 0))


# -------------------------------------------------------------------------------------------------
# Reading and editing a BSDF element's parameters
# -------------------------------------------------------------------------------------------------


def _substituted(element: ET.Element, values: dict) -> ET.Element:
    """A copy with every ``$name`` in attribute values replaced from ``values``."""
    out = copy.deepcopy(element)
    for e in out.iter():
        for key, text in e.attrib.items():
            if "$" in text:
                e.set(key, re.sub(r"\$(\w+)", lambda m: str(values.get(m.group(1), m.group(0))),
                                  text))
    return out


def _child(element, name):
    for c in element:
        if c.get("name") == name:
            return c
    return None


def _value(child):
    """A constant parameter's value (float, [r, g, b], str, bool), or None (a texture, ...)."""
    if child is None:
        return None
    text = child.get("value")
    try:
        if child.tag in ("float", "integer"):
            return float(text)
        if child.tag == "rgb":
            parts = [float(p) for p in re.split(r"[,\s]+", text.strip()) if p]
            return parts * 3 if len(parts) == 1 else parts
        if child.tag == "spectrum":
            return float(text)
        if child.tag == "string":
            return text
        if child.tag == "boolean":
            return text.strip().lower() == "true"
    except (TypeError, ValueError):
        return None
    return None


def _params(element) -> dict:
    """{name: value or None} of the element's named children."""
    return {c.get("name"): _value(c) for c in element if c.get("name")}


def _as_dict(element) -> dict | None:
    """The element as a ``mi.load_dict`` dict of plain values, or None where it has others."""
    spec = {"type": element.get("type")}
    for child in element:
        name, value = child.get("name"), _value(child)
        if name is None or value is None:
            return None
        spec[name] = {"type": "rgb", "value": value} if isinstance(value, list) else value
    return spec


def _set(element, tag, name, value):
    old = _child(element, name)
    if old is not None:
        element.remove(old)
    text = str(value).lower() if isinstance(value, bool) else (
        repr(float(value)) if isinstance(value, (int, float)) else str(value))
    element.append(ET.Element(tag, {"name": name, "value": text}))
    return element


def _drop(element, *names):
    for name in names:
        old = _child(element, name)
        if old is not None:
            element.remove(old)
    return element


def _retyped(element, kind: str) -> ET.Element:
    """A copy of ``element`` with another plugin type (id and name kept)."""
    out = copy.deepcopy(element)
    out.set("type", kind)
    return out


def _zero(value) -> bool:
    return value is not None and not isinstance(value, str) and \
        np.all(np.asarray(value, dtype=float) == 0)


def _diffuse_of(element, reflectance_name: str, default: float) -> ET.Element:
    """A ``diffuse`` with the reflectance of ``element``'s diffuse lobe (its texture too)."""
    out = ET.Element("bsdf", {k: v for k, v in element.attrib.items() if k != "type"})
    out.set("type", "diffuse")
    child = _child(element, reflectance_name)
    if child is None:
        out.append(ET.Element("float", {"name": "reflectance", "value": repr(float(default))}))
    else:
        child = copy.deepcopy(child)
        child.set("name", "reflectance")
        out.append(child)
    return out


def _from_spec(spec: dict, original: ET.Element) -> ET.Element:
    """A fitted spec dict as an element, with the original's id and name."""
    from .bsdfspec import to_xml

    out = ET.fromstring(to_xml(spec))
    for key in ("id", "name"):
        if original.get(key) is not None:
            out.set(key, original.get(key))
    return out


# -------------------------------------------------------------------------------------------------
# Candidates
# -------------------------------------------------------------------------------------------------


@dataclass
class Candidate:
    """A replacement of one material (or, for the verification, the simplified scene)."""

    label: str
    kind: str        # 'original', 'switch', 'built-in', 'lobe left out', 'fit', 'simplified'
    xml: str = ""
    note: str = ""
    error: str | None = None
    measured: dict = field(default_factory=dict)
    cached: bool = False
    # derived for a tolerance (see _derive)
    bias: float = 0.0
    bias_hi: float = 0.0
    bias_lo: float = 0.0
    time_to_tolerance: float = math.inf
    speedup: float = math.nan
    speedup_se: float = math.nan
    within: bool = False
    verdict: str = ""

    @property
    def ok(self) -> bool:
        return self.error is None and bool(self.measured)


def _lobe_albedos(element: ET.Element, diffuse: str, glossy: str) -> tuple:
    """
    (E_diffuse, E_glossy): mean directional albedo at 45° of each lobe of a two-lobe model
    alone (the other lobe's reflectance set to 0); None where the element does not load.
    """
    from .bsdfspec import load_bsdf
    from .checks.albedo import albedo_quadrature

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


# -------------------------------------------------------------------------------------------------
# Rendering and measuring
# -------------------------------------------------------------------------------------------------


def _key(*parts) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(part if isinstance(part, bytes) else json.dumps(part, sort_keys=True,
                                                                  default=str).encode())
        h.update(b"\0")
    return h.hexdigest()


class _Cache:
    """JSON records and .npz arrays in a folder; None: nothing stored."""

    def __init__(self, folder: Path | None):
        self.folder = folder
        if folder is not None:
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                raise MiBrdfsError(f"cannot create the cache folder {folder}: "
                                   f"{e.strerror or e}") from None

    def get(self, key: str):
        if self.folder is None:
            return None
        path = self.folder / f"{key[:32]}.json"
        try:
            return json.loads(path.read_text()) if path.is_file() else None
        except (OSError, ValueError):
            return None

    def put(self, key: str, record) -> None:
        if self.folder is None:
            return
        from .imageio import atomic_path
        with atomic_path(self.folder / f"{key[:32]}.json", ".json") as tmp:
            Path(tmp).write_text(json.dumps(record, default=float))

    def get_arrays(self, key: str):
        if self.folder is None:
            return None
        path = self.folder / f"{key[:32]}.npz"
        try:
            with np.load(path) as f:
                return {k: f[k] for k in f.files}
        except (OSError, ValueError):
            return None

    def put_arrays(self, key: str, **arrays) -> None:
        if self.folder is None:
            return
        from .imageio import atomic_path
        with atomic_path(self.folder / f"{key[:32]}.npz", ".npz") as tmp:
            np.savez_compressed(tmp, **arrays)


def default_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mi_brdfs" / "simplify"


class _Engine:
    """
    Renders the original and candidate scene texts at the seeds of a seed set, times them
    interleaved with the original, and caches every measurement (the difference images too, so
    that a rerun can add seeds).
    """

    def __init__(self, path: Path, data: bytes, defines: dict, spp: int, repeats: int,
                 timing_s: float, max_seeds: int, cache: _Cache, settings_key: str):
        import drjit as dr
        import mitsuba as mi

        self.path, self.data, self.defines = path, data, defines
        self.spp, self.repeats, self.timing_s = spp, repeats, timing_s
        self.max_seeds = max_seeds
        self.cache, self.settings_key = cache, settings_key
        self.jit = dr.is_jit_v(mi.Float)
        self._ref_scene = None
        self._refs: dict = {}       # seed set -> list of images
        self._ref_info = None
        self._ref_seconds: list = []  # seconds of the original's renders in this run
        self.renders = 0

    # -- loading and rendering ------------------------------------------------------------------

    def load(self, text: bytes):
        import mitsuba as mi

        if not self.jit:
            return None
        saved = mi.FileResolver(mi.file_resolver())
        mi.file_resolver().prepend(str(self.path.parent))
        try:
            return mi.load_string(text.decode("utf-8"), **self.defines)
        except RuntimeError as e:
            raise MiBrdfsError(mitsuba_error_line(e)) from None
        finally:
            mi.set_file_resolver(saved)

    def _render(self, scene, text: bytes, seed: int, spp: int) -> tuple[np.ndarray, float]:
        """(image float64, seconds) of one render (the scene object, or in scalar variants
        the text through :func:`mi_brdfs.render.render`)."""
        self.renders += 1
        if self.jit:
            import mitsuba as mi

            from .benchmark.timing import timed
            seconds, image = timed(lambda: np.array(mi.render(scene, seed=seed, spp=spp)))
            return image.astype(np.float64), seconds
        from .render import render

        folder = self.path.parent if os.access(self.path.parent, os.W_OK) else None
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.stem}.simplify.", suffix=".xml",
                                   dir=folder)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(text)
            # a fixed pass size: the same passes (seeds) for every scene
            result = render(tmp, spp=spp, seed=seed, defines=self.defines,
                            pass_spp=max(1, spp // 4), progress=False)
        finally:
            os.unlink(tmp)
        return result.image.astype(np.float64), result.wall_time

    # -- the original ---------------------------------------------------------------------------

    def ref_scene(self):
        """The original scene, loaded and compiled (one untimed render)."""
        if self._ref_scene is None:
            self._ref_scene = self.load(self.data)
        return self._ref_scene

    def info(self) -> dict:
        """The original's timing spp (renders of about ``timing_s``) and mean value."""
        if self._ref_info is None:
            key = _key("reference info", self.settings_key)
            record = self.cache.get(key)
            if record is None:
                images = self.references("main", 2)
                if len(self._ref_seconds) < 2:  # the renders came from the cache: time one
                    if self.jit and self._ref_scene is None:
                        self._ref_scene = self.load(self.data)
                    for seed in (998, 999):  # the first may compile
                        seconds = self._render(self._ref_scene, self.data, seed, self.spp)[1]
                    self._ref_seconds.append(seconds)
                seconds = self._ref_seconds[-1]  # the second render: compiled
                per_spp = seconds / self.spp
                timing_spp = int(min(4 * self.spp, max(1, round(self.timing_s / per_spp))))
                record = {"timing_spp": timing_spp, "seconds_per_spp": per_spp,
                          "mean": float(np.mean(images[0] + images[1]) / 2)}
                self.cache.put(key, record)
            mean = record["mean"]
            if not mean > 0 or not math.isfinite(mean):
                raise MiBrdfsError(f"{self.path.name} renders black (mean {mean:g}): a relative "
                                   f"error has no meaning there")
            self._ref_info = record
        return self._ref_info

    def references(self, seedset: str, count: int) -> list:
        """The original's renders at the first ``count`` seeds of ``seedset``."""
        have = self._refs.get(seedset)
        key = _key("reference", self.settings_key, seedset)
        if have is None:
            arrays = self.cache.get_arrays(key) or {}
            have = [arrays[f"r{i}"].astype(np.float64) for i in range(len(arrays))]
        if len(have) < count:
            if self.jit and self._ref_scene is None:
                self._ref_scene = self.load(self.data)
            for i in range(len(have), count):
                image, seconds = self._render(self._ref_scene, self.data,
                                              _seed(seedset, i), self.spp)
                have.append(image)
                self._ref_seconds.append(seconds)
            self.cache.put_arrays(key, **{f"r{i}": im.astype(np.float32)
                                          for i, im in enumerate(have)})
        self._refs[seedset] = have
        return have[:count]

    # -- a candidate ----------------------------------------------------------------------------

    def measure(self, text: bytes, tolerance: float, seedset: str = "main") -> tuple[dict, bool]:
        """
        (measurements, cached) of a scene text against the original: renders at 2, 4, 8, ...
        seeds of ``seedset`` while its bias is inconclusive for ``tolerance`` (below it, yet
        its bound above), up to ``max_seeds``; then the timing. The difference images
        D = C − R of every seed are kept (compressed: 0 wherever the material does not show).
        """
        key = _key("candidate", self.settings_key, seedset, text)
        record, stored = self.cache.get(key), self.cache.get_arrays(key)
        cached = record is not None and stored is not None
        if not cached:
            record, stored = {}, {}
        diffs = [stored[f"d{i}"].astype(np.float64) for i in range(len(stored))]
        scene = None
        info = self.info()
        while True:
            if len(diffs) >= 2:
                record.update(_statistics(self.references(seedset, len(diffs)), diffs,
                                          self.spp, info["mean"]))
                if not _inconclusive(record, tolerance) or len(diffs) >= self.max_seeds:
                    break
            target = min(self.max_seeds, max(2, 2 * len(diffs)))
            if scene is None:
                scene = self.load(text)
            refs = self.references(seedset, target)
            for i in range(len(diffs), target):
                diffs.append(self._render(scene, text, _seed(seedset, i), self.spp)[0] - refs[i])
            cached = False
        if "cost_ratio" not in record:
            if scene is None:
                scene = self.load(text)
            record.update(self._timing(scene, text))
            cached = False
        if not cached:
            self.cache.put(key, record)
            self.cache.put_arrays(key, **{f"d{i}": d.astype(np.float32)
                                          for i, d in enumerate(diffs)})
        return record, cached

    def _timing(self, scene, text: bytes) -> dict:
        """Time ratios candidate/original of renders interleaved R C C R R C ..."""
        spp = self.info()["timing_spp"]
        ratios, ref_times = [], []
        ref_scene = self.ref_scene()
        if self.jit:  # untimed: a kernel of another spp may have to be compiled first
            self._render(scene, text, 999, spp)
            self._render(ref_scene, self.data, 999, spp)
        for i in range(self.repeats):
            order = ("ref", "cand") if i % 2 == 0 else ("cand", "ref")
            times = {}
            for who in order:
                times[who] = self._render(ref_scene if who == "ref" else scene,
                                          self.data if who == "ref" else text, 1000 + i, spp)[1]
            ratios.append(times["cand"] / times["ref"])
            ref_times.append(times["ref"])
        logs = np.log(np.asarray(ratios))
        return {"cost_ratio": float(np.exp(np.median(logs))), "cost_ratio_se": _median_se(logs),
                "ref_seconds_per_spp": float(np.median(ref_times)) / spp,
                "timing_ratios": [float(r) for r in ratios]}


def _median_se(values: np.ndarray) -> float:
    """
    Standard error of the median of ``values``: 1.25 σ/√n (its efficiency for normal errors),
    σ from the median absolute deviation (1.4826 MAD, robust to a render slowed by another
    process) where there are 3 values or more.
    """
    n = len(values)
    if n < 2:
        return math.nan
    if n < 3:
        sigma = float(np.std(values, ddof=1))
    else:
        sigma = 1.4826 * float(np.median(np.abs(values - np.median(values))))
    return 1.25 * sigma / math.sqrt(n)


def _seed(seedset: str, index: int) -> int:
    """The seed of render ``index`` of a seed set: 1, 2, ... ('main') or 101, ... ('verify')."""
    return {"main": 1, "verify": 101}[seedset] + index


def _inconclusive(stats: dict, tolerance: float) -> bool:
    return stats["bias_lo"] <= tolerance < stats["bias_hi"]


def _flip_mean(reference: np.ndarray, test: np.ndarray, mean: float) -> float | None:
    """
    Mean HDR-FLIP of ``test`` against ``reference``, evaluated on the bounding box of the
    pixels that differ by more than 10⁻³ of the image mean, padded by 32 pixels (FLIP's
    filters are a few pixels wide), and counted as 0 elsewhere: the images of a candidate
    differ where its material is seen, and FLIP costs about 30 µs per pixel.
    """
    from .compare import flip_map

    differs = np.any(np.abs(test - reference) > 1e-3 * mean, axis=-1)
    if not differs.any():
        return 0.0
    rows, cols = np.flatnonzero(differs.any(axis=1)), np.flatnonzero(differs.any(axis=0))
    pad = 32
    r0, r1 = max(0, rows[0] - pad), min(differs.shape[0], rows[-1] + pad + 1)
    c0, c1 = max(0, cols[0] - pad), min(differs.shape[1], cols[-1] + pad + 1)
    fl = flip_map(reference[r0:r1, c0:c1], test[r0:r1, c0:c1])
    if fl is None:
        return None
    return float(fl[1] * (r1 - r0) * (c1 - c0) / differs.size)


def _statistics(refs: list, diffs: list, spp: int, mean: float) -> dict:
    """
    Bias, its standard error and bounds, noise, variance ratio and FLIP of a candidate from
    the original's renders R_s and the differences D_s = C_s − R_s at k seeds.
    """
    k = len(diffs)
    d = np.stack(diffs)
    r = np.stack(refs[:k])
    c = r + d
    dbar = d.mean(axis=0)
    s2 = d.var(axis=0, ddof=1)  # sample variance of D per pixel and channel
    var_dbar = s2 / k
    b2_pixels = dbar * dbar - var_dbar
    n = dbar.size
    b2 = float(np.mean(b2_pixels))
    # Var of D̄² − s²/k per pixel for Gaussian noise of variance σ² per seed:
    # 4b²σ²/k + 2σ⁴/k² + 2σ⁴/((k−1)k²), with σ⁴ ≈ s⁴(k−1)/(k+1); ×3: a pixel's channels
    sigma4 = s2 * s2 * (k - 1) / (k + 1)
    var = 4 * np.maximum(b2_pixels, 0.0) * var_dbar + sigma4 * (2 / k ** 2 + 2 / ((k - 1) * k ** 2))
    se = float(math.sqrt(3.0 * np.sum(var)) / n)
    var_r, var_c = r.var(axis=0, ddof=1), c.var(axis=0, ddof=1)
    vr = float(np.mean(var_r))
    var_ratio = float(np.mean(var_c) / vr) if vr > 0 else math.nan
    var_se = float(math.sqrt(3.0) * np.std(var_c - var_r) / math.sqrt(n) / vr / var_ratio) \
        if vr > 0 and var_ratio > 0 else math.nan
    m2 = mean * mean
    return {"b2": b2 / m2, "b2_se": se / m2, "seeds": k,
            "bias": math.sqrt(max(b2, 0.0) / m2),
            "bias_hi": math.sqrt(max(b2 + 2 * se, 0.0) / m2),
            "bias_lo": math.sqrt(max(b2 - 2 * se, 0.0) / m2),
            "noise": float(math.sqrt(np.mean(var_dbar)) / mean),
            "variance_ratio": var_ratio, "variance_ratio_se": var_se,
            "variance_1spp_ref": vr * spp / m2,
            "flip": _flip_mean(r.mean(axis=0), c.mean(axis=0), mean),
            "nonfinite": int((~np.isfinite(d)).sum())}


# -------------------------------------------------------------------------------------------------
# Results
# -------------------------------------------------------------------------------------------------


@dataclass
class MaterialResult:
    """One material: its candidates (the original first) and the choice."""

    material: Material
    candidates: list
    chosen: int = 0
    reason: str = ""

    @property
    def label(self) -> str:
        return self.material.label


@dataclass
class SimplifyResult:
    """What :func:`simplify` measured and chose; ``text`` is the simplified scene file."""

    scene: Path
    tolerance: float
    variant: str
    spp: int
    defines: dict
    quick: bool
    materials: list
    original: dict
    replacements: dict
    text: bytes
    verification: Candidate | None
    predicted: dict
    measured: dict
    output: Path | None = None
    report: Path | None = None
    figure: Path | None = None
    seconds: float = 0.0
    notes: list = field(default_factory=list)
    renders: int = 0

    def table(self, material: MaterialResult) -> str:
        """A Markdown table of one material's candidates."""
        from .campaign.core import md_table

        rows = []
        for i, c in enumerate(material.candidates):
            name = f"**{c.label}**" if i == material.chosen and i else c.label
            if not c.ok:
                rows.append((name, c.kind, "—", "—", "—", "—", "—", "—", "—",
                             f"not measured: {c.error or c.note}"))
                continue
            me = c.measured
            flip = f"{me['flip']:.4f}" if me.get("flip") is not None else "—"
            original = c.kind == "original"
            rows.append((
                name + (f" — {c.note}" if c.note else ""), c.kind,
                "0 (reference)" if original else
                f"{c.bias:.4f} [{c.bias_lo:.4f}, {c.bias_hi:.4f}]",
                "—" if original else f"{me['noise']:.2g} ({me['seeds']})",
                "—" if original else flip,
                _ratio(me["cost_ratio"], me["cost_ratio_se"]),
                _ratio(me["variance_ratio"], me["variance_ratio_se"]),
                _seconds(c.time_to_tolerance),
                "1" if original else
                _ratio(c.speedup, c.speedup_se) if math.isfinite(c.time_to_tolerance) else "—",
                c.verdict))
        return md_table(["candidate", "kind", "bias: rel. RMSE [±2 SE]", "noise (seeds)", "FLIP",
                         "cost/spp", "variance", f"time to {self.tolerance:g}", "speed-up",
                         "verdict"], rows)

    def tables(self) -> str:
        parts = []
        for mat in self.materials:
            where = "" if "(line" in mat.label else f", line {mat.material.line}"
            head = f"### {mat.label} (`{mat.material.type}`{where})"
            if len(mat.candidates) == 1:
                parts += [head, "", f"kept: {mat.reason}", ""]
            else:
                parts += [head, "", self.table(mat), "", f"→ {mat.reason}", ""]
        return "\n".join(parts)

    def summary(self) -> str:
        """The printed report: the tables, the replacements and the verification."""
        lines = [f"simplify {self.scene.name} (tolerance {self.tolerance:g} relative RMSE, "
                 f"{self.variant}, {self.spp} spp per render, {self.renders} renders"
                 + (f", {' '.join(f'{k}={v}' for k, v in self.defines.items())}"
                    if self.defines else "") + f", {self.seconds:.0f} s)", "",
                 self.tables()]
        lines += self.verdict_lines()
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def verdict_lines(self) -> list:
        chosen = [(m.label, m.candidates[m.chosen].label) for m in self.materials if m.chosen]
        lines = []
        if not chosen:
            lines.append("no material replaced: the simplified scene is the original")
        else:
            lines.append("replaced: " + "; ".join(f"{a} → {b}" for a, b in chosen))
        if self.verification is not None and self.verification.ok:
            v, me = self.verification, self.verification.measured
            lines.append(
                f"verification (the simplified scene against the original, {me['seeds']} "
                f"independent seeds): bias {v.bias:.4f} (≤ {v.bias_hi:.4f}, noise "
                f"{me['noise']:.2g}) "
                f"{'within' if v.bias_hi <= self.tolerance else 'OVER'} the tolerance "
                f"{self.tolerance:g}; speed-up to the tolerance predicted "
                f"{self.predicted['speedup']:.3f}×, measured "
                f"{_ratio(v.speedup, v.speedup_se)} (cost/spp "
                f"{_ratio(me['cost_ratio'], me['cost_ratio_se'])}, variance "
                f"{_ratio(me['variance_ratio'], me['variance_ratio_se'])})")
        if self.output:
            lines.append(f"wrote {self.output}")
        if self.report:
            lines.append(f"wrote {self.report}" + (f" and {self.figure}" if self.figure else ""))
        return lines


def _ratio(value: float, se_log: float) -> str:
    if not math.isfinite(value):
        return "—" if math.isnan(value) else "0"
    if not math.isfinite(se_log):
        return f"{value:.3f}×"
    return f"{value:.3f}× ±{100 * se_log:.1f}%"


def _seconds(t: float) -> str:
    if not math.isfinite(t):
        return "∞ (bias ≥ tolerance)"
    return f"{t:.3g} s"


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


# -------------------------------------------------------------------------------------------------
# The whole
# -------------------------------------------------------------------------------------------------


def _check_tolerance(tolerance) -> float:
    ok = isinstance(tolerance, (int, float)) and not isinstance(tolerance, bool) \
        and math.isfinite(tolerance) and tolerance > 0
    if not ok:
        raise MiBrdfsError(f"simplify: tolerance = {tolerance!r} is invalid: must be a finite "
                           f"number > 0 (a relative RMSE, e.g. 0.01)")
    return float(tolerance)


def _report_dir(report) -> Path | None:
    if report is None:
        return None
    from .imageio import output_folder

    return output_folder(report, f"report {report}", "SIMPLIFY.md")


@counts("spp", "repeats")
def simplify(scene, tolerance: float = 0.01, *, variant: str | None = None, output=None,
             report=None, quick: bool = False, spp: int | None = None,
             defines: dict | None = None, cache=True, confidence: float = 2.0,
             fits: bool = True, repeats: int | None = None,
             progress: bool = False) -> SimplifyResult:
    """
    Measure cheaper candidates for every material of ``scene`` and write the simplified scene
    (see the module docstring).

    Parameter ``scene``: a scene file or bundled name. ``tolerance``: on the relative RMSE
    (RMSE over the reference image's mean) of the converged image against the original's.
    ``variant``: Mitsuba variant (default: the current one, else llvm_ad_rgb where it works).
    ``output``: where to write the simplified scene (None: not written). ``report``: a folder
    for SIMPLIFY.md, the plot and (by default) the cache. ``quick``: ``res`` of
    :data:`QUICK_RES` (where the scene declares that default) and fewer spp, repeats and fit
    steps. ``spp``: per seed, for the original and every candidate. ``defines``: ``<default>``
    overrides. ``cache``: True (``report/cache`` or :func:`default_cache_dir`), a folder, or
    False. ``confidence``: standard errors by which a speed-up must exceed 1 to replace a
    material (0: any estimated gain). ``fits``: also fit cheaper models. ``repeats``: timing
    pairs per candidate.

    Returns → :class:`SimplifyResult`. Raises MiBrdfsError (one line) for bad input.
    """
    import mitsuba as mi

    import mi_brdfs
    from . import __version__
    from .imageio import check_writable
    from .progress import Progress
    from .scenes import scene_path

    clock = time.perf_counter()
    tolerance = _check_tolerance(tolerance)
    if not (isinstance(confidence, (int, float)) and math.isfinite(confidence)):
        raise MiBrdfsError(f"simplify: confidence = {confidence!r} is invalid: must be finite")
    path = scene_path(scene)
    data = path.read_bytes()
    out = check_writable(output) if output is not None else None
    if out is not None and out.resolve() == path.resolve():
        raise MiBrdfsError(f"simplify: the output {out} is the scene itself: write the "
                           f"simplified scene to another file")
    report_dir = _report_dir(report)
    materials, scene_defaults = scene_bsdfs(data)
    if not materials:
        raise MiBrdfsError(f"{path.name} has no <bsdf>: nothing to simplify")
    if variant is not None or mi.variant() is None:
        mi_brdfs.use_variant(variant)
    variant = mi.variant()

    defines = {k: str(v) for k, v in (defines or {}).items()}
    unknown = sorted(set(defines) - set(scene_defaults))
    if unknown:
        raise MiBrdfsError(f"{path.name} declares no <default> for {', '.join(unknown)} (a "
                           f"define must name a <default name=...> of the scene)")
    notes = []
    if quick and "res" not in defines:
        if "res" in scene_defaults:
            defines["res"] = str(QUICK_RES)
        else:
            notes.append("--quick: the scene declares no <default name=\"res\">, so it renders "
                         "at its own resolution")
    level = 1 if quick else 0
    spp = spp or SPP[level]
    repeats = repeats or REPEATS[level]
    values = dict(scene_defaults, **defines)
    max_seeds = MAX_SEEDS

    if cache is True:
        cache_dir = (report_dir / "cache") if report_dir else default_cache_dir()
    elif cache:
        cache_dir = Path(cache).expanduser()
    else:
        cache_dir = None
    scene_hash = hashlib.sha256(data).hexdigest()
    store = _Cache(cache_dir / scene_hash[:16] if cache_dir else None)
    settings = {"version": CACHE_VERSION, "mi_brdfs": __version__, "mitsuba": mi.__version__,
                "variant": variant, "defines": defines, "spp": spp, "repeats": repeats,
                "timing_s": TIMING_S[level], "scene": scene_hash}
    engine = _Engine(path, data, defines, spp, repeats, TIMING_S[level], max_seeds, store,
                     _key(settings))

    fit_sizes = FIT_SIZES[level]

    def fit_fn(target, model, free):
        key = _key("fit", target, model, free, fit_sizes, __version__)
        record = store.get(key)
        if record is not None:
            return record["result"] if "result" in record else record["note"]
        try:
            result = _fit(target, model, free, fit_sizes, variant)
            stored = {"result": result}
        except MiBrdfsError as e:
            result = f"fit failed: {e}"
            stored = {"note": result}
        store.put(key, stored)
        return result

    # candidates of every material (fits included), then the measurements
    plans = []
    for mat in materials:
        try:
            cands = candidates_for(mat, values, fit_fn if fits else None)
        except MiBrdfsError as e:
            cands = []
            notes.append(f"{mat.label}: no candidates ({e})")
        plans.append((mat, cands))
    total = 2 + sum(len(c) for _, c in plans)
    bar = Progress(total, label=f"simplify {path.name}", unit=" scenes") if progress else None
    done = 0
    try:
        engine.info()
        done += 1
        if bar:
            bar.update(done, note="the original")
        results = []
        for mat, cands in plans:
            entries = [Candidate("original", "original", mat.text)]
            for label, kind, element, note in cands:
                c = Candidate(label, kind, note=note)
                if element is None:
                    c.error = note or "no candidate"
                else:
                    c.xml = element_text(element, mat.indent)
                    try:
                        c.measured, c.cached = engine.measure(
                            splice(data, {(mat.start, mat.end): c.xml}), tolerance)
                    except (MiBrdfsError, RuntimeError) as e:
                        c.error = mitsuba_error_line(e)
                entries.append(c)
                done += 1
                if bar:
                    bar.update(done, note=f"{mat.label}: {label}"[:50])
            results.append(MaterialResult(mat, entries))

        ref_numbers = _original_numbers(results, engine)
        original_time = ref_numbers["variance_1spp_ref"] * ref_numbers["ref_seconds_per_spp"] \
            / tolerance ** 2
        for r in results:
            r.candidates[0].measured = dict(ref_numbers, b2=0.0, b2_se=0.0, noise=0.0,
                                            bias=0.0, bias_hi=0.0, bias_lo=0.0,
                                            variance_ratio=1.0, variance_ratio_se=0.0,
                                            cost_ratio=1.0, cost_ratio_se=0.0, flip=None)
            for c in r.candidates:
                if c.ok:
                    _derive(c, ref_numbers, tolerance, original_time)
            _choose(r, tolerance, confidence)

        predicted = _predict(results, ref_numbers, tolerance, original_time)
        while predicted["bias"] > tolerance:  # the parts' bias² add up beyond τ²
            worst = max((r for r in results if r.chosen),
                        key=lambda r: r.candidates[r.chosen].measured["b2"])
            notes.append(f"the chosen replacements' biases add up beyond the tolerance: "
                         f"{worst.label} kept as it was")
            worst.candidates[worst.chosen].verdict = "within alone, not with the others"
            worst.chosen, worst.reason = 0, "kept: the replacements together exceed the tolerance"
            worst.candidates[0].verdict = "kept"
            predicted = _predict(results, ref_numbers, tolerance, original_time)
        verification = None
        while True:
            chosen = [r for r in results if r.chosen]
            replacements = {(r.material.start, r.material.end): r.candidates[r.chosen].xml
                            for r in chosen}
            text = splice(data, replacements)
            if not chosen:
                verification = None  # none left: the original, which needs no verification
                break
            # independent seeds and timing: the simplified scene is measured afresh, even where
            # it is one candidate's scene
            verification = Candidate("simplified scene", "simplified")
            verification.measured, verification.cached = engine.measure(text, tolerance,
                                                                        "verify")
            _derive(verification, ref_numbers, tolerance, original_time)
            if verification.bias_hi <= tolerance:
                break
            worst = max(chosen, key=lambda r: r.candidates[r.chosen].measured["b2"])
            notes.append(f"the simplified scene's bias {verification.bias:.4f} (bound "
                         f"{verification.bias_hi:.4f}, {verification.measured['seeds']} seeds) "
                         f"was not within the tolerance: {worst.label} kept as it was")
            worst.candidates[worst.chosen].verdict = "within alone, not with the others"
            worst.chosen, worst.reason = 0, "kept: the replacements together exceeded the " \
                                            "tolerance"
            worst.candidates[0].verdict = "kept"
            predicted = _predict(results, ref_numbers, tolerance, original_time)
        done = total
        if bar:
            bar.update(done, note="verified")
    finally:
        if bar:
            bar.close()

    measured = {}
    if verification is not None and verification.ok:
        measured = {"speedup": verification.speedup, "bias": verification.bias}
    result = SimplifyResult(scene=path, tolerance=tolerance, variant=variant, spp=spp,
                            defines=defines, quick=quick, materials=results,
                            original=ref_numbers, replacements=replacements, text=text,
                            verification=verification, predicted=predicted, measured=measured,
                            notes=notes, renders=engine.renders)
    if out is not None:
        _write_scene(result, out)
    result.seconds = time.perf_counter() - clock
    if report_dir is not None:
        result.figure = plot(result, report_dir / "simplify.png")
        result.report = write_report(result, report_dir / "SIMPLIFY.md")
    return result


def _original_numbers(results, engine) -> dict:
    """
    The original's cost per spp (the median over every timing render of it) and the relative
    variance of its 1-spp image (from its renders at every seed rendered).
    """
    per_spp = [c.measured["ref_seconds_per_spp"] for r in results for c in r.candidates[1:]
               if c.ok]
    if not per_spp:
        per_spp = [engine.info()["seconds_per_spp"]]
    refs = engine.references("main", max(2, len(engine._refs.get("main", []))))
    var = float(np.mean(np.stack(refs).var(axis=0, ddof=1))) * engine.spp \
        / engine.info()["mean"] ** 2
    return {"ref_seconds_per_spp": float(np.median(per_spp)), "variance_1spp_ref": var,
            "seeds": len(refs)}


def _choose(r: MaterialResult, tolerance: float, confidence: float) -> None:
    original = r.candidates[0]
    original.verdict = "kept"
    best = None
    for c in r.candidates[1:]:
        if not c.ok:
            c.verdict = "failed"
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
        r.reason = ("a wrapper: its nested BSDFs are listed apart" if not r.material.leaf
                    else "no cheaper candidate (a built-in, or no switch applies)")
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


def _fit(target: dict, model: dict, free, sizes: dict, variant: str):
    """(fitted spec, residual, albedo error) of :func:`mi_brdfs.fit.fit`, in an AD variant."""
    import drjit as dr
    import mitsuba as mi

    import mi_brdfs
    from .fit import fit

    ad = dr.is_diff_v(mi.Float) and mi.is_rgb and not mi.is_polarized
    if not ad and not mi_brdfs.llvm_usable():
        raise MiBrdfsError("fits need llvm_ad_rgb, which this machine lacks")
    try:
        result = fit(target, model, free, variant=None if ad else "llvm_ad_rgb", **sizes)
    finally:
        if not ad:
            mi_brdfs.use_variant(variant, fallback=False)
    return result.spec, result.residual, result.albedo_error


def _write_scene(result: SimplifyResult, out: Path) -> None:
    """Write the simplified scene atomically and check that it loads."""
    from .imageio import atomic_path
    from .scenes import load_scene

    with atomic_path(out, ".xml") as tmp:
        Path(tmp).write_bytes(result.text)
    result.output = out
    if out.parent.resolve() != result.scene.parent.resolve() and \
            re.search(rb'name="filename"', result.text):
        result.notes.append(f"{out} lies in another folder than {result.scene.name}, whose "
                            f"relative file names (meshes, textures) then resolve elsewhere")
        return
    load_scene(out, result.defines)


# -------------------------------------------------------------------------------------------------
# Report and plot
# -------------------------------------------------------------------------------------------------


def plot(result: SimplifyResult, path) -> str:
    """
    Error against time, one panel per material with candidates: each candidate's predicted
    relative RMSE √(bias² + V/t) of a render of t seconds (V: its variance per unit time), the
    Pareto front (the least error any candidate reaches at each time), the tolerance, and
    each candidate's time to reach it (a dot).
    """
    from .plots import pyplot, save_figure

    plt = pyplot()
    panels = [m for m in result.materials if len(m.candidates) > 1]
    if result.verification is not None and result.verification.ok:
        panels.append(None)
    cols = min(4, max(1, len(panels)))
    rows = max(1, math.ceil(len(panels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.8 * cols, 3.2 * rows), squeeze=False)
    t0 = result.original["variance_1spp_ref"] * result.original["ref_seconds_per_spp"] \
        / result.tolerance ** 2
    t = np.geomspace(t0 / 100, t0 * 10, 200)
    for ax in axes.flat[len(panels):]:
        ax.axis("off")
    for ax, mat in zip(axes.flat, panels):
        cands = ([Candidate("original", "original", measured=result.materials[0].candidates[0]
                            .measured), result.verification] if mat is None else
                 mat.candidates)
        curves = []
        for i, c in enumerate(cands):
            if not c.ok:
                continue
            me = c.measured
            v = me["variance_1spp_ref"] * me["variance_ratio"] * \
                me["ref_seconds_per_spp"] * me["cost_ratio"]
            err = np.sqrt(max(me["b2"], 0.0) + v / t)
            curves.append(err)
            chosen = mat is not None and i == mat.chosen and i > 0
            style = "-" if c.kind == "original" else "--"
            line, = ax.loglog(t, err, style, lw=2.0 if chosen or c.kind == "original" else 1.0,
                              label=c.label + (" (chosen)" if chosen else ""))
            if math.isfinite(c.time_to_tolerance):
                ax.plot([c.time_to_tolerance], [result.tolerance], "o", ms=4,
                        color=line.get_color())
        if curves:
            ax.loglog(t, np.min(curves, axis=0), color="0.2", lw=4, alpha=0.2,
                      label="Pareto front")
        ax.axhline(result.tolerance, color="0.5", lw=0.8, ls=":")
        ax.set_title(("simplified scene" if mat is None else
                      f"{mat.label} ({mat.material.type})"), fontsize=8)
        ax.set_xlabel("render time (s)", fontsize=7)
        ax.set_ylabel("relative RMSE", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=5, loc="upper right")
    fig.suptitle(f"{result.scene.name}: predicted error against render time (error² = bias² + "
                 f"V/t), tolerance {result.tolerance:g}", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def write_report(result: SimplifyResult, path) -> Path:
    """SIMPLIFY.md: the settings, the method in short, every table, the plot, the verdict."""
    from .imageio import atomic_path

    path = Path(path)
    d = " ".join(f"-D {k}={v}" for k, v in result.defines.items())
    original = result.original
    original_time = original["variance_1spp_ref"] * original["ref_seconds_per_spp"] \
        / result.tolerance ** 2
    lines = [
        f"# Simplification of {result.scene.name}", "",
        f"`mi-brdfs simplify {result.scene.name} --tolerance {result.tolerance:g}"
        + (" --quick" if result.quick else "") + (f" {d}" if d else "") + f"`: "
        f"{result.variant}, {result.spp} spp per render, {result.renders} renders, "
        f"{result.seconds:.0f} s.", "",
        "Each candidate is rendered in the scene with only its material replaced; its **bias** "
        "is the relative RMSE (RMSE over the original image's mean) of its converged image "
        "against the original's, estimated from renders with common random numbers at 2 to "
        f"{MAX_SEEDS} seeds (more while its bounds, ± 2 standard errors, straddle the "
        "tolerance), **noise** the RMS noise of that estimate. "
        "**Cost/spp** and **variance** are relative to the original scene (cost: median of "
        "renders interleaved with the original's; ± one standard error); the **time to "
        f"{result.tolerance:g}** is V/(τ² − bias²), V the variance per second of render "
        "(error² = bias² + V/t). A candidate replaces the original only when it is within "
        "the tolerance and measurably faster (see `mi_brdfs.simplify`).", "",
        f"The original scene: {original['ref_seconds_per_spp'] * 1e3:.3g} ms per spp, "
        f"relative variance of a 1-spp image {original['variance_1spp_ref']:.3g}, so "
        f"{_seconds(original_time)} to reach {result.tolerance:g}.", "",
        "## Materials", "", result.tables(), "",
        "## Result", ""]
    lines += [f"* {line}" for line in result.verdict_lines() if not line.startswith("wrote ")]
    if result.predicted and any(m.chosen for m in result.materials):
        p = result.predicted
        lines.append(f"* predicted from the parts: bias {p['bias']:.4f}, cost/spp "
                     f"{p['cost_ratio']:.3f}×, variance {p['variance_ratio']:.3f}×, speed-up "
                     f"{p['speedup']:.3f}×")
    lines += [f"* note: {n}" for n in result.notes]
    if result.figure:
        lines += ["", f"![error against time]({os.path.relpath(result.figure, path.parent)})"]
    if result.replacements:
        lines += ["", "## Replaced elements", ""]
        for r in result.materials:
            if r.chosen:
                lines += [f"{r.label}:", "", "```xml", r.material.indent + r.material.text,
                          "```", "→", "```xml",
                          r.material.indent + r.candidates[r.chosen].xml, "```", ""]
    with atomic_path(path, ".md") as tmp:
        Path(tmp).write_text("\n".join(lines) + "\n")
    return path


__all__ = ["simplify", "SimplifyResult", "MaterialResult", "Candidate", "Material",
           "scene_bsdfs", "splice", "element_text", "candidates_for", "plot", "write_report"]
