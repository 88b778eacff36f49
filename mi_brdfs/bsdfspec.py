"""
One way to name a BSDF everywhere, and the one place that turns a name into what a layer needs.

A BSDF is given as a ``mi.load_dict`` dict, an XML fragment (``<bsdf ...>``), a command-line
string ``'roughconductor alpha=0.3 material=Au'``, or an already loaded ``mi.BSDF``. Every public
function of the package that takes a BSDF takes all four, through this module:

* :func:`parse`: the spec in canonical form (a command-line string becomes a dict or an XML
  fragment, once), with one-line errors for what is no BSDF spec at all;
* :func:`load_bsdf`: a ``mi.BSDF`` in the current variant (within :func:`loaded_once`, the
  same object for the same spec: a check that hands the spec to several helpers loads it
  once);
* :func:`to_xml`: an XML ``<bsdf>`` element to put into a scene file, for every form (a loaded
  ``mi.BSDF`` through a plugin registered to return that very object);
* :func:`describe`: a short name for tables and legends.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import re
import shlex
import weakref
from xml.sax.saxutils import quoteattr

from .errors import MiBrdfsError, mitsuba_error_line


def parse(spec):
    """
    The BSDF spec in canonical form: a dict (with a ``type``), an XML fragment (str starting
    with ``<``) or a ``mi.BSDF``; a command-line string is parsed into a dict or a fragment,
    a BSDF file (a ``pathlib.Path``, or a str naming an existing ``.xml`` file, blanks in its
    path included) becomes the fragment it holds, and a MERL file (``.binary``) the ``merl``
    plugin that reads it.

    Raises MiBrdfsError with one line for anything else.
    """
    import mitsuba as mi

    if isinstance(spec, mi.BSDF):
        return spec
    if isinstance(spec, mi.Object):  # the mi.BSDF of another variant, or no BSDF at all
        kind = spec.class_name() if type(spec).__module__ == "mitsuba" else type(spec).__name__
        if spec.variant_name() != mi.variant():
            raise MiBrdfsError(f"a {kind} loaded in {spec.variant_name()} cannot be used in "
                               f"{mi.variant()}, the variant this call works in: give it as a "
                               f"dict, an XML fragment or 'type key=value ...', or load it in "
                               f"{mi.variant()}")
        raise MiBrdfsError(f"a {kind} is not a BSDF")
    if isinstance(spec, dict):
        if not isinstance(spec.get("type"), str):
            raise MiBrdfsError(f"a BSDF dict needs a 'type' (e.g. 'diffuse'), got {spec}")
        return spec
    if isinstance(spec, str) and spec.lstrip().startswith("<"):
        return spec.strip()
    if str(spec).endswith(".binary") and (isinstance(spec, os.PathLike) or
                                          os.path.isfile(spec)):
        return {"type": "merl", "filename": os.fspath(spec)}  # MERL's format, blanks and all
    if isinstance(spec, os.PathLike) or (isinstance(spec, str) and spec.endswith(".xml")
                                         and os.path.isfile(spec)):
        return _bsdf_file(os.fspath(spec)).strip()  # a file, whatever blanks its path has
    if isinstance(spec, str):
        try:
            tokens = shlex.split(spec)
        except ValueError as e:
            raise MiBrdfsError(f"cannot read BSDF '{spec}': {e}") from None
        specs = parse_cli(tokens)
        if len(specs) != 1:
            raise MiBrdfsError(f"'{spec}' names {len(specs)} BSDFs, not one")
        return specs[0]
    raise MiBrdfsError(f"cannot make a BSDF from {spec!r} ({type(spec).__name__}): give a dict, "
                       f"an XML fragment, 'type key=value ...' or a loaded mi.BSDF")


#: spec key -> loaded BSDF while :func:`loaded_once` is active, else None
_loaded: dict | None = None


@contextlib.contextmanager
def loaded_once():
    """
    Within (a ``with`` block, or a function it decorates): :func:`load_bsdf` loads each spec
    once per variant and returns the same ``mi.BSDF`` for it again. The checks and the
    commands that run them open it, so that one check call loads its BSDF once; nested uses
    share the outermost one. The objects are the caller's to read, not to change.
    """
    global _loaded
    outer = _loaded is not None
    if not outer:
        _loaded = {}
    try:
        yield
    finally:
        if not outer:
            _loaded = None


def _key(spec) -> str:
    """The identity of a parsed spec for :func:`loaded_once`: its content (objects inside a
    dict, such as a texture or a transform, by identity: they live as long as the call)."""
    import mitsuba as mi

    text = spec if isinstance(spec, str) else json.dumps(
        spec, sort_keys=True, default=lambda o: f"<{type(o).__name__} {id(o)}>")
    return f"{mi.variant()}: {text}"


def load_bsdf(spec):
    """
    A ``mi.BSDF`` in the current variant from any form of spec (a ``mi.BSDF`` is returned as is).

    Raises MiBrdfsError with one line when Mitsuba or the plugin rejects the specification.
    """
    import mitsuba as mi

    spec = parse(spec)
    if isinstance(spec, mi.BSDF):
        return spec
    key = _key(spec) if _loaded is not None else None
    if key is not None and key in _loaded:
        return _loaded[key]
    try:
        if isinstance(spec, dict):
            obj = mi.load_dict(spec)
        else:
            xml = spec
            if "version=" not in xml.split(">", 1)[0]:
                xml = xml.replace("<bsdf", '<bsdf version="3.0.0"', 1)
            obj = mi.load_string(xml)
    except RuntimeError as e:
        raise MiBrdfsError(mitsuba_error_line(e)) from None
    if not isinstance(obj, mi.BSDF):
        raise MiBrdfsError(f"{describe(spec)} is a {type(obj).__name__}, not a BSDF")
    if key is not None:
        _loaded[key] = obj
    return obj


def describe(spec) -> str:
    """A short human-readable name of a BSDF specification, for tables and legends."""
    if isinstance(spec, dict):
        params = ", ".join(f"{k}={_short(v)}" for k, v in spec.items() if k != "type")
        return f"{spec.get('type', '?')}({params})" if params else str(spec.get("type", "?"))
    if isinstance(spec, str):
        return _describe_xml(spec)
    return type(spec).__name__


def _describe_xml(text: str) -> str:
    """An XML ``<bsdf>`` as :func:`describe` names a dict: its type and its direct parameters
    (a nested element by its type); its first 60 characters where it does not parse."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(text)
    except ET.ParseError:
        return " ".join(text.split())[:60]
    params = [f"{child.get('name')}={child.get('value', child.get('type', '…'))}"
              for child in root if child.get("name") is not None]
    kind = root.get("type", root.tag)
    return f"{kind}({', '.join(params)})" if params else kind


