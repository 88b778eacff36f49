"""
The explorer's computed views, as plain functions of a loaded ``mi.BSDF`` in a JIT variant:
NumPy arrays and small dataclasses that the page draws. Every number comes from the BSDF's own
``eval``, ``pdf`` and ``sample`` (through :mod:`mi_brdfs.checks.batch`), as the mean of its
channels; none re-implements a model.

The views are those of Disney's BRDF Explorer (Burley 2012, "Physically-Based Shading at
Disney", SIGGRAPH course notes, and its BRDF Explorer tool) and more:

* :func:`lobe3d`: the 3-D lobe, the surface r(ωo)·ωo with r = f·|cosθo| over the whole sphere;
* :func:`slice_image`: f over (θh, θd) at φd = 90°, Rusinkiewicz's half/difference
  parametrisation (Rusinkiewicz 1998, "A new change of variables for efficient BRDF
  representation", EGWR), BRDF Explorer's "image slice" and the plots of MERL's data;
* :func:`sampling_density`: where ``sample()`` puts its directions against f·cosθo;
* :func:`verdicts`: reciprocity, energy, positivity and a χ² test at the current θi;
* :func:`cost_per_sample`: nanoseconds per ``sample()`` + ``eval()`` of each BSDF.

Speed: each view is one or two vectorised calls of fixed sizes, so a parameter changed through
``mi.traverse`` (the same plugin object) launches the kernels the previous change compiled
(drjit's kernel cache: the parameter is an input of the kernel, not part of its code).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np

from ..checks import batch
from ..errors import arguments, counts, valid_angle
from ..plots import slice_directions

#: Incident angles the views accept (degrees): the upper hemisphere.
THETA_MAX = 90.0


def eval_pdf(bsdf, wi, wo: np.ndarray, ctx=None) -> tuple[np.ndarray, np.ndarray]:
    """(``eval`` = f·|cosθo| as the mean of the channels, ``pdf``) at ``wi`` (one direction or
    one per row) and the rows of ``wo`` (n, 3), in one launch
    (:func:`~mi_brdfs.checks.batch.eval_and_pdf`)."""
    value, pdf = batch.eval_and_pdf(bsdf, wi, wo, ctx)
    return value.mean(axis=1), pdf


def _random(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The random numbers of ``n`` samples, (n,) and (n, 2), the same for the same seed."""
    rng = np.random.default_rng(seed)
    return rng.random(n), rng.random((n, 2))


def sampled(bsdf, wi, n: int, seed: int = 0, ctx=None) -> tuple[np.ndarray, np.ndarray]:
    """
    (wo (n, 3), ok (n,)) of ``sample()`` at ``wi`` with ``n`` fixed random numbers (the same
    for the same ``seed``), evaluated in one launch: ``ok`` where the sample succeeded (its
    weight finite and not 0 in some channel, its direction finite).
    """
    ctx = ctx or mi.BSDFContext()
    u1, u2 = _random(n, seed)
    si = batch.interaction(wi, n)
    bs, weight = bsdf.sample(ctx, si, batch.floats(u1),
                             mi.Point2f(batch.floats(u2[:, 0]), batch.floats(u2[:, 1])))
    weight = mi.unpolarized_spectrum(weight)
    ok = dr.all(dr.isfinite(weight)) & dr.any(weight != 0) & dr.all(dr.isfinite(bs.wo))
    wo = mi.Vector3f(bs.wo)
    dr.eval(wo, ok)
    return np.array(wo, dtype=np.float32).T.reshape(n, 3), \
        np.broadcast_to(np.asarray(ok, dtype=bool).ravel(), (n,))


# ---------------------------------------------------------------------------------------------
# The 3-D lobe and the image slice


def sphere_directions(n_theta: int, n_phi: int) -> np.ndarray:
    """(n_theta, n_phi, 3) unit vectors: θ over [0°, 180°] and φ over [0°, 360°], both ends
    included (so that a surface drawn through them closes)."""
    theta = np.linspace(0.0, math.pi, n_theta)[:, None]
    phi = np.linspace(0.0, 2.0 * math.pi, n_phi)[None, :]
    return np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi),
                                        np.sin(theta) * np.sin(phi), np.cos(theta)), axis=-1)


