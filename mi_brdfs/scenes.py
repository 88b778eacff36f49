"""
The bundled scenes and scene loading with one-line errors.

The scenes live in ``scenes/`` at the top of the repository and inside the wheel as
``mi_brdfs/scenes`` (see ``pyproject.toml``); :func:`scene_path` finds them in both layouts.
"""

from __future__ import annotations

import os
import re
import struct
from pathlib import Path

from .errors import MiBrdfsError, mitsuba_error_line

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
        _not_measured_data(path)
        return path.resolve()
    bundled = scenes_dir() / (path.name if path.suffix == ".xml" else f"{path.name}.xml")
    if path.parent == Path(".") and bundled.is_file():
        return bundled
    if path.is_dir():
        raise MiBrdfsError(f"scene {path} is a directory, not an XML file")
    raise MiBrdfsError(f"scene file {path} does not exist (bundled scenes: "
                       f"{', '.join(sorted(p.stem for p in scenes_dir().glob('*.xml')))})")


def _not_measured_data(path: Path) -> None:
    """A MERL measured BRDF (a ``.binary`` file, or one that starts with MERL's dimensions 90,
    90, 180) where a scene is taken is one line saying it is a BSDF and how to use it."""
    with open(path, "rb") as f:
        head = f.read(12)
    if path.suffix.lower() == ".binary" or head == struct.pack("<3i", 90, 90, 180):
        raise MiBrdfsError(
            f"{path.name} is a MERL measured BRDF, not a scene: use it as a BSDF, merl "
            f"filename={path} (e.g. mi-brdfs check merl filename={path}; mi-brdfs compare "
            f"material --swap \"material=merl filename={path}\" renders it on a sphere; in "
            f"a scene, <bsdf type=\"merl\"><string name=\"filename\" value=\"{path}\"/>"
            f"</bsdf>)")


def parse_defines(items: list[str] | None) -> dict[str, str]:
    """``['spp=16', 'res=64']`` → ``{'spp': '16', 'res': '64'}``; one clear error for bad items."""
    defines = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name.strip()):
            raise MiBrdfsError(f"-D expects name=value (e.g. -D spp=64), got '{item}'")
        if not value.strip():  # Mitsuba would read an empty number as 0, silently
            raise MiBrdfsError(f"-D {item} has no value (give name=value, e.g. -D spp=64)")
        defines[name.strip()] = value.strip()
    return defines


def scene_text(path: Path) -> str:
    """
    The text of a scene file, read as UTF-8 (Mitsuba's XML; not the locale's encoding), with
    one line for a file that is not UTF-8 text or whose root element is not ``<scene>`` (a
    ``<bsdf>`` belongs to ``check``, ``furnace`` or ``plot``, a ``<shape>`` in a scene).
    """
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        raise MiBrdfsError(f"{path.name} is not UTF-8 text (byte {e.start}: {e.reason}); "
                           f"Mitsuba's scene files are UTF-8") from None
    root = re.search(r"<\s*([A-Za-z_][\w.-]*)", re.sub(r"<\?.*?\?>|<!--.*?-->", "", text,
                                                     flags=re.S))
    if root is not None and root.group(1) != "scene":
        hint = (" (check, furnace and plot take a BSDF file)" if root.group(1) == "bsdf"
                else "")
        raise MiBrdfsError(f"{path.name} holds a <{root.group(1)}>, not a <scene>: a scene "
                           f"file's root element is <scene version=\"3.0.0\">{hint}")
    return text


def used_defines(defines: dict, text: bytes, known: tuple = ()) -> dict:
    """
    The defines but those of a ``<default>`` that the scene text no longer references
    (``$name``): Mitsuba refuses a parameter that nothing uses, and a swapped or replaced
    material (its values substituted) or a merged ``<include>`` (its file name resolved) may
    have held the only reference. A define the scene does not declare is kept, for Mitsuba to
    refuse; so is every define while the text includes a file not named in ``known`` (whose
    text is part of ``text``), which may reference any.
    """
    text = re.sub(rb"<!--.*?-->", b"", text, flags=re.S)  # Mitsuba reads no comment
    names = re.findall(rb"""<include\b[^>]*?filename\s*=\s*["']([^"']*)["']""", text)
    if any(name.decode("utf-8") not in known for name in names):
        return dict(defines)
    declared = set(re.findall(rb"""<default\b[^>]*?name\s*=\s*["']([^"']*)["']""", text))
    return {k: v for k, v in defines.items() if k.encode("utf-8") not in declared
            or re.search(rb"\$" + re.escape(k.encode("utf-8")) + rb"\b", text)}


