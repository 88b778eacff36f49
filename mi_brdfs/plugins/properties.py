"""
Reading and validating the plugins' properties: numbers, choices, booleans, reflectances and other
textures, roughness.

Every reader raises :class:`mi_brdfs.ParameterError` with one line naming the plugin, the
parameter, the value and what is allowed. Mitsuba wraps an exception raised in a plugin
constructor into its own ``RuntimeError`` (with the scene location); the CLI unwraps it again.
A texture whose range cannot be known when the scene loads is clipped into range where the
models evaluate it (:func:`clip_at`), so that no value outside a parameter's range reaches a
model.
"""

from __future__ import annotations

import difflib
import math
import re

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import presets
from ..errors import Description, ParameterError
from ..materials import material_ior
from ..scattering.fresnel import IOR_MAX
from ..scattering.microfacet import ALPHA_MIN

_T = None


def _types():
    global _T
    if _T is None:
        _T = mi.Properties.Type
    return _T


def as_float(value) -> float:
    """A Python float from a Python scalar or a width-1 drjit array."""
    return float(np.asarray(value, dtype=np.float64).ravel()[0])


#: Textures whose every value is the value of one of their nested textures.
SELECTING_TEXTURES = ("Checkerboard",)


def texture_range(tex) -> tuple[float, float] | None:
    """
    The (min, max) a texture can return, where that can be known cheaply, else ``None``.

    Exact for constant textures (``uniform``, ``srgb``), for ``bitmap`` (its pixel data, after
    Mitsuba's sRGB linearisation) and for textures that only select among nested textures
    (:data:`SELECTING_TEXTURES`: ``checkerboard``), from their nested textures' ranges; ``None``
    for others (``mesh_attribute``, textures written in Python), whose values depend on the
    shape or on code that cannot be inspected at load time.
    """
    if tex.class_name() in SELECTING_TEXTURES:
        children = []

        class Collect(mi.TraversalCallback):
            def put(self, key, obj, *flags):
                if isinstance(obj, mi.Texture):
                    children.append(obj)

        tex.traverse(Collect())
        ranges = [texture_range(child) for child in children]
        if not ranges or any(r is None for r in ranges):
            return None
        return (min(r[0] for r in ranges), max(r[1] for r in ranges))
    if not tex.is_spatially_varying():
        try:
            mean = as_float(tex.mean())
        except RuntimeError:  # no mean either (mesh_attribute: values live on the shape)
            return None
        try:
            hi = as_float(tex.max())
        except RuntimeError:  # Texture::max() is not implemented by every texture
            hi = mean
        # A constant texture's minimum is not exposed; its mean bounds it from above, which
        # catches negative uniform values (the only way to get one: <rgb> is checked by Mitsuba).
        return (min(mean, hi), hi)
    params = mi.traverse(tex)
    if "data" in params:
        data = np.asarray(params["data"])
        if _spectral_coefficients(tex, data):
            # the coefficients of Mitsuba's RGB-to-spectrum model (Jakob & Hanika 2019, "A
            # Low-Dimensional Function Space for Efficient Spectral Upsampling"): a sigmoid,
            # so every texel's reflectance lies within (0, 1) at every wavelength
            return (0.0, 1.0)
        if np.issubdtype(data.dtype, np.integer):
            # 8/16-bit storage: normalised values (sRGB-decoded at lookup), within [0, 1] by design
            scale = float(np.iinfo(data.dtype).max)
            return (float(data.min()) / scale, float(data.max()) / scale) if data.size else None
        data = data.astype(np.float64)
        if data.size:
            finite = np.isfinite(data)
            if not finite.all():
                return (math.nan, math.nan)
            return (float(data.min()), float(data.max()))
    return None


def _spectral_coefficients(tex, data) -> bool:
    """Whether a bitmap's stored data are spectral upsampling coefficients, not values: in
    spectral variants, a bitmap of three channels that is not ``raw`` (as Mitsuba's
    ``bitmap`` decides it)."""
    return mi.is_spectral and data.ndim == 3 and data.shape[-1] == 3 and \
        "raw = 0" in str(tex)


def clip(x, lo: float, hi: float):
    """``x`` clipped into [``lo``, ``hi``] by selection, so that a value inside passes its
    derivative unchanged, at the ends too (``dr.clip``'s maximum gives 0 at a tie)."""
    return dr.select(x < lo, lo, dr.select(x > hi, hi, x))


