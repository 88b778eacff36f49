"""
Measured BRDFs in ``make bench``: the ``merl`` plugin's sampler against cosine sampling, as the
efficiency of the albedo estimator and as the time to 1 % relative RMSE in a render, on a
glossy and a diffuse material; and its render cost against ``cooktorrance`` on the same scene.
The materials are known BSDFs tabulated by the virtual gonioreflectometer
(:func:`mi_brdfs.measured.tabulate.measure`) into a temporary folder.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import drjit as dr
import mitsuba as mi

from ..bsdfspec import load_bsdf
from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from ..measured.tabulate import measure
from ..scenes import load_scene
from ..timing import interleaved, median, median_ratio
from . import error_time, strategies

#: The measured materials: (label, the BSDF tabulated, the sampler's target against cosine).
MATERIALS = [
    ("glossy: roughconductor Au, GGX α = 0.1", "roughconductor material=Au alpha=0.1 "
                                                "distribution=ggx", 10.0),
    ("diffuse: diffuse ρ = 0.5", "diffuse reflectance=0.5", None),
]

#: The render-cost pair: cooktorrance (Smith, Au, α = 0.2) tabulated, against itself.
COST_SOURCE = "cooktorrance material=Au alpha=0.2 shadowing=smith"
#: Target: merl's render time at most this many times cooktorrance's, llvm_ad_rgb.
TARGET_COST = 1.3

#: A BSDF sampled by the cosine-weighted hemisphere alone (the baseline of the comparison).
COSINE = "mi_brdfs_bench_cosine"


def _register_cosine() -> None:
    """Register :data:`COSINE` in the current variant: a Python BSDF that evaluates its nested
    ``bsdf`` and samples ωo from the cosine-weighted hemisphere, pdf cosθo/π; with
    ``two_sided``, from either hemisphere with probability 1/2 each, pdf |cosθo|/(2π) (a BSDF
    that transmits)."""
    class Cosine(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.inner = props["bsdf"]
            self.two_sided = props.get("two_sided", False)
            self.m_flags = int(self.inner.flags())
            self.m_components = [int(self.inner.flags(0))]

        def eval(self, ctx, si, wo, active=True):
            return self.inner.eval(ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):
            if self.two_sided:
                w = mi.Vector3f(wo.x, wo.y, dr.abs(wo.z))
                ok = active & (si.wi.z > 0) & (wo.z != 0)
                return dr.select(ok, 0.5 * mi.warp.square_to_cosine_hemisphere_pdf(w), 0.0)
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            if self.two_sided:
                bs.wo.z = dr.select(sample1 < 0.5, bs.wo.z, -bs.wo.z)
            bs.pdf = self.pdf(ctx, si, bs.wo, active)
            bs.eta, bs.sampled_component = 1.0, 0
            bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.GlossyReflection))
            ok = bs.pdf > 0
            value = self.inner.eval(ctx, si, bs.wo, active & ok)
            return bs, dr.select(ok, value / dr.select(ok, bs.pdf, 1.0), 0.0)

    mi.register_bsdf(COSINE, Cosine)


def cosine_sampled(bsdf, two_sided: bool = False) -> mi.BSDF:
    """``bsdf`` (loaded) sampled by the cosine-weighted hemisphere (of either side with
    ``two_sided``)."""
    _register_cosine()
    return mi.load_dict({"type": COSINE, "bsdf": bsdf, "two_sided": two_sided})


def time_ratio(ctx: Context, scene: str, bsdf, two_sided: bool = False) -> tuple:
    """(time to 1 % with the BSDF's own sampler, with the cosine's (of either side with
    ``two_sided``), their ratio) in ``scene``."""
    spps = [2 ** k for k in range(ctx.n(6, 2))]
    reference_spp = 16 * spps[-1]
    rows, _ = error_time.measure(scene, {"own": bsdf,
                                         "cosine": cosine_sampled(bsdf, two_sided)},
                                 spps, ctx.n(96, 16), ctx.n(7, 2), reference_spp)
    times = {k: error_time.time_to(rows, k, reference_spp) for k in ("own", "cosine")}
    return times["own"], times["cosine"], times["cosine"] / times["own"]


def _skipped_material(s: Section, label: str) -> tuple:
    """A material a quick run leaves unmeasured (it measures the first alone: each tabulation,
    and each material in each scene, is a kernel to compile): its figures named
    (:data:`SKIPPED`), its row."""
    s.values[f"merl sampling vs cosine, estimator efficiency: {label}"] = SKIPPED
    for key in (f" (furnace): {label}", f": {label}"):
        s.values[f"merl sampling vs cosine, time to 1 %{key}"] = SKIPPED
    return (label, "—", "—", SKIPPED, *["—"] * 6)


def _efficiency(ctx: Context, s: Section, label: str, merl, target) -> tuple:
    """Estimator efficiency, and time to 1 % in the furnace and the showcase, merl's sampler
    against cosine sampling."""
    m = strategies.measure({"sample()": (strategies.own, merl),
                            "cosine": (strategies.cosine, merl)}, ctx)
    eff = {k: 1.0 / (v * t) if v > 0 else math.inf for k, (v, t, _) in m.items()}
    s.values[f"merl sampling vs cosine, estimator efficiency: {label}"] = \
        f"{eff['sample()'] / eff['cosine']:.3g}×"
    cells = []
    for scene, key in (("furnace", f" (furnace): {label}"), ("showcase", f": {label}")):
        if ctx.quick and scene == "showcase":  # the quick run checks the machinery alone
            s.values[f"merl sampling vs cosine, time to 1 %{key}"] = SKIPPED
            cells += ["—"] * 3
            continue
        t_merl, t_cos, ratio = time_ratio(ctx, scene, merl)
        shown = f"{ratio:.3g}×" if math.isfinite(ratio) else "— (too short to time)"
        s.values[f"merl sampling vs cosine, time to 1 %{key}"] = shown
        cells += [error_time.seconds_text(t_merl), error_time.seconds_text(t_cos),
                  f"**{shown}**"]
        if target and scene == "furnace":
            s.rows.append(Row(f"merl, {label}", "time to 1 % rel. RMSE in the furnace, "
                              "cosine sampling / merl's", shown, f"≥ {target:g}×",
                              bool(ratio >= target)))
    return (label, f"{m['sample()'][0]:.3g}", f"{m['cosine'][0]:.3g}",
            f"{eff['sample()'] / eff['cosine']:.3g}×", *cells)


def render_cost(bsdf, res: int, spp: int, repeats: int,
                against=COST_SOURCE) -> tuple[float, dict]:
    """(ratio, ns per sample): ``bsdf`` (any BSDF form) against ``against`` on every sphere of
    the showcase, the median of per-repeat ratios of interleaved renders after a first render
    of each (the JIT compilation, apart), and each one's median time per sample (keys "bsdf",
    "against")."""
    ids = error_time.SCENES["showcase"]
    scenes = {k: load_scene("showcase", {"res": str(res)}, bsdfs={i: b for i in ids})
              for k, b in (("bsdf", bsdf), ("against", against))}
    for sc in scenes.values():
        mi.render(sc, spp=spp)
    times = interleaved({k: (lambda sc=sc: mi.render(sc, spp=spp)) for k, sc in scenes.items()},
                        repeats=repeats, warmup=0)
    per = {k: median(t) / (res * res * spp) * 1e9 for k, t in times.items()}
    return median_ratio(times, "bsdf", "against"), per


def _cost(ctx: Context, s: Section, merl) -> tuple:
    """merl against the cooktorrance it tabulates (:func:`render_cost`), the section's row."""
    ratio, per = render_cost(merl, ctx.n(128, 32), ctx.n(32, 4), ctx.n(15, 2))
    s.values["merl vs cooktorrance, render time"] = f"{ratio:.3f}×"
    s.rows.append(Row("merl vs cooktorrance (Smith, Au, α = 0.2, tabulated)",
                      f"{ctx.variant} render time ratio", f"{ratio:.3f}×", f"≤ {TARGET_COST}×",
                      ratio <= TARGET_COST))
    return f"{per['bsdf']:.1f} ns", f"{per['against']:.1f} ns", f"{ratio:.3f}×"


