"""
The models' parameterisations: which parameters of a model are fitted (the continuous ones
``mi.traverse`` exposes and the plugin takes by that name), the variable each is fitted in and
its range (:class:`Parameter`), the model as fitted and written back, and the closed-form
starts of a lobe width (see :mod:`mi_brdfs.fit`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ..errors import MiBrdfsError
from .spec import _number, _plain, _rgb, spec_text

#: Widths of a lobe: one number each, fitted in log space (``exponent_0``, ``exponent_1``, ...
#: of a model with numbered lobes too, :func:`base_name`).
WIDTHS = ("alpha", "alpha_u", "alpha_v", "exponent", "nu", "nv")

#: Widths that are exponents: the lobe narrows as they grow (Phong's n, Ashikhmin & Shirley's
#: nu and nv).
EXPONENTS = ("exponent", "nu", "nv")

#: Coefficients of a lobe, of any sign (Lafortune et al. 1997's Cx, Cy, Cz).
_SIGNED = ("cx", "cy", "cz")

#: Parameters with the spectrum's channels (fitted per RGB channel) among texture-valued ones.
_SPECTRAL_NAMES = ("eta", "k", "base_color")

#: The kernel weights of ``rtls``, within [0, 1] as the plugin takes them.
_KERNEL_WEIGHTS = ("f_iso", "f_vol", "f_geo")

#: Beckmann-type plugins whose ``alpha`` is the lobe width (built-ins included).
_MICROFACET = ("cooktorrance", "roughconductor", "roughplastic", "roughdielectric", "ward")


def base_name(name: str) -> str:
    """A parameter's name without the index of its lobe: ``exponent_1`` → ``exponent``,
    ``specular_reflectance_0`` → ``specular_reflectance`` (``lafortune`` numbers its lobes)."""
    return re.sub(r"_[0-9]+$", "", name)


#: The least index of refraction ``ocean`` is fitted with: it takes any η > 0 and ext_ior > 0,
#: and (η − 1)/(η + 1) clamped at −1 would write η = 0.
_IOR_MIN = 1e-3
#: The largest single-scattering albedo ``hapke`` is fitted with: Hapke's H-function goes as
#: γ = √(1 − w), whose derivative is infinite at w = 1 (a NaN gradient, and Adam diverges).
_HAPKE_W_MAX = 1.0 - 1e-6


def _plugin_bounds(kind: str | None, name: str):
    """
    (transform, lower, upper) of ``name`` where plugin ``kind`` takes a range of its own,
    read from the plugin, else None: ``rpv``'s ρ0, k (a Minnaert exponent, not an extinction
    coefficient), g and ρc; ``hapke``'s six (θ̄ in degrees); ``ocean``'s wind speed and
    indices of refraction (> 0).
    """
    if kind == "rpv":
        from ..plugins.rpv import RANGES
        return ("linear", *RANGES[name][1:]) if name in RANGES else None
    if kind == "hapke":
        from ..plugins.hapke import PARAMETERS
        if name not in PARAMETERS:
            return None
        return "linear", 0.0, _HAPKE_W_MAX if name == "w" else PARAMETERS[name][1]
    if kind == "ocean":
        from ..plugins.ocean import WIND_RANGE
        if name == "wind_speed":
            return ("linear", *WIND_RANGE)
        if name in ("eta", "ext_ior"):
            return "fresnel", _IOR_MIN, 1e3
    return None


def _bounds(name: str, kind: str | None = None):
    """(transform, lower, upper) of parameter ``name`` of plugin ``kind`` (see
    :mod:`mi_brdfs.fit`)."""
    own = _plugin_bounds(kind, name)
    if own is not None:
        return own
    name = base_name(name)
    if name in ("alpha", "alpha_u", "alpha_v"):
        return "log", 1e-3, 2.0
    if name in EXPONENTS:
        return "log", 1e-2, 1e6
    if name in _SIGNED:
        return "linear", -math.inf, math.inf
    if name == "eta":
        return "fresnel", 0.0, 1e3
    if name == "k":
        return "log1p", 0.0, 1e3
    if name == "sigma":
        return "square", 1e-3, math.pi / 2
    if name == "sigma0":  # he's rms height and autocorrelation length (µm): scales
        return "log", 1e-3, 10.0
    if name == "tau":
        return "log", 1e-2, 1e3
    if name == "film_thickness":  # nm, relative steps; 0 (no film) within reach
        from ..plugins.cooktorrance_film import THICKNESS_MAX
        return "log1p", 0.0, THICKNESS_MAX
    if name == "film_eta":
        from ..plugins.cooktorrance_film import FILM_ETA_MAX
        return "fresnel", _IOR_MIN, FILM_ETA_MAX
    if name.endswith(("reflectance", "transmittance")) or name in _KERNEL_WEIGHTS:
        return "linear", 0.0, 1.0
    return "linear", 0.0, math.inf


@dataclass
class Parameter:
    """A free parameter: its spec name, ``mi.traverse`` key, channels and reparametrisation."""

    name: str
    key: str
    channels: int
    transform: str
    lo: float
    hi: float

    def encode(self, value: np.ndarray) -> np.ndarray:
        """The optimised variable x of a parameter value (clamped into the range first)."""
        v = np.clip(np.asarray(value, dtype=np.float64), self.lo, self.hi)
        if self.transform == "log":
            return np.log(v)
        if self.transform == "log1p":
            return np.log1p(v)
        if self.transform == "fresnel":
            return (v - 1.0) / (v + 1.0)
        if self.transform == "square":
            return v * v
        return v

    def decode(self, x):
        """The parameter value of x (drjit or NumPy)."""
        import drjit as dr

        exp = dr.exp if not isinstance(x, np.ndarray) else np.exp
        if self.transform == "log":
            return exp(x)
        if self.transform == "log1p":
            return exp(x) - 1.0
        if self.transform == "fresnel":
            return (1.0 + x) / (1.0 - x)
        if self.transform == "square":
            return (dr.sqrt if not isinstance(x, np.ndarray) else np.sqrt)(x)
        return x

    def x_range(self):
        """The range of x: the transformed range of the parameter."""
        return float(self.encode(self.lo)), float(self.encode(self.hi))

    def drjit(self, x: np.ndarray):
        """x as the type ``mi.traverse`` holds (Float or Color3f)."""
        import mitsuba as mi

        x = np.asarray(x, dtype=np.float32).ravel()
        if self.channels == 1:
            return mi.Float(float(x[0]))
        return mi.Color3f(*[float(c) for c in x])


# -------------------------------------------------------------------------------------------------
# Parameters of a model
# -------------------------------------------------------------------------------------------------


def _fittable(bsdf) -> dict:
    """{spec name: (traverse key, value as float64 array)} of the continuous parameters."""
    import drjit as dr
    import mitsuba as mi

    params = mi.traverse(bsdf)
    found = {}
    for key in params.keys():  # (iterating SceneParameters yields (key, value) pairs)
        value = params[key]
        if params.flags(key) & int(mi.ParamFlags.NonDifferentiable):
            continue
        if not (dr.is_array_v(value) and dr.is_float_v(value)) or dr.width(value) != 1:
            continue  # Python floats, strings, bitmaps (a ``.data`` tensor) are not fitted
        name = key.removesuffix(".value")
        if "." in name:
            continue  # a parameter of a nested texture or BSDF
        array = np.array(value, dtype=np.float64).ravel()
        if array.size not in (1, 3):
            continue
        found[name] = (key, array)
    return found


def _spectral(name: str, key: str) -> bool:
    """Whether a texture-valued parameter has spectrum channels (fitted per RGB channel)."""
    name = base_name(name)
    return key.endswith(".value") and (name.endswith(("reflectance", "transmittance"))
                                       or name in _SPECTRAL_NAMES)


def _free_names(free, available: dict, model) -> list[str]:
    """The free parameters asked for (a list or 'a,b'; None: all), checked against ``available``."""
    if free is None:
        names = list(available)
    else:
        if isinstance(free, str):
            free = free.split(",")
        names = []
        for name in free:
            name = str(name).strip()
            name = name.removesuffix(".value")
            if name and name not in names:
                names.append(name)
        unknown = [n for n in names if n not in available]
        if unknown:
            allowed = ", ".join(available) or "none"
            hint = ""
            if any(n.endswith("reflectance") for n in unknown):
                hint = (" (a lobe whose reflectance is 0 or left at a default of 0 has no "
                        "parameters: give it a value > 0 in MODEL to fit it)")
            raise MiBrdfsError(f"--free {','.join(unknown)}: not a continuous parameter of "
                               f"{spec_text(model)}; it has: {allowed}{hint}")
    if not names:
        raise MiBrdfsError(f"{spec_text(model)} has no free parameter to fit (its continuous "
                           f"parameters: {', '.join(available) or 'none'})")
    return names


def _prepare_model(model: dict, free) -> tuple[dict, list[str]]:
    """
    The model dict to fit (spectral free parameters promoted to RGB; ``eta`` and ``k`` written
    out, and ``material`` dropped, when one of them is free; a lobe's three coefficients written
    out when one of them is free) and the free names.
    """
    from ..bsdfspec import load_bsdf

    available = _accepted(model, _fittable(load_bsdf(model)))
    names = _free_names(free, available, model)
    spec = dict(model)
    if ("eta" in names or "k" in names) and "eta" in available and "k" in available:
        spec.pop("material", None)  # the written spec must hold the values the fit started from
        for name in ("eta", "k"):
            if name not in spec and _spectral(name, available[name][0]):
                spec[name] = _plain(available[name][1])
    for name in names:
        key, value = available[name]
        if _spectral(name, key):
            spec[name] = _rgb(value)
        for sibling in _coefficients_of(name):  # a lobe takes all three of its C, or none
            if sibling not in spec and sibling in available:
                spec[sibling] = _plain(available[sibling][1])
    return spec, names


def _coefficients_of(name: str) -> list[str]:
    """The three coefficients of the lobe of coefficient ``name`` (``cz_0`` → ``cx_0``,
    ``cy_0``, ``cz_0``: ``lafortune`` takes all three or none), else []."""
    base = base_name(name)
    return [base[:-1] + axis + name[len(base):] for axis in "xyz"] if base in _SIGNED else []


def _accepted(model: dict, available: dict) -> dict:
    """
    The parameters of ``available`` that the plugin takes under that name in a spec: a traverse
    key need not be one (``roughplastic`` exposes ``eta`` but takes ``int_ior``/``ext_ior``).
    Those absent from ``model`` are tried all together, else one by one (``eta`` with ``k``).
    """
    from ..bsdfspec import load_bsdf

    def loads(names) -> bool:
        try:
            load_bsdf(dict(model, **{n: _plain(available[n][1]) for n in names}))
        except MiBrdfsError:
            return False
        return True

    missing = [n for n in available if n not in model]
    if missing and not loads(missing):
        groups = [[n] for n in missing if n not in ("eta", "k")]
        groups.append([n for n in missing if n in ("eta", "k")])
        missing = [n for group in groups if group and loads(group) for n in group]
    return {n: v for n, v in available.items() if n in model or n in missing}


def _parameters(bsdf, names: list[str], kind: str | None = None
                ) -> tuple[list[Parameter], dict]:
    """The free parameters ``names`` of the loaded model (plugin ``kind``), and their values
    {name: array}."""
    available = _fittable(bsdf)
    params = []
    for name in names:
        key, value = available[name]
        params.append(Parameter(name, key, value.size, *_bounds(name, kind)))
    given = {name: available[name][1] for name in names}
    return params, given


def _written(params: list[Parameter], values: dict, spec: dict) -> tuple[dict, dict]:
    """(fitted spec, {name: float or [r, g, b]}): the values in the form the spec takes."""
    spec, out = dict(spec), {}
    for p in params:
        v = np.clip(values[p.name], p.lo, p.hi)
        if p.channels == 1 or np.all(v == v[0]):
            out[p.name] = spec[p.name] = _number(v[0])
        else:
            out[p.name] = [_number(c) for c in v]
            spec[p.name] = {"type": "rgb", "value": out[p.name]}
    return spec, out


# -------------------------------------------------------------------------------------------------
# Closed-form starts
# -------------------------------------------------------------------------------------------------


def _scalar(values: dict, name: str):
    return float(np.mean(values[name][1])) if name in values else None


def _halfway_alpha(n: float) -> float:
    """Beckmann's α of a halfway Phong lobe of exponent n (Walter et al. 2007, §5.2)."""
    return math.sqrt(2.0 / (n + 2.0))


