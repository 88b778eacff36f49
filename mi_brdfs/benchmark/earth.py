"""
The models of Earth observation and planetary science in ``make bench``: the render cost of
``rtls``, ``rpv``, ``hapke`` and ``ocean`` against ``cooktorrance`` on the same scene, and each
one's sampler against cosine sampling as the time to 1 % relative RMSE in the white furnace, at
a configuration where its lobe is peaked: the hot spot of a sparse canopy (``rtls``), of a
backscattering ``rpv`` surface and of a regolith's opposition effect (``hapke``), and the
sunglint of a calm sea (``ocean``).
"""

from __future__ import annotations

import math

from ..bsdfspec import load_bsdf
from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from . import error_time
from .measured import COST_SOURCE, render_cost, time_ratio

#: (label, the BSDF, whether it is held to the targets): each model where its lobe is
#: peaked, and the regolith of the plugin's example, whose opposition peak is too narrow to
#: carry much of its albedo (measured, not judged).
CONFIGS = [
    ("rtls, hot spot of a sparse canopy", "rtls f_iso=0.2 f_vol=0.1 f_geo=0.03", True),
    ("rpv, backscattering (g = −0.3, k = 0.8)", "rpv rho_0=0.1 k=0.8 g=-0.3", True),
    ("hapke, backscattering grains (b = 0.5, c = 0.9, B_0 = 1, h = 0.2)",
     "hapke w=0.9 b=0.5 c=0.9 theta=0 B_0=1 h=0.2", True),
    ("hapke, the example's regolith (B_0 = 1, h = 0.06)",
     "hapke w=0.3 b=0.25 c=0.7 theta=20 B_0=1 h=0.06", False),
    ("ocean, sunglint of a calm sea (2 m/s)", "ocean wind_speed=2", True),
]
#: Targets: each model's render time at most this many times cooktorrance's; its sampler
#: faster to 1 % than the cosine's.
TARGET_COST, TARGET_SAMPLING = 1.2, 1.0


def _one(ctx: Context, s: Section, label: str, spec: str, judged: bool) -> tuple:
    """The row of one configuration: ns per sample, its cost ratio, and the times to 1 % (its
    sampler, the cosine's, their ratio); the section's rows and values (keyed by the plugin,
    the first configuration of each)."""
    plugin = spec.split()[0]
    if f"{plugin}: render time" in s.values:
        plugin = label
    if ctx.quick:  # each model is a kernel to compile: the quick run names the figures
        for key in ("render time", "time to 1 %"):
            s.values[f"{plugin}: {key}"] = SKIPPED
        return (label, "—", SKIPPED, "—", "—", SKIPPED)
    ratio, per = render_cost(spec, ctx.n(128, 32), ctx.n(32, 4), ctx.n(15, 2))
    s.values[f"{plugin}: render time"] = f"{ratio:.3f}×"
    if judged:
        s.rows.append(Row(f"{plugin} vs cooktorrance", f"{ctx.variant} render time ratio",
                          f"{ratio:.3f}×", f"≤ {TARGET_COST}×", ratio <= TARGET_COST))
    t_own, t_cos, speedup = time_ratio(ctx, "furnace", load_bsdf(spec))
    shown = f"{speedup:.3g}×" if math.isfinite(speedup) else "— (too short to time)"
    s.values[f"{plugin}: time to 1 %"] = shown
    if judged:
        s.rows.append(Row(label, "time to 1 % rel. RMSE in the furnace, cosine sampling / "
                          "the plugin's", shown, f"> {TARGET_SAMPLING:g}×",
                          bool(speedup > TARGET_SAMPLING)))
    return (label, f"{per['bsdf']:.1f} ns", f"{ratio:.3f}×", error_time.seconds_text(t_own),
            error_time.seconds_text(t_cos), f"**{shown}**")


def section(ctx: Context) -> Section:
    s = Section("Earth observation: rtls, rpv, hapke, ocean")
    rows = [_one(ctx, s, *config) for config in CONFIGS]
    if ctx.quick:  # the machinery: every configuration loads in this variant
        for _, spec, _ in CONFIGS:
            load_bsdf(spec)
    s.markdown = "\n".join([
        f"Each model where its lobe is peaked, against `{COST_SOURCE}` on every sphere of the "
        f"showcase (`{ctx.variant}`, medians of interleaved renders after a first render of "
        f"each: the JIT compilation apart; target ≤ {TARGET_COST:g}×), and its sampler against "
        "the cosine-weighted hemisphere alone (`benchmark.measured.mi_brdfs_bench_cosine`) as "
        "the time to 1 % relative RMSE in the white furnace (target: faster than the "
        "cosine's).", "",
        md_table(["configuration", "per sample", "vs cooktorrance", "to 1 %: own",
                  "cosine", "cosine / own"], rows)])
    return s

