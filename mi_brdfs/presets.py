r"""
Published fits as presets of the plugins: the fits of Ngan, Durand & Matusik (2005,
"Experimental Analysis of BRDF Models", EGSR, §4–5) to the MERL materials, in the files of
bbm (https://github.com/bsdfbenchmark/bbm, ``fits/ngan_*.fit``, BSD licence; shipped in
``mi_brdfs/data/ngan/`` with the licence and their source), converted to the parameters of
this package's plugins. docs/presets.md gives every conversion and what differs where one is
not exact.

A preset is named ``ngan:<material>`` (the fit of the plugin's own model: :data:`DEFAULT_MODEL`)
or ``ngan-<model>:<material>`` (a fit file named explicitly, e.g. ``ngan-wardduer:`` for
``ward`` with the Ward-Dür normalisation). A plugin reads it through
:func:`mi_brdfs.plugins.properties.preset`, which fills every parameter the scene does not give
(:func:`missing`); :func:`spec` gives the whole spec as a dict.

Every model of a fit file is bbm's sum of a Lambertian term ρd/π and one specular term; bbm's
definitions (``include/bsdfmodel/*.h`` of bbm, read for their formulas only) are, with
h = (ωi + ωo)/‖ωi + ωo‖ and A the fit's RGB ``albedo``:

* NganWard, NganWardDuer: A·exp(−tan²θh/α²)/(4π α² √(cosθi cosθo)), and the same over
  cosθi cosθo (Ward 1992; Dür 2006);
* NganBlinnPhong: A·(n+2)/(2π)·cosⁿθh in Ngan et al.'s model, which the conversion takes;
  bbm's code evaluates cosⁿ of the mirror angle instead (see :func:`_blinnphong`);
* NganCookTorrance: A·D·G·F/(π cosθi cosθo), D the normalised Beckmann distribution of
  roughness m, G the V-groove masking of Torrance & Sparrow, F Schlick's with F0 = ``eta``
  (a reflectance at normal incidence, not an index) at ωi·h;
* NganAshikhminShirley: A·(n+1)/(8π)·cosⁿθh·F(ωi·h)/((ωi·h) max(cosθi, cosθo)), F Schlick's
  with F0 = ``fresnelReflectance`` (Ashikhmin & Shirley 2000, the specular term alone);
* NganLafortune: A·(n+2)/(2π)·max(0, Cxy(ix ox + iy oy) + Cz iz oz)ⁿ / max(Cxy², Cz²)^(n/2);
* NganHe: A times He et al.'s (1991) directional diffuse term as Westin et al.'s code has it
  (the errata's shadowing, v_xy in wave numbers, at bbm's RGB wavelengths 0.645, 0.526 and
  0.444 µm), of rms roughness ``roughness`` and autocorrelation length ``autocorrelation``
  (µm) and a real index ``eta`` (Cook & Torrance's Fresnel term, the exact one for k = 0), the
  series blended linearly into Beckmann's asymptote over 18 ≤ g ≤ 19; no specular delta.
"""

from __future__ import annotations

import difflib
import functools
import math
import re
from pathlib import Path
from typing import NamedTuple

from .errors import ParameterError

#: The shipped fit files, their licence and README.
DATA = Path(__file__).resolve().parent / "data" / "ngan"
#: The source of the fits, as in a preset's name.
SOURCE = "ngan"
#: The fit files, by model (``ngan_<model>.fit``).
MODELS = ("ashikhminshirley", "blinnphong", "cooktorrance", "he", "lafortune", "ward",
          "wardduer")
#: The specular term's name in each file.
TERMS = {"ashikhminshirley": "NganAshikhminShirley", "blinnphong": "NganBlinnPhong",
         "cooktorrance": "NganCookTorrance", "he": "NganHe", "lafortune": "NganLafortune",
         "ward": "NganWard", "wardduer": "NganWardDuer"}
