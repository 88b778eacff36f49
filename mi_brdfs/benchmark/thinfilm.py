"""
The thin film of ``cooktorrance`` in ``make bench``: the render time of a film against the same
``cooktorrance`` without one, on every sphere of the showcase, in the RGB variant (the
reflectance integrated against the channels' sensitivities) and in ``llvm_ad_spectral`` (exact
at each sampled wavelength), on a conductor and on a dielectric interface.
"""

from __future__ import annotations

from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from ..variants import variant_kept
from .measured import render_cost

FILM = "film_thickness=300 film_eta=1.4"
#: (label, cooktorrance without the film): each is rendered with :data:`FILM` added.
CONFIGS = [
    ("gold, α = 0.2", "cooktorrance material=Au alpha=0.2 shadowing=smith"),
    ("water interface, α = 0.2", "cooktorrance eta=1.33 transmission=true alpha=0.2"),
]
SPECTRAL = "llvm_ad_spectral"
#: The target: a film's render time at most this many times the plugin's without it.
TARGET_COST = 1.15


def _one(ctx: Context, s: Section, variant: str, label: str, bare: str) -> tuple:
    """One configuration in one variant: its row of the table and its summary row."""
    name = f"film, {label}, {variant}: render time"
    if ctx.quick:  # each configuration is a kernel to compile: the quick run names it
        s.values[name] = SKIPPED
        return (label, variant, "—", "—", SKIPPED)
    from ..registry import use_variant

    with variant_kept():
        use_variant(variant)
        ratio, per = render_cost(f"{bare} {FILM}", ctx.n(128, 32), ctx.n(32, 4),
                                 ctx.n(15, 2), against=bare)
    s.values[name] = f"{ratio:.3f}×"
    s.rows.append(Row(f"cooktorrance film vs none, {label}", f"{variant} render time ratio",
                      f"{ratio:.3f}×", f"≤ {TARGET_COST}×", ratio <= TARGET_COST))
    return (label, variant, f"{per['bsdf']:.1f} ns", f"{per['against']:.1f} ns", f"{ratio:.3f}×")


def section(ctx: Context) -> Section:
    s = Section("Thin film: cooktorrance with film_thickness")
    rows = [_one(ctx, s, variant, label, bare) for variant in (ctx.variant, SPECTRAL)
            for label, bare in CONFIGS]
    s.markdown = "\n".join([
        f"`cooktorrance` with a film ({FILM.replace(' ', ', ')}) against the same plugin "
        "without it, on every sphere of the showcase (128 × 128, 32 spp, medians of 15 "
        "interleaved renders after a first render of each: the JIT compilation apart; "
        f"target ≤ {TARGET_COST:g}×), in RGB (the Fourier-space integration) and spectral "
        "(exact at each sampled wavelength).", "",
        md_table(["configuration", "variant", "with the film, per sample", "without",
                  "ratio"], rows)])
    return s
