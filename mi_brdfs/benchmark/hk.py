"""
Hanrahan & Krueger's layer in ``make bench``: the render cost of ``hk`` against
``cooktorrance`` on the same scene (every sphere of the showcase), index-matched, under glass
and over a Lambertian base, the single model and every order.
"""

from __future__ import annotations

import math

from ..bsdfspec import load_bsdf
from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from . import error_time
from .measured import COST_SOURCE, render_cost, time_ratio

#: (label, the BSDF, whether it is held to the target): the plugin's example, under glass
#: and over a base, the single model and every order.
CONFIGS = [
    ("index-matched (the example: σs = 1, σa = 0.1, d = 0.5, g = 0.6)",
     "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6", True),
    ("under glass (η = 1.5)", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.5", True),
    ("over a base (η = 1.33, ρ = 0.5)",
     "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.33 diffuse_reflectance=0.5", True),
    ("under glass, every order", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.5 "
     "scattering=all", True),
    ("over a base, every order", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.33 "
     "diffuse_reflectance=0.5 scattering=all", True),
    # a medium that may vary over the surface reads the grid (interpolated in albedo and
    # depth): measured, not judged
    ("under glass, every order, σs a texture (the grid)",
     {"type": "hk", "sigma_s": {"type": "checkerboard", "color0": 1.0, "color1": 0.8},
      "sigma_a": 0.1, "thickness": 0.5, "g": 0.6, "eta": 1.5, "scattering": "all"}, False),
]
#: The target: hk's render time at most this many times cooktorrance's.
TARGET_COST = 1.5
#: The sampler against the cosine's of both sides: forward-scattering free slabs,
#: index-matched (no mirror; the unscattered beam is a null interaction, which the furnace's
#: path crosses), thin (single scattering shapes the lobe) and thick (multiple scattering
#: broadens it: measured, not judged), time to 1 % in the white furnace; target: faster
#: than the cosine's.
SAMPLING = [("thin forward-scattering slab (g = 0.8, η = 1, τ = 0.5, every order)",
             "hk sigma_s=0.45 sigma_a=0.05 thickness=1 g=0.8 scattering=all", True),
            ("thick forward-scattering slab (g = 0.7, η = 1, τ = 2, every order)",
             "hk sigma_s=1.9 sigma_a=0.1 thickness=1 g=0.7 scattering=all", False)]
TARGET_SAMPLING = 1.0


def _one(ctx: Context, s: Section, label: str, spec, judged: bool) -> tuple:
    """One configuration's row: ns per sample of each, the ratio; its summary row."""
    if ctx.quick:  # each configuration is a kernel to compile: the quick run names the figure
        load_bsdf(spec)
        s.values[f"hk, {label}: render time"] = SKIPPED
        return (label, "—", "—", SKIPPED)
    ratio, per = render_cost(spec, 128, 32, 15)
    s.values[f"hk, {label}: render time"] = f"{ratio:.3f}×"
    if judged:
        s.rows.append(Row(f"hk vs cooktorrance, {label}", f"{ctx.variant} render time ratio",
                          f"{ratio:.3f}×", f"≤ {TARGET_COST}×", ratio <= TARGET_COST))
    return (label, f"{per['bsdf']:.1f} ns", f"{per['against']:.1f} ns", f"{ratio:.3f}×")


def _sampling(ctx: Context, s: Section, label: str, spec: str, judged: bool) -> tuple:
    """The sampler against the cosine's: time to 1 % in the furnace, and their ratio."""
    key = f"hk, {label}: time to 1 %, cosine / own"
    if ctx.quick:
        load_bsdf(spec)
        s.values[key] = SKIPPED
        return (label, "—", "—", SKIPPED)
    t_own, t_cos, speedup = time_ratio(ctx, "furnace", load_bsdf(spec), two_sided=True)
    shown = f"{speedup:.3g}×" if math.isfinite(speedup) else "— (too short to time)"
    s.values[key] = shown
    if judged:
        s.rows.append(Row(f"hk, {label}", "time to 1 % rel. RMSE in the furnace, cosine sampling "
                          "/ hk's", shown, f"> {TARGET_SAMPLING:g}×",
                          bool(speedup > TARGET_SAMPLING)))
    return (label, error_time.seconds_text(t_own), error_time.seconds_text(t_cos), shown)


def section(ctx: Context) -> Section:
    s = Section("Hanrahan-Krueger: hk")
    rows = [_one(ctx, s, *config) for config in CONFIGS]
    sampling = [_sampling(ctx, s, *config) for config in SAMPLING]
    s.markdown = "\n".join([
        f"`hk` against `{COST_SOURCE}` on every sphere of the showcase (`{ctx.variant}`, "
        "128 × 128, 32 spp, medians of 15 interleaved renders after a first render of each: "
        f"the JIT compilation apart; target ≤ {TARGET_COST:g}×).", "",
        md_table(["configuration", "hk per sample", "cooktorrance", "ratio"], rows), "",
        "hk's sampler (a Henyey-Greenstein lobe about −ωi mixed with cosines, its exact "
        "density) against the cosine-weighted hemispheres of both sides "
        "(`benchmark.measured.mi_brdfs_bench_cosine`, `two_sided`): the time to 1 % relative RMSE in the "
        f"white furnace (target: faster than the cosine's, > {TARGET_SAMPLING:g}×).", "",
        md_table(["configuration", "to 1 %: hk's sampler", "cosine", "cosine / hk's"],
                 sampling)])
    return s
