"""
Error against time: each plugin and its built-in counterpart rendered at spp = 1, 2, 4, …, with
the wall time of each render and its error against a high-spp reference; log-log curves, and
the time each needs for a 1 % relative RMSE, as a ratio to the built-in.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..compare import flip_map, rel_mse, rmse
from ..scenes import load_scene
from ..campaign.core import Context, Row, Section, image, md_table
from .timing import interleaved, median

#: (label, plugin, built-in counterpart); the campaign's plugins join as they land.
PAIRS = [
    ("lambert vs diffuse", "lambert reflectance=0.5,0.5,0.5", "diffuse reflectance=0.5,0.5,0.5"),
]

#: Scenes: the material sphere (scenes/material.xml) and the white furnace.
SCENES = ("material", "furnace")

#: Target of issue #7: time to 1 % relative RMSE at most 1.05 × the built-in's.
TARGET = 1.05


def relative_rmse(image_, reference) -> float:
    """RMSE divided by the reference's mean value: 0.01 is a 1 % error."""
    return rmse(reference, image_) / float(np.mean(reference))


def measure(scene_name: str, ours, ref, spps, res: int, repeats: int, reference_spp: int):
    """Times and errors of both contenders at every spp; the reference is the built-in's."""
    scenes = {name: load_scene(scene_name, {"res": str(res)}, bsdfs={"material": spec})
              for name, spec in (("plugin", ours), ("built-in", ref))}
    reference = np.array(mi.render(scenes["built-in"], spp=reference_spp, seed=10_000))
    rows = []
    for spp in spps:
        images = {}

        def render(name, spp=spp):
            images[name] = mi.render(scenes[name], spp=spp, seed=spp)
            return images[name]
        times = interleaved({n: (lambda n=n: render(n)) for n in scenes}, repeats=repeats)
        for name in scenes:
            img = np.array(images[name])
            fl = flip_map(reference, img)
            rows.append(dict(who=name, spp=spp, time=median(times[name]),
                             rel_rmse=relative_rmse(img, reference),
                             rel_mse=rel_mse(reference, img), flip=fl[1] if fl else math.nan))
    return rows


def time_to(rows, who: str, target: float = 0.01) -> float:
    """
    Seconds to reach ``target`` relative RMSE, from the largest-spp point: Monte Carlo variance
    falls as 1/spp, so time · (error / target)² (the error of a converged point is its noise).
    """
    last = max((r for r in rows if r["who"] == who), key=lambda r: r["spp"])
    return last["time"] * (last["rel_rmse"] / target) ** 2


def plot(rows_by_pair, path) -> str:
    from ..plots import _pyplot, _save

    plt = _pyplot()
    fig, axes = plt.subplots(1, len(rows_by_pair), figsize=(4.6 * len(rows_by_pair), 3.8),
                             squeeze=False)
    for ax, (title, rows) in zip(axes[0], rows_by_pair.items()):
        for who, style in (("plugin", "o-"), ("built-in", "s--")):
            pts = sorted((r for r in rows if r["who"] == who), key=lambda r: r["spp"])
            ax.loglog([p["time"] for p in pts], [p["rel_rmse"] for p in pts], style, ms=3,
                      label=who)
        ax.axhline(0.01, color="0.6", lw=0.8, ls=":")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("render time (s)")
        ax.grid(alpha=0.3, which="both")
    axes[0][0].set_ylabel("relative RMSE vs reference")
    axes[0][0].legend(fontsize=8)
    return _save(fig, path)


def section(ctx: Context) -> Section:
    s = Section("Error against time")
    res = ctx.n(128, 32)
    spps = [2 ** k for k in range(ctx.n(9, 5))]       # 1 … 256 (quick: 1 … 16)
    repeats = ctx.n(5, 2)
    reference_spp = 64 * spps[-1]
    table, curves = [], {}
    for scene_name in SCENES:
        for label, ours, ref in PAIRS:
            rows = measure(scene_name, ours, ref, spps, res, repeats, reference_spp)
            curves[f"{label}, {scene_name}"] = rows
            t_ours, t_ref = time_to(rows, "plugin"), time_to(rows, "built-in")
            ratio = t_ours / t_ref
            table.append((label, scene_name, f"{t_ours:.3g} s", f"{t_ref:.3g} s",
                          f"**{ratio:.3f}×**"))
            s.rows.append(Row(label, f"time to 1 % rel. RMSE, {scene_name}", f"{ratio:.3f}×",
                              f"≤ {TARGET}×", ratio <= TARGET))
    fig = plot(curves, ctx.figure("error_vs_time.png"))
    detail = []
    for title, rows in curves.items():
        for r in sorted(rows, key=lambda r: (r["who"], r["spp"])):
            detail.append((title, r["who"], r["spp"], f"{r['time']:.4f}", f"{r['rel_rmse']:.4f}",
                           f"{r['rel_mse']:.3g}", f"{r['flip']:.4f}"))
    s.markdown = "\n".join([
        f"Each plugin and its built-in counterpart on the sphere of `scenes/material.xml` and in "
        f"the white furnace, {res}×{res}, at spp = {', '.join(map(str, spps))}; each time is the "
        f"median of {repeats} interleaved renders in one process (after a warm-up render that "
        f"holds the JIT compilation); the error is against the built-in at {reference_spp} spp. "
        "The time to 1 % relative RMSE (RMSE / mean of the reference) is extrapolated from the "
        "largest spp as time · (error / 0.01)², since the variance falls as 1/spp.", "",
        md_table(["pair", "scene", "plugin: time to 1 %", "built-in", "ratio"], table), "",
        image(ctx, fig, "error against time"), "",
        "<details><summary>every measurement</summary>", "",
        md_table(["pair, scene", "who", "spp", "time (s)", "rel. RMSE", "rel. MSE", "mean FLIP"],
                 detail), "", "</details>"])
    return s


__all__ = ["section", "measure", "time_to", "PAIRS"]
