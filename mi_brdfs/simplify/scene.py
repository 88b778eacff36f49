"""
The scene file as bytes: every ``<bsdf>`` element with its exact byte span and the scene's
``<default>`` values (:func:`scene_bsdfs`), the files it ``<include>``s (:func:`includes`), those
files merged in as Mitsuba merges them (:func:`merge_includes`; :func:`locate` says where each
material is written, :func:`unmerge` puts each replacement back in its file), byte spans
replaced by other text with every other byte kept (:func:`splice`), and an element written as
text for the place of a material (:func:`element_text`).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from xml.parsers import expat
from xml.sax.saxutils import escape, quoteattr

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
    #: the ``<include>``d file it is written in (as the scene names it), None for the scene's
    file: str | None = None

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
    return [attrs.get("filename", "") for _, _, attrs, _, _ in _element_spans(data, "include")]


#: XML that names a file (a ``filename`` property, an ``<include>``), relative to its folder.
NAMES_FILES = re.compile(rb"""name\s*=\s*["']filename["']|<include\b""")


@dataclass(eq=False)
class Part:
    """An ``<include>``d file merged into the scene's bytes in place of its ``<include>``."""

    name: str            #: its ``filename`` as the scene writes it
    file: Path
    data: bytes          #: the file's bytes
    span: tuple          #: the ``<include>`` element's byte span in the scene file
    content: tuple       #: the byte span of its root's content (between <scene> and </scene>)
    at: int = 0          #: where that content starts in the merged bytes

    @property
    def length(self) -> int:
        return self.content[1] - self.content[0]

    @property
    def growth(self) -> int:
        """How many bytes longer the merged bytes are for it than the scene file."""
        return self.length - (self.span[1] - self.span[0])


def _element_spans(data: bytes, tag: str, depth: int | None = None) -> list[tuple]:
    """(start, end, attributes, content start, content end) of every element ``tag`` (at
    ``depth`` only, 0 the root, when given); the content span is empty for ``<tag/>``."""
    parser = expat.ParserCreate()
    stack: list = []
    found: list = []

    def start(name, attrs):
        stack.append((name, attrs, parser.CurrentByteIndex))

    def end(name):
        name, attrs, begin = stack.pop()
        if name != tag or (depth is not None and len(stack) != depth):
            return
        open_end = _tag_end(data, begin)
        if data[open_end - 2:open_end] == b"/>":
            found.append((begin, open_end, attrs, open_end, open_end))
        else:
            here = parser.CurrentByteIndex
            found.append((begin, data.index(b">", here) + 1, attrs, open_end, here))

    parser.StartElementHandler, parser.EndElementHandler = start, end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as e:
        raise MiBrdfsError(f"the scene is not valid XML: {e}") from None
    return found


def merge_includes(folder: Path, data: bytes, values: dict) -> tuple[bytes, list[Part]]:
    """
    The scene's bytes with each ``<include>`` of a readable scene file replaced by that file's
    content, as Mitsuba merges it, and a :class:`Part` for each: a file in ``folder`` (the
    scene's own), or in another that names no file (no ``filename`` property, no
    ``<include>``), whose relative names would resolve elsewhere once merged or written beside
    the output. Others (unreadable, included twice, included by an included file) stay
    ``<include>`` elements.
    """
    parts, seen = [], set()
    for start, end, attrs, _, _ in _element_spans(data, "include"):
        name = re.sub(r"\$(\w+)", lambda m: str(values.get(m.group(1), m.group(0))),
                      attrs.get("filename", ""))
        file = (folder / name).resolve()
        if file in seen:
            continue
        seen.add(file)
        try:
            text = file.read_bytes()
            roots = _element_spans(text, "scene", depth=0)
        except (OSError, MiBrdfsError):
            continue
        elsewhere = file.parent != folder.resolve() and re.search(NAMES_FILES, text)
        if roots and not elsewhere:
            parts.append(Part(name, file, text, (start, end), roots[0][3:5]))
    shift = 0
    for part in parts:
        part.at = part.span[0] + shift
        shift += part.growth
    return splice(data, {p.span: p.data[slice(*p.content)] for p in parts}), parts


def unmerge(data: bytes, parts: list[Part], replacements: dict, names: dict) -> tuple:
    """
    (the scene file's bytes, {part: its file's bytes}) of ``replacements``, byte spans of the
    merged bytes (:func:`merge_includes`): each replaced in the file it came from, every other
    byte kept. Only the parts with a replacement are returned, and their ``<include>``s name
    the file ``names[part.file]`` instead.
    """
    own, theirs = {}, {}
    for (start, end), text in replacements.items():
        part = next((p for p in parts if p.at <= start and end <= p.at + p.length), None)
        if part is not None:
            offset = part.content[0] - part.at
            theirs.setdefault(part, {})[(start + offset, end + offset)] = text
        else:
            shift = sum(p.growth for p in parts
                        if p.at + p.length <= start)
            own[(start - shift, end - shift)] = text
    for part in theirs:
        name = escape(names[part.file], {'"': "&quot;", "'": "&apos;"}).encode("utf-8")
        own[part.span] = re.sub(rb"(filename\s*=\s*)([\"'])(.*?)\2",
                                lambda m: m.group(1) + m.group(2) + name + m.group(2),
                                data[slice(*part.span)], count=1)
    return splice(data, own), {p: splice(p.data, r) for p, r in theirs.items()}


def _where(parts: list[Part], data: bytes, offset: int) -> tuple:
    """(the included file's name, or None for the scene file; line) of a byte offset of the
    merged bytes, ``data`` the scene file's own."""
    for p in parts:
        if p.at <= offset < p.at + p.length:
            return p.name, p.data.count(b"\n", 0, offset - p.at + p.content[0]) + 1
    shift = sum(p.growth for p in parts if p.at + p.length <= offset)
    return None, data.count(b"\n", 0, offset - shift) + 1


def locate(materials: list[Material], parts: list[Part], data: bytes) -> None:
    """The materials of merged bytes (:func:`merge_includes`) told where they are written: each
    one's file and line, and "(line N)" in the labels of unnamed ones, in that file."""
    lines = {}
    for mat in materials:
        merged_line = mat.line
        mat.file, mat.line = _where(parts, data, mat.start)
        if mat.parent is None and mat.label == f"{mat.type} (line {merged_line})":
            lines[merged_line] = f"(line {mat.line}" + (f" of {mat.file})" if mat.file else ")")

    def fix(label):
        return label and re.sub(r"\(line (\d+)\)", lambda m: lines.get(int(m.group(1)),
                                                                     m.group(0)), label)
    for mat in materials:
        mat.label, mat.parent = fix(mat.label), fix(mat.parent)


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
