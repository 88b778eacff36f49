"""
The audit's outputs: ``MITSUBA_AUDIT.md`` (a verdict table, then each defect with its numbers,
reproducer, source location and impact, then each check limitation and model property) and
``audit/findings.json`` (one object per BSDF × configuration × check).
"""

from __future__ import annotations

import json
import platform
import re
from collections import Counter, defaultdict
from pathlib import Path

from . import triage

#: Short column names of the verdict table, in order.
COLUMNS = (("consistency", "consistency"), ("chi2", "χ² (ours)"),
           ("mitsuba chi2", "χ² (Mitsuba's harness)"), ("energy", "energy"),
           ("albedo", "albedo"), ("lobes", "lobes"), ("pdf integral", "∫ pdf"),
           ("reciprocity", "reciprocity"), ("positivity", "positivity"),
           ("stability", "stability"), ("gradients", "gradients"), ("sides", "sides"),
           ("load", "loads"),
           ("crash", "crash"))

#: The variant whose audit the report names when it was made in another one.
GPU_VARIANT = "cuda_ad_rgb"

MARK = {"pass": "✓", "defect": "**defect**", "check-limitation": "check-lim.",
        "model-property": "model", "statistical": "stat.", "untriaged": "**untriaged**",
        "skipped": "n/a"}

#: Which verdict a cell shows when its checks (e.g. χ² at three angles) have several: the most
#: important first.
PRIORITY = ("untriaged", "defect", "model-property", "check-limitation", "statistical", "pass",
            "skipped")


def _column(check: str) -> str:
    for key, _ in COLUMNS:
        if check == key or check.startswith(key + " "):
            return key
    return check


def findings_list(records: list[dict], table=None) -> list[dict]:
    """One object per record that was judged (skipped checks are left out): bsdf, config,
    check, verdict, summary, reproducer, source, issue, fixed_upstream."""
    out = []
    for r in records:
        if r.get("skipped"):
            continue
        verdict, finding = triage.verdict(r, table)
        out.append({"bsdf": r["bsdf"], "config": r["config"], "check": r["check"],
                    "verdict": verdict,
                    "summary": finding.summary if finding else
                    (r["message"] if verdict != "untriaged" else "UNTRIAGED: " + r["message"]),
                    "reproducer": finding.reproducer if finding else None,
                    "source": finding.source if finding else None,
                    "issue": finding.issue if finding else None,
                    "fixed_upstream": finding.fixed_upstream if finding else None})
    return out


def _cell(verdicts: list[tuple]) -> str:
    """The most important (verdict, fixed upstream) of a cell; ⁺ marks a defect that is fixed
    upstream in every record of the cell that shows it."""
    if not verdicts:
        return ""
    worst = min((v for v, _ in verdicts), key=PRIORITY.index)
    fixed = worst == "defect" and all(f for v, f in verdicts if v == worst)
    return MARK[worst] + (" ⁺" if fixed else "")


def paths(out: Path, quick: bool, build: tuple | None = None) -> tuple[Path, Path]:
    """The report and its findings in the folder ``out``: ``MITSUBA_AUDIT.md`` and
    ``audit/findings.json`` for Mitsuba itself; for a fork (``build``: its distribution and
    version, :func:`mi_brdfs.registry.mitsuba_build`), ``audit/<name>.md`` and
    ``audit/<name>/findings.json`` (``eradiate`` for ``eradiate-mitsuba``), beside Mitsuba's."""
    tail = "-quick" if quick else ""
    if build is None or build[0] == "mitsuba":
        return out / f"MITSUBA_AUDIT{tail}.md", out / "audit" / f"findings{tail}.json"
    name = fork_name(build)
    return out / "audit" / f"{name}{tail}.md", out / "audit" / name / f"findings{tail}.json"


def fork_name(build: tuple) -> str:
    """The short name of a fork's files: ``eradiate`` for ``eradiate-mitsuba``."""
    return build[0].removesuffix("-mitsuba")