def clip_at(tex, si, active, lo: float = 0.0, hi: float = 1.0):
    """
    ``tex`` evaluated at ``si``, clipped into [``lo``, ``hi``] (a reflectance's [0, 1] by
    default). Every bounded parameter is read this way: a texture whose range can be known
    at load is checked then (:func:`texture`), but one whose range cannot (``mesh_attribute``,
    a texture written in Python) and a value set later through ``mi.traverse`` reach the model
    only here, so that no negative or energy-creating value does.
    """
    return mi.UnpolarizedSpectrum(clip(tex.eval(si, active), lo, hi))


def _range_text(lo: float, hi: float, lo_open: bool) -> str:
    if math.isinf(hi):
        return f"must be finite and {'>' if lo_open else '≥'} {lo:g}"
    return f"must be finite and within {'(' if lo_open else '['}{lo:g}, {hi:g}]"


def _in_range(x: float, lo: float, hi: float, lo_open: bool) -> bool:
    return math.isfinite(x) and (x > lo if lo_open else x >= lo) and x <= hi


def texture(props, plugin: str, name: str, default: float, lo: float = 0.0, hi: float = 1.0,
            lo_open: bool = False, scalar: bool = False):
    """
    A spectrally or spatially varying parameter: a float, ``<rgb>``, ``<spectrum>`` or any
    texture, with every value finite and within [``lo``, ``hi``] (``(lo, hi]`` with ``lo_open``).
    With ``scalar`` (one value per point, such as a roughness) an ``<rgb>`` and a ``<spectrum>``
    that is not uniform are refused: the model would average their channels.

    Values bounded by 1 are read with ``get_texture`` (reflectances, which Mitsuba upsamples as
    such); others with ``get_unbounded_texture`` (η, k, α), which accepts RGB values above 1.

    A texture whose range can be known at load (:func:`texture_range`) is checked then; one
    whose range cannot (``mesh_attribute``, a texture written in Python) is returned as it is:
    the models clip its values into range where they evaluate it (:func:`clip_at`).

    Returns → mi.Texture. Raises ParameterError for values out of range or not finite, and for
    properties that are neither numbers nor colours nor textures.
    """
    VALID.setdefault(plugin, {})[name] = (lo, hi)
    T = _types()
    allowed = _range_text(lo, hi, lo_open)
    getter = props.get_texture if hi <= 1.0 else props.get_unbounded_texture
    if name in props:
        kind = props.type(name)
        if scalar:
            _refuse_channels(props, plugin, name, kind, getter, default)
        if kind in (T.Float, T.Integer):
            value = float(props[name])
            if not _in_range(value, lo, hi, lo_open):
                raise ParameterError(plugin, name, value, allowed)
        elif kind == T.Color:
            # Checked here, before Mitsuba's own check, so the message names plugin and parameter.
            value = [float(c) for c in props[name]]
            if not all(_in_range(c, lo, hi, lo_open) for c in value):
                raise ParameterError(plugin, name, value, allowed + " in every channel")
        elif kind in (T.Spectrum, T.Object):
            tex = getter(name, default)
            rng = texture_range(tex)
            if rng is None:  # unknowable at load: clipped where it is evaluated (clip_at)
                return tex
            if not (_in_range(rng[0], lo, hi, lo_open) and _in_range(rng[1], lo, hi, lo_open)):
                shown = Description(f"a texture with values in [{rng[0]:g}, {rng[1]:g}]")
                raise ParameterError(plugin, name, shown, allowed)
            return tex
        else:
            raise ParameterError(plugin, name, props[name],
                                 "must be a float or a texture" if scalar else
                                 "must be a float, <rgb>, <spectrum> or a texture")
    return getter(name, default)


def _refuse_channels(props, plugin, name, kind, getter, default) -> None:
    """:func:`texture`'s refusal of colours for a parameter with one value per point."""
    T = _types()
    why = ("must be a float or a texture, one value per point (the model would average the "
           "channels of an <rgb> or a varying <spectrum>)")
    if kind == T.Color:
        raise ParameterError(plugin, name, [float(c) for c in props[name]], why)
    if kind == T.Spectrum:
        rng = texture_range(getter(name, default))
        if rng is None or rng[0] != rng[1]:
            raise ParameterError(plugin, name, props[name], why)


def reflectance(props, plugin: str, name: str, default: float):
    """A reflectance: :func:`texture` with values in [0, 1]."""
    return texture(props, plugin, name, default, 0.0, 1.0)


