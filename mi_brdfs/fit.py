"""
Fit one BSDF model to another: the parameters of MODEL that make its ``eval`` (f·cosθo) match
TARGET's, by Mitsuba's automatic differentiation (``mi.traverse`` and ``mi.ad.Adam``).

    from mi_brdfs.fit import fit
    result = fit("cooktorrance alpha=0.2 fresnel=none", "phong lobe=halfway diffuse_reflectance=0")
    print(result.summary())          # fitted values, residual, albedo error, command line, XML

and ``mi-brdfs fit TARGET --model MODEL [--free p1,p2] [-o fit.json] [--plot fit.png]``.

**Parameters.** The free parameters are the continuous ones ``mi.traverse`` exposes for MODEL
(``alpha``, ``exponent``, ``sigma``, ``specular_reflectance``, ``eta``, ...) that the plugin
also takes under that name, named as the spec names them (a traverse key
``reflectance.value`` is the parameter ``reflectance``); strings and booleans (``form``,
``lobe``, ``fresnel``, ``distribution``) are never free. A lobe whose reflectance is 0 has no
parameters in our plugins (it is left out at load time), so it cannot be fitted: give it a
value above 0 in MODEL to fit it. Reflectances, ``eta`` and ``k`` are fitted per RGB channel
and written back as one number when the three channels come out equal, else as ``[r, g, b]``;
widths (α, the exponent, σ) are one number. ``eta`` and ``k`` go together: when either is free
and MODEL names a ``material`` (or relies on the default one), both are written out as numbers
and the material is dropped. With ``fresnel=schlick`` only R0 = ((η−1)² + k²)/((η+1)² + k²)
matters: free ``eta`` with ``k`` fixed (at 0) is identifiable, both free are not (the fit then
returns one of many equivalent pairs).

**Ranges: reparametrisation plus clamping.** Adam works on a transformed variable x, clamped
after every step to the image of the parameter's valid range (each plugin's docstring):

* α, ``alpha_u``, ``alpha_v``: x = log α, α ∈ [10⁻³, 2] (a roughness acts multiplicatively: a
  step of 0.1 in x is 10 % of α, whatever α);
* ``exponent``: x = log n, n ∈ [10⁻², 10⁶] (Phong exponents span decades, likewise);
* ``eta``: x = (η − 1)/(η + 1), η ∈ [0, 10³]: for k = 0, R0 = x², so the Fresnel reflectance
  moves evenly with x, up to R0 → 1 (gold's red R0 = 0.967 needs a Schlick η ≈ 106, which
  log η reached only after thousands of steps: the gradient in log η fades as 4/η);
* ``k``: x = log(1 + k), k ∈ [0, 10³] (0 allowed: a dielectric; relative steps for large k);
* ``sigma``: x = σ², σ ∈ [10⁻³, π/2]: Oren & Nayar's (1994) coefficients depend on σ², so the
  objective is flat in σ at σ = 0, where a fit that passes through 0 would stay; in σ² it is not
  (the floor 10⁻³ keeps the square root differentiable; σ = 10⁻³ is Lambert to 10⁻⁶);
* reflectances and transmittances: x = ρ ∈ [0, 1]; any other parameter: x = v ≥ 0.

One learning rate then suits every parameter (0.1 in x), decayed along a cosine to 1/100 of it
over the run so that the last steps settle instead of oscillating.

**Direction pairs.** The pairs are drawn in Rusinkiewicz's (1998, "A New Change of Variables
for Efficient BRDF Representation") half/difference angles, with θh = (π/2)u² (dense near the
specular peak, as the MERL tables of Matusik et al. 2003 space θh by its square root), θd
uniform in [0, π/2) (up to grazing incidence and exitance), φd and φh uniform (anisotropy); a
pair is kept when both directions lie above the horizon (cosθ > 10⁻³; about 3/4 of them). A
fixed seed makes the pairs, and so the fit, deterministic. The objective is the mean over the
pairs and the RGB channels, so the density of the pairs is the implicit weight of each region:
the peak, where the model's width is decided, gets many of them, the diffuse and grazing
regions the rest.

**Error weighting.** Ngan, Durand & Matusik (2005, "Experimental Analysis of BRDF Models",
EGSR) fit measured BRDFs under an L2 metric of the cosine-weighted values, because the plain
L2 of the BRDF is dominated by a few samples: the specular peak and grazing angles, where many
models grow without bound; compressing the values before the L2 (a log, a cube root) is the
other usual remedy. We use both:

    L = mean over pairs and channels of ((e_fit·cosθi + ε)^(1/3) − (e_target·cosθi + ε)^(1/3))²,

with e = ``eval`` = f·cosθo, so the compared quantity is f·cosθi·cosθo, and ε = 10⁻⁶:

* f·cosθi·cosθo is symmetric in the two directions (it weighs a reciprocal model's incidence
  and exitance alike) and bounded for microfacet models (D·G·F/4), whereas f·cosθo alone grows
  as 1/cosθi at grazing incidence: for Beckmann α = 0.2 it reaches 1.7·10³ at θd → 90°, and
  those few pairs outweighed the whole lobe even after the cube root;
* the cube root compresses a peak 1000 times the diffuse level to 10 times, so the peak cannot
  outweigh the rest of the lobe, yet unlike the log it stays finite at 0 (a log needs an offset
  whose choice decides how much the near-zero tails weigh). It is also the lightness
  compression of CIE L*, and Forés, Ferwerda & Gu (2012, "Toward a Perceptually Based Metric
  for BRDF Modeling", CIC) found fits under a cube-root metric perceptually closer than under
  RMS metrics.

The **residual** reported is not this objective but the plain relative L2 of the raw values over
the same pairs, ‖eval_fit − eval_target‖ / ‖eval_target‖ (dominated by the largest values: for
a microfacet target, its grazing pairs; the same of f·cosθi·cosθo, the quantity compared, is
given beside it), and the **albedo error** is max over θ and channels of
|E_fit(θ) − E_target(θ)| by :func:`~mi_brdfs.checks.albedo.albedo_quadrature` (256² nodes; a
lobe much sharper than α ≈ 0.05 is not resolved by it). Both are computed for the fitted spec
as written (values rounded to 6 significant digits), loaded afresh.

**Starts.** Gradient descent finds a local minimum, and a lobe's width is where the objective is
least convex. ``starts='auto'`` runs from the values MODEL gives (or its defaults) and, where
target and model both have a lobe width, from the closed-form mapping between them (Walter et
al. 2007, "Microfacet Models for Refraction through Rough Surfaces", EGSR, §5.2: the Blinn-Phong
exponent n and the Beckmann roughness α match for n = 2/α² − 2; Ward's α is Beckmann's; a mirror
Phong lobe of exponent n/4 is about as wide as a halfway lobe of exponent n; GGX's α is taken as
Beckmann's, a start, not an equivalence), else from the given width divided and multiplied by 4,
and keeps the run with the lowest objective. ``starts='given'`` runs from MODEL's values only.

**Cost.** A step evaluates MODEL once on every pair, with its gradient: about 1-3 ms for 12 000
pairs in ``llvm_ad_rgb``, so a default fit (800 steps, one to three starts, the albedo
comparison) takes 2-5 s on two cores. A built-in whose update rebuilds tables (Mitsuba's
``roughplastic`` recomputes its internal reflectance) is slower by orders of magnitude.
"""