@counts("n_theta", "n_phi")
@arguments(theta_i_deg=valid_angle(THETA_MAX, "degrees"), phi_i_deg=valid_angle(360, "degrees"))
def lobe3d(bsdf, theta_i_deg: float, phi_i_deg: float = 0.0, n_theta: int = 32,
           n_phi: int = 64) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    The 3-D lobe as BRDF Explorer draws it (Burley 2012): the surface r(ωo)·ωo, with
    r = f·|cosθo| (``eval()``, the mean of the channels), over the whole sphere of ωo (the
    upper hemisphere is reflection, the lower one transmission; r = 0 where the BSDF scatters
    nothing), for ωi at (θi, φi). A non-finite value (which the positivity verdict reports) is
    drawn as 0.

    Returns → (x, y, z), each (n_theta, n_phi): θo along rows from 0° to 180°, φo along
    columns from 0° to 360° (:func:`sphere_directions`).
    """
    wo = sphere_directions(n_theta, n_phi)
    wi = batch.direction(math.radians(theta_i_deg), math.radians(phi_i_deg))
    r, _ = eval_pdf(bsdf, wi, wo.reshape(-1, 3))
    r = np.nan_to_num(r, nan=0.0, posinf=0.0, neginf=0.0).reshape(n_theta, n_phi)
    return r * wo[..., 0], r * wo[..., 1], r * wo[..., 2]


@counts("n")
def slice_image(bsdf, n: int = 64) -> np.ndarray:
    """
    f (``eval()``/cosθo, without the cosine; the mean of the channels) over the (θh, θd)
    square [0°, 90°]² at φd = 90° and φh = 0 (Rusinkiewicz 1998: ωi and ωo from the half
    vector h at (θh, φh) and the difference vector, ωi in h's frame, at (θd, φd)): BRDF
    Explorer's "image slice" (Burley 2012) and the plots of MERL's measurements. Cell centres,
    (k + ½)·90°/n; rows are θd (row 0 at θd ≈ 0), columns θh (column 0 at θh ≈ 0): a mirror
    lobe is the left columns, Fresnel's rise towards grazing the top rows (θd → 90°),
    retro-reflection the bottom rows (ωo → ωi as θd → 0).
    NaN where ωi or ωo lies on or below the horizon (never at φd = 90°, where both cosines
    are cosθh·cosθd).

    Returns → (n, n) float64.
    """
    wi, wo = slice_directions(n, 90.0)
    value, _ = eval_pdf(bsdf, wi, wo)
    above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    f = np.where(above, value / np.where(above, wo[:, 2], 1.0), np.nan)
    return f.reshape(n, n)


# ---------------------------------------------------------------------------------------------
# Where importance sampling misses


#: A cell is "missed" where the sampler's density is below this fraction of the ideal one.
MISSED_FRACTION = 0.25


@dataclass
class Density:
    """
    The sampling density of a BSDF at one ωi on a grid uniform in (cosθo, φo): rows of cosθo
    (``cos_edges``, row 0 lowest) over the upper hemisphere [0, 1], ``bins`` rows, or for a
    BSDF that transmits over the whole sphere [−1, 1], 2·``bins`` rows; ``bins`` columns of φo
    over [−180°, 180°] (``phi_edges``, degrees). Every cell has the same solid angle
    ``cell_sr`` = 2π/bins² (Archimedes: a band's area is 2π·Δcosθ). All in 1/sr:

    - ``histogram``: the directions ``sample()`` returned with a non-zero, finite weight, per
      cell, divided by (all samples × ``cell_sr``): a density that integrates to the share of
      samples that succeeded;
    - ``pdf``: ``pdf()`` at the cells' centres;
    - ``target``: f·|cosθo| (``eval()``) at the centres divided by ``integral``, its
      midpoint-rule integral E over the grid (the albedo): the pdf of a perfect importance
      sampler (Dirac lobes, which ``eval`` does not see, aside);
    - ``missed``: the share of E in the cells where ``pdf`` < :data:`MISSED_FRACTION`·``target``:
      light the sampler rarely draws, found by few samples with large weights (noise). NaN
      where E = 0 (nothing smooth to sample: e.g. only Dirac lobes).

    A BSDF that refracts is taken in importance transport (as its energy verdict,
    :func:`mi_brdfs.checks.albedo.energy_context`): there f·|cosθo| is the share of the energy
    leaving towards ωo, which a perfect sampler's pdf follows; in radiance transport the
    refracted part carries 1/η² (Veach 1997, §5.2), which ``sample()`` does not draw.
    """

    cos_edges: np.ndarray
    phi_edges: np.ndarray
    cell_sr: float
    histogram: np.ndarray
    pdf: np.ndarray
    target: np.ndarray
    integral: float
    missed: float


def density_cells(bins: int, sphere: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(cos_edges, phi_edges in radians (bins+1,), centres (rows, bins, 3)) of the grid of
    :class:`Density`, over the upper hemisphere or the whole ``sphere``."""
    cos_edges = np.linspace(-1.0 if sphere else 0.0, 1.0, (2 if sphere else 1) * bins + 1)
    phi_edges = np.linspace(-math.pi, math.pi, bins + 1)
    mu = 0.5 * (cos_edges[1:] + cos_edges[:-1])[:, None]
    phi = 0.5 * (phi_edges[1:] + phi_edges[:-1])[None, :]
    s = np.sqrt(1.0 - mu * mu)
    centres = np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), mu), axis=-1)
    return cos_edges, phi_edges, centres