def _short(value) -> str:
    if isinstance(value, dict):
        if value.get("type") in ("rgb", "spectrum"):
            return str(value.get("value"))
        return value.get("type", "?")
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def plugin_kind(name: str) -> str:
    """
    'BSDF', 'Texture', 'Shape', ... or 'Unknown' for a plugin name in the current variant.

    ``PluginManager.plugin_type`` knows Python plugins only in the variant where they were
    registered first, so a plugin it calls Unknown is instantiated to find out, at its defaults:
    whatever that instance warns of (rpv's energy at its defaults) is not the user's BSDF's, and
    is not shown.
    """
    import warnings

    import mitsuba as mi

    kind = str(mi.PluginManager.instance().plugin_type(name)).split(".")[-1]
    if kind != "Unknown":
        return kind
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            obj = mi.load_dict({"type": name})
    except RuntimeError as e:
        return "Unknown" if "not found" in str(e) else "BSDF"  # exists, but needs parameters
    for kind in ("BSDF", "Texture", "Shape", "Emitter", "Sensor", "Integrator"):
        if isinstance(obj, getattr(mi, kind)):
            return kind
    return type(obj).__name__


# -------------------------------------------------------------------------------------------------
# dict -> XML (to put a BSDF given as a dict into an XML scene)
# -------------------------------------------------------------------------------------------------