def write(records: list[dict], out: Path, command: str, seconds: float, variant: str,
          quick: bool, table=None, exits: dict | None = None,
          build: tuple | None = None) -> tuple[Path, Path, Counter]:
    """
    Write the report and the findings (:func:`paths`); returns their paths and the count of
    verdicts. ``exits``: the exit status of each reproducer in this run (:mod:`.reproducers`),
    None where they were not run. ``build``: the Mitsuba fork audited (None: Mitsuba).
    """
    fork = build is not None and build[0] != "mitsuba"
    table = triage.findings(build[0] if build else None) if table is None else table
    md_path, json_path = paths(out, quick, build)
    json_path.parent.mkdir(parents=True, exist_ok=True)
    items = findings_list(records, table)
    counts = Counter(f["verdict"] for f in items)
    json_path.write_text(json.dumps(items, indent=1, ensure_ascii=False) + "\n")

    lines = _introduction(command, seconds, variant, quick, counts, build if fork else None)
    lines += _verdict_table(records, table, build[0] if fork else "mitsuba")
    lines += _finding_sections(records, items, table, exits, fork)
    lines += _coverage(records)
    lines += _limitations()
    lines += _untriaged(records, table)
    text = "\n".join(lines)
    if fork:  # links are written relative to the repository's root from OUT: one folder deeper
        text = text.replace("](../", "](../../")
    md_path.write_text(text)
    return md_path, json_path, counts


def _introduction(command: str, seconds: float, variant: str, quick: bool,
                  counts: Counter, fork: tuple | None = None) -> list[str]:
    """The report's title, how it was made, what it runs and the count of each verdict."""
    import mitsuba as mi

    from .._version import __version__

    title = (f"{fork[0]} {fork[1]}'s BSDFs (Mitsuba {mi.__version__})" if fork else
             f"Mitsuba {mi.__version__}'s BSDFs")
    lines = [f"# Audit of {title}", "",
             f"Generated by `{command}` (mi_brdfs {__version__}, {variant}, Python "
             f"{platform.python_version()}, {platform.machine()}) in {seconds / 60:.1f} min"
             + (" — **quick mode**: fewer samples, fewer configurations." if quick else "."),
             "", "Every BSDF plugin of the installed Mitsuba that can be built standalone, and "
             + ("the fork's own" if fork else "the package's own") + ", over a grid of "
             "configurations ([`mi_brdfs/audit/grid.py`](../mi_brdfs/audit/grid.py)), "
             "through the battery of `mi-brdfs check` (consistency, χ² at normal, 45° and "
             "grazing incidence, energy, albedo agreement, reciprocity, positivity, "
             "stability, and the gradients of every differentiable parameter: `mi-brdfs "
             "check --gradients`), the audit's own check of BSDFs whose lobes differ by side "
             "at back-facing wi (sides: [`mi_brdfs/audit/sides.py`]"
             "(../mi_brdfs/audit/sides.py)) and Mitsuba's own χ² "
             "harness (`mi.chi2.BSDFAdapter`, default resolution). Every failure has one "
             "verdict ([`mi_brdfs/audit/triage.py`](../mi_brdfs/audit/triage.py)): "
             "**defect** (of the BSDF: a standalone reproducer exits 1 while it is present), "
             "**check-lim.** (a limitation of the check, shown by a finer check that passes), "
             "**model** (declared by the BSDF or inherent to the published model), **stat.** "
             "(a false rejection other seeds do not repeat); ✓ passed, n/a not applicable.", "",
             "Verdicts: " + ", ".join(f"{counts[v]} {v}" for v in (*triage.VERDICTS, "untriaged")
                                      if counts[v]) + ".", ""]
    lines += _variants(variant)
    if fork:
        lines += _fork_note(fork)
    if counts["untriaged"]:
        lines += [f"**{counts['untriaged']} failures are not triaged yet** (listed at the end).",
                  ""]
    return lines


