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
* ``exponent`` (and ``ashikhmin``'s ``nu``, ``nv``, ``lafortune``'s ``exponent_0``, ...):
  x = log n, n ∈ [10⁻², 10⁶] (Phong exponents span decades, likewise);
* ``eta``: x = (η − 1)/(η + 1), η ∈ [0, 10³]: for k = 0, R0 = x², so the Fresnel reflectance
  moves evenly with x, up to R0 → 1 (gold's red R0 = 0.967 needs a Schlick η ≈ 106, which
  log η approaches slowly: the gradient in log η fades as 4/η);
* ``k``: x = log(1 + k), k ∈ [0, 10³] (0 allowed: a dielectric; relative steps for large k);
* ``sigma``: x = σ², σ ∈ [10⁻³, π/2]: Oren & Nayar's (1994) coefficients depend on σ², so the
  objective is flat in σ at σ = 0, where a fit that passes through 0 would stay; in σ² it is not
  (the floor 10⁻³ keeps the square root differentiable; σ = 10⁻³ is Lambert to 10⁻⁶);
* ``lafortune``'s coefficients ``cx_i``, ``cy_i``, ``cz_i``: x = C, of any sign (with its
  default ``normalize`` the lobe depends on C/max|C| only, so C and λC are one lobe: leave one
  coefficient fixed, e.g. ``cx_i`` and ``cy_i`` at −1 with ``cz_i`` free);
* reflectances, transmittances and ``rtls``'s kernel weights: x = ρ ∈ [0, 1];
* the parameters of ``rpv`` (ρ0, its Minnaert k, g, ρc) and ``hapke`` (w, b, c, θ̄ in degrees,
  B_0, h): x = v within the range the plugin takes (``mi_brdfs.plugins.rpv.RANGES``,
  ``mi_brdfs.plugins.hapke.PARAMETERS``), but w ≤ 1 − 10⁻⁶ (H's derivative in w is infinite
  at 1); ``ocean``'s wind speed: x = U ∈ [0, 37.54] m/s, its ``eta`` and ``ext_ior``:
  x = (η − 1)/(η + 1), η ∈ [10⁻³, 10³] (the plugin takes η > 0);
* ``cooktorrance``'s ``film_thickness``: x = log(1 + d), d ∈ [0, 10⁵] nm (relative steps, 0, no
  film, within reach; in nanometres a step of 0.1 would take hundreds of steps to cross a
  fringe), its ``film_eta``: x = (η − 1)/(η + 1), η ∈ [10⁻³, 100] (the range the plugin takes);
* any other parameter: x = v ≥ 0.

A numbered parameter of ``lafortune`` (``exponent_1``, ``specular_reflectance_1``) is fitted as
the parameter of its kind is.

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