def _fit_costs(ctx: Context, s: Section, folder: Path, files: list) -> list:
    """--models all on one material (fits, scores, figures), its slowest fit, and a sweep of
    ``files`` on 1 and 2 workers (one process per fit)."""
    import time

    from ..fit.models import STYLES, fit_models
    from ..fit.sweep import sweep

    sizes = dict(pairs=ctx.n(16384, 1024), steps=ctx.n(800, 40))
    models = list(STYLES) if not ctx.quick else ["ward"]  # quick: the machinery alone
    clock = time.perf_counter()
    # quick: no figures (their renders are kernels to compile; tests/test_fit_measured.py
    # draws them)
    done = fit_models(files[0], models, "cuberoot", folder / "models", **sizes,
                      figures=not ctx.quick)
    total = time.perf_counter() - clock
    slowest = max(r.seconds for r in done["results"].values())
    s.rows.append(Row("fit", f"one model fitted to one MERL material (slowest of "
                      f"{len(models)})", f"{slowest:.1f} s", "≤ 30 s", slowest <= 30.0))
    s.rows.append(Row("fit", "--models all on one MERL material" +
                      (", figures included" if not ctx.quick else ""),
                      f"{total:.0f} s", "≤ 300 s", total <= 300.0))
    if ctx.quick:  # a sweep's processes each import Mitsuba: tests/test_sweep.py runs them
        s.values["fit sweep speed-up, 2 workers vs 1"] = SKIPPED
        return [("sweep", "—", "—", "—"), ("--models all, one material",
                                           f"{total:.1f} s", "—", "—")]
    times = {}
    for workers in (1, 2):
        clock = time.perf_counter()
        sweep(files, models, "cuberoot", folder / f"sweep-{workers}", workers=workers, **sizes)
        times[workers] = time.perf_counter() - clock
    speedup = times[1] / times[2]
    s.values["fit sweep speed-up, 2 workers vs 1"] = f"{speedup:.2f}×"
    return [(f"{len(files)} materials × {len(models)} models", f"{times[1]:.1f} s",
             f"{times[2]:.1f} s", f"{speedup:.2f}×"), ("--models all, one material",
                                                       f"{total:.1f} s", "—", "—")]


