"""
Directional albedo E(θ) = ∫ f(ωi, ωo) |cosθo| dωo and energy conservation, for any BSDF.

Three independent estimators, as in pbrt's ``BxDF::rho`` and the white furnace tests of
Mitsuba's hair model, each with its own error:

* **sampled**: the mean of ``sample()`` weights (tests ``sample`` and its weight);
* **eval**: ``eval()`` at directions drawn by *us* (cosine-weighted or uniform), divided by our
  own pdf (tests ``eval`` independently of the BSDF's sampler);
* **quadrature**: a dense tensor-product rule of ``eval()`` (Gauss-Legendre in cosθo, uniform in
  φo), computed at two resolutions so that an unresolved (too sharp) lobe is detected instead of
  trusted;

plus, where the package has one, the model's **float64 reference** (:mod:`mi_brdfs.reference`).
BSDFs with transmission are integrated over the whole sphere, and incident angles θ > 90° light
them from inside. Delta lobes have eval = 0, so only the sampled estimator sees them.

**Transport mode.** For a BSDF that refracts (it declares ``Transmission`` and
``NonSymmetric``) the albedo is taken in importance transport unless a context is given:
there ``eval(ωi, ωo)`` is the fraction of the light arriving along ωi that leaves towards ωo,
so E(θ) ≤ 1 is energy conservation; in radiance transport the refracted part carries the
factor 1/η² of radiance crossing an interface (Veach 1997, §5.2) and E(θ) from inside glass
exceeds 1 without any energy being created (:func:`energy_context`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import (
    arguments, counts, nonnegative, positive, valid_angle, valid_angles, valid_seed,
)
from ..reference.quadrature import sphere_grid
from . import batch
from .result import CheckResult

#: Incident angles (degrees) of the default albedo curve: dense towards grazing.
DEFAULT_THETAS = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 84.26, 87.0, 89.0)

#: Samples per incident angle: JIT variants vectorise, scalar ones call Python per sample.
DEFAULT_SAMPLES = {True: 1_000_000, False: 4_000}


def _default_n(n: int | None) -> int:
    return n if n is not None else DEFAULT_SAMPLES[batch.is_jit()]


def _flags(bsdf) -> int:
    return int(bsdf.flags())


def _has(bsdf, name: str) -> bool:
    return bool(_flags(bsdf) & int(getattr(mi.BSDFFlags, name)))


def energy_context(bsdf):
    """The context the albedo of ``bsdf`` is an energy in: importance transport for a BSDF that
    refracts (``Transmission`` and ``NonSymmetric``), else None (radiance, Mitsuba's default;
    the two agree for a symmetric BSDF)."""
    if _has(bsdf, "Transmission") and _has(bsdf, "NonSymmetric"):
        return mi.BSDFContext(mi.TransportMode.Importance)
    return None


def _mean_err(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error of the mean along axis 0."""
    n = len(x)
    return x.mean(axis=0), x.std(axis=0, ddof=1) / math.sqrt(max(n, 2))


def _sampled(bsdf, theta: float, n: int, seed: int, ctx):
    rng = np.random.default_rng(seed)
    s = batch.sample(bsdf, batch.direction(theta), rng.random(n), rng.random((n, 2)), ctx)
    weight = np.where(np.isfinite(s.weight), s.weight, np.nan)
    ok = np.any(s.weight != 0, axis=1) & np.isfinite(s.pdf)
    pdf_max = float(s.pdf[ok].max()) if ok.any() else 0.0
    return _mean_err(weight) + (pdf_max,)


@counts("n")
@arguments(theta=valid_angle(math.pi, "radians"), seed=valid_seed)
def albedo_sampled(bsdf, theta: float, n: int | None = None, seed: int = 0, ctx=None):
    """
    E(θ) as the mean ``sample()`` weight over ``n`` samples at incident angle ``theta`` (radians).

    Returns → (mean (channels,), standard error (channels,)).
    """
    mean, err, _ = _sampled(load_bsdf(bsdf), theta, _default_n(n), seed, ctx)
    return mean, err


def _our_directions(rng, n: int, strategy: str, sphere: bool):
    """Directions drawn by the checker itself, with their pdf (cosine-weighted or uniform)."""
    u1, u2 = rng.random(n), rng.random(n)
    phi = 2 * math.pi * u2
    if strategy == "cosine":
        r = np.sqrt(u1)
        z = np.sqrt(np.maximum(1 - u1, 0))
        pdf = z / math.pi
    elif strategy == "uniform":
        z = u1
        r = np.sqrt(np.maximum(1 - z * z, 0))
        pdf = np.full(n, 1 / (2 * math.pi))
    else:
        raise ValueError(f"strategy must be 'cosine' or 'uniform', got {strategy!r}")
    wo = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    if sphere:  # mirror half of them below the surface: the pdf halves
        flip = rng.random(n) < 0.5
        wo[flip, 2] *= -1
        pdf = pdf / 2
    return wo, pdf


