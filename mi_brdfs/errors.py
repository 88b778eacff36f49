"""Exceptions for user errors: each carries one line that names the problem and the fix."""

import os
import re


class MiBrdfsError(Exception):
    """A user error (bad input, missing file, unusable environment): one line, no traceback."""


class ParameterError(MiBrdfsError, ValueError):
    """A parameter of a plugin, or an argument of a public function (``plugin`` then names the
    function), with a value outside what it allows."""

    def __init__(self, plugin: str, name: str, value, allowed: str):
        self.plugin, self.name, self.value, self.allowed = plugin, name, value, allowed
        super().__init__(f'{plugin}: parameter "{name}" = {_show(value)} is invalid: {allowed}')


class Description(str):
    """A value shown as prose in an error message, not quoted (e.g. 'a texture with ...')."""


class MiBrdfsWarning(UserWarning):
    """Something works, but not the way the user probably wants (e.g. a fallback variant)."""


def _show(value) -> str:
    if isinstance(value, Description):
        return str(value)
    if hasattr(value, "class_name") and callable(value.class_name):  # a Mitsuba object
        return f"a {value.class_name()}"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).replace("\n", " ")


def mitsuba_error_line(error: BaseException) -> str:
    """
    One line from a Mitsuba loader error: the location Mitsuba gives and the last line of the
    cause (a Python plugin's exception arrives inside Mitsuba's message with its traceback).
    A Ctrl-C that Mitsuba wrapped so (a Python plugin's constructor interrupted) is raised
    again as KeyboardInterrupt: every caller would otherwise take it for a bad input, and one
    that skips bad inputs (simplify's candidates) would carry on.
    """
    text = str(error).strip()
    if "KeyboardInterrupt" in text:
        raise KeyboardInterrupt from error
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


class CountError(MiBrdfsError, ValueError):
    """A count (samples, resolution, processes) that is not a whole number ≥ 1."""


def counts(*names: str):
    """
    Decorator: the parameters ``names`` of the function, where given (not None), must be whole
    numbers ≥ 1; else one CountError naming the function, the parameter and the value, before
    any work (a count of 0 once made Mitsuba divide by zero, a pass of 0 spp loop forever).
    """
    import functools
    import inspect
    import numbers

    def decorate(fn):
        signature = inspect.signature(fn)
        where = f"{fn.__module__.removeprefix('mi_brdfs.')}.{fn.__name__}"

        @functools.wraps(fn)
        def checked(*args, **kwargs):
            bound = signature.bind_partial(*args, **kwargs)
            for name in names:
                value = bound.arguments.get(name)
                if value is None:
                    continue
                ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
                if not ok or value < 1:
                    raise CountError(f"{where}: {name} = {value!r} is invalid: must be a whole "
                                     f"number ≥ 1")
            return fn(*args, **kwargs)
        return checked
    return decorate


# -------------------------------------------------------------------------------------------------
# Arguments of public functions: each rule returns the value (converted) or raises ValueError
# with what is allowed; :func:`arguments` turns that into one ParameterError
# -------------------------------------------------------------------------------------------------


def _is_real(value) -> bool:
    import numbers

    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _array(value, allowed: str):
    """``value`` as a flat float64 array: a number or a sequence of numbers (no string)."""
    import numpy as np

    if isinstance(value, (str, bytes, dict)) or value is None:
        raise ValueError(allowed)
    try:
        return np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ValueError(allowed) from None


def valid_seed(value) -> int:
    """A seed: a whole number in [0, 2³²) (what NumPy's and DrJit's generators take)."""
    import numbers

    if not (isinstance(value, numbers.Integral) and not isinstance(value, bool)
            and 0 <= value < 2 ** 32):
        raise ValueError("must be a whole number in [0, 2^32)")
    return int(value)


def valid_direction(value):
    """A direction in the local frame: 3 finite numbers, not all 0 (as a float64 array)."""
    import numpy as np

    allowed = ("must be 3 finite numbers, not all 0 (a direction in the local frame, e.g. "
               "(0.6, 0, 0.8))")
    a = _array(value, allowed)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or not np.any(a != 0):
        raise ValueError(allowed)
    return a


def valid_angles(hi: float, unit: str):
    """A rule: one or more finite angles in [0, ``hi``] ``unit`` (as a tuple of floats)."""
    def rule(value) -> tuple:
        import numpy as np

        allowed = f"must be one or more finite angles in [0, {hi:g}] {unit}"
        a = _array(value, allowed)
        if a.size == 0 or not np.all(np.isfinite(a)) or not np.all((a >= 0) & (a <= hi)):
            raise ValueError(allowed)
        return tuple(float(x) for x in a)
    return rule


def valid_angle(hi: float, unit: str):
    """A rule: one finite angle in [0, ``hi``] ``unit``."""
    def rule(value) -> float:
        if not (_is_real(value) and 0 <= value <= hi):
            raise ValueError(f"must be a finite angle in [0, {hi:g}] {unit}")
        return float(value)
    return rule


def nonnegative(value) -> float:
    """A tolerance: a finite number ≥ 0."""
    import math

    if not (_is_real(value) and math.isfinite(value) and value >= 0):
        raise ValueError("must be a finite number >= 0")
    return value


def positive(value) -> float:
    """A finite number > 0 (a number of standard errors, a scale)."""
    import math

    if not (_is_real(value) and math.isfinite(value) and value > 0):
        raise ValueError("must be a finite number > 0")
    return value


def fraction(value) -> float:
    """A number in (0, 1) (a significance level)."""
    if not (_is_real(value) and 0 < value < 1):
        raise ValueError("must be a number in (0, 1)")
    return value


def nonempty_specs(value):
    """One BSDF spec or a non-empty list of them."""
    if isinstance(value, (list, tuple)) and len(value) == 0:
        raise ValueError("must be one BSDF spec or a non-empty list of them")
    return value


def arguments(**rules):
    """
    Decorator: each named argument, where given (not None), is checked (and converted) by its
    rule (:func:`valid_seed`, :func:`valid_direction`, :func:`valid_angles`, ...) before any work; a value a rule
    refuses ends in one ParameterError naming the function, the parameter, the value and what
    is allowed, instead of NumPy's or DrJit's ValueError, IndexError or TypeError from deep
    inside.
    """
    import functools
    import inspect

    def decorate(fn):
        signature = inspect.signature(fn)
        where = f"{fn.__module__.removeprefix('mi_brdfs.')}.{fn.__name__}"

        @functools.wraps(fn)
        def checked(*args, **kwargs):
            try:
                bound = signature.bind_partial(*args, **kwargs)
            except TypeError:
                return fn(*args, **kwargs)  # Python's own error for a wrong call
            for name, rule in rules.items():
                value = bound.arguments.get(name)
                if value is None:
                    continue
                try:
                    bound.arguments[name] = rule(value)
                except ValueError as e:
                    raise ParameterError(where, name, value, str(e)) from None
            return fn(*bound.args, **bound.kwargs)
        return checked
    return decorate