from __future__ import annotations

import math
import shlex
import time
from dataclasses import dataclass, field

import numpy as np

from .errors import MiBrdfsError, counts

#: Incident angles (degrees) of the albedo comparison: dense towards grazing.
ALBEDO_THETAS = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 84.26, 87.0, 89.0)

#: ε of the cube-root objective (f·cosθi·cosθo units): keeps its gradient finite where it is 0.
EPSILON = 1e-6

#: Widths of a lobe: one number each, fitted in log space.
WIDTHS = ("alpha", "alpha_u", "alpha_v", "exponent")

#: Parameters with the spectrum's channels (fitted per RGB channel) among texture-valued ones.
_SPECTRAL_NAMES = ("eta", "k", "base_color")

#: Beckmann-type plugins whose ``alpha`` is the lobe width (built-ins included).
_MICROFACET = ("cooktorrance", "roughconductor", "roughplastic", "roughdielectric", "ward")


def _bounds(name: str):
    """(transform, lower, upper) of parameter ``name`` (see the module docstring)."""
    if name in ("alpha", "alpha_u", "alpha_v"):
        return "log", 1e-3, 2.0
    if name == "exponent":
        return "log", 1e-2, 1e6
    if name == "eta":
        return "fresnel", 0.0, 1e3
    if name == "k":
        return "log1p", 0.0, 1e3
    if name == "sigma":
        return "square", 1e-3, math.pi / 2
    if name.endswith(("reflectance", "transmittance")):
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