@counts("n")
@arguments(theta=valid_angle(math.pi, "radians"), seed=valid_seed)
def albedo_eval(bsdf, theta: float, n: int | None = None, seed: int = 1,
                strategy: str = "cosine", ctx=None):
    """
    E(θ) from ``eval()`` at directions drawn by the checker (``cosine`` or ``uniform``), each
    divided by that pdf: independent of the BSDF's own sampler and pdf.

    Returns → (mean (channels,), standard error (channels,)).
    """
    bsdf = load_bsdf(bsdf)
    n = _default_n(n)
    rng = np.random.default_rng(seed)
    wo, pdf = _our_directions(rng, n, strategy, sphere=_has(bsdf, "Transmission"))
    ok = pdf > 0
    value = batch.evaluate(bsdf, batch.direction(theta), wo[ok], ctx).value
    return _mean_err(np.concatenate([value / pdf[ok, None],
                                     np.zeros((int((~ok).sum()), value.shape[1]))]))


@counts("n_mu", "n_phi")
@arguments(theta=valid_angle(math.pi, "radians"))
def sphere_quadrature(bsdf, theta: float, n_mu: int = 256, n_phi: int = 256, ctx=None,
                      whole_sphere: bool = False):
    """
    (∫ eval dμ dφ (channels,), ∫ pdf dω) at incident angle ``theta`` (radians) on
    :func:`~mi_brdfs.reference.quadrature.sphere_grid` (Gauss-Legendre in μ = cosθo, midpoint
    in φo; ``eval`` already holds the cosine), over the upper hemisphere, and the lower one too
    for a BSDF that transmits or with ``whole_sphere``. A NaN pdf counts as 0.
    """
    bsdf = load_bsdf(bsdf)
    ranges = [(0.0, 1.0)] + ([(-1.0, 0.0)] if whole_sphere or _has(bsdf, "Transmission")
                             else [])
    value, pdf = 0.0, 0.0
    for mu_range in ranges:
        wo, weights = sphere_grid(n_mu, n_phi, mu_range)
        e = batch.evaluate(bsdf, batch.direction(theta), wo, ctx)
        value = value + np.einsum("n,nc->c", weights, e.value)
        pdf += float(np.dot(weights, np.nan_to_num(e.pdf)))
    return np.asarray(value), pdf


@counts("n_mu", "n_phi")
@arguments(theta=valid_angle(math.pi, "radians"))
def albedo_quadrature(bsdf, theta: float, n_mu: int = 256, n_phi: int = 256, ctx=None):
    """
    E(θ) = ∫ eval(ωo) dμ dφ by :func:`sphere_quadrature`.

    Returns → (channels,). Costs n_mu·n_phi evaluations (twice with transmission).
    """
    return sphere_quadrature(bsdf, theta, n_mu, n_phi, ctx)[0]


@dataclass
class AlbedoCurve:
    """E(θ) over incident angles by every estimator; arrays are (angles, channels)."""

    spec: object
    theta_deg: np.ndarray
    sampled: np.ndarray
    sampled_err: np.ndarray
    eval: np.ndarray | None = None
    eval_err: np.ndarray | None = None
    quadrature: np.ndarray | None = None
    quadrature_resolved: np.ndarray | None = None
    reference: np.ndarray | None = None
    notes: list = field(default_factory=list)

    def best(self) -> np.ndarray:
        """The most trustworthy curve: the reference, else the sampled estimate."""
        return self.reference if self.reference is not None else self.sampled

    def table(self) -> str:
        """A plain-text table: θ, sampled ± error, eval ± error, quadrature, reference."""
        head = f"{'θ (deg)':>8}  {'sample() mean ± err':>22}  {'eval() mean ± err':>22}  " \
               f"{'quadrature':>11}  {'reference':>10}"
        lines = [head, "-" * len(head)]
        for i, t in enumerate(self.theta_deg):
            c = int(np.argmax(self.sampled[i]))  # the brightest channel
            row = f"{t:8.2f}  {self.sampled[i, c]:12.5f} ± {self.sampled_err[i, c]:7.5f}"
            row += (f"  {self.eval[i, c]:12.5f} ± {self.eval_err[i, c]:7.5f}"
                    if self.eval is not None else f"  {'—':>22}")
            if self.quadrature is not None and self.quadrature_resolved[i]:
                row += f"  {self.quadrature[i, c]:11.5f}"
            else:
                row += f"  {'unresolved' if self.quadrature is not None else '—':>11}"
            row += f"  {self.reference[i, c]:10.5f}" if self.reference is not None else \
                f"  {'—':>10}"
            lines.append(row)
        return "\n".join(lines)


