"""
The results of :func:`mi_brdfs.simplify.simplify`: the records of candidates, materials and the
whole (:class:`SimplifyResult`, whose ``summary()`` is the printed report), SIMPLIFY.md
(:func:`write_report`) and the plot of error against render time (:func:`plot`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..markdown import md_table
from .measure import MAX_SEEDS
from .scene import Material


@dataclass
class Candidate:
    """A replacement of one material (or, for the verification, the simplified scene)."""

    label: str
    kind: str        # 'original', 'switch', 'built-in', 'lobe left out', 'fit', 'simplified'
    xml: str = ""
    note: str = ""
    error: str | None = None
    measured: dict = field(default_factory=dict)
    cached: bool = False
    # derived for a tolerance (see choose._derive)
    bias: float = 0.0
    bias_hi: float = 0.0
    bias_lo: float = 0.0
    time_to_tolerance: float = math.inf
    speedup: float = math.nan
    speedup_se: float = math.nan
    within: bool = False
    verdict: str = ""

    @property
    def ok(self) -> bool:
        return self.error is None and bool(self.measured)


@dataclass
class MaterialResult:
    """One material: its candidates (the original first) and the choice."""

    material: Material
    candidates: list
    chosen: int = 0
    reason: str = ""

    @property
    def label(self) -> str:
        return self.material.label


@dataclass
class SimplifyResult:
    """What :func:`simplify` measured and chose; ``text`` is the simplified scene file, and
    ``included`` the included files it simplified (which ``text`` includes)."""

    scene: Path
    tolerance: float
    variant: str
    spp: int
    defines: dict
    quick: bool
    materials: list
    original: dict
    replacements: dict
    text: bytes
    verification: Candidate | None
    predicted: dict
    measured: dict
    output: Path | None = None
    report: Path | None = None
    figure: Path | None = None
    seconds: float = 0.0
    notes: list = field(default_factory=list)
    renders: int = 0
    objective: str = "simplicity"
    #: {file name: bytes} of each simplified included file, written beside the scene file
    included: dict = field(default_factory=dict)

    def table(self, material: MaterialResult) -> str:
        """A Markdown table of one material's candidates."""
        rows = []
        for i, c in enumerate(material.candidates):
            name = f"**{c.label}**" if i == material.chosen and i else c.label
            if not c.ok:
                rows.append((name, c.kind, "—", "—", "—", "—", "—", "—", "—",
                             f"not measured: {c.error or c.note}"))
                continue
            me = c.measured
            flip = f"{me['flip']:.4f}" if me.get("flip") is not None else "—"
            original = c.kind == "original"
            rows.append((
                name + (f" — {c.note}" if c.note else ""), c.kind,
                "0 (reference)" if original else
                f"{c.bias:.4f} [{c.bias_lo:.4f}, {c.bias_hi:.4f}]",
                "—" if original else f"{me['noise']:.2g} ({me['seeds']})",
                "—" if original else flip,
                _ratio(me["cost_ratio"], me["cost_ratio_se"]),
                _ratio(me["variance_ratio"], me["variance_ratio_se"]),
                _seconds(c.time_to_tolerance),
                "1" if original else
                _ratio(c.speedup, c.speedup_se) if math.isfinite(c.time_to_tolerance) else "—",
                c.verdict))
        return md_table(["candidate", "kind", "bias: rel. RMSE [±2 SE]", "noise (seeds)", "FLIP",
                         "cost/spp", "variance", f"time to {self.tolerance:g}", "speed-up",
                         "verdict"], rows)

    def tables(self) -> str:
        parts = []
        for mat in self.materials:
            where = "" if "(line" in mat.label else f", line {mat.material.line}" + (
                f" of {mat.material.file}" if mat.material.file else "")
            head = f"### {mat.label} (`{mat.material.type}`{where})"
            if len(mat.candidates) == 1:
                parts += [head, "", f"kept: {mat.reason}", ""]
            else:
                parts += [head, "", self.table(mat), "", f"→ {mat.reason}", ""]
        return "\n".join(parts)

    def summary(self) -> str:
        """The printed report: the tables, the replacements and the verification."""
        lines = [f"simplify {self.scene.name} (objective {self.objective}, tolerance "
                 f"{self.tolerance:g} relative RMSE, "
                 f"{self.variant}, {self.spp} spp per render, {self.renders} renders"
                 + (f", {' '.join(f'{k}={v}' for k, v in self.defines.items())}"
                    if self.defines else "") + f", {self.seconds:.0f} s)", "",
                 self.tables()]
        lines += self.verdict_lines()
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def verdict_lines(self) -> list:
        chosen = [(m.label, m.candidates[m.chosen].label) for m in self.materials if m.chosen]
        lines = []
        if not chosen:
            lines.append("no material replaced: the simplified scene is the original")
        else:
            lines.append("replaced: " + "; ".join(f"{a} → {b}" for a, b in chosen))
        if self.verification is not None and self.verification.ok:
            v, me = self.verification, self.verification.measured
            lines.append(
                f"verification (the simplified scene against the original, {me['seeds']} "
                f"independent seeds): bias {v.bias:.4f} (≤ {v.bias_hi:.4f}, noise "
                f"{me['noise']:.2g}) "
                f"{'within' if v.bias_hi <= self.tolerance else 'OVER'} the tolerance "
                f"{self.tolerance:g}; speed-up to the tolerance predicted "
                f"{_ratio(self.predicted['speedup'], self.predicted.get('speedup_se', math.nan))}, "
                f"measured {_ratio(v.speedup, v.speedup_se)}: "
                f"{agreement(self.predicted, v)} (cost/spp "
                f"{_ratio(me['cost_ratio'], me['cost_ratio_se'])}, variance "
                f"{_ratio(me['variance_ratio'], me['variance_ratio_se'])})")
        if self.output:
            lines.append(f"wrote {self.output}" + "".join(
                f" and {self.output.parent / name}" for name in self.included))
        if self.report:
            lines.append(f"wrote {self.report}" + (f" and {self.figure}" if self.figure else ""))
        return lines