**Measured targets and other metrics.** A MERL file (``fit X.binary``, or ``merl
filename=X.binary``) is compared at its own bins: ``pairs`` measured bins drawn at random, at
their centres, with the file's values, not interpolated (:func:`~mi_brdfs.fit.optimise.
measured_pairs`). Since MERL spaces its bins uniformly in (√θh, θd, φd), as the pairs above
are drawn, the cube-root objective is the mean over MERL's bins either way. ``metric`` selects
the metric of the literature instead (:data:`~mi_brdfs.fit.optimise.METRICS`): Ngan et al.'s
(2005) L2 of f·cosθi, Low et al.'s (2012) L2 of log(1 + f·cosθi), Bieron & Peers' (2020) the
same weighed by cosθo, each an integral over dωi dωo, each pair weighed by the solid angle its
bin covers (4 cosθd·sinθd·sinθh dθh dθd dφd dφh, Rusinkiewicz 1998).

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
exponent n and the Beckmann roughness α match for n = 2/α² − 2, and so do Ashikhmin &
Shirley's nu, nv, whose lobe is a Blinn-Phong one; Ward's α is Beckmann's; a mirror Phong lobe
of exponent n/4, and a Lafortune lobe taken as one, is about as wide as a halfway lobe of
exponent n; GGX's α is taken as Beckmann's, a start, not an equivalence), else from the given
width divided and multiplied by 4, and keeps the run with the lowest objective.
``starts='given'`` runs from MODEL's values only.

**Cost.** A step evaluates MODEL once on every pair, with its gradient, so a fit costs in
proportion to pairs × steps × starts, plus the albedo comparison at the end. A built-in whose
update rebuilds tables (Mitsuba's ``roughplastic`` recomputes its internal reflectance) is
much slower per step.

**Modules.** :mod:`~mi_brdfs.fit.parameters` (which parameters are fitted, their ranges and
starts), :mod:`~mi_brdfs.fit.optimise` (the pairs, the objective, Adam),
:mod:`~mi_brdfs.fit.result` (:class:`FitResult`, its JSON file and plot),
:mod:`~mi_brdfs.fit.flags` (what makes a fit useless or unphysical) and
:mod:`~mi_brdfs.fit.spec` (the fitted BSDF as written); :func:`fit` here.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import MiBrdfsError, arguments, counts, valid_seed
from ..variants import keeps_variant
from .flags import fit_flags
from .optimise import (
    EPSILON, METRICS, _best, _run_starts, _target_values, check_metric,
    direction_pairs,
)
from .parameters import (
    WIDTHS, Parameter, _parameters, _prepare_model, _starts, _written, beckmann_width,
)
from .result import ALBEDO_THETAS, FitResult, _figures, plot_fit, write_json
from .spec import command_line, spec_text

__all__ = ["ALBEDO_THETAS", "EPSILON", "METRICS", "WIDTHS", "FitResult", "Parameter", "beckmann_width",
           "command_line", "direction_pairs", "fit", "plot_fit", "spec_text", "write_json"]


def _checked(starts: str, lr: float, thetas_deg) -> np.ndarray:
    """The angles of the albedo comparison as an array, once ``starts``, ``lr`` and they are
    checked (MiBrdfsError, one line)."""
    if starts not in ("auto", "given"):
        raise MiBrdfsError(f"fit: starts = {starts!r} is invalid: must be 'auto' or 'given'")
    if not (isinstance(lr, (int, float)) and math.isfinite(lr) and lr > 0):
        raise MiBrdfsError(f"fit: lr = {lr!r} is invalid: must be a finite number > 0")
    try:
        thetas = np.asarray(thetas_deg, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        thetas = np.array([np.nan])
    if isinstance(thetas_deg, str) or thetas.size == 0 \
            or not np.all((thetas >= 0) & (thetas <= 90)):
        raise MiBrdfsError(f"fit: thetas_deg = {thetas_deg!r} is invalid: must be one or more "
                           f"angles within [0, 90] degrees")
    return thetas


@counts("pairs", "steps")
@arguments(seed=valid_seed)
@keeps_variant
def fit(target, model, free=None, *, pairs: int = 16384, steps: int = 800, lr: float = 0.1,
        seed: int = 0, starts: str = "auto", thetas_deg=ALBEDO_THETAS, variant: str | None = None,
        progress: bool = False, metric: str = "cuberoot") -> FitResult:
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
    Parameter ``metric``: the objective, one of :data:`~mi_brdfs.fit.optimise.METRICS`
    (default: the cube root).
    Parameter ``variant``: an RGB AD variant to fit in (default: the current one where it is
    one, else ``llvm_ad_rgb``: from ``scalar_rgb``, say, the fit switches to it). The caller's
    variant is set again on return, and when the fit raises
    (:func:`mi_brdfs.variants.variant_kept`); a loaded ``mi.BSDF`` is of its variant, so give
    the target as a dict or a string to fit from another.

    Returns → :class:`FitResult`, whose ``flags`` say in words what makes the fit useless or
    unphysical (:mod:`~mi_brdfs.fit.flags`: a parameter at a bound, no better than the zero
    model, a diverged start, an albedo above 1); empty when nothing does. Raises MiBrdfsError
    (one line) for bad input.
    """
    import drjit as dr
    import mitsuba as mi

    from ..bsdfspec import load_bsdf, parse
    from ..registry import use_rgb_jit

    clock = time.perf_counter()
    variant = use_rgb_jit("fit", variant, ad=True)
    thetas = _checked(starts, lr, thetas_deg)
    check_metric(metric)
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
    params, given = _parameters(bsdf, names, spec["type"])
    wi, wo, target_values = _target_values(target, target_bsdf, pairs, seed, notes)
    candidates = _starts(starts, spec, names, given, target, target_bsdf)
    runs = _run_starts(bsdf, params, candidates, wi, wo, target_values, steps, lr, model,
                       progress, metric)
    best = _best(runs, model)
    values, loss = runs[best]
    fitted, written = _written(params, values, spec)
    dr.sync_thread()
    figures = _figures(target_bsdf, fitted, wi, wo, target_values, thetas)
    flags = fit_flags(params, written, fitted, runs, best, figures, wi, wo, target_values,
                      metric)
    return FitResult(target=target, model=model, spec=fitted, parameters=written, loss=loss,
                     start=best, starts={label: r[1] for label, r in runs.items()},
                     pairs=len(wi), steps=steps, seed=seed, variant=variant, metric=metric,
                     seconds=time.perf_counter() - clock, notes=notes, flags=flags, **figures)
