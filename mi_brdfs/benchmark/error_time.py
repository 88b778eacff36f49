"""
Error against time: each plugin and its built-in counterpart rendered at spp = 1, 2, 4, …, with
the wall time of each render and its error against a high-spp reference; log-log curves, and
the time each needs for a 1 % relative RMSE, as a ratio to the built-in.

Each contender's error is measured against its own high-spp reference, so the error is its
Monte Carlo noise alone and two different models (V-cavity against Smith shadowing, Phong
against a microfacet lobe) compare fairly; how far the two references lie apart (the models'
difference, bias) is reported beside it.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..compare import flip_map, rel_mse, rmse
from ..scenes import load_scene
from ..campaign.core import SKIPPED, Context, Row, Section, image, md_table
from ..timing import interleaved, median

#: The showcase's sphere materials (scenes/showcase.xml, ids "<sphere>-material"): every one
#: is swapped for the contender, so the whole image measures it.
SHOWCASE_IDS = ("lambert", "diffuse", "phong-normalized", "phong-lecture", "phong-original",
                "phong-halfway", "cooktorrance", "roughconductor")

#: (label, plugin, built-in counterpart, target applies). The Phong lobe has no built-in: it is
#: set beside the Beckmann lobe of the same width, α = √(2/(n + 2)), with F = 1.
PAIRS = [
    ("lambert vs diffuse", "lambert reflectance=0.5", "diffuse reflectance=0.5", True),
    ("cooktorrance (Smith) vs roughconductor",
     "cooktorrance material=Au alpha=0.2 shadowing=smith",
     "roughconductor material=Au alpha=0.2", True),
    ("cooktorrance (V-cavity) vs roughconductor", "cooktorrance material=Au alpha=0.2",
     "roughconductor material=Au alpha=0.2", True),
    ("phong (n = 48) vs roughconductor (α = 0.2, F = 1)",
     "phong exponent=48 diffuse_reflectance=0 specular_reflectance=1",
     "roughconductor material=none alpha=0.2", False),
]

#: Scenes: the showcase (every sphere the contender) and the white furnace (its sphere).
SCENES = {"showcase": {f"{i}-material" for i in SHOWCASE_IDS}, "furnace": {"material"}}

#: Image side per scene (full, quick), large enough that renders take tens to hundreds of ms:
#: the time of a shorter render is dominated by the noise of a shared machine, which then
#: moves even identical kernels (lambert and diffuse) apart.
RES = {"showcase": (128, 16), "furnace": (256, 16)}

#: Target: time to 1 % relative RMSE at most 1.05 × the built-in's.
TARGET = 1.05


def relative_rmse(image_, reference) -> float:
    """RMSE divided by the reference's mean value: 0.01 is a 1 % error."""
    return rmse(reference, image_) / float(np.mean(reference))


def measure(scene_name: str, specs: dict, spps, res: int, repeats: int, reference_spp: int):
    """
    Times and errors of each contender ({name: BSDF}) at every spp, each against its own
    reference at ``reference_spp``; returns (rows, {name: reference image}).
    """
    scenes = {name: load_scene(scene_name, {"res": str(res)},
                               bsdfs={i: spec for i in SCENES[scene_name]})
              for name, spec in specs.items()}
    references = {name: np.array(mi.render(scene, spp=reference_spp, seed=10_000))
                  for name, scene in scenes.items()}
    rows = []
    for spp in spps:
        images = {}

        def render(name, spp=spp):
            images[name] = mi.render(scenes[name], spp=spp, seed=spp)
            return images[name]
        times = interleaved({n: (lambda n=n: render(n)) for n in scenes}, repeats=repeats)
        for name in scenes:
            img, ref = np.array(images[name]), references[name]
            fl = flip_map(ref, img)
            rows.append(dict(who=name, spp=spp, time=median(times[name]),
                             rel_rmse=relative_rmse(img, ref), rel_mse=rel_mse(ref, img),
                             flip=fl[1] if fl else math.nan))
    return rows, references


def time_to(rows, who: str, reference_spp: int, target: float = 0.01) -> float:
    """
    Seconds for one render to reach ``target`` relative RMSE. Each render's squared error is
    σ²(1/spp + 1/spp_ref), σ² the noise variance per sample (the reference being a noisy
    estimate too), so each is an independent estimate of σ², and their mean is the one used:
    from the largest spp alone, the V-cavity's showcase ratio varied from run to run by more than
    its distance from 1, while its errors at the seven spp lay on both sides of the built-in's.
    The spp needed is σ²/target². The time of a render of that many spp is the least-squares line
    time = a + b·spp through the measured renders (a holds the per-render cost: JIT tracing,
    kernel launch, film development).
    """
    pts = sorted((r for r in rows if r["who"] == who), key=lambda r: r["spp"])
    variance = float(np.mean([p["rel_rmse"] ** 2 / (1.0 / p["spp"] + 1.0 / reference_spp)
                              for p in pts]))
    spp_needed = variance / target ** 2
    b, a = np.polyfit([p["spp"] for p in pts], [p["time"] for p in pts], 1)
    if not b > 0:  # time does not grow with spp: renders too short to measure
        return math.nan
    return float(max(a, 0.0) + b * spp_needed)


def seconds_text(t: float) -> str:
    """A time in seconds to three digits, "—" when it could not be measured."""
    return f"{t:.3g} s" if math.isfinite(t) else "—"


