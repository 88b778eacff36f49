"""
Precision against cost: the float32 plugin against its float64 reference over each parameter's
range (the sweeps of the validation campaign's extremes matrix), beside the cost of an
evaluation at that parameter value.
"""

from __future__ import annotations

from .. import checks
from ..campaign.core import Context, Section, image, md_table
from ..campaign.extremes import SWEEPS, param_name
from ..plots import pyplot, save_figure
from .models import jit_seconds


def section(ctx: Context) -> Section:
    s = Section("Precision against cost")
    rows, spread = [], []
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for plugin, name, base, values in SWEEPS[1:] if not ctx.quick else SWEEPS[1:2]:
        key = param_name(name)
        values = values if not ctx.quick else values[::4]
        errs, costs = [], []
        for v in values:
            spec = dict(base, **{key: v})
            p = checks.eval_precision(spec, n=ctx.n(20_000, 3_000))
            cost = jit_seconds(spec, ctx)
            errs.append(p.p99)
            costs.append(cost)
            rows.append((plugin, name, f"{v:.7g}", f"{p.p99:.1e}", f"{cost:.3f} s"))
        spread.append((plugin, name, max(costs) / min(costs)))
        axes[0].loglog([max(v, 1e-7) for v in values], [max(e, 1e-9) for e in errs], "o-",
                       ms=3, label=f"{plugin}: {name}")
        axes[1].semilogx([max(v, 1e-7) for v in values], costs, "o-", ms=3,
                         label=f"{plugin}: {name}")
    axes[0].set_ylabel("99th percentile relative error, float32 vs float64")
    axes[1].set_ylabel("seconds per 1e7 eval_pdf")
    for ax in axes:
        ax.set_xlabel("parameter value")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6)
    path = save_figure(fig, ctx.figure("precision_cost.png"))
    worst = max(spread, key=lambda x: x[2])
    s.markdown = "\n".join([
        "The float32 error of `eval` (99th percentile at the directions the plugin samples, "
        "against the float64 reference; `checks.eval_precision`) next to the cost of an "
        f"evaluation (`eval_pdf`, {ctx.variant}, the kernels' execution time, median of "
        "interleaved repeats), across each "
        "parameter's range. The largest spread of the cost over one range in this run is "
        f"{worst[2]:.2f}× ({worst[0]}, {worst[1]})" + (
            ": the extreme values, where float32 error grows, cost no more to evaluate than the "
            "middle of the range." if worst[2] < 1.25 else
            ": the cost depends on the value (table below)."), "",
        image(ctx, path, "precision and cost"), "",
        md_table(["plugin", "parameter", "value", "p99 rel. error", "cost per 1e7"], rows)])
    return s
