"""Campaign section: lambert against Mitsuba's diffuse."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from .. import checks
from ..compare import compare, figure
from ..scenes import load_scene
from .core import Context, Row, Section, image, md_table

RGB = {"type": "rgb", "value": [0.2, 0.5, 0.9]}
SPECS = [("ρ = 0.5 (default)", {"type": "lambert"}, {"type": "diffuse"}),
         ("ρ = 1", {"type": "lambert", "reflectance": 1.0},
          {"type": "diffuse", "reflectance": 1.0}),
         ("ρ = (0.2, 0.5, 0.9)", {"type": "lambert", "reflectance": RGB},
          {"type": "diffuse", "reflectance": RGB})]


def section(ctx: Context) -> Section:
    s = Section("Lambert vs diffuse")
    n = ctx.n(1_000_000, 100_000)
    lines = ["`lambert` computes what Mitsuba's `diffuse` computes, in the same order "
             "(`mi_brdfs/plugins/lambert.py`). Expected: identical.", "",
             "**Pointwise** (eval, pdf, eval_pdf and sample() with the same random numbers, "
             f"{n:,} random direction pairs over the sphere, `checks.check_equal`):", ""]
    table = []
    for label, ours, ref in SPECS:
        r = checks.check_equal(ours, ref, n=n, rtol=0.0, atol=0.0)
        table.append((label, f"{r.value:.3g}", ", ".join(f"{k} {v:.1g}" for k, v in
                                                        r.details["max"].items())))
        s.rows.append(Row.of("lambert", r, f"= diffuse pointwise, {label}"))
    lines += [md_table(["reflectance", "largest relative difference", "per quantity"], table), ""]

    # Rendered: bit-identical on one thread; the compare figure with its noise floor
    res, spp = ctx.n(256, 64), ctx.n(64, 16)
    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        imgs = [np.array(mi.render(load_scene("cbox", material=m, res=res), spp=spp, seed=3))
                for m in ("lambert", "diffuse")]
    finally:
        dr.set_thread_count(threads)
    identical = bool(np.array_equal(imgs[0], imgs[1]))
    shown = "identical" if identical else f"max |Δ| {np.abs(imgs[0] - imgs[1]).max():.3g}"
    s.rows.append(Row("lambert", f"cbox render = diffuse, one thread ({res}², {spp} spp)",
                      shown, "bit for bit", identical))
    result = compare("cbox", spp=spp, defines={"res": str(res), "material": "diffuse"},
                     defines_b={"material": "lambert"}, labels=("diffuse", "lambert"))
    fig = figure(result, ctx.figure("lambert_vs_diffuse.png"), "Cornell box: diffuse | lambert")
    s.rows.append(Row("lambert", "cbox render vs diffuse (all threads)",
                      result.verdict().split(" (")[0], "≤ 3 × noise floor", not result.different()))
    lines += ["**Rendered** (Cornell box, every surface one material, same seed): on one thread "
              f"the two renders are {'bit-identical' if identical else 'NOT identical'}; on all "
              "threads the film's parallel accumulation order varies from run to run, for the "
              "built-in too:", "", "```", result.summary(), "```", "",
              image(ctx, fig, "Cornell box, diffuse vs lambert"), ""]

    # The battery on lambert, in both variants
    lines += ["**Checks** on `lambert` (ρ = 0.8) in the JIT and the scalar variant:", ""]
    for variant in (ctx.variant, ctx.scalar_variant):
        from ..registry import use_variant
        use_variant(variant)
        results = checks.run_battery({"type": "lambert", "reflectance": 0.8}, quick=ctx.quick,
                                     render=variant == ctx.variant, progress=False)
        s.rows += [Row.of(f"lambert ({variant})", r) for r in results if not r.skipped]
        lines += [f"`{variant}`:", "", "```", checks.format_table(results), "```", ""]
    s.markdown = "\n".join(lines)
    return s