@loaded_once()
@counts("n")
@arguments(thetas_deg=valid_angles(180.0, "degrees"), seed=valid_seed)
def albedo_curve(spec, thetas_deg=DEFAULT_THETAS, n: int | None = None, seed: int = 0,
                 estimators=("eval", "quadrature", "reference"), ctx=None,
                 progress: bool = False) -> AlbedoCurve:
    """
    E(θ) at each incident angle (degrees) by the sampled estimator and the ``estimators`` asked
    for. The quadrature runs at 128² and 256² nodes; where the two differ by more than 1e-3, or
    its grid is coarser than a quarter of the lobe's width, it is marked unresolved.
    """
    from .. import reference as ref
    from ..progress import Progress

    bsdf = load_bsdf(spec)
    thetas = np.asarray(thetas_deg, dtype=np.float64)
    model = ref.for_spec(spec) if "reference" in estimators and ctx is None else None
    ctx = ctx or energy_context(bsdf)
    delta_only = not (_flags(bsdf) & int(mi.BSDFFlags.Smooth))
    do_eval = "eval" in estimators and not delta_only
    do_quad = "quadrature" in estimators and not delta_only and batch.is_jit()
    rows = []
    bar = Progress(len(thetas), label=f"albedo {describe(spec)}", unit=" angles") \
        if progress else None
    for i, t in enumerate(np.radians(thetas)):
        row = dict(zip(("sampled", "sampled_err", "pdf_max"),
                       _sampled(bsdf, t, _default_n(n), seed + i, ctx)))
        if do_eval:
            row["eval"], row["eval_err"] = albedo_eval(bsdf, t, n, seed + 1000 + i, "cosine", ctx)
        if do_quad:
            coarse = albedo_quadrature(bsdf, t, 128, 128, ctx)
            row["quadrature"] = albedo_quadrature(bsdf, t, 256, 256, ctx)
            # Resolved where the two grids agree and the grid spacing (2π/256 in φ) is below a
            # quarter of the lobe's width, estimated from the sampler's largest pdf as
            # 1/sqrt(pdf): two grids that both miss a sharp lobe agree on 0.
            width = 1.0 / math.sqrt(max(row["pdf_max"], 1e-12))
            row["resolved"] = bool(np.all(np.abs(row["quadrature"] - coarse) <= 1e-3)
                                   and 2 * math.pi / 256 < width / 4)
        if model is not None:
            row["reference"] = model.albedo(t)
        rows.append(row)
        if bar:
            bar.update(i + 1)
    if bar:
        bar.close()

    def column(key):
        return np.array([r[key] for r in rows])
    curve = AlbedoCurve(spec, thetas, column("sampled"), column("sampled_err"))
    if delta_only:
        curve.notes.append("delta lobes only: eval() is 0, so only sample() sees them")
    if do_eval:
        curve.eval, curve.eval_err = column("eval"), column("eval_err")
    if do_quad:
        curve.quadrature, curve.quadrature_resolved = column("quadrature"), column("resolved")
    if model is not None:
        curve.reference = column("reference")
    return curve


@loaded_once()
@counts("n")
@arguments(thetas_deg=valid_angles(180.0, "degrees"), sigmas=positive)
def check_energy(spec, thetas_deg=DEFAULT_THETAS, n: int | None = None, sigmas: float = 5.0,
                 curve: AlbedoCurve | None = None) -> CheckResult:
    """
    Energy conservation, ∫ f cosθo dωo ≤ 1: the directional albedo E(θ) estimated from
    ``sample()`` weights and from ``eval()`` (at directions the checker draws, independent of the
    BSDF's sampler) must not exceed 1 by more than ``sigmas`` standard errors (and 1e-4) at any
    incident angle and channel. A BSDF whose ``eval()`` creates energy while its sample weights
    do not (or the reverse) fails.
    """
    curve = curve or albedo_curve(spec, thetas_deg, n, estimators=("eval",))
    estimates = [("sample()", curve.sampled, curve.sampled_err)]
    if curve.eval is not None:
        estimates.append(("eval()", curve.eval, curve.eval_err))
    worst_score, worst = -np.inf, None
    for label, value, err in estimates:
        score = value - 1.0 - np.maximum(sigmas * err, 1e-4)
        i, c = np.unravel_index(int(np.nanargmax(score)), score.shape)
        if worst is None or score[i, c] > worst_score:
            worst_score, worst = score[i, c], (label, value[i, c], err[i, c], i, c)
    label, value, err, i, c = worst
    if all(np.all(v == 0) for _, v, _ in estimates):
        return CheckResult("energy", False, 0.0, f"≤ 1 + {sigmas:g}σ",
                           f"energy: {describe(spec)}: E(θ) = 0 at every angle by "
                           f"{' and '.join(lbl for lbl, _, _ in estimates)}: no sample "
                           f"succeeded and eval() is 0 everywhere, so the check would pass "
                           f"vacuously", details={"curve": curve})
    passed = bool(all(np.all(np.isfinite(v)) for _, v, _ in estimates) and worst_score <= 0)
    where = f"θ = {curve.theta_deg[i]:.1f}°"
    if curve.sampled.shape[1] > 1:
        where += f", channel {c}"
    by = " and ".join(lbl for lbl, _, _ in estimates)
    if passed:
        msg = (f"energy: {describe(spec)}: max E(θ) = {value:.5f} ± {err:.5f} (from {label}) at "
               f"{where}: ≤ 1 by {by}")
    else:
        msg = (f"energy: {describe(spec)}: E(θ) from {label} = {value:.5f} ± {err:.5f} at "
               f"{where} exceeds 1 by {value - 1:.5f} (> {sigmas:g}σ): the BSDF creates energy")
    return CheckResult("energy", passed, float(value), f"≤ 1 + {sigmas:g}σ", msg,
                       details={"curve": curve})


