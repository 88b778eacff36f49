"""
Sampling strategies: variance per sample and efficiency 1/(variance × time) of the directional
albedo estimator, E(θ) = ∫ f cosθo dωo, for each lobe and each way to draw ωo:

* ``sample()``: the plugin's (or built-in's) own importance sampling, weight f·cos/pdf;
* ``cosine``: the cosine-weighted hemisphere, eval/(cosθo/π);
* ``uniform``: the uniform hemisphere, eval·2π.

The albedo estimator is the one-bounce estimate a path tracer makes under uniform light, so its
variance is the noise each strategy adds per sample. Times are per 1e6 samples (drawing the
directions included), medians of interleaved repeats.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..bsdfspec import load_bsdf
from ..campaign.core import Context, Row, Section, md_table
from ..checks import batch
from ..timing import interleaved, kernel_timed, median

_CT = {"type": "cooktorrance", "alpha": 0.2, "fresnel": "none"}
_RC = {"type": "roughconductor", "alpha": 0.2}

#: (lobe, {strategy: BSDF dict whose sample() is that strategy}, {strategy: built-in's dict}).
#: The cosine and uniform strategies evaluate the first dict's ``eval()``.
LOBES = [
    ("Phong, n = 10", {"sample()": {"type": "phong", "exponent": 10.0, "diffuse_reflectance": 0.0,
                                    "specular_reflectance": 1.0}}, {}),
    ("Phong, n = 100", {"sample()": {"type": "phong", "exponent": 100.0,
                                     "diffuse_reflectance": 0.0, "specular_reflectance": 1.0}},
     {}),
    ("Cook-Torrance V-cavity, α = 0.2", {"VNDF sample()": _CT,
                                         "D·cos sample()": dict(_CT, sample_visible=False)}, {}),
    ("Cook-Torrance Smith, α = 0.2",
     {"VNDF sample()": dict(_CT, shadowing="smith"),
      "D·cos sample()": dict(_CT, shadowing="smith", sample_visible=False)},
     {"VNDF sample()": _RC, "D·cos sample()": dict(_RC, sample_visible=False)}),
]

THETAS = (0.0, 45.0, 75.0)


def random_draws(theta: float, n: int, seed: int):
    """A surface interaction with n lanes at incidence θ and the uniform numbers to sample it
    with, from ``seed``: the same draws for every strategy compared."""
    rng = np.random.default_rng(seed)
    si = batch.interaction(batch.direction(theta), n)
    s1 = batch.floats(rng.random(n, dtype=np.float32))
    s2 = mi.Point2f(batch.floats(rng.random(n, dtype=np.float32)),
                    batch.floats(rng.random(n, dtype=np.float32)))
    return si, s1, s2


def own(bsdf, si, s1, s2):
    """
    The BSDF's importance sampling: the sample weight f·cos/pdf, taken where bs.pdf ≥ 0 (so
    everywhere), so that the kernel computes the pdf, which a path tracer uses for MIS: DrJit
    leaves out what an estimate does not use, and a sampler whose weight does not need its pdf
    would look cheaper than it renders.
    """
    bs, w = bsdf.sample(mi.BSDFContext(), si, s1, s2)
    return dr.select(bs.pdf >= 0, dr.mean(mi.unpolarized_spectrum(w)), 0.0)


def cosine(bsdf, si, s1, s2):
    """The cosine-weighted hemisphere: eval / (cosθo/π)."""
    wo = mi.warp.square_to_cosine_hemisphere(s2)
    value = dr.mean(mi.unpolarized_spectrum(bsdf.eval(mi.BSDFContext(), si, wo)))
    return value / dr.maximum(mi.warp.square_to_cosine_hemisphere_pdf(wo), 1e-30)


def uniform(bsdf, si, s1, s2):
    """The uniform hemisphere: eval · 2π."""
    wo = mi.warp.square_to_uniform_hemisphere(s2)
    return dr.mean(mi.unpolarized_spectrum(bsdf.eval(mi.BSDFContext(), si, wo))) * (2 * math.pi)


def measure(strategies: dict, ctx: Context) -> dict:
    """
    {strategy: (variance per sample averaged over θ, kernel seconds per 1e6 samples, tracing
    seconds per call)} for ``strategies`` = {name: (estimator, BSDF)}, all timed interleaved in
    one run. The per-sample cost is the kernels' execution time (JIT variants: what grows with
    the number of samples); tracing the Python code is a fixed cost per launch, kept apart.
    """
    n = ctx.n(2_000_000, 100_000)
    variance: dict[str, list] = {}
    seconds: dict[str, list] = {}
    tracing: dict[str, list] = {}
    for i, t in enumerate(THETAS):
        draws = random_draws(math.radians(t), n, seed=i)
        funcs = {k: (lambda f=f, b=b: f(b, *draws)) for k, (f, b) in strategies.items()}
        times = interleaved(funcs, repeats=ctx.n(7, 2), timer=kernel_timed)
        for k, f in funcs.items():
            x = np.array(f(), dtype=np.float64).ravel()
            variance.setdefault(k, []).append(float(np.var(x)))
            seconds.setdefault(k, []).append(median([kt for _, kt in times[k]]) / n * 1e6)
            tracing.setdefault(k, []).append(median([tt for tt, _ in times[k]]))
    return {k: (float(np.mean(variance[k])), float(np.mean(seconds[k])),
                float(np.mean(tracing[k]))) for k in strategies}


def _two_digits(x: float) -> str:
    """``x`` to two significant digits, without an exponent (5.2, 23, 1900)."""
    if not math.isfinite(x) or x <= 0:
        return f"{x:g}"
    rounded = round(x, 1 - math.floor(math.log10(x)))
    return f"{rounded:.{max(1 - math.floor(math.log10(rounded)), 0)}f}"


def section(ctx: Context) -> Section:
    s = Section("Sampling strategies")
    rows = []
    for label, ours, builtins in LOBES:
        bsdfs = {k: load_bsdf(v) for k, v in ours.items()}
        first = next(iter(bsdfs.values()))
        strategies = {k: (own, b) for k, b in bsdfs.items()}
        strategies.update({"cosine": (cosine, first), "uniform": (uniform, first)})
        strategies.update({f"built-in {k}": (own, load_bsdf(v)) for k, v in builtins.items()})
        m = measure(strategies, ctx)
        eff = {k: 1.0 / (v * t) if v > 0 else math.inf for k, (v, t, _) in m.items()}
        winner = max((k for k in eff if not k.startswith("built-in")), key=eff.get)
        best, default = eff[winner], next(iter(ours))
        for k in eff:
            if k != default and not k.startswith("built-in"):
                s.values[f"efficiency: {label}, {default} vs {k}"] = \
                    f"{_two_digits(eff[default] / eff[k])}×"
        for k, (v, t, tr) in m.items():
            ref = eff.get(f"built-in {k}")
            rows.append((label, k, f"{v:.3g}", f"{t * 1e3:.2f} ms", f"{tr * 1e3:.2f} ms",
                         f"{eff[k]:.3g}", f"{eff[k] / best:.2f}",
                         f"{eff[k] / ref:.2f}" if ref else "—"))
            if ref:
                s.values[f"efficiency vs the built-in: {label}, {k}"] = f"{eff[k] / ref:.2f}×"
                s.rows.append(Row(f"{label}, {k}", "efficiency vs the built-in's same sampler",
                                  f"{eff[k] / ref:.2f}×", "≥ 1.0×", eff[k] / ref >= 1.0))
        s.rows.append(Row(label, "the plugin's default sample() is the most efficient strategy",
                          winner, default, winner == default))
    s.markdown = "\n".join([
        "Variance per sample and efficiency 1/(variance × time) of the directional albedo "
        f"estimator, averaged over θ ∈ {{{', '.join(f'{t:g}°' for t in THETAS)}}}, for each "
        "lobe and each way to draw the outgoing direction: the plugin's own `sample()` (both "
        "samplers where it has two), the cosine-weighted hemisphere and the uniform hemisphere "
        "(both evaluating `eval()`), and the built-in's `sample()` for the same lobe where "
        "Mitsuba has one (F ≡ 1, so the models are comparable). The time per sample is the "
        f"execution time of the kernels (DrJit's kernel history, {ctx.variant}) per 1e6 "
        "samples, drawing the direction included, and for `sample()` its `bs.pdf`, which a "
        "path tracer uses for MIS (DrJit leaves out of a kernel what its result does not "
        "use); tracing the Python code before them is a "
        "fixed cost per launch, whatever the number of samples, and shown apart (a render "
        "traces once for all its samples; Backends has the first-render cost). Medians of "
        "interleaved repeats; efficiency ratios are to the best of the plugin's strategies "
        "and to the built-in's same sampler.", "",
        md_table(["lobe", "strategy", "variance per sample", "kernel time per 1e6",
                  "tracing per call", "efficiency", "vs best", "vs built-in"], rows), "",
        "Where the plugin's `sample()` and the built-in's draw the same directions with the same "
        "variance, the kernel time decides. The plugin's `sample()` evaluates its terms at the "
        "half vector of the stored `bs.wo` (so that its pdf is `pdf(bs.wo)` and its weight "
        "eval/pdf to float32 rounding: Consistency in REPORT.md), with the weight in closed "
        "form and D and G1 in forms with one division each; `roughconductor` evaluates them at "
        "the sampled normal, and its D·cos sampler takes D·cosθ in closed form from the random "
        "number, without the exponential."])
    return s