@dataclass
class FitResult:
    """What :func:`fit` found; ``parameters``: the free ones as written back (float, [r, g, b])."""

    target: object
    model: dict
    spec: dict
    parameters: dict
    residual: float
    residual_projected: float
    albedo_error: float
    albedo_theta: float
    loss: float
    start: str
    starts: dict
    thetas_deg: np.ndarray
    albedo_target: np.ndarray
    albedo_fit: np.ndarray
    pairs: int
    steps: int
    seed: int
    variant: str
    seconds: float
    notes: list = field(default_factory=list)

    def command_line(self) -> str:
        """The fitted BSDF as a command-line spec (``plugin key=value ...``)."""
        return command_line(self.spec)

    def xml(self) -> str:
        """The fitted BSDF as an XML ``<bsdf>`` element."""
        from .bsdfspec import to_xml

        return to_xml(self.spec)

    def to_json(self) -> dict:
        """The JSON document of ``mi-brdfs fit -o``."""
        return {"target": spec_text(self.target), "model": spec_text(self.model),
                "parameters": self.parameters, "residual": self.residual,
                "albedo_error": self.albedo_error, "residual_projected": self.residual_projected,
                "fitted": self.command_line(),
                "xml": self.xml(), "objective": self.loss, "start": self.start,
                "variant": self.variant, "pairs": self.pairs, "steps": self.steps,
                "seed": self.seed}

    def summary(self) -> str:
        """The printed report: fitted values, residual, albedo error, command line and XML."""
        width = max(len(n) for n in self.parameters)
        lines = [f"fit of {spec_text(self.model)} to {spec_text(self.target)} "
                 f"({self.pairs} direction pairs, {self.steps} steps, start: {self.start}, "
                 f"{self.seconds:.1f} s)"]
        lines += [f"  {name:<{width}} = {_show(value)}"
                  for name, value in self.parameters.items()]
        lines.append(f"residual      ‖f_fit − f_target‖/‖f_target‖ = {self.residual:.4g} "
                     f"(f·cosθo over the pairs; of f·cosθi·cosθo: "
                     f"{self.residual_projected:.4g})")
        lines.append(f"albedo error  max |ΔE(θ)| = {self.albedo_error:.4g} "
                     f"(at θ = {self.albedo_theta:g}°)")
        if len(self.starts) > 1:
            lines.append("starts        " + ", ".join(f"{label}: objective {loss:.4g}"
                                                      for label, loss in self.starts.items()))
        lines += [f"note: {n}" for n in self.notes]
        lines.append(f"fitted BSDF   {self.command_line()}")
        lines.append(self.xml())
        return "\n".join(lines)