#: The fit a plugin takes for ``ngan:<material>``.
DEFAULT_MODEL = {"ward": "ward", "phong": "blinnphong", "cooktorrance": "cooktorrance",
                 "ashikhmin": "ashikhminshirley", "lafortune": "lafortune", "he": "he"}
#: The plugin of each model; a model without one says why in :data:`NO_PLUGIN`.
PLUGIN_OF = {"ward": "ward", "wardduer": "ward", "blinnphong": "phong",
             "cooktorrance": "cooktorrance", "ashikhminshirley": "ashikhmin",
             "lafortune": "lafortune", "he": "he"}
#: The models without a plugin, and why (none now).
NO_PLUGIN: dict = {}
#: The models whose fits convert to no parameters of their plugin exactly: what differs.
NOT_EXACT = {
    "ashikhminshirley": (
        "Ngan's Ashikhmin-Shirley fit has no exact form in ashikhmin: its specular term is "
        "A·F(ωi·h) with an RGB albedo A and Schlick's F of a grey F0, which rises to A at "
        "grazing, whereas ashikhmin's is F of Rs alone, which rises to 1 (the two agree only "
        "for A = 1), and its diffuse term is Lambertian ρd/π, whereas ashikhmin's is "
        "Ashikhmin & Shirley's coupled 28Rd(1 − Rs)/(23π)·(1 − (1 − cosθi/2)⁵)(1 − (1 − "
        "cosθo/2)⁵)"),
}

#: What the overview (:func:`table`) adds to an exact conversion.
NOTES = {"blinnphong": "; Blinn-Phong's cosⁿθh, where bbm evaluates cosⁿ of the mirror angle",
         "he": "; westin's switch to the asymptote at g = 18.5, where bbm blends over "
               "18 ≤ g ≤ 19; and the plugin's specular delta, which bbm's model has not"}

#: Properties the scene gives that a preset's entries give way to: (a preset entry, the
#: scene's names that replace it). Explicit parameters win, alternatives included.
ALTERNATIVES = {"alpha": ("alpha_u", "alpha_v"), "eta": ("material", "int_ior", "ext_ior"),
                "k": ("material", "int_ior", "ext_ior")}


class Fit(NamedTuple):
    """One line of a fit file: the material, the Lambertian albedo ρd (RGB) and the specular
    term's name and parameters (a float, or a tuple for an RGB value)."""
    material: str
    diffuse: tuple
    term: str
    params: dict


# -------------------------------------------------------------------------------------------------
# The fit files: ``name = Aggregate(Lambertian(albedo = [r, g, b]), Term(key = value, ...))``
# -------------------------------------------------------------------------------------------------

_TOKEN = re.compile(r"\s*(?:(?P<number>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
                    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<punct>[()\[\],=]))")


def _tokens(text: str) -> list[tuple[str, str]]:
    """(kind, text) of each token of a call expression; ValueError at anything else."""
    out, pos, text = [], 0, text.strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            raise ValueError(f"unexpected {text[pos:pos + 10]!r}")
        out.append((m.lastgroup, m.group(m.lastgroup)))
        pos = m.end()
    return out


class _Parser:
    """A call ``Name(arg, ...)``: an argument is a call or ``key = value``, a value a number
    or a list of numbers. Returns nested (name, [positional calls], {key: value})."""

    def __init__(self, text: str):
        self.tokens, self.i = _tokens(text), 0

    def next(self, kind: str, text: str | None = None) -> str:
        if self.i >= len(self.tokens):
            raise ValueError(f"expected {text or kind} at the end")
        k, t = self.tokens[self.i]
        if k != kind or (text is not None and t != text):
            raise ValueError(f"expected {text or kind}, found {t!r}")
        self.i += 1
        return t

    def peek(self) -> str | None:
        return self.tokens[self.i][1] if self.i < len(self.tokens) else None

    def call(self):
        name, calls, keys = self.next("name"), [], {}
        self.next("punct", "(")
        while self.peek() != ")":
            if self.i + 1 < len(self.tokens) and self.tokens[self.i + 1][1] == "=":
                key = self.next("name")
                self.next("punct", "=")
                keys[key] = self.value()
            else:
                calls.append(self.call())
            if self.peek() != ")":
                self.next("punct", ",")
        self.next("punct", ")")
        return name, calls, keys

    def value(self):
        if self.peek() != "[":
            return float(self.next("number"))
        self.next("punct", "[")
        values = [float(self.next("number"))]
        while self.peek() == ",":
            self.next("punct", ",")
            values.append(float(self.next("number")))
        self.next("punct", "]")
        return tuple(values)

    def parse(self):
        result = self.call()
        if self.i != len(self.tokens):
            raise ValueError(f"unexpected {self.tokens[self.i][1]!r} after the expression")
        return result


