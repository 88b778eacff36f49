"""
The bundled scenes and scene loading with one-line errors.

The scenes live in ``scenes/`` at the top of the repository and inside the wheel as
``mi_brdfs/scenes`` (see ``pyproject.toml``); :func:`scene_path` finds them in both layouts.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from .errors import MiBrdfsError

_PACKAGE = Path(__file__).resolve().parent


def scenes_dir() -> Path:
    """The folder of the bundled scenes (installed wheel or source checkout)."""
    for candidate in (_PACKAGE / "scenes", _PACKAGE.parent / "scenes"):
        if (candidate / "showcase.xml").is_file():
            return candidate
    raise MiBrdfsError("the bundled scenes are missing from this installation of mi_brdfs")


def scene_path(name_or_path: str | os.PathLike) -> Path:
    """
    A scene file: an existing path, or the name of a bundled scene (``showcase``, ``furnace``,
    ``cbox``, ``metalbox``, with or without ``.xml``).
    """
    path = Path(name_or_path).expanduser()
    if path.is_file():
        return path.resolve()
    bundled = scenes_dir() / (path.name if path.suffix == ".xml" else f"{path.name}.xml")
    if path.parent == Path(".") and bundled.is_file():
        return bundled
    if path.is_dir():
        raise MiBrdfsError(f"scene {path} is a directory, not an XML file")
    raise MiBrdfsError(f"scene file {path} does not exist (bundled scenes: "
                       f"{', '.join(sorted(p.stem for p in scenes_dir().glob('*.xml')))})")


def parse_defines(items: list[str] | None) -> dict[str, str]:
    """``['spp=16', 'res=64']`` → ``{'spp': '16', 'res': '64'}``; one clear error for bad items."""
    defines = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name.strip()):
            raise MiBrdfsError(f"-D expects name=value (e.g. -D spp=64), got '{item}'")
        defines[name.strip()] = value.strip()
    return defines


def mitsuba_error_line(error: BaseException) -> str:
    """
    One line from a Mitsuba loader error: the location Mitsuba gives and the last line of the
    cause (a Python plugin's exception arrives inside Mitsuba's message with its traceback).
    """
    text = str(error).strip()
    text = re.sub(r"^\[[\w.]+:\d+\]\s*", "", text)  # Mitsuba's [parser.cpp:1718] source tag
    head, sep, tail = text.partition("Traceback (most recent call last):")
    if sep:
        lines = [ln.strip() for ln in tail.strip().splitlines() if ln.strip()]
        cause = lines[-1] if lines else ""
        cause = re.sub(r"^(mi_brdfs\.errors\.)?(\w+Error): ", "", cause)
        head = head.strip().rstrip(":")
        head = re.sub(r'failed to instantiate (\w+) plugin of type "[\w-]+"', "", head).strip(" :")
        text = f"{head}: {cause}" if head else cause
    # 'At /long/path/scene.xml (line 29, col 6): ...' -> 'scene.xml (line 29, col 6): ...'
    text = re.sub(r'At "?([^"\s]+?)"? (\(line \d+, col \d+\))',
                  lambda m: f"{os.path.basename(m.group(1))} {m.group(2)}", text)
    unused = re.findall(r"\$(\w+)=", text) if "unused parameters" in text else []
    if unused:
        return ("the scene declares no <default> for " + ", ".join(unused) +
                " (a -D name=value must name a <default name=...> of the scene)")
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    return " ".join(lines)


def load_scene(path: str | os.PathLike, defines: dict | None = None, bsdfs: dict | None = None,
               **kwargs):
    """
    Load a scene file (path or bundled name) with ``<default>`` overrides, raising MiBrdfsError
    with one line for a missing file, a parse error or a plugin that rejects its parameters.

    Parameter ``bsdfs`` (dict | None): ``{id: BSDF}`` replaces the ``<bsdf id="...">`` elements
    of the scene by these BSDFs (dicts, XML fragments or ``'type key=value'`` strings), e.g.
    ``load_scene('furnace', bsdfs={'material': {'type': 'roughconductor', 'alpha': 0.3}})``.
    """
    import mitsuba as mi

    path = scene_path(path)
    params = dict(defines or {})
    params.update({k: str(v) for k, v in kwargs.items()})
    try:
        if not bsdfs:
            return mi.load_file(str(path), **params)
        xml = swap_bsdfs(path.read_text(), bsdfs)
        # relative paths in the scene (textures, meshes) resolve against its folder, as in
        # mi.load_file; the resolver is global, so it is restored afterwards
        saved = mi.FileResolver(mi.file_resolver())
        mi.file_resolver().prepend(str(path.parent))
        try:
            return mi.load_string(xml, **params)
        finally:
            mi.set_file_resolver(saved)
    except RuntimeError as e:
        line = mitsuba_error_line(e)
        raise MiBrdfsError(line if path.name in line else f"{path.name}: {line}") from None


def swap_bsdfs(xml: str, bsdfs: dict) -> str:
    """The scene XML text with each ``<bsdf id=...>`` of ``bsdfs`` replaced (see load_scene)."""
    import xml.etree.ElementTree as ET

    from .bsdfspec import parse_cli, to_xml

    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        raise MiBrdfsError(f"cannot parse the scene to swap its materials: {e}") from None
    for bsdf_id, spec in bsdfs.items():
        if isinstance(spec, str) and not spec.lstrip().startswith("<"):
            import shlex
            specs = parse_cli(shlex.split(spec))
            if len(specs) != 1:
                raise MiBrdfsError(f"'{spec}' names {len(specs)} BSDFs, not one")
            spec = specs[0]
        found = False
        for parent in root.iter():
            for i, child in enumerate(list(parent)):
                if child.tag == "bsdf" and child.get("id") == bsdf_id:
                    new = ET.fromstring(to_xml(spec, id=bsdf_id))
                    parent.remove(child)
                    parent.insert(i, new)
                    found = True
        if not found:
            ids = sorted({e.get("id") for e in root.iter("bsdf") if e.get("id")})
            raise MiBrdfsError(f"the scene has no <bsdf id=\"{bsdf_id}\"> "
                               f"(its BSDF ids: {', '.join(ids) or 'none'})")
    return ET.tostring(root, encoding="unicode")