def _fork_note(fork: tuple) -> list[str]:
    """What differs in the audit of a fork: the plugins, the triage, the reproducers."""
    name = fork_name(fork)
    return [f"This build is a fork of Mitsuba: the audit runs Mitsuba's built-in BSDFs as this "
            f"build ships them and the plugins the fork adds, not the package's own (audited "
            f"under Mitsuba itself: [`MITSUBA_AUDIT.md`](../validation/MITSUBA_AUDIT.md)); "
            f"where a plugin of the fork has the name of one of the package's, the fork's is "
            f"the one loaded and audited (`mi_brdfs.registry.own_plugins`). A failure of a "
            f"built-in takes the verdict of the same failure in Mitsuba's own audit, whose "
            f"reproducers (`validation/audit/repro_*.py`) the whole audit reruns under this "
            f"build: exit 1, the defect is in this build too; exit 0, it is not (absent from "
            f"this older "
            f"Mitsuba, or fixed). The findings about the fork's own plugins have their "
            f"reproducers in [`validation/audit/{name}/`]({name}/), each runnable with this "
            f"build's Python alone (`make audit-{name}` sets up `.venv-{name}` and regenerates "
            f"this report).", ""]


def _variants(variant: str) -> list[str]:
    """Which variants the report ran, and how to run the GPU audit where it did not."""
    from .grid import polarized_variant

    text = (f"Variants: `{variant}`, and `{polarized_variant(variant)}` for the polarized BSDFs "
            f"(the configurations marked so). Only these ran.")
    if not variant.startswith("cuda"):
        text += (f" **The `{GPU_VARIANT}` audit was not run for this report**, and nothing here "
                 f"is a result of it: it needs a CUDA GPU. On a machine with one, "
                 f"`mi-brdfs audit --variant {GPU_VARIANT} --out DIR` runs the same grid "
                 f"(polarized BSDFs in `{polarized_variant(GPU_VARIANT)}`) and writes "
                 f"DIR/MITSUBA_AUDIT.md; the reproducers in `validation/audit/` set "
                 f"`llvm_ad_rgb` and run in a cuda variant by changing that line.")
    return [text, ""]


def _coverage(records: list[dict]) -> list[str]:
    """Per built-in plugin the report ran, a table of its switches (:mod:`.switches`): the
    configurations in each state, or why the grid leaves the switch at its default."""
    from . import grid, switches

    ran = {(r["bsdf"], r["config"]) for r in records}
    table = switches.coverage([c for c in grid.mitsuba_cases() if (c.bsdf, c.config) in ran])
    if not table:
        return []
    lines = ["## Coverage: the switches of the built-in BSDFs", "",
             "Every parameter of a built-in BSDF whose value selects a code path of Mitsuba "
             "3.9.1's plugin ([`mi_brdfs/audit/switches.py`](../mi_brdfs/audit/switches.py)), "
             "with the configurations of this report in each of its states, read off the "
             "grid's configurations. Parameters that only change a value (α, η, a colour, a "
             "sampling rate, a tilt) are not switches.", ""]
    for plugin, rows in table.items():
        if not rows:
            continue
        every = {c for row in rows for names in row.configs.values() for c in names}
        lines += [f"### `{plugin}`", "",
                  "| switch | selects | configurations per state | left at its default: why |",
                  "|---|---|---|---|"]
        for row in rows:
            states = "; ".join(
                f"{state}: " + ("—" if not row.configs.get(state) else
                                f"all {len(every)}" if set(row.configs[state]) == every else
                                ", ".join(row.configs[state]))
                for state in row.switch.states)
            why = row.switch.default_only or (
                f"**not exercised here: {', '.join(row.missing)}**" if row.missing else "")
            lines.append(f"| `{row.switch.name}` | {row.switch.selects} | {states} | {why} |")
        lines.append("")
    plain = [f"`{p}`" for p, rows in table.items() if not rows]
    if plain:
        lines += ["No switch (one code path, parameters that are values only): "
                  + ", ".join(plain) + ".", ""]
    return lines


