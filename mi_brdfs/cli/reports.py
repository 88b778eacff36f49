"""
The commands that write a report into a folder, ``--out DIR`` (``validate``, ``bench``,
``audit``; ``fit --models`` and a sweep share :func:`report_folder`), and what they share: the
report's files checked before any work, the sections ``--only`` names, the quoted figures
``--readme`` fills in.
"""

from __future__ import annotations

from pathlib import Path


#: The files of each report in its folder (--out DIR), by its main file: those that one
#: already there refuses without --force (their figures go in DIR/figures/, the audit's cases
#: in DIR/audit/, a sweep's cache in DIR/.sweep-cache/).
REPORT_FILES = {
    "models.md": ("models.md", "models.json", "lobes.png", "spheres.png"),
    "sweep.md": ("sweep.md", "sweep.json"),
    "MITSUBA_AUDIT.md": ("MITSUBA_AUDIT.md", "audit/findings.json"),
    "MITSUBA_AUDIT-quick.md": ("MITSUBA_AUDIT-quick.md", "audit/findings-quick.json"),
}


def report_folder(args, filename: str) -> Path:
    """The report folder --out DIR (created), its files (:data:`REPORT_FILES`, else
    ``filename``) checked before any work: one already there is refused unless --force."""
    from ..imageio import planned_outputs

    out = Path(args.out).expanduser().absolute()
    planned_outputs(args.command, unnamed=[
        (out / name, "", "name another folder with --out")
        for name in REPORT_FILES.get(filename, (filename,))],
        force=args.force, folder=(out, f"--out {args.out}"))
    return out


def jit_variant(what: str) -> str:
    import mi_brdfs
    from ..errors import MiBrdfsError

    variant = mi_brdfs.use_variant(None)
    if not variant.startswith(("llvm", "cuda")):
        raise MiBrdfsError(f"{what} needs a JIT variant; {variant} is all this machine offers")
    return variant


def _run_report(args, sections, what: str, quotes: str | None = None, **kwargs) -> list:
    """
    Run a report's sections and print its verdict; the rows that are not as expected. With
    ``quotes`` (a tag) and ``args.readme``, the figures the document quotes under that tag are
    filled in from the run.
    """
    from ..campaign import Context, run
    from ..campaign.core import fill_quotes
    from ..errors import MiBrdfsError

    readmes = getattr(args, "readme", None) or []
    for readme in readmes:
        if not Path(readme).is_file():
            raise MiBrdfsError(f"--readme {readme}: no such file")
    sections = _only_sections(args, sections, kwargs)
    out = report_folder(args, kwargs.get("filename", "REPORT.md"))
    variant = jit_variant(f"the {kwargs.get('title', 'report')}")
    report, done, values = run(sections, Context(out=out, quick=args.quick, variant=variant),
                               progress=not args.quiet, what=what, **kwargs)
    rows = [r for s in done for r in s.rows]
    failed = [r for r in rows if not r.ok]
    if rows and not rows[0].judged:
        print(f"wrote {report}: {len(rows)} {what}, not judged (quick run: "
              f"{kwargs.get('quick_note', 'too small to judge')})")
    else:
        print(f"wrote {report}: {len(rows) - len(failed)} of {len(rows)} {what} as expected")
    for r in failed:
        print(f"  unexpected: {r.plugin}: {r.check}: {r.result} ({r.verdict})")
    for readme in readmes if quotes else []:
        count = fill_quotes(readme, values, quotes)
        print(f"updated {readme}: {count} figures quoted from {report.name}")
    return failed


def section_name(section) -> str:
    """A report section's name for ``--only``: the module that defines it (``campaign/ward.py``:
    ``ward``)."""
    return section.__module__.rsplit(".", 1)[-1]


def _only_names(value: str) -> list[str]:
    """The names of ``--only``, comma-separated; none at all (``--only ''``, ``--only ,``) is
    an error, not a run of everything or of nothing."""
    from ..errors import MiBrdfsError

    names = [n.strip() for n in value.split(",") if n.strip()]
    if not names:
        raise MiBrdfsError(f"--only {value!r} names nothing: give one or more names, "
                           f"comma-separated (or leave --only out to run everything)")
    return names