def _counts(wo: np.ndarray, cos_edges: np.ndarray, bins: int) -> np.ndarray:
    """How many of the directions ``wo`` (n, 3) fall in each cell of the (cosθ, φ) grid."""
    rows = len(cos_edges) - 1
    row = np.clip(np.floor((wo[:, 2] - cos_edges[0]) * bins).astype(np.int64), 0, rows - 1)
    phi = np.arctan2(wo[:, 1], wo[:, 0])
    col = np.clip(((phi + math.pi) / (2 * math.pi) * bins).astype(np.int64), 0, bins - 1)
    return np.bincount(row * bins + col, minlength=rows * bins).reshape(rows, bins)


@counts("n_samples", "bins")
@arguments(theta_i_deg=valid_angle(THETA_MAX, "degrees"))
def sampling_density(bsdf, theta_i_deg: float, n_samples: int = 2 ** 16,
                     bins: int = 32) -> Density:
    """
    ``sample()``'s directions, ``pdf()`` and f·|cosθo| at ωi = (θi, φi = 0) on the grid of
    :class:`Density` (read there what each array is): where ``pdf`` falls below ``target``,
    importance sampling misses light; where ``histogram`` differs from ``pdf``, ``sample()``
    does not draw what ``pdf()`` reports (the χ² verdict tests that). The random numbers are
    fixed, so the histogram moves only with the BSDF.
    """
    from ..checks.albedo import energy_context

    ctx = energy_context(bsdf)
    sphere = bool(int(bsdf.flags()) & int(mi.BSDFFlags.Transmission))
    wi = batch.direction(math.radians(theta_i_deg))
    cos_edges, phi_edges, centres = density_cells(bins, sphere)
    cell_sr = 2.0 * math.pi / (bins * bins)
    value, pdf = eval_pdf(bsdf, wi, centres.reshape(-1, 3), ctx)
    value, pdf = value.reshape(centres.shape[:2]), pdf.reshape(centres.shape[:2])
    wo, ok = sampled(bsdf, wi, n_samples, ctx=ctx)
    ok = ok & (sphere | (wo[:, 2] > 0))
    histogram = _counts(wo[ok], cos_edges, bins) / (n_samples * cell_sr)
    integral = float(np.sum(value) * cell_sr)
    if not integral > 0:
        return Density(cos_edges, np.degrees(phi_edges), cell_sr, histogram, pdf,
                       np.zeros_like(value), integral, float("nan"))
    target = value / integral
    missed = float(np.sum(np.where(pdf < MISSED_FRACTION * target, target, 0.0)) * cell_sr)
    return Density(cos_edges, np.degrees(phi_edges), cell_sr, histogram, pdf, target,
                   integral, missed)


# ---------------------------------------------------------------------------------------------
# Verdicts beside each BSDF


@dataclass
class Verdict:
    """One live check: its ``name``, whether the BSDF passes it, the number it judged and one
    line to show; ``skipped`` where the check could not judge this BSDF here (``ok`` is then
    True: nothing was found wrong, and the text says why)."""

    name: str
    ok: bool
    value: float
    text: str
    skipped: bool = False


