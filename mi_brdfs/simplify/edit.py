"""
Reading and editing a BSDF element's parameters (:mod:`xml.etree.ElementTree` elements of the
scene's ``<bsdf>`` text): constant values, ``$name`` references substituted, children set or
dropped, another plugin type, a ``diffuse`` from a diffuse lobe, a fitted spec as an element.
"""

from __future__ import annotations

import copy
import re
import xml.etree.ElementTree as ET

import numpy as np


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
    """Whether a constant value (a number, [r, g, b], or an ``rgb``/``spectrum`` dict of a
    spec) is 0 in every channel; False for anything else (a texture, a string, None)."""
    if isinstance(value, dict):
        value = value.get("value")
    if value is None or isinstance(value, (str, bool)):
        return False
    try:
        return bool(np.all(np.asarray(value, dtype=float) == 0))
    except (TypeError, ValueError):
        return False


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
    from ..bsdfspec import to_xml

    out = ET.fromstring(to_xml(spec))
    for key in ("id", "name"):
        if original.get(key) is not None:
            out.set(key, original.get(key))
    return out