def roughness(props, plugin: str, default: float = 0.1):
    """
    (α_u, α_v) textures from ``alpha`` (the same texture twice) or from ``alpha_u`` and
    ``alpha_v``, as Mitsuba's ``roughconductor`` reads them (:func:`isotropic_or_pair`);
    warns where a value is below the clamp :data:`mi_brdfs.scattering.microfacet.ALPHA_MIN`
    of the microfacet terms.
    """
    names, alphas = isotropic_or_pair(props, plugin, "alpha", ("alpha_u", "alpha_v"), default)
    for name, tex in zip(names, alphas):
        low = texture_range(tex)
        if low is not None and low[0] < float(np.float32(ALPHA_MIN)):  # 1e-4 held in float32
            warn(plugin, f"{name} = {low[0]:g} is clamped to {ALPHA_MIN:g}, as in Mitsuba's "
                         f"microfacet models")
    return alphas[0], alphas[-1]


def isotropic_or_pair(props, plugin: str, single: str, pair: tuple[str, str], default: float,
                      hi: float = math.inf):
    """
    A parameter with one value per point for an isotropic surface (``single``) or one along
    the tangent and one along the bitangent (the two names of ``pair``): both or neither of
    the pair, not together with ``single``; each a float or a texture, finite and within
    [0, ``hi``]. Returns → (the names given, their textures): one name or two.
    """
    given = [name for name in pair if name in props]
    if given:
        if single in props:
            raise ParameterError(plugin, given[0], props[given[0]],
                                 f"must not be given together with {single} (give {single} for "
                                 f"an isotropic surface, {pair[0]} and {pair[1]} for an "
                                 f"anisotropic one)")
        if len(given) == 1:
            other = pair[1] if given[0] == pair[0] else pair[0]
            raise ParameterError(plugin, given[0], props[given[0]],
                                 f"needs {other} as well (an anisotropic surface has both)")
        names = given
    else:
        names = [single]
    return names, [texture(props, plugin, name, default, lo=0.0, hi=hi, scalar=True)
                   for name in names]


def number_or_texture(props, plugin: str, name: str, default: float, lo: float, hi: float,
                      unit: str = ""):
    """
    A parameter given as a number (-> float) or a texture (-> mi.Texture, with
    :func:`texture`'s checks), finite and within [``lo``, ``hi``]; a colour is refused (one
    value per point is meant). ``unit`` is named in the error (e.g. "radians").
    """
    T = _types()
    if name in props and props.type(name) not in (T.Float, T.Integer):
        if props.type(name) != T.Object:
            raise ParameterError(plugin, name, props[name], "must be a float or a texture"
                                 + (f" ({unit})" if unit else ""))
        return texture(props, plugin, name, default, lo, hi)
    return number(props, plugin, name, default, lo, hi)


def roughness_at(alpha_u, alpha_v, si, active):
    """
    (αu, αv) of :func:`roughness`'s textures at ``si``, clamped to
    :data:`mi_brdfs.scattering.microfacet.ALPHA_MIN` as Mitsuba clamps it; αv is None when
    isotropic (``alpha_v`` is ``alpha_u``), as
    :class:`~mi_brdfs.scattering.microfacet.Distribution` takes them.
    """
    a_u = dr.maximum(alpha_u.eval_1(si, active), ALPHA_MIN)
    if alpha_v is alpha_u:
        return a_u, None
    return a_u, dr.maximum(alpha_v.eval_1(si, active), ALPHA_MIN)


def number(props, plugin: str, name: str, default: float, lo: float = -math.inf,
           hi: float = math.inf, lo_open: bool = False) -> float:
    """A plain number (not a texture), finite and within [``lo``, ``hi``]."""
    VALID.setdefault(plugin, {})[name] = (lo, hi)
    if name not in props:
        return float(default)
    T = _types()
    if props.type(name) not in (T.Float, T.Integer):
        raise ParameterError(plugin, name, props[name], "must be a number")
    value = float(props[name])
    if not _in_range(value, lo, hi, lo_open):
        raise ParameterError(plugin, name, value, _range_text(lo, hi, lo_open))
    return value


#: plugin → {switch: (its default, its choices)}: every :func:`choice` and :func:`boolean` a
#: plugin has read, so that a tool offers a plugin's switches (``mi-brdfs explore``'s menus)
#: from the plugin's own reading of them, not from a second list.
SWITCHES: dict[str, dict[str, tuple]] = {}