def _ratio(value: float, se_log: float) -> str:
    if not math.isfinite(value):
        return "—" if math.isnan(value) else "0"
    if not math.isfinite(se_log):
        return f"{value:.3f}×"
    return f"{value:.3f}× ±{100 * se_log:.1f}%"


def _seconds(t: float) -> str:
    if not math.isfinite(t):
        return "∞ (bias ≥ tolerance)"
    return f"{t:.3g} s"


def agreement(predicted: dict, measured, confidence: float = 2.0) -> str:
    """Whether the measured speed-up agrees with the predicted one within ``confidence``
    standard errors of their difference (of logs), in words for the report."""
    p, m = predicted.get("speedup", math.nan), measured.speedup
    se = math.hypot(predicted.get("speedup_se", math.nan), measured.speedup_se)
    if not (p > 0 and m > 0 and math.isfinite(se)):
        return "their agreement is unknown (no standard error)"
    gap = abs(math.log(m / p))
    if gap <= confidence * se:
        return f"they agree within {confidence:g} standard errors"
    return (f"they DO NOT agree: {gap / se:.1f} standard errors apart (the parts' costs "
            f"and variances do not add up to the whole scene's)")


def plot(result: SimplifyResult, path) -> str:
    """
    Error against time, one panel per material with candidates: each candidate's predicted
    relative RMSE √(bias² + V/t) of a render of t seconds (V: its variance per unit time), the
    Pareto front (the least error any candidate reaches at each time), the tolerance, and
    each candidate's time to reach it (a dot).
    """
    from ..plots import pyplot, save_figure

    plt = pyplot()
    panels = [m for m in result.materials if len(m.candidates) > 1]
    if result.verification is not None and result.verification.ok:
        panels.append(None)
    cols = min(4, max(1, len(panels)))
    rows = max(1, math.ceil(len(panels) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.8 * cols, 3.2 * rows), squeeze=False)
    t0 = result.original["variance_1spp_ref"] * result.original["ref_seconds_per_spp"] \
        / result.tolerance ** 2
    t = np.geomspace(t0 / 100, t0 * 10, 200)
    for ax in axes.flat[len(panels):]:
        ax.axis("off")
    for ax, mat in zip(axes.flat, panels):
        cands = ([Candidate("original", "original", measured=result.materials[0].candidates[0]
                            .measured), result.verification] if mat is None else
                 mat.candidates)
        curves = []
        for i, c in enumerate(cands):
            if not c.ok:
                continue
            me = c.measured
            v = me["variance_1spp_ref"] * me["variance_ratio"] * \
                me["ref_seconds_per_spp"] * me["cost_ratio"]
            err = np.sqrt(max(me["b2"], 0.0) + v / t)
            curves.append(err)
            chosen = mat is not None and i == mat.chosen and i > 0
            style = "-" if c.kind == "original" else "--"
            line, = ax.loglog(t, err, style, lw=2.0 if chosen or c.kind == "original" else 1.0,
                              label=c.label + (" (chosen)" if chosen else ""))
            if math.isfinite(c.time_to_tolerance):
                ax.plot([c.time_to_tolerance], [result.tolerance], "o", ms=4,
                        color=line.get_color())
        if curves:
            ax.loglog(t, np.min(curves, axis=0), color="0.2", lw=4, alpha=0.2,
                      label="Pareto front")
        ax.axhline(result.tolerance, color="0.5", lw=0.8, ls=":")
        ax.set_title(("simplified scene" if mat is None else
                      f"{mat.label} ({mat.material.type})"), fontsize=8)
        ax.set_xlabel("render time (s)", fontsize=7)
        ax.set_ylabel("relative RMSE", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=5, loc="upper right")
    fig.suptitle(f"{result.scene.name}: predicted error against render time (error² = bias² + "
                 f"V/t), tolerance {result.tolerance:g}", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def write_report(result: SimplifyResult, path) -> Path:
    """SIMPLIFY.md: the settings, the method in short, every table, the plot, the verdict."""
    from ..imageio import atomic_path

    path = Path(path)
    d = " ".join(f"-D {k}={v}" for k, v in result.defines.items())
    original = result.original
    original_time = original["variance_1spp_ref"] * original["ref_seconds_per_spp"] \
        / result.tolerance ** 2
    lines = [
        f"# Simplification of {result.scene.name}", "",
        f"`mi-brdfs simplify {result.scene.name} --tolerance {result.tolerance:g}"
        + (" --quick" if result.quick else "")
        + (" --objective speed" if result.objective == "speed" else "")
        + (f" {d}" if d else "") + f"`: "
        f"{result.variant}, {result.spp} spp per render, {result.renders} renders, "
        f"{result.seconds:.0f} s.", "",
        "Each candidate is rendered in the scene with only its material replaced; its **bias** "
        "is the relative RMSE (RMSE over the original image's mean) of its converged image "
        "against the original's, estimated from renders with common random numbers at 2 to "
        f"{MAX_SEEDS} seeds (more while its bounds, ± 2 standard errors, straddle the "
        "tolerance), **noise** the RMS noise of that estimate. "
        "**Cost/spp** and **variance** are relative to the original scene (cost: median of "
        "renders interleaved with the original's; ± one standard error); the **time to "
        f"{result.tolerance:g}** is V/(τ² − bias²), V the variance per second of render "
        "(error² = bias² + V/t). " + (
            "A candidate replaces the original only when it is within the tolerance and "
            "measurably faster (objective speed)."
            if result.objective == "speed" else
            "A candidate replaces the original when it is within the tolerance, simpler "
            "(in this order: Mitsuba's built-in of the same model, a lobe fewer, a fitted "
            "model of fewer lobes or parameters, a feature left out: the energy compensation, "
            "the exact Fresnel term, Oren-Nayar's full form) and not measurably slower; of "
            "several, the fastest (objective simplicity; see `mi_brdfs.simplify`)."), "",
        f"The original scene: {original['ref_seconds_per_spp'] * 1e3:.3g} ms per spp, "
        f"relative variance of a 1-spp image {original['variance_1spp_ref']:.3g}, so "
        f"{_seconds(original_time)} to reach {result.tolerance:g}.", "",
        "## Materials", "", result.tables(), "",
        "## Result", ""]
    lines += [f"* {line}" for line in result.verdict_lines() if not line.startswith("wrote ")]
    if result.predicted and any(m.chosen for m in result.materials):
        p = result.predicted
        lines.append(f"* predicted from the parts: bias {p['bias']:.4f}, cost/spp "
                     f"{p['cost_ratio']:.3f}×, variance {p['variance_ratio']:.3f}×, speed-up "
                     f"{_ratio(p['speedup'], p.get('speedup_se', math.nan))}")
    lines += [f"* note: {n}" for n in result.notes]
    if result.figure:
        lines += ["", f"![error against time]({os.path.relpath(result.figure, path.parent)})"]
    if result.replacements:
        lines += ["", "## Replaced elements", ""]
        for r in result.materials:
            if r.chosen:
                lines += [f"{r.label}:", "", "```xml", r.material.indent + r.material.text,
                          "```", "→", "```xml",
                          r.material.indent + r.candidates[r.chosen].xml, "```", ""]
    with atomic_path(path, ".md") as tmp:
        Path(tmp).write_text("\n".join(lines) + "\n")
    return path
