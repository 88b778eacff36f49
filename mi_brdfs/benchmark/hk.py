"""
Hanrahan & Krueger's layer in ``make bench``: the render cost of ``hk`` against
``cooktorrance`` on the same scene (every sphere of the showcase), index-matched, under glass
and over a Lambertian base, the single model and every order.
"""

from __future__ import annotations

from ..bsdfspec import load_bsdf
from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from .measured import COST_SOURCE, render_cost

#: (label, the BSDF): the plugin's example, under glass and over a base.
CONFIGS = [
    ("index-matched (the example: σs = 1, σa = 0.1, d = 0.5, g = 0.6)",
     "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6"),
    ("under glass (η = 1.5)", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.5"),
    ("over a base (η = 1.33, ρ = 0.5)",
     "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.33 diffuse_reflectance=0.5"),
    ("under glass, every order", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.5 "
     "scattering=all"),
    ("over a base, every order", "hk sigma_s=1 sigma_a=0.1 thickness=0.5 g=0.6 eta=1.33 "
     "diffuse_reflectance=0.5 scattering=all"),
]
#: The target: hk's render time at most this many times cooktorrance's.
TARGET_COST = 1.5


def _one(ctx: Context, s: Section, label: str, spec: str) -> tuple:
    """One configuration's row: ns per sample of each, the ratio; its summary row."""
    if ctx.quick:  # each configuration is a kernel to compile: the quick run names the figure
        load_bsdf(spec)
        s.values[f"hk, {label}: render time"] = SKIPPED
        return (label, "—", "—", SKIPPED)
    ratio, per = render_cost(spec, 128, 32, 15)
    s.values[f"hk, {label}: render time"] = f"{ratio:.3f}×"
    s.rows.append(Row(f"hk vs cooktorrance, {label}", f"{ctx.variant} render time ratio",
                      f"{ratio:.3f}×", f"≤ {TARGET_COST}×", ratio <= TARGET_COST))
    return (label, f"{per['bsdf']:.1f} ns", f"{per['against']:.1f} ns", f"{ratio:.3f}×")


def section(ctx: Context) -> Section:
    s = Section("Hanrahan-Krueger: hk")
    rows = [_one(ctx, s, label, spec) for label, spec in CONFIGS]
    s.markdown = "\n".join([
        f"`hk` against `{COST_SOURCE}` on every sphere of the showcase (`{ctx.variant}`, "
        "128 × 128, 32 spp, medians of 15 interleaved renders after a first render of each: "
        f"the JIT compilation apart; target ≤ {TARGET_COST:g}×).", "",
        md_table(["configuration", "hk per sample", "cooktorrance", "ratio"], rows)])
    return s
