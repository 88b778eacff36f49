"""
The scene file as bytes: every ``<bsdf>`` element with its exact byte span and the scene's
``<default>`` values (:func:`scene_bsdfs`), the files it ``<include>``s (:func:`includes`), byte
spans replaced by other text with every other byte kept (:func:`splice`), and an element
written as text for the place of a material (:func:`element_text`).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from xml.parsers import expat
from xml.sax.saxutils import quoteattr

from ..errors import MiBrdfsError


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
    #: (id, name or None) of each ``<ref>`` among its children
    refs: tuple = ()

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
    scene's ``<default>`` values. A ``<bsdf>`` is a leaf when it nests no ``<bsdf>`` and no
    ``<ref>`` to one (a ``<ref>`` without a name, or to the id of a ``<bsdf>``: a wrapper such
    as ``twosided`` may reference its BSDF). Raises MiBrdfsError for XML that does not parse.
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
        if name == "ref" and stack and stack[-1]["name"] == "bsdf":
            stack[-1].setdefault("refs", []).append((attrs.get("id", ""), attrs.get("name")))
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
                              leaf=entry["bsdf_children"] == 0, parent=entry["parent"],
                              refs=tuple(entry.get("refs", ()))))

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise MiBrdfsError(f"the scene is not valid XML: {e}") from None
    found.sort(key=lambda m: m.start)
    ids = {m.label for m in found}
    for m in found:
        m.leaf = m.leaf and not any(name is None or ref in ids for ref, name in m.refs)
    return found, defaults


def includes(data: bytes) -> list[str]:
    """The ``filename`` of every ``<include>`` of the scene file's bytes, in document order."""
    parser = expat.ParserCreate()
    found: list[str] = []
    parser.StartElementHandler = lambda name, attrs: found.append(attrs.get("filename", "")) \
        if name == "include" else None
    try:
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise MiBrdfsError(f"the scene is not valid XML: {e}") from None
    return found


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