def load_scene(path: str | os.PathLike, defines: dict | None = None, bsdfs: dict | None = None,
               **kwargs):
    """
    Load a scene file (path or bundled name) with ``<default>`` overrides, raising MiBrdfsError
    with one line for a missing file, a parse error or a plugin that rejects its parameters.

    Parameter ``bsdfs`` (dict | None): ``{id: BSDF}`` replaces the ``<bsdf id="...">`` elements
    of the scene by these BSDFs (in any form of :mod:`mi_brdfs.bsdfspec`: dicts, XML fragments,
    ``'type key=value'`` strings or loaded ``mi.BSDF`` objects), e.g.
    ``load_scene('furnace', bsdfs={'material': {'type': 'roughconductor', 'alpha': 0.3}})``.
    """
    import mitsuba as mi

    path = scene_path(path)
    params = dict(defines or {})
    params.update({k: str(v) for k, v in kwargs.items()})
    text = scene_text(path)
    _check_film(path.name, text, params)
    try:
        if not bsdfs:
            scene = mi.load_file(str(path), **params)  # (relative paths: the file's folder)
        else:
            xml = swap_bsdfs(text, bsdfs, path.parent)
            # relative paths in the scene (textures, meshes) resolve against its folder, as in
            # mi.load_file; the resolver is global, so it is restored afterwards
            saved = mi.FileResolver(mi.file_resolver())
            mi.file_resolver().prepend(str(path.parent))
            try:
                scene = mi.load_string(xml, **used_defines(params, xml.encode("utf-8")))
            finally:
                mi.set_file_resolver(saved)
    except RuntimeError as e:
        line = mitsuba_error_line(e)
        raise MiBrdfsError(line if path.name in line else f"{path.name}: {line}") from None
    _check_renderable(path.name, scene)
    return scene


def _check_renderable(name: str, scene) -> None:
    """A scene that cannot render gets one line; one that renders black a one-line warning."""
    import warnings

    from .errors import MiBrdfsWarning

    if scene.integrator() is None:
        raise MiBrdfsError(f'{name} has no <integrator> (add e.g. <integrator type="path"/>)')
    if not scene.sensors():
        raise MiBrdfsError(f'{name} has no <sensor> (add e.g. <sensor type="perspective"> '
                           f'with a <film>)')
    if not scene.emitters():
        warnings.warn(f"{name} has no emitter: its image is black", MiBrdfsWarning,
                      stacklevel=3)


def _check_film(name: str, xml: str, params: dict) -> None:
    """
    Every film's width and height, where the XML gives them as numbers or as ``$name`` of a
    ``<default>`` or a define, must be ≥ 1 (Mitsuba reports a width of 0 as a field of view
    outside [0, 180]).
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(xml)
    except ET.ParseError:
        return  # Mitsuba reports it, with the line
    values = {e.get("name"): e.get("value") for e in root.iter("default")}
    values.update(params)
    for film in root.iter("film"):
        for child in film:
            key, text = child.get("name"), child.get("value") or ""
            if key not in ("width", "height"):
                continue
            if text.startswith("$"):
                text = str(values.get(text[1:], ""))
            try:
                value = int(text)
            except ValueError:
                continue  # not a whole number: Mitsuba says so
            if value < 1:
                raise MiBrdfsError(f"{name}: the film's {key} is {value}: it must be at least 1"
                                   + (f" (from {child.get('value')})"
                                      if child.get("value", "").startswith("$") else ""))


def _inline_includes(root, folder: Path, depth: int = 0) -> None:
    """Replace each ``<include filename=...>`` under ``root`` by the elements of the scene file
    it names (relative to ``folder``), as Mitsuba merges them, so that their BSDFs can be
    swapped too; included files may include others (up to 16 deep)."""
    import xml.etree.ElementTree as ET

    for parent in list(root.iter()):
        for i, child in enumerate(list(parent)):
            if child.tag != "include" or depth > 16:
                continue
            path = folder / child.get("filename", "")
            try:
                included = ET.fromstring(scene_text(path))
            except (OSError, ET.ParseError) as e:
                raise MiBrdfsError(f"cannot read the included file {path.name}: {e}") from None
            _inline_includes(included, path.parent, depth + 1)
            parent.remove(child)
            for j, element in enumerate(list(included)):
                parent.insert(i + j, element)


def swap_bsdfs(xml: str, bsdfs: dict, folder: Path | None = None) -> str:
    """The scene XML text with each ``<bsdf id=...>`` of ``bsdfs`` replaced (see load_scene),
    those of files it includes too (``folder``: the scene's, where they are found)."""
    import xml.etree.ElementTree as ET

    from .bsdfspec import to_xml

    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        raise MiBrdfsError(f"cannot parse the scene to swap its materials: {e}") from None
    if folder is not None:
        _inline_includes(root, folder)
    for bsdf_id, spec in bsdfs.items():
        new = ET.fromstring(to_xml(spec, id=bsdf_id))
        found = False
        for parent in root.iter():
            for i, child in enumerate(list(parent)):
                if child.tag == "bsdf" and child.get("id") == bsdf_id:
                    parent.remove(child)
                    parent.insert(i, new)
                    found = True
        if not found:
            ids = sorted({e.get("id") for e in root.iter("bsdf") if e.get("id")})
            raise MiBrdfsError(f"the scene has no <bsdf id=\"{bsdf_id}\"> "
                               f"(its BSDF ids: {', '.join(ids) or 'none'})")
    return ET.tostring(root, encoding="unicode")