def parse_line(line: str) -> Fit:
    """One fit: ``material = Aggregate(Lambertian(albedo = [...]), Term(...))``; ValueError
    naming what is wrong otherwise."""
    material, sep, expression = line.partition("=")
    material = material.strip()
    if not sep or not re.fullmatch(r"[\w.-]+", material):
        raise ValueError("expected 'material = Aggregate(...)'")
    name, calls, keys = _Parser(expression).parse()
    if name != "Aggregate" or keys or len(calls) != 2 or calls[0][0] != "Lambertian":
        raise ValueError("expected Aggregate(Lambertian(...), <specular term>(...))")
    lambertian, (term, nested, params) = calls[0], calls[1]
    diffuse = lambertian[2].get("albedo")
    if lambertian[1] or set(lambertian[2]) != {"albedo"} or not isinstance(diffuse, tuple) \
            or len(diffuse) != 3 or nested:
        raise ValueError("expected Lambertian(albedo = [r, g, b]) and a term of key = value")
    return Fit(material, diffuse, term, params)


@functools.lru_cache(maxsize=None)
def load(model: str) -> dict[str, Fit]:
    """The fits of ``model`` (:data:`MODELS`), by material, from ``ngan_<model>.fit``."""
    path = DATA / f"ngan_{model}.fit"
    fits = {}
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            fit = parse_line(line)
        except ValueError as e:
            raise ValueError(f"{path.name}, line {number}: {e}") from None
        if fit.term != TERMS[model]:
            raise ValueError(f"{path.name}, line {number}: {fit.term}, expected {TERMS[model]}")
        fits[fit.material] = fit
    return fits


def materials() -> list[str]:
    """The materials every fit file holds (86 of MERL's 100), sorted."""
    names = set(load(MODELS[0]))
    for model in MODELS[1:]:
        names &= set(load(model))
    return sorted(names)


def models(plugin: str | None = None) -> list[str]:
    """The models with fit files, or those that convert exactly to ``plugin``'s parameters."""
    if plugin is None:
        return list(MODELS)
    return [m for m in MODELS if PLUGIN_OF.get(m) == plugin and m not in NOT_EXACT]


def fit(model: str, material: str) -> Fit:
    """The fit of ``model`` to ``material``, as its file gives it (KeyError if none)."""
    return load(model)[material]


# -------------------------------------------------------------------------------------------------
# The conversions: a fit's parameters in bbm's definition -> the plugin's properties. A value is
# a float, a string, a bool or an RGB tuple.
# -------------------------------------------------------------------------------------------------


def _ward(fit: Fit, form: str) -> dict:
    """NganWard (NganWardDuer) is ``ward`` with ``form`` original (duer): the same
    A·E/(4π α²·√(cosθi cosθo)) (over cosθi cosθo), ρs = A, α = the fit's roughness."""
    return {"form": form, "alpha": fit.params["roughness"],
            "specular_reflectance": fit.params["albedo"], "diffuse_reflectance": fit.diffuse}