def _show(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(f"{v:.6g}" for v in value) + "]"
    return f"{value:.6g}"


def _number(v: float) -> float:
    """A fitted number, rounded to 6 significant digits (what is written back)."""
    return float(f"{float(v):.6g}")


def _text(value) -> str:
    """A number as the command line reads it back exactly (shortest repr, no '.0')."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def command_line(spec) -> str:
    """A command-line spec ``plugin key=value ...`` of a BSDF dict of plain values."""
    from .bsdfspec import describe

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
    from .bsdfspec import describe

    try:
        return command_line(spec)
    except MiBrdfsError:
        return describe(spec)


# -------------------------------------------------------------------------------------------------
# Direction pairs
# -------------------------------------------------------------------------------------------------


def direction_pairs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    (wi, wo), each (m, 3) with m ≤ n: ``n`` pairs drawn in half/difference angles (θh = (π/2)u²,
    θd uniform, φd and φh uniform; see the module docstring), those with both directions above
    the horizon (cosθ > 10⁻³).
    """
    rng = np.random.default_rng(seed)
    u = rng.random((n, 4))
    th, td = (math.pi / 2) * u[:, 0] ** 2, (math.pi / 2) * u[:, 1]
    pd, ph = 2 * math.pi * u[:, 2], 2 * math.pi * u[:, 3]
    h = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=1)
    t = np.stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), -np.sin(th)], axis=1)
    b = np.cross(h, t)
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], axis=1)
    wi = d[:, :1] * t + d[:, 1:2] * b + d[:, 2:3] * h  # the difference vector in h's frame
    wo = 2 * np.sum(wi * h, axis=1, keepdims=True) * h - wi
    ok = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    return wi[ok], wo[ok]


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


def _rgb(values) -> dict:
    return {"type": "rgb", "value": [float(v) for v in np.broadcast_to(values, 3)]}


def _prepare_model(model: dict, free) -> tuple[dict, list[str]]:
    """
    The model dict to fit (spectral free parameters promoted to RGB; ``eta`` and ``k`` written
    out, and ``material`` dropped, when one of them is free) and the free names.
    """
    from .bsdfspec import load_bsdf

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
    return spec, names


def _accepted(model: dict, available: dict) -> dict:
    """
    The parameters of ``available`` that the plugin takes under that name in a spec: a traverse
    key need not be one (``roughplastic`` exposes ``eta`` but takes ``int_ior``/``ext_ior``).
    Those absent from ``model`` are tried all together, else one by one (``eta`` with ``k``).
    """
    from .bsdfspec import load_bsdf

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


def _plain(values):
    """A spec value: one number when the channels agree, else an ``rgb``."""
    values = np.asarray(values, dtype=np.float64).ravel()
    if np.all(values == values[0]):
        return _number(values[0])
    return {"type": "rgb", "value": [_number(v) for v in values]}


# -------------------------------------------------------------------------------------------------
# Closed-form starts
# -------------------------------------------------------------------------------------------------


def _scalar(values: dict, name: str):
    return float(np.mean(values[name][1])) if name in values else None


def beckmann_width(spec, values: dict | None = None):
    """
    The Beckmann roughness α equivalent to the lobe of ``spec`` (a dict), or None: α itself for
    microfacet models and Ward (√(αu·αv) when anisotropic), √(2/(n+2)) for a halfway Phong lobe of
    exponent n (Walter et al. 2007, §5.2), and that of exponent 4n for a mirror lobe.
    """
    from .bsdfspec import load_bsdf

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
    if kind == "phong" and "exponent" in values:
        n = _scalar(values, "exponent")
        n_halfway = n if spec.get("lobe", "mirror") == "halfway" else 4 * n
        return math.sqrt(2.0 / (n_halfway + 2.0))
    return None


def _width_start(spec: dict, names: list[str], alpha: float) -> dict:
    """{name: value} of the model's free width parameters for a Beckmann roughness α."""
    kind, start = spec["type"], {}
    for name in names:
        if name in ("alpha", "alpha_u", "alpha_v") and kind in _MICROFACET:
            start[name] = alpha
        elif name == "exponent" and kind == "phong":
            n = 2.0 / alpha ** 2 - 2.0
            start[name] = n if spec.get("lobe", "mirror") == "halfway" else n / 4
    return start


