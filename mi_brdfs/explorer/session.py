"""
What ``mi-brdfs explore`` shows, without the page: a :class:`Session` holds up to four BSDFs
loaded once in a JIT variant, the controls that their ``mi.traverse`` parameters give
(:class:`Control`), and computes each view from the BSDF's own ``eval`` and ``sample``. A
change of a parameter goes through ``mi.traverse`` (``params.update()``), never through a new
plugin object, so the kernels traced for the views are reused (Mitsuba's documentation,
"Scene parameters": parameters updated in place keep the kernels' inputs, not their code).

Ranges of the sliders: Mitsuba's ``mi.traverse`` gives values, not ranges; a parameter's
range is taken from its name (:data:`RANGES`: roughness, indices, reflectances, exponents,
lengths), else from its value (0 to twice it), within the valid range our plugins check it
against (``properties.VALID``, as the plugin read it), and a value typed beyond it is still
accepted where the plugin accepts it.
"""

from __future__ import annotations

import math
import re
import warnings
from dataclasses import dataclass

import numpy as np

from ..bsdfspec import describe, load_bsdf, parse, to_xml
from ..errors import MiBrdfsError, MiBrdfsWarning

#: Up to this many BSDFs side by side.
MAX_BSDFS = 4

#: (pattern on the parameter's last name, lo, hi, log scale): the first that matches.
RANGES = (
    (r"^(alpha(_u|_v)?|roughness|sigma0?|m)$", 1e-3, 2.0, True),
    (r"^(int_ior|ext_ior|eta|film_eta)$", 1.0, 3.0, False),
    (r"^k$", 0.0, 10.0, False),
    (r"(reflectance|transmittance|albedo|weight)$", 0.0, 1.0, False),
    (r"^(exponent(_\d+)?|n|shininess|nu|nv)$", 1.0, 1e4, True),
    (r"^(film_thickness|thickness)$", 1.0, 1e4, True),
    (r"^(sigma_s|sigma_a)$", 1e-3, 1e3, True),
    (r"^g$", -0.99, 0.99, False),
)


@dataclass
class Control:
    """One parameter of one BSDF: its ``mi.traverse`` key, ``channels`` numbers (1, or 3 for
    a colour), the slider's range and scale, and its value now (a float or a 3-tuple)."""
    key: str
    channels: int
    lo: float
    hi: float
    log: bool
    value: object

    @property
    def label(self) -> str:
        """The parameter's name without Mitsuba's ``.value`` suffix."""
        return _label(self.key)


def _label(key: str) -> str:
    """A ``mi.traverse`` key without its ``.value`` (a constant texture's): the parameter's
    name as the plugin reads it."""
    return key[:-len(".value")] if key.endswith(".value") else key


def _range(key: str, low: float, high: float, valid=None) -> tuple[float, float, bool]:
    """(lo, hi, log) of a parameter from its last name, else from its values; within the
    plugin's ``valid`` range (lo, hi) where it is known; widened to its values (``low`` to
    ``high``)."""
    name = _label(key).split(".")[-1]
    lo, hi, log = next(((lo, hi, log) for pattern, lo, hi, log in RANGES
                        if re.search(pattern, name)), (0.0, max(1.0, 2.0 * abs(high)), False))
    if valid is not None:
        lo = lo if log and valid[0] <= 0.0 else max(lo, valid[0])
        hi = min(hi, valid[1])
    return (min(lo, low) if not log or low > 0 else lo), max(hi, high), log


def controls(params, valid: dict | None = None) -> list[Control]:
    """A control for each parameter of ``params`` (``mi.traverse``) that is one number or one
    colour: the differentiable and the discontinuous ones alike; textures with more values
    (bitmaps) and other types have none. ``valid``: the plugin's valid range of each
    parameter by name (``properties.VALID``), which bounds its slider."""
    import drjit as dr

    out = []
    for key in params.keys():
        value = params[key]
        if not dr.is_array_v(value) or dr.width(value) != 1:
            continue
        numbers = np.array(value, np.float64).ravel()
        if numbers.size not in (1, 3) or not np.all(np.isfinite(numbers)):
            continue
        lo, hi, log = _range(key, float(numbers.min()), float(numbers.max()),
                             (valid or {}).get(_label(key)))
        shown = float(numbers[0]) if numbers.size == 1 else tuple(float(v) for v in numbers)
        out.append(Control(key, numbers.size, lo, hi, log, shown))
    return out