def blinnphong_factor(n: float) -> float:
    """ks/A of the Blinn-Phong conversion: (n+2)/(2π) over ``phong``'s normalized halfway
    factor (n+2)(n+4)/(8π(n + 2^(−n/2))), i.e. 4(n + 2^(−n/2))/(n + 4)."""
    return 4.0 * (n + 2.0 ** (-0.5 * n)) / (n + 4.0)


def _blinnphong(fit: Fit) -> dict:
    """
    Ngan's Blinn-Phong A·(n+2)/(2π)·cosⁿθh is ``phong``'s normalized halfway lobe
    ks·(n+2)(n+4)/(8π(n + 2^(−n/2)))·cosⁿθh with ks = A·:func:`blinnphong_factor` (n).

    bbm evaluates NganBlinnPhong as its modified Phong, cosⁿ of the angle between ωo and the
    mirror direction of ωi (``nganblinnphong = phong`` in bbm's ngan.h). The fits are
    Blinn-Phong's (Ngan et al. 2005, §4): read with the mirror direction, every highlight
    would be half as wide as those of the Cook-Torrance, Ward and Ashikhmin-Shirley fits of
    the same material, read with the half vector it is as wide (tests/test_presets.py
    measures both); the conversion takes the half vector and bbm's (n+2)/(2π).
    """
    n, albedo = fit.params["sharpness"], fit.params["albedo"]
    scale = blinnphong_factor(n)
    return {"form": "normalized", "lobe": "halfway", "exponent": n,
            "specular_reflectance": tuple(a * scale for a in albedo),
            "diffuse_reflectance": fit.diffuse}


def schlick_eta(f0: float) -> float:
    """The index η (k = 0) whose Schlick R0 = ((η−1)/(η+1))² is ``f0``: (1 + √F0)/(1 − √F0)."""
    root = math.sqrt(f0)
    return (1.0 + root) / (1.0 - root)


def _cooktorrance(fit: Fit) -> dict:
    """
    NganCookTorrance A·D·G·F/(π cosθi cosθo) is ``cooktorrance``'s ks·F·D·G/(4 cosθi cosθo)
    with ks = 4A/π, Beckmann D of α = the fit's roughness, the V-cavity G, Schlick's F with
    R0 = the fit's ``eta`` (bbm's Schlick term takes a reflectance at normal incidence), given
    as η = (1 + √R0)/(1 − √R0), k = 0; single scattering.
    """
    return {"distribution": "beckmann", "shadowing": "vcavity", "fresnel": "schlick",
            "multiscatter": False, "alpha": fit.params["roughness"],
            "eta": schlick_eta(fit.params["eta"]), "k": 0.0,
            "specular_reflectance": tuple(4.0 * a / math.pi for a in fit.params["albedo"]),
            "diffuse_reflectance": fit.diffuse}


def _lafortune(fit: Fit) -> dict:
    """
    NganLafortune A·(n+2)/(2π)·max(0, g)ⁿ/max(Cxy², Cz²)^(n/2), g = Cxy(ix ox + iy oy) +
    Cz iz oz, is ``lafortune``'s lobe 0 with ``normalize`` true: ρs·(n+2)/(2π)·max(0, g/c)ⁿ,
    c = max(|Cx|, |Cy|, |Cz|) = max(|Cxy|, |Cz|), with Cx = Cy = Cxy, ρs = A.
    """
    p = fit.params
    return {"normalize": True, "cx_0": p["Cxy"], "cy_0": p["Cxy"], "cz_0": p["Cz"],
            "exponent_0": p["sharpness"], "specular_reflectance_0": p["albedo"],
            "diffuse_reflectance": fit.diffuse}


def _he(fit: Fit) -> dict:
    """
    NganHe A·ρ_dd is ``he``'s directional diffuse term with ``specular_reflectance`` A, in the
    westin reading: σ0 = ``roughness``, τ = ``autocorrelation`` (both µm, as ``he`` takes them),
    η = ``eta``, k = 0. Two differences, documented and measured (tests/test_presets.py): bbm
    blends the series into the asymptote over 18 ≤ g ≤ 19, where westin (Westin et al.'s code)
    switches at g = 18.5; and ``he`` adds the coherent delta of weight ρ_s·A that He et al.'s
    model has and bbm's (fitted to measurements without it) has not.
    """
    p = fit.params
    return {"variant": "westin", "sigma0": p["roughness"], "tau": p["autocorrelation"],
            "eta": p["eta"], "k": 0.0, "specular_reflectance": p["albedo"],
            "diffuse_reflectance": fit.diffuse}