# -------------------------------------------------------------------------------------------------
# The fit
# -------------------------------------------------------------------------------------------------


def _require_ad_rgb(variant: str | None) -> str:
    import drjit as dr
    import mitsuba as mi

    from .registry import use_variant

    if variant is not None:
        use_variant(variant, fallback=False)
    elif mi.variant() is None:
        use_variant("llvm_ad_rgb", fallback=False)
    current = mi.variant()
    if not dr.is_diff_v(mi.Float) or not mi.is_rgb or mi.is_polarized:
        raise MiBrdfsError(f"fit needs an RGB variant with automatic differentiation "
                           f"(llvm_ad_rgb or cuda_ad_rgb); {current} has "
                           f"{'no AD' if not dr.is_diff_v(mi.Float) else 'no plain RGB'}")
    return current


def _cbrt(x):
    import drjit as dr

    return dr.power(x + EPSILON, 1.0 / 3.0)


def _run(bsdf, params: list[Parameter], start: dict, si, wo, target_c, steps: int, lr: float,
         bar, done: int):
    """Adam from ``start`` ({name: value}); returns (values {name: array}, final objective)."""
    import drjit as dr
    import mitsuba as mi

    traversed = mi.traverse(bsdf)
    ctx = mi.BSDFContext()
    opt = mi.ad.Adam(lr=lr)
    ranges = {p.name: p.x_range() for p in params}
    for p in params:
        opt[p.name] = p.drjit(p.encode(start[p.name]))

    def objective():
        for p in params:
            traversed[p.key] = p.decode(opt[p.name])
        traversed.update()
        diff = _cbrt(bsdf.eval(ctx, si, wo) * si.wi.z) - target_c
        return dr.mean(dr.squared_norm(diff)) / 3.0

    for step in range(steps):
        # cosine decay from lr to lr/100: large steps first, then settle
        opt.set_learning_rate(lr * (0.01 + 0.99 * 0.5 * (1 + math.cos(math.pi * step / steps))))
        loss = objective()
        dr.backward(loss)
        opt.step()
        for p in params:
            lo, hi = ranges[p.name]
            opt[p.name] = dr.clip(opt[p.name], lo, hi)
        if bar is not None:
            bar.update(done + step + 1)
    with dr.suspend_grad():
        loss = float(np.asarray(objective()).ravel()[0])
    values = {p.name: p.decode(np.array(opt[p.name], dtype=np.float64).ravel()) for p in params}
    return values, loss


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


