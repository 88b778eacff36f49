"""
A fitted BSDF as the fit writes it: its values rounded to 6 significant digits, one number
where the channels agree, and its command-line form (``plugin key=value ...``).
"""

from __future__ import annotations

import shlex

import numpy as np

from ..errors import MiBrdfsError


def _number(v: float) -> float:
    """A fitted number, rounded to 6 significant digits (what is written back)."""
    return float(f"{float(v):.6g}")


def _text(value) -> str:
    """A number as the command line reads it back exactly (shortest repr, no '.0')."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def command_line(spec) -> str:
    """A command-line spec ``plugin key=value ...`` of a BSDF dict of plain values."""
    from ..bsdfspec import describe

    if not isinstance(spec, dict):
        raise MiBrdfsError(f"{describe(spec)} has no command-line form")
    parts = [spec["type"]]
    for key, value in spec.items():
        if key in ("type", "id"):
            continue
        if isinstance(value, bool):
            text = str(value).lower()
        elif isinstance(value, (int, float)):
            text = _text(value)
        elif isinstance(value, dict) and value.get("type") == "rgb":
            text = ",".join(_text(c) for c in value["value"])
        elif isinstance(value, str):
            text = value
        else:
            raise MiBrdfsError(f"parameter {key} of {describe(spec)} has no command-line form")
        parts.append(shlex.quote(f"{key}={text}"))
    return " ".join(parts)


def spec_text(spec) -> str:
    """A BSDF as its command line where it has one, else its short description."""
    from ..bsdfspec import describe

    try:
        return command_line(spec)
    except MiBrdfsError:
        return describe(spec)


def _rgb(values) -> dict:
    return {"type": "rgb", "value": [float(v) for v in np.broadcast_to(values, 3)]}


def _plain(values):
    """A spec value: one number when the channels agree, else an ``rgb``."""
    values = np.asarray(values, dtype=np.float64).ravel()
    if np.all(values == values[0]):
        return _number(values[0])
    return {"type": "rgb", "value": [_number(v) for v in values]}