#: model -> the conversion of one of its fits to the plugin's properties.
CONVERSIONS = {"ward": lambda f: _ward(f, "original"), "wardduer": lambda f: _ward(f, "duer"),
               "blinnphong": _blinnphong, "cooktorrance": _cooktorrance,
               "lafortune": _lafortune, "he": _he}

#: Properties of a reflectance within [0, 1]: a fit outside it cannot be that plugin's preset
#: (he's specular_reflectance is a factor ≥ 0, unbounded, as Ngan et al.'s He albedos are).
_BOUNDED = ("specular_reflectance", "diffuse_reflectance", "specular_reflectance_0")
_UNBOUNDED = {"he": ("specular_reflectance",)}


# -------------------------------------------------------------------------------------------------
# Preset names, the error of each wrong one, and the properties a preset gives
# -------------------------------------------------------------------------------------------------

_NAME = re.compile(r"^(?P<source>[a-z]+)(?:-(?P<model>[a-z]+))?:(?P<material>.+)$")
_FORMAT = (f'must be "{SOURCE}:<material>" or "{SOURCE}-<model>:<material>" (docs/presets.md), '
           f'e.g. "{SOURCE}:gold-metallic-paint"')


def resolve(plugin: str, preset) -> tuple[str, str]:
    """(model, material) of ``preset`` for ``plugin``; one-line ParameterError naming the
    plugin, ``preset``, the value and what is allowed where it names no fit that converts."""
    def refuse(allowed):
        return ParameterError(plugin, "preset", preset, allowed)

    m = _NAME.match(preset) if isinstance(preset, str) else None
    if m is None or m["source"] != SOURCE:
        raise refuse(_FORMAT)
    model = m["model"] or DEFAULT_MODEL.get(plugin)
    if model is None:
        raise refuse(f"{plugin} has no preset: the presets are for "
                     f"{', '.join(sorted(DEFAULT_MODEL))}")
    if model not in MODELS:
        raise refuse(f'"{SOURCE}-{model}" names no fit file: the models are '
                     f"{', '.join(MODELS)}")
    if model in NO_PLUGIN:
        raise refuse(f"{SOURCE}-{model}: {NO_PLUGIN[model]}")
    if PLUGIN_OF[model] != plugin:
        raise refuse(f"the {SOURCE}-{model} fits are presets of {PLUGIN_OF[model]}, not of "
                     f"{plugin} ({plugin}'s: {', '.join(models(plugin)) or 'none'})")
    if model in NOT_EXACT:
        raise refuse(NOT_EXACT[model])
    material = m["material"]
    if material not in load(model):
        close = difflib.get_close_matches(material, list(load(model)), n=3, cutoff=0.6)
        hint = (f"did you mean {' or '.join(repr(c) for c in close)}? " if close else "")
        raise refuse(f"{material!r} is not among the {len(load(model))} materials of "
                     f"{SOURCE}_{model}.fit ({hint}mi_brdfs.presets.materials() lists them)")
    return model, material


