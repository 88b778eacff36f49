"""
Backends: the cost of a Python plugin against the C++ built-in in each variant, the scalar
render arrangement, the trace overhead per BSDF instance in a scene with many materials, and
the first-render (trace + compile) time.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

import mi_brdfs
from ..campaign.core import Context, Row, Section, md_table
from ..render import render
from ..scenes import load_scene
from .timing import interleaved, median, median_ratio, timed

#: (label, cbox material of the plugin, of the built-in); the plugins join as they land.
CBOX_PAIRS = [("lambert vs diffuse", {"material": "lambert"}, {"material": "diffuse"})]

TARGET_LLVM, TARGET_SCALAR, TARGET_TRACE = 1.03, 12.0, 1.2


def jit_ratio(ctx: Context, s: Section) -> list:
    """llvm: mi.render of the Cornell box, plugin vs built-in, per sample."""
    res, spp, repeats = ctx.n(256, 64), ctx.n(64, 8), ctx.n(15, 3)
    table = []
    for label, ours, ref in CBOX_PAIRS:
        scenes = {k: load_scene("cbox", dict(d, res=str(res))) for k, d in
                  (("plugin", ours), ("built-in", ref))}
        first = {k: timed(lambda sc=sc: mi.render(sc, spp=spp))[0] for k, sc in scenes.items()}
        times = interleaved({k: (lambda sc=sc: mi.render(sc, spp=spp)) for k, sc in
                             scenes.items()}, repeats=repeats, warmup=0)
        ratio = median_ratio(times, "plugin", "built-in")
        per = {k: median(t) / (res * res * spp) * 1e9 for k, t in times.items()}
        table.append((label, ctx.variant, f"{per['plugin']:.1f} ns", f"{per['built-in']:.1f} ns",
                      f"**{ratio:.3f}×**", f"≤ {TARGET_LLVM}", f"{first['plugin']:.2f} s / "
                      f"{first['built-in']:.2f} s"))
        s.rows.append(Row(label, f"{ctx.variant} render time ratio", f"{ratio:.3f}×",
                          f"≤ {TARGET_LLVM}×", ratio <= TARGET_LLVM))
    return table


def scalar_ratio(ctx: Context, s: Section) -> list:
    """scalar: both through the package's render path (which picks the arrangement)."""
    res, spp, repeats = ctx.n(128, 16), ctx.n(16, 2), ctx.n(5, 2)
    table = []
    mi_brdfs.use_variant(ctx.scalar_variant)
    for label, ours, ref in CBOX_PAIRS:
        results = {}

        def run(key, defines):
            results[key] = render("cbox", spp=spp, defines=dict(defines, res=str(res)),
                                  progress=False)
        times = interleaved({"plugin": lambda: run("plugin", ours),
                             "built-in": lambda: run("built-in", ref)}, repeats=repeats)
        ratio = median_ratio(times, "plugin", "built-in")
        per = {k: median(t) / (res * res * spp) * 1e9 for k, t in times.items()}
        table.append((label, f"{ctx.scalar_variant} ({results['plugin'].arrangement})",
                      f"{per['plugin']:.0f} ns", f"{per['built-in']:.0f} ns", f"**{ratio:.2f}×**",
                      f"≤ {TARGET_SCALAR:g}", "—"))
        s.rows.append(Row(label, f"{ctx.scalar_variant} render-path time ratio", f"{ratio:.2f}×",
                          f"≤ {TARGET_SCALAR:g}×", ratio <= TARGET_SCALAR))
    return table


def scalar_threads(ctx: Context) -> list:
    """Why the arrangement: the plugin in scalar on 1 and 2 render threads, in-process."""
    res, spp = ctx.n(64, 16), ctx.n(8, 2)
    rows = []
    mi_brdfs.use_variant(ctx.scalar_variant)
    threads = dr.thread_count()
    try:
        for material in ("lambert", "diffuse"):
            scene = load_scene("cbox", {"res": str(res), "material": material})
            for n in (1, 2):
                dr.set_thread_count(n)
                seconds = median([timed(lambda: mi.render(scene, spp=spp))[0]
                                  for _ in range(ctx.n(3, 1))])
                rows.append((material, n, f"{seconds:.3f} s"))
    finally:
        dr.set_thread_count(threads)
    return rows