def _verdict_table(records: list[dict], table, build: str = "mitsuba") -> list[str]:
    """One row per BSDF × configuration, one column per check that ran, then the BSDFs that
    are not built standalone."""
    from .grid import skipped_for

    cells: dict = defaultdict(lambda: defaultdict(list))
    order: list = []
    for r in records:
        key = (r["bsdf"], r["config"])
        if key not in cells:
            order.append(key)
        v, finding = ("skipped", None) if r.get("skipped") else triage.verdict(r, table)
        cells[key][_column(r["check"])].append((v, bool(finding and finding.fixed_upstream)))
    used = [(k, name) for k, name in COLUMNS if any(cells[key][k] for key in order)]

    header = ["BSDF", "configuration"] + [name for _, name in used]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for key in order:
        lines.append("| " + " | ".join([f"`{key[0]}`", key[1]] +
                                       [_cell(cells[key][k]) for k, _ in used]) + " |")
    skipped = "; ".join(f"`{k}` ({why})" for k, why in skipped_for(build).items())
    lines += ["", "⁺ fixed upstream after the audited release (the finding says where). Not "
              f"built standalone: {skipped}.", ""]
    return lines


def _finding_sections(records: list[dict], items: list[dict], table,
                      exits: dict | None = None, fork: bool = False) -> list[str]:
    """A section per verdict (defects, model properties, check limitations, statistical): each
    finding that some record has, with its summary, reproducer, source and records."""
    by_finding: dict = defaultdict(list)
    for r, f in zip([r for r in records if not r.get("skipped")], items):
        verdict, finding = triage.verdict(r, table)
        if finding is not None:
            by_finding[finding].append(f"{r['config']}: {r['check']}")
    lines = []
    for verdict, title in (("defect", "Defects"), ("model-property", "Model properties"),
                           ("check-limitation", "Check limitations"),
                           ("statistical", "Statistical")):
        chosen = [f for f in table if f.verdict == verdict and by_finding.get(f)]
        if not chosen:
            continue
        lines += [f"## {title}", ""]
        for f in chosen:
            checks = " or ".join(re.sub(r"[()^$]", "", f.check).split("|"))
            lines += [f"### `{f.bsdf}`: {checks} ({len(by_finding[f])} records)",
                      "", f.summary, ""]
            if f.reproducer:
                lines.append(f"- Reproducer: [`{f.reproducer}`](../{f.reproducer}) "
                             f"(exits 1 while the defect is present)" + _rerun(f, exits, fork))
            if f.source:
                lines.append(f"- Source: {f.source}")
            if f.issue:
                lines.append(f"- Issue text and prior art: [`{f.issue}`](../{f.issue})")
            if f.verdict == "defect":
                lines.append("- Fixed upstream: " + (f.fixed_upstream or
                                                     "no (see the issue text's prior art)"))
            lines.append("- Records: " + "; ".join(sorted(set(by_finding[f]))[:12]))
            lines.append("")
    return lines


def _rerun(finding, exits: dict | None, fork: bool = False) -> str:
    """What this run's rerun of a finding's reproducer said, where the audit reran them."""
    from .reproducers import describe

    if exits is None or finding.reproducer not in exits:
        return "; not rerun in this run (`make audit` reruns them)"
    return "; " + describe(exits[finding.reproducer], fork)


def _limitations() -> list[str]:
    """The table of the check limitations the audit exposed, with their fixes and tests."""
    lines = ["## Limitations of our checks that the audit exposed, and their fixes", "",
             "| what the check got wrong | the fix | test (fails with the old check) |",
             "|---|---|---|"]
    lines += [f"| {what} | {fix} | `{path}::{test}` |"
              for what, fix, (path, test) in triage.FIXED_LIMITATIONS]
    lines.append("")
    return lines


def _untriaged(records: list[dict], table) -> list[str]:
    """The failures without a verdict yet, one line each (none: no section)."""
    untriaged = [r for r in records if not r.get("skipped") and
                 triage.verdict(r, table)[0] == "untriaged"]
    lines = []
    if untriaged:
        lines += ["## Untriaged failures", ""]
        lines += [f"- `{r['bsdf']}` {r['config']}, {r['check']}: {r['message'][:400]}"
                  for r in untriaged]
        lines.append("")
    return lines