def section(ctx: Context) -> Section:
    s = Section("Measured BRDFs: merl")
    with tempfile.TemporaryDirectory() as folder:
        def tabulated(spec, name):
            path = Path(folder) / f"{name}.binary"
            measure(spec, path, variant=ctx.variant)
            return load_bsdf({"type": "merl", "filename": str(path)})

        rows = [_efficiency(ctx, s, label, tabulated(spec, f"m{i}"), target)
                if not (ctx.quick and i > 0) else _skipped_material(s, label)
                for i, (label, spec, target) in enumerate(MATERIALS)]
        if ctx.quick:  # validation/merl_layout.py --quick runs render_cost
            s.values["merl vs cooktorrance, render time"] = SKIPPED
            cost = ("—", "—", SKIPPED)
        else:
            cost = _cost(ctx, s, tabulated(COST_SOURCE, "cost"))
        files = [str(Path(folder) / f"m{i}.binary")
                 for i in range(len(MATERIALS) if not ctx.quick else 1)]
        costs = _fit_costs(ctx, s, Path(folder), files)
    s.markdown = "\n".join([
        "The `merl` plugin on materials of known BSDFs tabulated by `mi-brdfs measure`. Its "
        "sampler (through the half vector, a tenth of its density the cosine's) against "
        "the cosine-weighted hemisphere alone (the same BSDF evaluated, "
        f"`benchmark.measured.{COSINE}`): the variance per sample of the albedo estimator and "
        "its efficiency 1/(variance × time) (Sampling strategies' method, averaged over "
        f"θ ∈ {{{', '.join(f'{t:g}°' for t in strategies.THETAS)}}}), and the time to 1 % "
        "relative RMSE (Error against time's method) in the white furnace, where the BSDF's "
        "sampler alone finds the light (emitter sampling draws the constant environment "
        "uniformly), and in the showcase, every sphere the material, where emitter sampling "
        "under MIS carries much of the direct light whichever way the BSDF samples; "
        f"`{ctx.variant}`.", "",
        md_table(["material", "variance: merl", "variance: cosine", "estimator efficiency",
                  "furnace, time to 1 %: merl", "cosine", "cosine / merl",
                  "showcase: merl", "cosine", "cosine / merl"], rows), "",
        f"Render cost: `merl` of `{COST_SOURCE}` tabulated against that `cooktorrance`, every "
        f"sphere of the showcase, `{ctx.variant}`, medians of interleaved renders (target "
        f"≤ {TARGET_COST}×).", "",
        md_table(["merl per sample", "cooktorrance per sample", "ratio"], [cost]), "",
        "Fits to measured data (the materials above): every lecture model fitted to the "
        "glossy one (`fit --models all`, figures included), and a sweep of both materials "
        "(`mi_brdfs.fit.sweep`: one process per fit) on one worker and on two, "
        f"{sum(1 for _ in MATERIALS)} files, {ctx.n(16384, 1024)} pairs, "
        f"{ctx.n(800, 40)} steps:", "",
        md_table(["work", "1 worker", "2 workers", "speed-up"], costs)])
    return s