def many_materials(ctx: Context, s: Section) -> list:
    """Trace overhead per BSDF instance: K spheres, each with its own material instance."""
    mi_brdfs.use_variant(ctx.variant)
    res, spp = ctx.n(128, 32), ctx.n(16, 4)
    rows = []
    for k in ctx.n((1, 16, 64), (1, 8)):
        scenes = {}
        for who, kind in (("plugin", "lambert"), ("built-in", "diffuse")):
            d = {"type": "scene", "integrator": {"type": "path", "max_depth": 4},
                 "light": {"type": "constant"},
                 "sensor": {"type": "perspective", "fov": 40,
                            "to_world": mi.ScalarTransform4f().look_at(
                                origin=[0, 0, 12], target=[0, 0, 0], up=[0, 1, 0]),
                            "film": {"type": "hdrfilm", "width": res, "height": res}}}
            side = int(np.ceil(np.sqrt(k)))
            for i in range(k):
                x, y = i % side - (side - 1) / 2, i // side - (side - 1) / 2
                d[f"s{i}"] = {"type": "sphere", "radius": 0.4 * 8 / max(side, 1) / 2,
                              "center": [x * 8 / side, y * 8 / side, 0],
                              "bsdf": {"type": kind, "reflectance": 0.1 + 0.8 * i / max(k, 1)}}
            scenes[who] = mi.load_dict(d)
        first = {w: timed(lambda sc=sc: mi.render(sc, spp=spp))[0] for w, sc in scenes.items()}
        times = interleaved({w: (lambda sc=sc: mi.render(sc, spp=spp)) for w, sc in
                             scenes.items()}, repeats=ctx.n(7, 2), warmup=0)
        ratio = median_ratio(times, "plugin", "built-in")
        rows.append((k, f"{first['plugin']:.2f} s", f"{first['built-in']:.2f} s",
                     f"{first['plugin'] / first['built-in']:.2f}×",
                     f"{median(times['plugin']):.3f} s", f"{median(times['built-in']):.3f} s",
                     f"**{ratio:.3f}×**"))
        s.rows.append(Row("lambert vs diffuse", f"{k} material instances, render time",
                          f"{ratio:.3f}×", f"≤ {TARGET_TRACE}×", ratio <= TARGET_TRACE))
    return rows


def section(ctx: Context) -> Section:
    s = Section("Backends")
    table = jit_ratio(ctx, s) + scalar_ratio(ctx, s)
    threads = scalar_threads(ctx)
    many = many_materials(ctx, s)
    s.markdown = "\n".join([
        "Render time of the Cornell box with every surface the plugin against every surface "
        "the built-in, same spp and seeds, medians of interleaved repeats in one process. In "
        "the JIT variant both go through `mi.render` (a warm-up render each, excluded, holds "
        "the tracing and compilation: its time is the last column); in the scalar variant "
        "through the package's render path `mi_brdfs.render.render`, which renders scenes "
        "with Python plugins on one thread per process.", "",
        md_table(["pair", "variant", "plugin per sample", "built-in per sample", "ratio",
                  "target", "first render plugin / built-in"], table), "",
        "Why one thread per process in scalar variants: Mitsuba calls a Python plugin once per "
        "ray from its render threads, and those calls serialise on the GIL "
        f"(Cornell box, in-process `mi.render`, {ctx.scalar_variant}):", "",
        md_table(["material", "render threads", "time"], threads), "",
        "Trace overhead per BSDF instance (JIT): a scene of K spheres, each with its own "
        "material instance (a different reflectance), `lambert` against `diffuse`. Every "
        "Python instance is traced into the kernel once per render pass; the first render also "
        "compiles:", "",
        md_table(["K", "first render plugin", "built-in", "ratio", "render plugin",
                  "render built-in", "ratio"], many)])
    return s