#: Random pairs of the reciprocity verdict, samples of the energy verdict, and the χ² test's
#: samples, largest θ resolution and per-cell integration (2·res cells in φ), significance.
RECIPROCITY_PAIRS = 256
ENERGY_SAMPLES = 2 ** 15
CHI2_SAMPLES = 2 ** 16
CHI2_MAX_RES, CHI2_MAX_IRES = 201, 16
CHI2_SIGNIFICANCE = 0.01


def reciprocity_verdict(bsdf) -> Verdict:
    """
    Helmholtz reciprocity over :data:`RECIPROCITY_PAIRS` random pairs on one side of the
    surface (:func:`mi_brdfs.checks.reciprocity.reciprocity`): the largest relative asymmetry
    |f(a,b) − f(b,a)| / max, against its float32 tolerance. Pairs across the surface are not
    drawn: a refracting BSDF is reciprocal there only with η² weighting (Veach 1997, §5.2), so
    transmission is skipped, not weighted. A BSDF that declares ``NonSymmetric`` or replaces
    the shading frame is shown, not judged.
    """
    from ..checks.reciprocity import expected_asymmetry, reciprocity

    r = reciprocity(bsdf, n=RECIPROCITY_PAIRS, seed=0)
    worst = float(np.max(r["asym"])) if len(r["asym"]) else 0.0
    within = bool(np.all(r["asym"] <= r["tol"]))
    why = expected_asymmetry(bsdf)
    text = f"reciprocity: largest relative asymmetry {worst:.2g} over {len(r['asym'])} pairs"
    if why:
        return Verdict("reciprocity", True, worst, f"{text} (not expected: {why})")
    return Verdict("reciprocity", within, worst,
                   text + (" (float32 rounding)" if within else " (beyond float32 rounding)"))


def energy_verdict(bsdf, theta_i_deg: float) -> Verdict:
    """
    Energy conservation at θi: the albedo E(θi), the mean ``sample()`` weight over
    :data:`ENERGY_SAMPLES` (:func:`mi_brdfs.checks.albedo.albedo_sampled`, in importance
    transport for a refracting BSDF), passes where every channel's E ≤ 1 + 3 standard errors.
    The value is the largest channel's E.
    """
    from ..checks.albedo import albedo_sampled, energy_context

    mean, err = albedo_sampled(bsdf, math.radians(theta_i_deg), n=ENERGY_SAMPLES, seed=0,
                               ctx=energy_context(bsdf))
    worst = int(np.argmax(mean - 3.0 * err))
    ok = bool(np.all(mean <= 1.0 + 3.0 * err))
    return Verdict("energy", ok, float(np.max(mean)),
                   f"energy: albedo E({theta_i_deg:g}°) = {float(np.mean(mean)):.3f} (largest "
                   f"channel {float(mean[worst]):.3f} ± {float(err[worst]):.1g})"
                   + ("" if ok else ": more light out than in"))


def positivity_verdict(bsdf, theta_i_deg: float) -> Verdict:
    """
    f ≥ 0 and finite, and pdf ≥ 0 and finite, at ωi = (θi, 0) and ωo on a 5° grid of the
    whole sphere (37 × 72, the poles and the horizon included, where 0/0 lurks). The value is
    the number of bad directions.
    """
    wo = sphere_directions(37, 72).reshape(-1, 3)
    value, pdf = eval_pdf(bsdf, batch.direction(math.radians(theta_i_deg)), wo)
    negative = int(np.sum((value < 0) | (pdf < 0)))
    nonfinite = int(np.sum(~np.isfinite(value) | ~np.isfinite(pdf)))
    ok = negative == 0 and nonfinite == 0
    text = (f"positivity: eval and pdf finite and ≥ 0 at {len(wo)} directions" if ok else
            f"positivity: {negative} negative and {nonfinite} non-finite of {len(wo)} "
            f"directions")
    return Verdict("positivity", ok, float(negative + nonfinite), text)