def beckmann_width(spec, values: dict | None = None):
    """
    The Beckmann roughness α equivalent to the lobe of ``spec`` (a dict), or None: α itself for
    microfacet models and Ward (√(αu·αv) when anisotropic), √(2/(n+2)) for a halfway Phong lobe of
    exponent n (Walter et al. 2007, §5.2), Ashikhmin & Shirley's (n·h)ⁿ among them (√(αu·αv) of
    nu and nv), and that of exponent 4n for a mirror lobe (``phong``'s, and ``lafortune``'s
    lobe 0 taken as one).
    """
    from ..bsdfspec import load_bsdf

    if not isinstance(spec, dict):
        return None
    values = values if values is not None else _fittable(load_bsdf(spec))
    kind = spec["type"]
    if kind in _MICROFACET:
        if "alpha" in values:
            return _scalar(values, "alpha")
        if "alpha_u" in values and "alpha_v" in values:
            return math.sqrt(_scalar(values, "alpha_u") * _scalar(values, "alpha_v"))
        return None
    if kind == "ashikhmin":
        if "exponent" in values:
            return _halfway_alpha(_scalar(values, "exponent"))
        if "nu" in values and "nv" in values:
            return math.sqrt(_halfway_alpha(_scalar(values, "nu"))
                             * _halfway_alpha(_scalar(values, "nv")))
        return None
    name = {"phong": "exponent", "lafortune": "exponent_0"}.get(kind)
    if name in values:
        halfway = kind == "phong" and spec.get("lobe", "mirror") == "halfway"
        n = _scalar(values, name)
        return _halfway_alpha(n if halfway else 4 * n)
    return None