@counts("pairs", "steps")
def fit(target, model, free=None, *, pairs: int = 16384, steps: int = 800, lr: float = 0.1,
        seed: int = 0, starts: str = "auto", thetas_deg=ALBEDO_THETAS, variant: str | None = None,
        progress: bool = False) -> FitResult:
    """
    Fit the continuous parameters of ``model`` so that its ``eval`` (f·cosθo) matches that of
    ``target`` (see the module docstring for the objective, the pairs and the ranges).

    Parameter ``target``: any BSDF spec (:mod:`mi_brdfs.bsdfspec`: a plugin with its parameters,
    a built-in, an XML fragment or file, a loaded ``mi.BSDF``).
    Parameter ``model``: a plugin name with ``key=value`` parameters (a string or a dict): its
    values are the start, and those not in ``free`` stay fixed.
    Parameter ``free``: names of the parameters to fit (a list or ``'alpha,exponent'``); None:
    all of the model's continuous parameters.
    Parameter ``pairs``: direction pairs drawn (those below the horizon are dropped: about 3/4
    are kept). ``steps``: Adam steps per start. ``lr``: Adam's learning rate in the transformed
    variables. ``seed``: of the pairs. ``starts``: ``'auto'`` (MODEL's values, and the closed-form
    width mapping or spread widths) or ``'given'`` (MODEL's values only).
    Parameter ``variant``: an RGB AD variant to set first (default: the current one, which must
    be one; ``llvm_ad_rgb`` when none is set).

    Returns → :class:`FitResult`. Raises MiBrdfsError (one line) for bad input.
    """
    import drjit as dr
    import mitsuba as mi

    from .bsdfspec import load_bsdf, parse
    from .checks import batch
    from .checks.albedo import albedo_quadrature
    from .progress import Progress

    clock = time.perf_counter()
    variant = _require_ad_rgb(variant)
    if starts not in ("auto", "given"):
        raise MiBrdfsError(f"fit: starts = {starts!r} is invalid: must be 'auto' or 'given'")
    if not (isinstance(lr, (int, float)) and math.isfinite(lr) and lr > 0):
        raise MiBrdfsError(f"fit: lr = {lr!r} is invalid: must be a finite number > 0")
    thetas = np.asarray(thetas_deg, dtype=np.float64).ravel()
    if thetas.size == 0 or not np.all((thetas >= 0) & (thetas <= 90)):
        raise MiBrdfsError(f"fit: thetas_deg = {thetas_deg!r} is invalid: must be one or more "
                           f"angles within [0, 90] degrees")
    target = parse(target)
    model = parse(model)
    if not isinstance(model, dict):
        raise MiBrdfsError(f"MODEL {spec_text(model)} must be a plugin name with key=value "
                           f"parameters (or a dict): its values are rewritten by the fit, which "
                           f"an XML fragment or a loaded BSDF does not allow")
    target_bsdf = load_bsdf(target)
    notes = []
    if int(target_bsdf.flags()) & int(mi.BSDFFlags.Transmission):
        notes.append("the target transmits: the fit matches its reflection (pairs above the "
                     "surface), while its albedo E(θ) includes the transmitted part")
    spec, names = _prepare_model(model, free)
    bsdf = load_bsdf(spec)
    available = _fittable(bsdf)
    params = []
    for name in names:
        key, value = available[name]
        params.append(Parameter(name, key, value.size, *_bounds(name)))
    given = {name: available[name][1] for name in names}

    wi, wo = direction_pairs(pairs, seed)
    target_values = batch.evaluate(target_bsdf, wi, wo).value
    target_values = np.broadcast_to(target_values, (len(wi), 3)) if target_values.shape[1] == 1 \
        else target_values
    finite = np.all(np.isfinite(target_values), axis=1)
    if not finite.all():
        notes.append(f"{int((~finite).sum())} pairs where the target's eval is not finite were "
                     f"left out")
        wi, wo, target_values = wi[finite], wo[finite], target_values[finite]
    if not np.any(target_values > 0):
        raise MiBrdfsError(f"the target {spec_text(target)} has eval = 0 at every direction pair "
                           f"(only delta lobes, or no reflection?): nothing to fit")

    candidates = {"given": given}
    width_names = [n for n in names if n in WIDTHS]
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
                    n: given[n] * (factor if n != "exponent" else 1 / factor)
                    for n in width_names})

    si, w = batch.interaction(wi, len(wi)), batch.vectors(wo)
    projected = target_values * wi[:, 2:3]  # f·cosθi·cosθo
    target_c = mi.Color3f(*[mi.Float(np.cbrt(projected[:, c] + EPSILON).astype(np.float32))
                            for c in range(3)])
    bar = Progress(steps * len(candidates), label=f"fit {spec_text(model)}", unit=" steps") \
        if progress else None
    runs = {}
    try:
        for i, (label, start) in enumerate(candidates.items()):
            runs[label] = _run(bsdf, params, start, si, w, target_c, steps, lr, bar, i * steps)
    finally:
        if bar is not None:
            bar.close()
    best = min(runs, key=lambda label: (not math.isfinite(runs[label][1]), runs[label][1]))
    values, loss = runs[best]
    if not math.isfinite(loss):
        raise MiBrdfsError(f"the fit of {spec_text(model)} diverged (objective {loss}) from every "
                           f"start")
    fitted, written = _written(params, values, spec)
    dr.sync_thread()

    # the reported figures, from the fitted spec as written (rounded), loaded afresh
    fitted_bsdf = load_bsdf(fitted)
    fit_values = batch.evaluate(fitted_bsdf, wi, wo).value
    residual = float(np.linalg.norm(fit_values - target_values) / np.linalg.norm(target_values))
    cos_i = wi[:, 2:3]
    residual_projected = float(np.linalg.norm((fit_values - target_values) * cos_i)
                               / np.linalg.norm(target_values * cos_i))
    e_target = np.array([albedo_quadrature(target_bsdf, t) for t in np.radians(thetas)])
    e_fit = np.array([albedo_quadrature(fitted_bsdf, t) for t in np.radians(thetas)])
    e_target = np.broadcast_to(e_target, e_fit.shape) if e_target.shape[1] == 1 else e_target
    diff = np.abs(e_fit - e_target)
    worst = np.unravel_index(int(np.argmax(diff)), diff.shape)
    return FitResult(target=target, model=model, spec=fitted, parameters=written,
                     residual=residual, residual_projected=residual_projected,
                     albedo_error=float(diff[worst]),
                     albedo_theta=float(thetas[worst[0]]), loss=loss, start=best,
                     starts={label: r[1] for label, r in runs.items()}, thetas_deg=thetas,
                     albedo_target=e_target, albedo_fit=e_fit, pairs=len(wi), steps=steps,
                     seed=seed, variant=variant, seconds=time.perf_counter() - clock,
                     notes=notes)