def plot(rows_by_pair, path) -> str:
    from ..plots import pyplot, save_figure

    plt = pyplot()
    cols = min(4, len(rows_by_pair))
    lines = math.ceil(len(rows_by_pair) / cols)
    fig, axes = plt.subplots(lines, cols, figsize=(3.6 * cols, 3.2 * lines), squeeze=False)
    for ax in axes.flat[len(rows_by_pair):]:
        ax.axis("off")
    for ax, (title, rows) in zip(axes.flat, rows_by_pair.items()):
        for who, style in (("plugin", "o-"), ("built-in", "s--")):
            pts = sorted((r for r in rows if r["who"] == who), key=lambda r: r["spp"])
            ax.loglog([p["time"] for p in pts], [p["rel_rmse"] for p in pts], style, ms=3,
                      label=who)
        ax.axhline(0.01, color="0.6", lw=0.8, ls=":")
        ax.set_title(title.replace(" vs ", "\nvs "), fontsize=7)
        ax.set_xlabel("render time (s)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3, which="both")
    for ax in axes[:, 0]:
        ax.set_ylabel("relative RMSE", fontsize=8)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


def _skipped(s: Section, scene_name: str, res: int, label: str, ours: str, builtin: str,
             targeted: bool) -> tuple:
    """A pair a quick run leaves unmeasured (it measures the first pair in the furnace alone:
    each contender is a kernel to compile): its scenes loaded, its figure named
    (:data:`SKIPPED`); the table's row."""
    for spec in (ours, builtin):
        load_scene(scene_name, {"res": str(res)}, bsdfs={key: spec for key in SCENES[scene_name]})
    s.values[f"time to 1 %: {label}, {scene_name}"] = SKIPPED
    return (label, scene_name, "—", "—", SKIPPED, f"≤ {TARGET}" if targeted else "—", "—")


def section(ctx: Context) -> Section:
    s = Section("Error against time")
    spps = [2 ** k for k in range(ctx.n(7, 2))]       # 1 … 64 (quick: 1, 2)
    repeats = ctx.n(15, 2)
    reference_spp = 16 * spps[-1]
    table, curves = [], {}
    for scene_name in SCENES:
        res = ctx.n(*RES[scene_name])
        for i, (label, ours, builtin, targeted) in enumerate(PAIRS):
            if ctx.quick and (i > 0 or scene_name != "furnace"):
                table.append(_skipped(s, scene_name, res, label, ours, builtin, targeted))
                continue
            rows, refs = measure(scene_name, {"plugin": ours, "built-in": builtin}, spps, res,
                                 repeats, reference_spp)
            curves[f"{label}, {scene_name}"] = rows
            t_ours = time_to(rows, "plugin", reference_spp)
            t_ref = time_to(rows, "built-in", reference_spp)
            ratio = t_ours / t_ref
            bias = relative_rmse(refs["plugin"], refs["built-in"])
            shown = f"{ratio:.3f}×" if math.isfinite(ratio) else "— (too short to time)"
            s.values[f"time to 1 %: {label}, {scene_name}"] = shown
            table.append((label, scene_name, seconds_text(t_ours), seconds_text(t_ref), f"**{shown}**",
                          f"≤ {TARGET}" if targeted else "—", f"{bias:.4f}"))
            if targeted:
                s.rows.append(Row(label, f"time to 1 % rel. RMSE, {scene_name}",
                                  shown, f"≤ {TARGET}×", bool(ratio <= TARGET)))
    fig = plot(curves, ctx.figure("error_vs_time.png"))
    detail = []
    for title, rows in curves.items():
        for r in sorted(rows, key=lambda r: (r["who"], r["spp"])):
            detail.append((title, r["who"], r["spp"], f"{r['time']:.4f}", f"{r['rel_rmse']:.4f}",
                           f"{r['rel_mse']:.3g}", f"{r['flip']:.4f}"))
    s.markdown = "\n".join([
        f"Each plugin and its built-in counterpart in the showcase (`scenes/showcase.xml`, every "
        f"sphere's material swapped for the contender) and in the white furnace "
        f"(`scenes/furnace.xml`), "
        f"{' and '.join(f'{ctx.n(*r)}²' for r in RES.values())} pixels, `{ctx.variant}`, at spp = "
        f"{', '.join(map(str, spps))}; each time is the median of {repeats} interleaved "
        "renders in one process, after a warm-up render that holds the JIT compilation. Each "
        f"contender's error is against its own render at {reference_spp} spp (so it is noise "
        "alone); the last column, the relative RMSE between the two references, is how far the "
        "models lie apart (the references' own noise adds about "
        f"√(2/{reference_spp}) = {math.sqrt(2 / reference_spp):.3f} × the 1-spp error to it). "
        "The time to 1 % relative RMSE (RMSE / mean of the reference) is the time of one "
        "render with the spp that reaches it "
        "(`benchmark.error_time.time_to`: the noise variance per sample is the mean of its "
        "estimates from the renders at every spp, the time from a line through the measured "
        "renders).", "",
        md_table(["pair", "scene", "plugin: time to 1 %", "built-in", "ratio", "target",
                  "models' difference (rel. RMSE)"], table), "",
        image(ctx, fig, "error against time"), "",
        "<details><summary>every measurement</summary>", "",
        md_table(["pair, scene", "who", "spp", "time (s)", "rel. RMSE", "rel. MSE", "mean FLIP"],
                 detail), "", "</details>"])
    return s


__all__ = ["section", "measure", "time_to", "PAIRS"]