#: plugin → {parameter: (lo, hi)}: the valid range of every :func:`texture` and :func:`number`
#: a plugin has read (its sliders' range in ``mi-brdfs explore``), likewise.
VALID: dict[str, dict[str, tuple]] = {}


def choice(props, plugin: str, name: str, default: str, choices) -> str:
    """A string among ``choices`` (case-sensitive, as Mitsuba's own options)."""
    SWITCHES.setdefault(plugin, {})[name] = (default, tuple(choices))
    if name not in props:
        return default
    value = props[name]
    if not isinstance(value, str) or value not in choices:
        raise ParameterError(plugin, name, value,
                             "must be one of " + ", ".join(f'"{c}"' for c in choices))
    return value


def filename(props, plugin: str, name: str = "filename", suffix: str = "") -> str:
    """A required file name, resolved as Mitsuba resolves its own (relative to the scene's
    folder and the file resolver's paths); ``suffix``: the extension it must have."""
    if name not in props:
        raise ParameterError(plugin, name, Description("missing"),
                             f"the plugin needs a file{f' ({suffix})' if suffix else ''}")
    value = props[name]
    if not isinstance(value, str) or not value.endswith(suffix):
        raise ParameterError(plugin, name, value, f"must be a file name ending in {suffix}"
                             if suffix else "must be a file name")
    return str(mi.file_resolver().resolve(value))


def boolean(props, plugin: str, name: str, default: bool) -> bool:
    SWITCHES.setdefault(plugin, {})[name] = (default, (False, True))
    if name not in props:
        return default
    value = props[name]
    if not isinstance(value, bool):
        raise ParameterError(plugin, name, value, "must be a boolean (true or false)")
    return value


def preset(props, plugin: str) -> None:
    """
    Fill in, on ``props`` itself, every parameter the ``preset`` property defines that the
    scene does not give (explicit parameters win; :func:`mi_brdfs.presets.missing`), before
    the plugin reads its properties: called first in each plugin's ``__init__``. No
    ``preset``: nothing changes. RGB values become ``<rgb>`` properties.
    """
    if "preset" not in props:
        return
    value = props["preset"]
    if not isinstance(value, str):
        raise ParameterError(plugin, "preset", value,
                             'must be a string such as "ngan:gold-metallic-paint"')
    given = [key for key in props.keys() if key != "preset"]
    for name, entry in presets.missing(plugin, value, given).items():
        props[name] = mi.ScalarColor3f(*entry) if isinstance(entry, tuple) else entry


#: A row of a ``.. pluginparameters::`` table: its first cell, the names it documents.
_PARAMETER_ROW = re.compile(r"^\s*\*\s+-\s+(.+?)\s*$")


def documented(doc: str) -> list[str]:
    """The parameter names of a plugin's docstring: the first cell of each row of its
    ``.. pluginparameters::`` table, split at commas (``alpha, alpha_u, alpha_v``; a numbered
    parameter as ``exponent_i``), as the plugin reference shows them."""
    table = doc.partition(".. pluginparameters::")[2]
    return [name.strip() for m in map(_PARAMETER_ROW.match, table.splitlines()) if m
            for name in m.group(1).split(",")]


def check_all_read(props, plugin: str, doc: str) -> None:
    """
    Refuse, in one line, a property the plugin did not read, which Mitsuba would report after
    the constructor as an "unreferenced property" of an "unknown plugin" (its wording for a
    Python plugin in a variant other than the first), with no hint: the line names the plugin,
    the property and the closest of the plugin's documented parameters (:func:`documented`),
    or lists them where none is close; it keeps Mitsuba's term, which its built-ins use. A
    documented parameter left unread is unused with the others given.
    """
    unread = list(props.unqueried())
    if not unread:
        return
    name, known = unread[0], documented(doc)
    index = re.search(r"_([0-9]+)$", name)  # lafortune's exponent_1 for its exponent_i
    if index:
        known = [k[:-1] + index.group(1) if k.endswith("_i") else k for k in known]
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.6)
    allowed = f"an unreferenced property in {plugin}, which "
    if name in known:
        allowed += "does not use it with the other parameters given"
    elif close:
        options = " or ".join([", ".join(close[:-1]), close[-1]] if len(close) > 1 else close)
        allowed += f"has no such parameter; did you mean {options}?"
    else:
        allowed += f"has no such parameter; its parameters: {', '.join(known)}"
    if len(unread) > 1:
        allowed += f" (also unreferenced: {', '.join(unread[1:])})"
    raise ParameterError(plugin, name, props[name], allowed)


