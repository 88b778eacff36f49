"""Exceptions for user errors: each carries one line that names the problem and the fix."""

import os
import re


class MiBrdfsError(Exception):
    """A user error (bad input, missing file, unusable environment): one line, no traceback."""


class ParameterError(MiBrdfsError, ValueError):
    """A plugin parameter with a value outside what the plugin allows."""

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
