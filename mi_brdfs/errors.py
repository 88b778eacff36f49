"""Exceptions for user errors: each carries one line that names the problem and the fix."""


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
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    return str(value).replace("\n", " ")