def _heard(action):
    """(``action()``, the messages of the MiBrdfsWarnings it gave, each once): what a plugin
    says of the values it was given (e.g. a form that reflects more than it receives), which
    the page shows beside the BSDF; other warnings pass on as they were."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = action()
    said = []
    for w in caught:
        if issubclass(w.category, MiBrdfsWarning):
            said.append(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return result, list(dict.fromkeys(said))


class Entry:
    """One BSDF of a session: the spec it was given as, the loaded ``mi.BSDF``, its
    parameters and controls; ``warnings``: what its plugin said of the values as they are
    (when it last loaded them or checked a new one)."""

    def __init__(self, spec):
        spec = parse(spec)
        self.name = describe(spec)
        self._load(_expanded(spec))

    def _load(self, spec) -> None:
        import mitsuba as mi

        bsdf, said = _heard(lambda: load_bsdf(spec))
        self.spec, self.bsdf, self.params = spec, bsdf, mi.traverse(bsdf)
        self.warnings = said
        self.controls = {c.key: c for c in controls(self.params, _valid(spec))}
        #: the labels of the parameters set since loading (the dict and XML write those)
        self.changed = set()

    @property
    def switches(self) -> dict:
        """name → (value now, the values allowed) of the configuration switches of the BSDF's
        plugin: ours as the plugin itself read them (``properties.SWITCHES``), Mitsuba's
        built-ins' as the audit's table lists them; none where the BSDF was given as XML."""
        from ..audit.switches import SWITCHES as BUILTIN
        from ..plugins.properties import SWITCHES as OURS

        if not isinstance(self.spec, dict):
            return {}
        kind = self.spec.get("type")
        table = dict(OURS.get(kind, {}))
        table.update({s.name: (s.menu[0], s.menu) for s in BUILTIN.get(kind, ()) if s.menu})
        return {name: (self.spec.get(name, default), options)
                for name, (default, options) in table.items()}

    def replace(self, spec) -> None:
        """Load the BSDF anew from ``spec`` (a dict: the fit button's result), its name kept."""
        self._load(_expanded(parse(spec)))

    def switch(self, name: str, value) -> None:
        """Set a configuration switch: it selects the plugin's code, so the BSDF is loaded
        anew (a new plugin object, its kernels traced anew) with the parameters as they are;
        a value the plugin refuses raises MiBrdfsError in its words and changes nothing."""
        switches = self.switches
        if name not in switches:
            raise MiBrdfsError(f"{self.name}: no switch {name!r} (it has: "
                               f"{', '.join(switches) or 'none'})")
        self._load(self.as_dict({name: value}))

    def set(self, key: str, value) -> None:
        """Set a parameter through ``mi.traverse`` (no new plugin object, no re-trace); a value
        the plugin refuses, or that is no number, raises MiBrdfsError with one line and leaves
        the BSDF as it was."""
        import drjit as dr

        control = self.controls.get(key)
        if control is None:
            raise MiBrdfsError(f"{self.name}: no parameter {key!r} (it has: "
                               f"{', '.join(self.controls) or 'none'})")
        numbers = _numbers(self.name, control, value)
        checked, said = _heard(lambda: self._validate(control, numbers))
        old = self.params[key]
        new = type(old)(*numbers) if control.channels == 3 else type(old)(numbers[0])
        dr.make_opaque(new)  # an input of the kernels, not a literal traced into their code
        self.params[key] = new
        try:
            self.params.update()
        except RuntimeError as e:
            self.params[key] = old
            self.params.update()
            raise MiBrdfsError(f"{self.name}: {control.label} = {value}: "
                               f"{str(e).strip().splitlines()[-1]}") from None
        dr.eval(self.params[key])
        control.value = numbers[0] if control.channels == 1 else tuple(numbers)
        self.changed.add(control.label)
        if checked:
            self.warnings = said

    def _validate(self, control: Control, numbers: list[float]) -> bool:
        """Where the BSDF was given as a dict, the plugin's own checks of the new value: the
        dict with it is loaded (and dropped), and what the plugin refuses is raised in its
        own words (``mi.traverse`` updates are not checked by every plugin). Whether it was
        checked."""
        if isinstance(self.spec, dict) and "." not in control.label:
            value = numbers[0] if control.channels == 1 else tuple(numbers)
            load_bsdf(self.as_dict({control.label: value}))
            return True
        return False

    def values(self) -> dict:
        """The controls' current values by label."""
        return {c.label: c.value for c in self.controls.values()}

    def as_dict(self, pending: dict | None = None) -> dict | None:
        """The spec as a ``mi.load_dict`` dict with the parameters set since loading (and the
        ``pending`` values by label), where it was given as a dict or a command line (else
        None: the XML fragment it was given as is shown as it is). A colour is an ``rgb``
        object; an index set over ``material`` replaces it, the other index keeping the
        material's value."""
        if not isinstance(self.spec, dict):
            return None
        values = dict(self.values(), **(pending or {}))
        changed = {label for label in self.changed | set(pending or ()) if "." not in label}
        if changed & {"eta", "k"} and "material" in self.spec:
            changed |= {"eta", "k"} & set(values)
        out = {k: v for k, v in self.spec.items() if not (k == "material" and
                                                          changed & {"eta", "k"})}
        for label in sorted(changed):  # a nested object's parameter is no key of this dict
            value = values[label]
            out[label] = {"type": "rgb", "value": list(value)} \
                if isinstance(value, tuple) else value
        return out

    def python(self) -> str:
        """The Python that loads the BSDF with the current values (``mi.load_dict`` of
        :meth:`as_dict`, or ``mi.load_string`` of the XML fragment it was given as)."""
        import pprint

        spec = self.as_dict()
        if spec is None:
            return f"mi.load_string({self.xml()!r})"
        return f"mi.load_dict({pprint.pformat(spec, sort_dicts=False)})"

    def xml(self) -> str:
        """The XML fragment that reproduces the BSDF with the current values."""
        spec = self.as_dict()
        return to_xml(spec if spec is not None else self.spec)


def _valid(spec) -> dict:
    """The valid range of each parameter of our plugin that ``spec`` loaded, as the plugin
    read it (``properties.VALID``; none for Mitsuba's built-ins and XML)."""
    from ..plugins.properties import VALID

    return VALID.get(spec.get("type"), {}) if isinstance(spec, dict) else {}


def _expanded(spec):
    """A dict with a ``preset`` as the preset's parameters (those given winning, as in a
    scene), so that the switches, the dict and the XML show what the plugin uses."""
    from ..presets import spec as preset_spec

    if not isinstance(spec, dict) or not isinstance(spec.get("preset"), str):
        return spec
    given = {k: v for k, v in spec.items() if k not in ("type", "preset")}
    return preset_spec(spec["type"], spec["preset"], **given)


def _numbers(name: str, control: Control, value) -> list[float]:
    """The value as ``control.channels`` finite floats (a number, or three for a colour; one
    number for a colour is grey), else MiBrdfsError with one line."""
    try:
        numbers = [float(v) for v in (value if isinstance(value, (list, tuple)) else [value])]
    except (TypeError, ValueError):
        numbers = []
    if len(numbers) == 1 and control.channels == 3:
        numbers = numbers * 3
    if len(numbers) != control.channels or not all(math.isfinite(v) for v in numbers):
        raise MiBrdfsError(f"{name}: {control.label} = {value!r}: expected "
                           f"{'a number' if control.channels == 1 else 'a colour (r, g, b)'}")
    return numbers


class Session:
    """Up to :data:`MAX_BSDFS` BSDFs, loaded in the current (JIT) variant."""

    def __init__(self, specs):
        specs = list(specs)
        if not 1 <= len(specs) <= MAX_BSDFS:
            raise MiBrdfsError(f"explore: give 1 to {MAX_BSDFS} BSDFs, got {len(specs)}")
        self.entries = [Entry(spec) for spec in specs]

    def polar(self, theta_i_deg: float, n: int = 181, cosine: bool = True):
        """The views' polar plot: θo from −90° to 90° in the plane of incidence (ωi on the
        negative side) and each BSDF's f·cosθo (or f), the mean of its channels."""
        from ..plots import lobe_values

        curves = [lobe_values(e.bsdf, theta_i_deg, n, cosine) for e in self.entries]
        return curves[0][0], [values for _, values in curves]

    def albedo(self, i: int, thetas_deg, n: int = 20_000, seed: int = 0):
        """E(θi) of BSDF ``i`` over ``thetas_deg`` and its standard errors (the channels'
        mean): the mean ``sample()`` weight of ``n`` samples per angle, all angles in one
        launch (one kernel, not one per angle)."""
        from ..checks import batch

        t = np.repeat(np.radians(np.asarray(thetas_deg, np.float64)), n)
        wi = np.stack([np.sin(t), 0.0 * t, np.cos(t)], axis=1)
        rng = np.random.default_rng(seed)
        s = batch.sample(self.entries[i].bsdf, wi, rng.random(t.size), rng.random((t.size, 2)))
        w = np.where(np.isfinite(s.weight), s.weight, np.nan).mean(axis=1).reshape(-1, n)
        return w.mean(axis=1), w.std(axis=1, ddof=1) / math.sqrt(n)