def _only_sections(args, sections, kwargs) -> list:
    """The sections ``--only`` names (all without it), in the report's order; the command line
    in ``kwargs`` says which. An unknown name is one error (``--only`` with ``--readme``, which
    a partial run cannot fill, is refused by cli.modes)."""
    from ..errors import MiBrdfsError

    if getattr(args, "only", None) is None:
        return sections
    names = _only_names(args.only)
    known = [section_name(s) for s in sections]
    unknown = [n for n in names if n not in known]
    if unknown:
        raise MiBrdfsError(f"--only {args.only}: no section {', '.join(unknown) or 'named'} "
                           f"(sections: {', '.join(known)})")
    kwargs["command"] = kwargs.get("command", "mi-brdfs validate") + f" --only {args.only}"
    return [s for s in sections if section_name(s) in names]


def cmd_audit(args) -> int:
    import os
    import time

    from ..audit import grid, report, run
    from ..errors import MiBrdfsError
    from ..registry import mitsuba_build, use_variant

    if not args.variant.startswith(("llvm_", "cuda_")):
        raise MiBrdfsError(f"--variant {args.variant}: the audit needs a JIT variant (χ² runs "
                           f"on mitsuba.chi2), e.g. llvm_ad_rgb")
    build = mitsuba_build()  # a fork of Mitsuba (Eradiate's) has its own report and cases
    md, _ = report.paths(Path(args.out), args.quick, build)
    out = report_folder(args, str(md.relative_to(args.out)))
    _, js = report.paths(out, args.quick, build)
    use_variant(args.variant, fallback=False)  # fail here, in one line, if it is unusable
    cases = grid.cases_for(build[0])
    if args.quick:
        cases = [c for c in cases if c.quick]
    if args.only is not None:
        names = set(_only_names(args.only))
        known = {c.bsdf for c in grid.cases_for(build[0])}
        unknown = names - known
        if unknown:
            raise MiBrdfsError(f"--only {args.only}: no audit configuration for "
                               f"{', '.join(sorted(unknown))} (the audit knows: "
                               f"{', '.join(sorted(known))})")
        cases = [c for c in cases if c.bsdf in names]
        if not cases:  # before anything is written: the report stays as it was
            raise MiBrdfsError(f"--only {args.only} --quick: none of these is in the quick "
                               f"audit (its BSDFs: "
                               f"{', '.join(sorted({c.bsdf for c in grid.all_cases() if c.quick}))}"
                               f"); leave --quick out")
    t0 = time.perf_counter()
    records = run.run(cases, args.variant, args.quick, js.parent / ".cache",
                      processes=args.processes or min(os.cpu_count() or 1, 4),
                      progress=not args.quiet)
    exits = None
    if not args.quick and not args.only:  # the whole audit reruns its evidence
        from ..audit import reproducers
        exits = reproducers.run_all(processes=args.processes or 2)
        if build[0] != "mitsuba":  # and the fork's own
            name = report.fork_name(build)
            exits.update(reproducers.run_all(reproducers.FOLDER / name, args.processes or 2,
                                             f"validation/audit/{name}"))
    command = "mi-brdfs audit" + (" --quick" if args.quick else "") + \
        (f" --only {args.only}" if args.only else "") + \
        (f" --variant {args.variant}" if args.variant != "llvm_ad_rgb" else "")
    md, js, counts = report.write(records, out, command, time.perf_counter() - t0,
                                  args.variant, args.quick, exits=exits, build=build)
    print(f"wrote {md} and {js}: " + ", ".join(f"{n} {v}" for v, n in sorted(counts.items())))
    broken = [p for p, code in (exits or {}).items() if code not in (0, 1)]
    for path in broken:
        print(f"  broken reproducer: {path} (neither 0 nor 1; see the report)")
    return 1 if counts.get("untriaged") or broken else 0


def cmd_validate(args) -> int:
    from ..campaign import sections

    return 1 if _run_report(args, sections(), "checks", quotes="report") else 0


def cmd_bench(args) -> int:
    from ..benchmark import sections

    _run_report(args, sections(), "measurements", quotes="bench",
                title="mi_brdfs speed vs accuracy",
                filename="SPEED_ACCURACY.md", command="mi-brdfs bench", make_target="make bench",
                quick_note="tiny renders whose timings are too short to judge the targets",
                judge_quick=False)
    return 0  # a benchmark reports targets met or missed; it does not fail