def reject(props, plugin: str, name: str, hint: str) -> None:
    """Refuse a property the plugin deliberately does not take, saying what to do instead."""
    if name in props:
        raise ParameterError(plugin, name, props[name], hint)


def differentiated(values) -> bool:
    """Whether any of the numbers or textures (evaluated once) carries a gradient (a table
    built from them would hold numbers without one)."""
    if not dr.is_diff_v(mi.Float):
        return False
    si = dr.zeros(mi.SurfaceInteraction3f)
    return any(dr.grad_enabled(v.eval(si) if isinstance(v, mi.Texture) else v)
               for v in values if not isinstance(v, (int, float)))


def is_zero(tex) -> bool:
    """Whether a texture is the constant 0 (so the lobe it scales can be left out entirely)."""
    rng = texture_range(tex)
    return rng is not None and not tex.is_spatially_varying() and rng[0] == 0.0 == rng[1]


def upper_bound(props, name: str, tex) -> list[float] | None:
    """Per-channel upper bound of a parameter where it is cheap to know, else None."""
    T = _types()
    if name in props and props.type(name) in (T.Float, T.Integer):
        return [float(props[name])]
    if name in props and props.type(name) == T.Color:
        return [float(c) for c in props[name]]
    rng = texture_range(tex)
    return None if rng is None else [rng[1]]


def warn_sum(props, plugin: str, a, b, consequence: str) -> None:
    """
    Warn (values kept) where two reflectances, ``a`` and ``b`` as (name, texture), can add up
    to more than 1 in some channel, saying the ``consequence``.
    """
    bounds = [upper_bound(props, name, tex) for name, tex in (a, b)]
    if bounds[0] is None or bounds[1] is None:
        return
    total = float(np.max(np.add(*bounds)))  # per channel; one value stands for every channel
    if total > 1.0 + 1e-6:  # not for rounding: an <rgb> 0.8 is stored as 0.800000012
        warn(plugin, f"{a[0]} + {b[0]} reaches {total:g} > 1: {consequence}; values kept")


def warn(plugin: str, message: str) -> None:
    """A one-line warning from a plugin (values kept), shown by the CLI as such."""
    import warnings

    from ..errors import MiBrdfsWarning
    warnings.warn(f"{plugin}: {message}", MiBrdfsWarning, stacklevel=3)


def indent(obj, amount: int = 2) -> str:
    """``str(obj)`` with every line after the first indented, as Mitsuba's ``string::indent``."""
    return str(obj).replace("\n", "\n" + " " * amount)


def _constant_channels(props, name) -> list[float] | None:
    """The per-channel values of a float or ``<rgb>`` property, else None (a texture)."""
    kind = props.type(name)
    T = mi.Properties.Type
    if kind in (T.Float, T.Integer):
        return [float(props[name])]
    if kind == T.Color:
        return [float(c) for c in props[name]]
    return None


def ior(props, plugin: str, default_material: str | None):
    """
    ``(eta, k, material)``: the complex index η + ik of a named conductor (``material``, one of
    Mitsuba's measured spectra, :func:`mi_brdfs.materials.material_ior`), or the textures
    ``eta`` and ``k`` (each ≤ :data:`mi_brdfs.scattering.fresnel.IOR_MAX`; η = k = 0 refused);
    without either, ``default_material``, or η = 1.5, k = 0 where that is None.
    """
    if "material" in props:
        name = props["material"]
        return (*material_ior(name, plugin), name)
    if "eta" not in props and default_material is not None:
        return (*material_ior(default_material, plugin), default_material)
    eta = texture(props, plugin, "eta", 1.5, lo=0.0, hi=IOR_MAX)
    k = texture(props, plugin, "k", 0.0, lo=0.0, hi=IOR_MAX)
    eta_c = _constant_channels(props, "eta") if "eta" in props else [1.5]
    k_c = _constant_channels(props, "k") if "k" in props else [0.0]
    if eta_c is not None and k_c is not None:
        n = max(len(eta_c), len(k_c))
        if any(eta_c[i % len(eta_c)] == 0 and k_c[i % len(k_c)] == 0 for i in range(n)):
            raise ParameterError(plugin, "eta", props["eta"],
                                 "must be > 0 where k = 0 (a dielectric; η = 0 needs k > 0)")
    return eta, k, None
