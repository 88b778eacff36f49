"""
One way to name a BSDF everywhere: a ``mi.load_dict`` dict, an XML fragment (``<bsdf ...>``),
or an already loaded ``mi.BSDF``. :func:`load_bsdf` turns any of them into a ``mi.BSDF`` in the
current variant, with one-line errors.
"""

from __future__ import annotations

from .errors import MiBrdfsError


def load_bsdf(spec):
    """
    A ``mi.BSDF`` from a dict, an XML fragment or a ``mi.BSDF`` (returned as is).

    Raises MiBrdfsError with one line when Mitsuba or the plugin rejects the specification.
    """
    import mitsuba as mi

    from .scenes import mitsuba_error_line

    if isinstance(spec, mi.BSDF):
        return spec
    try:
        if isinstance(spec, dict):
            if "type" not in spec:
                raise MiBrdfsError(f"a BSDF dict needs a 'type' (e.g. 'diffuse'), got {spec}")
            obj = mi.load_dict(spec)
        elif isinstance(spec, str) and spec.lstrip().startswith("<"):
            xml = spec.strip()
            if "version=" not in xml.split(">", 1)[0]:
                xml = xml.replace("<bsdf", '<bsdf version="3.0.0"', 1)
            obj = mi.load_string(xml)
        else:
            raise MiBrdfsError(f"cannot make a BSDF from {spec!r}: give a dict or an XML fragment")
    except RuntimeError as e:
        raise MiBrdfsError(mitsuba_error_line(e)) from None
    if not isinstance(obj, mi.BSDF):
        raise MiBrdfsError(f"{spec!r} is a {type(obj).__name__}, not a BSDF")
    return obj


def describe(spec) -> str:
    """A short human-readable name of a BSDF specification, for tables and legends."""
    if isinstance(spec, dict):
        params = ", ".join(f"{k}={_short(v)}" for k, v in spec.items() if k != "type")
        return f"{spec.get('type', '?')}({params})" if params else str(spec.get("type", "?"))
    if isinstance(spec, str):
        return " ".join(spec.split())[:60]
    return type(spec).__name__


def _short(value) -> str:
    if isinstance(value, dict):
        if value.get("type") in ("rgb", "spectrum"):
            return str(value.get("value"))
        return value.get("type", "?")
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)