def _width_start(spec: dict, names: list[str], alpha: float) -> dict:
    """{name: value} of the model's free width parameters for a Beckmann roughness α."""
    kind, start = spec["type"], {}
    n = 2.0 / alpha ** 2 - 2.0  # the halfway lobe's exponent; a mirror lobe's is n/4
    for name in names:
        if name in ("alpha", "alpha_u", "alpha_v") and kind in _MICROFACET:
            start[name] = alpha
        elif name == "exponent" and kind == "phong":
            start[name] = n if spec.get("lobe", "mirror") == "halfway" else n / 4
        elif name in EXPONENTS and kind == "ashikhmin":
            start[name] = n
        elif base_name(name) == "exponent" and kind == "lafortune":
            start[name] = n / 4
    return start


def _starts(starts: str, spec: dict, names: list[str], given: dict, target, target_bsdf) -> dict:
    """
    {label: {name: value}}: the starts of the fit, MODEL's values and, with ``starts='auto'``,
    the closed-form width mapping from the target's lobe or else the given widths ÷ and × 4.
    """
    candidates = {"given": given}
    width_names = [n for n in names if base_name(n) in WIDTHS]
    if starts == "auto" and width_names:
        alpha = beckmann_width(target if isinstance(target, dict) else None,
                               _fittable(target_bsdf))
        mapped = _width_start(spec, width_names, alpha) if alpha else {}
        if mapped:
            candidates["closed form (Walter et al. 2007)"] = dict(given, **{
                n: np.broadcast_to(v, given[n].shape) for n, v in mapped.items()})
        else:
            for label, factor in (("widths ÷ 4", 0.25), ("widths × 4", 4.0)):
                candidates[label] = dict(given, **{
                    n: given[n] * (factor if base_name(n) not in EXPONENTS else 1 / factor)
                    for n in width_names})
    return candidates