def chi2_verdict(bsdf, theta_i_deg: float) -> Verdict:
    """
    Pearson's χ² test of ``sample()`` against ``pdf()`` at θi
    (:func:`mi_brdfs.checks.sampling.chi2_bsdf`), small enough to run live:
    :data:`CHI2_SAMPLES` samples and a fixed seed (the verdict does not flicker between redraws
    of the same BSDF), the resolution chosen from the lobe's sharpness
    (:func:`~mi_brdfs.checks.sampling.chi2_settings`) but at most :data:`CHI2_MAX_RES` in θ and
    :data:`CHI2_MAX_IRES` per cell (the full one, up to 401 and 32, takes seconds). That
    resolves GGX lobes of α ≥ 0.03 at every θi and α ≥ 0.01 up to θi = 70°; a sharper lobe
    that the capped test rejects is reported as skipped (inconclusive: Mitsuba's own
    roughconductor at α = 0.001 is rejected there and passes the full test), one it accepts as
    passed. Passes where p ≥ :data:`CHI2_SIGNIFICANCE` (one test, no correction: a correct
    sampler fails at one θi in a hundred). A BSDF with only Dirac lobes is skipped.
    """
    from ..checks.sampling import chi2_bsdf, chi2_settings

    wi = batch.direction(math.radians(theta_i_deg))
    res, ires, _, _ = chi2_settings(bsdf, wi)
    capped = res > CHI2_MAX_RES or ires > CHI2_MAX_IRES
    r = chi2_bsdf(bsdf, wi, res=min(res, CHI2_MAX_RES), ires=min(ires, CHI2_MAX_IRES),
                  sample_count=CHI2_SAMPLES, seed=0, significance=CHI2_SIGNIFICANCE)
    if r.skipped:
        return Verdict("chi2", True, float("nan"), "χ²: not applicable (only Dirac lobes)",
                       skipped=True)
    text = f"χ²: p = {r.value:.3g} {'≥' if r.passed else '<'} {CHI2_SIGNIFICANCE:g}"
    if not r.passed and capped:
        return Verdict("chi2", True, float(r.value),
                       f"{text}, inconclusive: the lobe is sharper than the live test resolves "
                       f"(it needs res {res}, ires {ires}: run mi-brdfs check)", skipped=True)
    if not r.passed:
        text += ": sample() does not draw what pdf() reports"
    return Verdict("chi2", bool(r.passed), float(r.value), text)


@arguments(theta_i_deg=valid_angle(THETA_MAX, "degrees"))
def verdicts(bsdf, theta_i_deg: float) -> list[Verdict]:
    """The live verdicts of one BSDF at θi: reciprocity, energy, positivity and χ² (each
    documented in its own function above)."""
    return [reciprocity_verdict(bsdf), energy_verdict(bsdf, theta_i_deg),
            positivity_verdict(bsdf, theta_i_deg), chi2_verdict(bsdf, theta_i_deg)]


# ---------------------------------------------------------------------------------------------
# Cost


@counts("n", "repeats")
def cost_per_sample(bsdfs, n: int = 2 ** 16, repeats: int = 5) -> list[float]:
    """
    Nanoseconds per ``sample()`` followed by ``eval()`` at the sampled direction, for each
    BSDF: the median over ``repeats`` of the kernels' execution time (drjit's kernel history,
    :func:`mi_brdfs.timing.kernel_timed`) for ``n`` samples, divided by ``n``. The BSDFs are
    timed interleaved (A B C C B A …, :func:`mi_brdfs.timing.interleaved`) after a warm-up
    round that holds the tracing and compilation. Kernel time, not wall time: Python's tracing
    of a launch is a fixed cost that a renderer pays once per pass, not per sample. The ωi are
    random over the upper hemisphere (fixed), as a renderer's are.
    """
    from ..timing import interleaved, kernel_timed, median

    rng = np.random.default_rng(0)
    wi = batch.random_directions(rng, n, sphere=False)
    u1, u2 = _random(n, 1)
    ctx = mi.BSDFContext()
    si = batch.interaction(wi, n)
    s1, s2 = batch.floats(u1), mi.Point2f(batch.floats(u2[:, 0]), batch.floats(u2[:, 1]))

    def run(bsdf):
        def one():
            bs, weight = bsdf.sample(ctx, si, s1, s2)
            return weight, bsdf.eval(ctx, si, bs.wo)
        return one

    contenders = {k: run(b) for k, b in enumerate(bsdfs)}
    times = interleaved(contenders, repeats=repeats, timer=lambda fn: kernel_timed(fn)[1])
    return [median(times[k]) / n * 1e9 for k in contenders]