def parameters(plugin: str, preset: str) -> dict:
    """Every property the preset gives ``plugin``: name -> float, string, bool or RGB tuple
    (ParameterError as :func:`resolve`, and where a converted value leaves the plugin's
    range)."""
    model, material = resolve(plugin, preset)
    fit = load(model)[material]
    if model == "he" and fit.params["eta"] <= 1.0:
        albedo = "[" + ", ".join(f"{v:.3g}" for v in fit.params["albedo"]) + "]"
        raise ParameterError(plugin, "preset", preset, (
            f"the fit's eta is {fit.params['eta']:g} as its file prints it (3 digits), for "
            f"which Fresnel's reflectance is 0 and the lobe vanishes; its albedo {albedo} "
            f"made up for an index the file rounds away, so the fit cannot be reproduced"))
    params = CONVERSIONS[model](fit)
    for name in _BOUNDED:
        if name in _UNBOUNDED.get(plugin, ()):
            continue
        value = params.get(name)
        if value is not None and max(value) > 1.0:
            raise ParameterError(plugin, "preset", preset, _beyond(model, name, value))
    return params


def _beyond(model: str, name: str, value) -> str:
    """Why a fit whose converted reflectance exceeds 1 is no preset (what would differ)."""
    shown = "[" + ", ".join(f"{v:.4g}" for v in value) + "]"
    source = {"cooktorrance": "4A/π of the fit's albedo A",
              "blinnphong": "A·4(n + 2^(−n/2))/(n + 4) of the fit's albedo A"}.get(
        model, "the fit's albedo")
    return (f"its {name} would be {source} = {shown}, above 1, the plugin's bound on a "
            f"reflectance, so no parameters of the plugin give this fit exactly")


def missing(plugin: str, preset: str, given) -> dict:
    """The properties of :func:`parameters` that the scene does not give (``given``: the names
    it gives), nor an alternative of (:data:`ALTERNATIVES`: ``alpha_u``, ``alpha_v`` replace
    ``alpha``; ``material``, ``int_ior``, ``ext_ior`` replace ``eta`` and ``k``)."""
    given = set(given)
    return {name: value for name, value in parameters(plugin, preset).items()
            if name not in given and not given & set(ALTERNATIVES.get(name, ()))}


def spec(plugin: str, preset: str, **overrides) -> dict:
    """
    The spec dict of ``plugin`` with ``preset``'s parameters, for ``mi.load_dict``, e.g.
    ``spec("ward", "ngan:gold-metallic-paint")`` → {'type': 'ward', 'form': 'original', ...};
    RGB values as {'type': 'rgb', 'value': [...]}; ``overrides`` win, as in a scene.
    """
    params = missing(plugin, preset, overrides)
    out = {"type": plugin}
    for name, value in params.items():
        out[name] = {"type": "rgb", "value": list(value)} if isinstance(value, tuple) else value
    out.update(overrides)
    return out


def names(plugin: str | None = None) -> list[str]:
    """Every preset name that converts exactly, for ``plugin`` (all plugins: None), e.g.
    ``ngan:blue-acrylic`` and ``ngan-wardduer:blue-acrylic`` for ``ward``."""
    plugins = sorted(DEFAULT_MODEL) if plugin is None else [plugin]
    out = []
    for p in plugins:
        for model in models(p):
            prefix = SOURCE if DEFAULT_MODEL.get(p) == model else f"{SOURCE}-{model}"
            for material in sorted(load(model)):
                try:
                    parameters(p, f"{prefix}:{material}")
                except ParameterError:
                    continue
                out.append(f"{prefix}:{material}")
    return out


def table() -> list[tuple[str, str, str, int, str]]:
    """(model, term, plugin, materials, conversion) per fit file: the overview of
    docs/presets.md and of ``mi_brdfs.presets``."""
    rows = []
    for model in MODELS:
        plugin = PLUGIN_OF.get(model, "—")
        if model in NO_PLUGIN:
            how = NO_PLUGIN[model]
        elif model in NOT_EXACT:
            how = "not exact (docs/presets.md)"
        else:
            prefix = SOURCE if DEFAULT_MODEL.get(plugin) == model else f"{SOURCE}-{model}"
            converted = len([n for n in names(plugin) if n.startswith(prefix + ":")])
            how = f"exact: {prefix}:<material> ({converted} materials)" + NOTES.get(model, "")
        rows.append((model, TERMS[model], plugin, len(load(model)), how))
    return rows