def _xml_value(name: str, value, indent: str) -> str:
    n = quoteattr(name)
    if isinstance(value, bool):
        return f'{indent}<boolean name={n} value="{str(value).lower()}"/>'
    if isinstance(value, int):
        return f'{indent}<integer name={n} value="{value}"/>'
    if isinstance(value, float):
        return f'{indent}<float name={n} value="{value!r}"/>'
    if isinstance(value, str):
        return f"{indent}<string name={n} value={quoteattr(value)}/>"
    if isinstance(value, dict):
        kind = value.get("type")
        if kind == "rgb":
            v = ", ".join(repr(float(x)) for x in _as_list(value["value"]))
            return f'{indent}<rgb name={n} value="{v}"/>'
        if kind == "spectrum":
            v = value["value"]
            if isinstance(v, (int, float)):
                text = repr(float(v))
            else:
                text = ", ".join(f"{float(w)!r}:{float(x)!r}" for w, x in v)
            return f'{indent}<spectrum name={n} value="{text}"/>'
        return _xml_object(value, indent, name=name)
    raise MiBrdfsError(f"cannot write parameter {name!r} = {value!r} as XML")


def _as_list(value) -> list:
    if isinstance(value, (int, float)):
        return [float(value)] * 3
    return [float(x) for x in value]


def _xml_object(spec: dict, indent: str = "", name: str | None = None) -> str:

    kind = spec.get("type")
    if not isinstance(kind, str):
        raise MiBrdfsError(f"a BSDF dict needs a 'type' (e.g. 'diffuse'), got {spec}")
    tag = {"BSDF": "bsdf", "Texture": "texture", "Spectrum": "spectrum"}.get(plugin_kind(kind))
    if tag is None:
        raise MiBrdfsError(f"unknown plugin '{kind}' (not a BSDF or texture of this Mitsuba)")
    attrs = f" type={quoteattr(kind)}"
    if name:
        attrs += f" name={quoteattr(name)}"
    if "id" in spec:
        attrs += f" id={quoteattr(str(spec['id']))}"
    children = [_xml_value(k, v, indent + "    ") for k, v in spec.items()
                if k not in ("type", "id")]
    if not children:
        return f"{indent}<{tag}{attrs}/>"
    return "\n".join([f"{indent}<{tag}{attrs}>"] + children + [f"{indent}</{tag}>"])


def to_xml(spec, id: str | None = None) -> str:
    """
    An XML ``<bsdf>`` element, with ``id`` set, for a BSDF in any form (see :func:`parse`).
    Dict values: bool, int, float, str, ``{'type': 'rgb'|'spectrum', 'value': ...}`` and nested
    plugin dicts (textures, BSDFs). A loaded ``mi.BSDF`` becomes a ``<bsdf>`` of a plugin type
    registered (in the current variant) to return that very object.
    """
    import mitsuba as mi

    spec = parse(spec)
    if isinstance(spec, mi.BSDF):
        attrs = f" id={quoteattr(id)}" if id else ""
        return f"<bsdf type={quoteattr(_object_plugin(spec))}{attrs}/>"
    if isinstance(spec, dict):
        return _xml_object(dict(spec, id=id) if id else spec)
    xml = spec
    if id:
        xml = re.sub(r"\sid=(\"[^\"]*\"|'[^']*')", "", xml, count=1)
        xml = xml.replace("<bsdf", f"<bsdf id={quoteattr(id)}", 1)
    return xml


_object_names = (f"mi_brdfs_loaded_bsdf_{i}" for i in itertools.count())


def _object_plugin(bsdf) -> str:
    """
    The name of a BSDF plugin, registered now, whose every instance is ``bsdf`` itself.

    Mitsuba keeps a registered plugin for the life of the process, and a JIT render traces the
    methods of every BSDF alive in the process into its kernels (a symbolic virtual call
    records each registered instance): a plugin that held its object would keep it alive, and
    every later render would pay for it. The plugin holds a Python plugin's object weakly (it
    lives while its caller or a scene holds it); a built-in's, which cannot be referenced
    weakly, strongly.
    """
    import mitsuba as mi

    name = next(_object_names)
    try:
        ref = weakref.ref(bsdf)
    except TypeError:
        ref = lambda: bsdf  # noqa: E731

    def instance(props):
        obj = ref()
        if obj is None:
            raise MiBrdfsError(f"<bsdf type=\"{name}\">: the loaded BSDF it stands for has "
                               "been freed; keep a reference to it while scenes name it")
        return obj

    mi.register_bsdf(name, instance)
    return name


# -------------------------------------------------------------------------------------------------
# Command-line BSDF specifications: `type key=value ...`, several per command line
# -------------------------------------------------------------------------------------------------