# -------------------------------------------------------------------------------------------------
# Output
# -------------------------------------------------------------------------------------------------


def write_json(result: FitResult, path) -> str:
    """Write :meth:`FitResult.to_json` to ``path`` atomically; return the path."""
    import json
    import os

    from .imageio import atomic_path

    path = os.fspath(path)
    with atomic_path(path, ".json") as tmp, open(tmp, "w") as f:
        json.dump(result.to_json(), f, indent=1)
        f.write("\n")
    return path


def plot_fit(result: FitResult, path, thetas_deg=(0.0, 30.0, 60.0, 80.0)) -> str:
    """
    Target against fit: f·cosθo in the plane of incidence at ``thetas_deg`` (polar, radius
    (f·cosθo)^(1/3), the fit's compression) and the directional albedo E(θ) (mean of channels).
    """
    from .bsdfspec import describe
    from .plots import cube_root_lobe, lobe_values, pyplot, save_figure

    plt = pyplot()
    k = len(thetas_deg)
    fig = plt.figure(figsize=(3.6 * k + 4.8, 4.2))
    for j, theta_i in enumerate(thetas_deg):
        ax = fig.add_subplot(1, k + 1, j + 1, projection="polar")
        cube_root_lobe(ax, [(*lobe_values(spec, theta_i), style, dict(lw=1.4, label=label))
                            for spec, label, style in ((result.target, "target", "-"),
                                                       (result.spec, "fit", "--"))],
                       f"θi = {theta_i:g}°")
    ax.legend(loc="lower right", fontsize=7)
    ax = fig.add_subplot(1, k + 1, k + 1)
    ax.plot(result.thetas_deg, result.albedo_target.mean(axis=1), "-o", ms=3, label="target")
    ax.plot(result.thetas_deg, result.albedo_fit.mean(axis=1), "--s", ms=3, label="fit")
    ax.set_xlabel("incident angle θ (degrees)")
    ax.set_ylabel("albedo E(θ)")
    ax.set_xlim(0, 90)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.subplots_adjust(wspace=0.45)
    fig.suptitle(f"fit {describe(result.spec)}\nto {describe(result.target)}: residual "
                 f"{result.residual:.3g}, max |ΔE(θ)| {result.albedo_error:.3g}; lobes: "
                 f"(f·cosθo)^(1/3) in the plane of incidence", fontsize=9)
    return save_figure(fig, path)