#: Relative tolerance of the sample()-vs-eval() albedo agreement. Set by the built-in it must
#: accept: Mitsuba's roughconductor (Beckmann, visible-normal sampling) samples the exact
#: Beckmann visible normals but weighs them with its rational Smith G1 approximation, so its
#: sample() albedo departs from its eval() albedo near grazing by a few tenths of a percent
#: (GGX, and Beckmann without visible normals, agree far more closely). Bugs this check is for
#: (a missing cosine, a wrong pdf normalisation) are factors, far above it.
AGREEMENT_RTOL = 5e-3


@loaded_once()
@counts("n")
@arguments(thetas_deg=valid_angles(180.0, "degrees"), sigmas=positive, rtol=nonnegative)
def check_albedo_agreement(spec, thetas_deg=DEFAULT_THETAS, n: int | None = None,
                           sigmas: float = 5.0, rtol: float = AGREEMENT_RTOL,
                           curve: AlbedoCurve | None = None) -> CheckResult:
    """
    The albedo from ``sample()`` weights must match the one from ``eval()``: the float64
    reference where there is one, else the resolved quadrature of ``eval``. Tolerance:
    ``sigmas`` standard errors of the sampled estimate plus ``rtol`` relative
    (:data:`AGREEMENT_RTOL`).
    """
    if curve is None:
        bsdf = load_bsdf(spec)
        flags, delta = _flags(bsdf), int(mi.BSDFFlags.Delta)
        ctx = None
        if flags & delta and flags & int(mi.BSDFFlags.Smooth):
            # eval() does not see Dirac lobes: compare the other lobes only (sampled alone)
            ctx = mi.BSDFContext(mi.TransportMode.Radiance, flags & ~delta)
        curve = albedo_curve(bsdf if ctx is not None else spec, thetas_deg, n, ctx=ctx)
        curve.spec = spec
    every = np.ones(len(curve.theta_deg), bool)
    if curve.reference is not None:
        target, what, ok_rows = curve.reference, "float64 reference", every
    elif curve.quadrature is not None:
        target, what, ok_rows = curve.quadrature, "quadrature of eval()", curve.quadrature_resolved
    elif curve.eval is not None:
        target, what, ok_rows = curve.eval, "eval() Monte Carlo", every
    else:
        return CheckResult("albedo", True, float("nan"), "n/a", f"albedo: {describe(spec)}: "
                           f"nothing to compare sample() with ({'; '.join(curve.notes)})",
                           {"curve": curve}, skipped=True)
    err = curve.sampled_err if curve.eval is None or target is not curve.eval else \
        np.sqrt(curve.sampled_err ** 2 + curve.eval_err ** 2)
    dev = np.abs(curve.sampled - target)
    allowed = sigmas * err + rtol * np.abs(target) + 1e-5
    score = np.where(ok_rows[:, None], dev / allowed, 0.0)
    if not ok_rows.any():
        return CheckResult("albedo", True, float("nan"), "n/a", f"albedo: {describe(spec)}: the "
                           f"lobe is too sharp for the quadrature at every angle: not compared",
                           {"curve": curve}, skipped=True)
    i, c = np.unravel_index(int(np.argmax(score)), score.shape)
    passed = bool(score.max() <= 1.0)
    msg = (f"albedo: {describe(spec)}: sample() {curve.sampled[i, c]:.5f} vs {what} "
           f"{target[i, c]:.5f} at θ = {curve.theta_deg[i]:.1f}° "
           f"({'within' if passed else 'outside'} {sigmas:g}σ + {rtol:g} relative)")
    return CheckResult("albedo", passed, float(dev[i, c]), f"{sigmas:g}σ + {rtol:g}·E", msg,
                       details={"curve": curve, "compared_with": what})