def parse_value(text: str):
    """
    A command-line parameter value: ``true``/``false`` → bool, a number → float, three
    comma-separated numbers → ``{'type': 'rgb'}``, anything else → str (``Au``, ``ggx``).
    """
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    parts = [p for p in text.split(",")]
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        return text
    if len(numbers) == 1:
        return numbers[0]
    if len(numbers) == 3:
        return {"type": "rgb", "value": numbers}
    raise MiBrdfsError(f"'{text}': a value is a number or three comma-separated numbers (rgb)")


def _bsdf_file(path: str) -> str:
    """The text of an XML file that holds one ``<bsdf>``."""
    import xml.etree.ElementTree as ET

    if not os.path.isfile(path):
        raise MiBrdfsError(f"BSDF file {path} does not exist")
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except UnicodeDecodeError as e:
        raise MiBrdfsError(f"BSDF file {path} is not UTF-8 text (byte {e.start}: "
                           f"{e.reason})") from None
    try:
        tag = ET.fromstring(text).tag
    except ET.ParseError as e:
        raise MiBrdfsError(f"BSDF file {path}: XML parsing failed: {e}") from None
    if tag != "bsdf":
        raise MiBrdfsError(f"{path} holds a <{tag}>, not a <bsdf> (give a BSDF's XML file, a "
                           f"plugin name such as 'diffuse', or an XML fragment)")
    return text


def _words(tokens) -> list[str]:
    """
    The words of command-line tokens: a token with blanks that is no XML fragment and no
    existing file (a quoted ``'roughconductor alpha=0.3'``) is split as a shell splits it, so
    that one spec reads the same quoted or not.
    """
    if isinstance(tokens, str):
        raise MiBrdfsError(f"parse_cli takes a list of tokens, not the string {tokens!r} "
                           f"(parse() reads one spec from a string)")
    words = []
    for token in tokens:
        token = str(token)
        if len(token.split()) <= 1 or token.lstrip().startswith("<") or os.path.isfile(token):
            words.append(token)
            continue
        try:
            words += shlex.split(token)
        except ValueError as e:
            raise MiBrdfsError(f"cannot read BSDF '{token}': {e}") from None
    return words


def parse_cli(tokens: list[str]) -> list:
    """
    BSDFs from command-line tokens. A token without '=' starts a BSDF: a plugin name (followed
    by its ``key=value`` parameters), an XML file holding one ``<bsdf>``, or an XML fragment.
    A quoted spec with blanks is the same as its words (:func:`_words`): every command and
    :func:`parse` read one grammar.

        parse_cli(['roughconductor', 'alpha=0.3', 'material=Au', 'diffuse'])
        → [{'type': 'roughconductor', 'alpha': 0.3, 'material': 'Au'}, {'type': 'diffuse'}]
        parse_cli(['roughconductor alpha=0.3 material=Au', 'diffuse'])  → the same
    """

    specs: list = []
    for token in _words(tokens):
        if "=" in token and not token.lstrip().startswith("<"):
            key, _, value = token.partition("=")
            if not specs or not isinstance(specs[-1], dict):
                raise MiBrdfsError(f"parameter '{token}' comes before any BSDF name "
                                   f"(write e.g. 'roughconductor alpha=0.3')")
            if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.]*", key) or value == "":
                raise MiBrdfsError(f"malformed parameter '{token}': expected key=value")
            if key in specs[-1]:
                raise MiBrdfsError(f"parameter '{key}' is given twice for "
                                   f"'{specs[-1]['type']}' (give it once)")
            specs[-1][key] = parse_value(value)
        elif token.lstrip().startswith("<"):
            specs.append(token)
        elif token.endswith(".xml"):
            specs.append(_bsdf_file(token))
        elif token.endswith(".binary"):  # measured data in MERL's format: the merl plugin
            specs.append({"type": "merl", "filename": token})
        else:
            kind = plugin_kind(token)
            if kind == "Unknown":
                raise MiBrdfsError(f"unknown plugin '{token}' "
                                   f"(neither Mitsuba nor mi_brdfs has it)")
            if kind != "BSDF":
                raise MiBrdfsError(f"plugin '{token}' is a {kind.lower()}, not a BSDF")
            specs.append({"type": token})
    if not specs:
        raise MiBrdfsError("no BSDF given (e.g. 'diffuse' or 'roughconductor alpha=0.3')")
    return specs
