"""
The ``mi-brdfs`` subcommands: one ``cmd_*`` function each, which takes the parsed arguments
(:mod:`mi_brdfs.cli.parser`) and returns the exit status, and the helpers they share.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..bsdfspec import loaded_once

EXIT_USER_ERROR = 2
EXIT_INTERRUPTED = 130


def _bsdfs(tokens):
    from ..bsdfspec import load_bsdf, parse_cli

    specs = parse_cli(tokens)
    for spec in specs:
        load_bsdf(spec)  # reject bad parameters before any long work, in one line
    return specs


def _thetas(text):
    from ..errors import MiBrdfsError

    if text is None:
        return None
    try:
        values = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise MiBrdfsError(f"--thetas expects degrees separated by commas, got '{text}'") from None
    if not values or any(not 0 <= v <= 90 for v in values):
        raise MiBrdfsError(f"--thetas: angles must lie in [0, 90] degrees, got '{text}'")
    return values


@loaded_once()
def cmd_check(args) -> int:
    import json

    import mi_brdfs
    from ..bsdfspec import describe
    from ..checks import format_table, run_battery

    from ..imageio import check_writable

    json_path = check_writable(args.json) if args.json else None
    variant = mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    failed, report = 0, []
    for spec in specs:
        results = run_battery(spec, quick=args.quick, render=args.render,
                              progress=not args.quiet, gradients=args.gradients)
        failed += sum(not r.passed for r in results)
        print(f"\n{describe(spec)} ({variant})")
        print(format_table(results, messages=not args.quiet))
        report.append({"bsdf": describe(spec), "variant": variant, "checks": [
            {"name": r.name, "passed": r.passed, "value": r.value, "tolerance": str(r.tolerance),
             "message": r.message} for r in results]})
    if json_path:
        from ..imageio import atomic_path
        with atomic_path(json_path, ".json") as tmp:
            with open(tmp, "w") as f:
                json.dump(_strict_json(report), f, indent=1, allow_nan=False)
    print(f"\n{failed} check(s) failed" if failed else "\nall checks passed")
    return 1 if failed else 0


@loaded_once()
def cmd_furnace(args) -> int:
    import mi_brdfs
    from ..bsdfspec import describe
    from ..checks.albedo import DEFAULT_THETAS, albedo_curve
    from ..checks.furnace import check_furnace
    from ..imageio import check_writable, write_exr, write_png

    variant = mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    thetas = _thetas(args.thetas) or DEFAULT_THETAS
    out = check_writable(args.output) if args.render else None
    for spec in specs:
        curve = albedo_curve(spec, thetas, n=args.samples, progress=True)
        print(f"\ndirectional albedo of {describe(spec)} ({variant}; brightest channel)")
        print(curve.table())
        for note in curve.notes:
            print(f"note: {note}")
    if args.render:
        result = check_furnace(specs[0], spp=args.spp, res=args.res, n=args.samples)
        r = result.details["render"]
        meta = {"mi_brdfs.check": "white furnace", "furnace.bsdf": describe(specs[0]),
                "furnace.mean": f"{r.mean:.6f}", "furnace.expected": str(r.expected),
                "furnace.nonfinite": r.nonfinite, "render.variant": variant,
                "render.spp": r.spp, "mi_brdfs.version": mi_brdfs.__version__}
        write_exr(out, r.image, meta)
        write_png(out.with_suffix(".png"), r.image)
        print(f"\n{result.message}\nwrote {out} and {out.with_suffix('.png')}")
        return 0 if result.passed else 1
    return 0


def cmd_plot(args) -> int:
    import mi_brdfs
    from .. import plots
    from ..imageio import check_writable

    mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    out = check_writable(args.output or f"{args.kind}.png")
    thetas = _thetas(args.thetas)
    if args.kind == "lobe":
        plots.plot_lobe(specs, out, thetas or (0.0, 30.0, 60.0, 80.0), log=args.log,
                        cosine=not args.no_cos)
    elif args.kind == "albedo":
        plots.plot_albedo(specs, out, thetas, n=args.samples)
    else:
        plots.plot_slice(specs, out, res=args.res)
    print(f"wrote {out}")
    return 0


def cmd_render(args) -> int:
    import mi_brdfs
    from ..imageio import check_writable, write_exr, write_png
    from ..render import render
    from ..scenes import parse_defines, scene_path

    path = scene_path(args.scene)
    out = check_writable(Path(args.output) if args.output else Path.cwd() / f"{path.stem}.exr")
    png = out.with_suffix(".png")
    if not args.no_png:
        check_writable(png)
    defines = parse_defines(args.defines)
    variant = mi_brdfs.use_variant(args.variant)

    result = render(path, spp=args.spp, seed=args.seed, time_budget=args.time_budget,
                    defines=defines, pass_spp=args.pass_spp, processes=args.processes,
                    progress=not args.quiet)
    write_exr(out, result.image, result.metadata())
    written = [str(out)]
    if not args.no_png:
        write_png(png, result.image, exposure=args.exposure)
        written.append(str(png))
    h, w = result.image.shape[:2]
    state = "interrupted after" if result.interrupted else "rendered"
    print(f"{state} {result.spp} spp of {w}×{h} in {result.wall_time:.2f} s "
          f"({variant}, {result.arrangement}); wrote {' and '.join(written)}")
    return EXIT_INTERRUPTED if result.interrupted else 0


def cmd_compare(args) -> int:
    import mi_brdfs
    from ..compare import compare, parse_swaps, write_outputs
    from ..errors import MiBrdfsError
    from ..imageio import check_writable
    from ..scenes import parse_defines, scene_path

    if len(args.scenes) > 2 or (len(args.scenes) == 1 and not args.swap):
        raise MiBrdfsError("compare takes A.xml B.xml, or one scene with --swap ID=BSDF")
    paths = [scene_path(s) for s in args.scenes]
    out = check_writable(args.output)
    swaps = parse_swaps(args.swap)
    defines = parse_defines(args.defines)
    mi_brdfs.use_variant(args.variant)
    result = compare(paths[0], paths[1] if len(paths) > 1 else None, swap=swaps or None,
                     spp=args.spp, seed=args.seed, defines=defines)
    written = write_outputs(result, out)
    print(result.summary())
    for note in result.notes:
        print(f"note: {note}")
    print("wrote " + ", ".join(written))
    return 0


def cmd_fit(args) -> int:
    import mi_brdfs
    from ..bsdfspec import parse_cli
    from ..fit import fit, plot_fit, write_json
    from ..imageio import check_writable

    json_path = check_writable(args.output) if args.output else None
    plot_path = check_writable(args.plot) if args.plot else None
    if plot_path or args.models:
        from ..plots import pyplot
        pyplot()  # matplotlib missing: say so before the fit
    mi_brdfs.use_variant(args.variant, fallback=False)
    targets = parse_cli(args.target)
    if args.models and (len(targets) > 1 or args.scheduler or args.workers):
        return _sweep(args, targets)
    (target,) = _one_bsdf(targets, "TARGET")
    if args.models:
        return _fit_models(args, target)
    (model,) = _one_bsdf(parse_cli(args.model), "--model")
    result = fit(target, model, args.free, pairs=args.pairs, steps=args.steps, seed=args.seed,
                 variant=args.variant, progress=not args.quiet, metric=args.metric)
    print(result.summary())
    written = []
    if json_path:
        written.append(write_json(result, json_path))
    if plot_path:
        written.append(plot_fit(result, plot_path))
    if written:
        print("wrote " + " and ".join(written))
    return 0


def _fit_models(args, target) -> int:
    """``mi-brdfs fit TARGET --models ...``."""
    from ..errors import MiBrdfsError
    from ..fit.models import chosen, fit_models, published_table, ranking_table
    from ..fit.optimise import METRICS
    from ..markdown import md_table

    names = chosen(args.models)
    if args.free or args.output or args.plot:
        raise MiBrdfsError("--models writes its own report (--out DIR): --free, -o and --plot "
                           "go with --model")
    material = args.compare_published
    if material == "":  # the name of the MERL file
        if not (isinstance(target, dict) and target["type"] == "merl"):
            raise MiBrdfsError("--compare-published without a MATERIAL needs a MERL .binary "
                               "TARGET, whose file name is the material's")
        material = Path(target["filename"]).stem
    out = _report_folder(args, "models.md")
    done = fit_models(target, names, args.metric, out, pairs=args.pairs, steps=args.steps,
                      seed=args.seed, progress=not args.quiet, compare_published=material)
    print(md_table(["model", *METRICS], ranking_table(done["scores"])))
    if done["published"] is not None:
        print(md_table(["model", f"ours ({args.metric})", "published", "published / ours"],
                       published_table(done["scores"], done["published"], args.metric)))
    print("wrote " + ", ".join(done["written"]))
    return 0


def _sweep(args, targets) -> int:
    """``mi-brdfs fit A.binary B.binary ... --models ...``: one task per (file, model)."""
    from ..errors import MiBrdfsError
    from ..fit.models import chosen
    from ..fit.sweep import sweep

    files = [t["filename"] for t in targets if isinstance(t, dict) and t["type"] == "merl"
             and set(t) == {"type", "filename"}]
    if len(files) != len(targets):
        raise MiBrdfsError("a sweep (several TARGETs, --workers or --scheduler) takes MERL "
                           ".binary files only")
    names = chosen(args.models)
    out = _report_folder(args, "sweep.md")
    done = sweep(files, names, args.metric, out, pairs=args.pairs, steps=args.steps,
                 seed=args.seed, workers=args.workers, scheduler=args.scheduler,
                 progress=not args.quiet)
    print(Path(done["written"][0]).read_text())
    print(f"{done['computed']} fits computed, {len(done['results']) - done['computed']} from "
          f"the cache; wrote " + ", ".join(done["written"]))
    return 0


def cmd_simplify(args) -> int:
    import mi_brdfs
    from ..imageio import check_writable
    from ..scenes import parse_defines, scene_path
    from ..simplify import simplify

    path = scene_path(args.scene)
    out = check_writable(Path(args.output) if args.output
                         else Path.cwd() / f"{path.stem}-simplified.xml")
    defines = parse_defines(args.defines)
    mi_brdfs.use_variant(args.variant)
    result = simplify(path, args.tolerance, output=out, report=args.report, quick=args.quick,
                      spp=args.spp, defines=defines, cache=not args.no_cache,
                      confidence=args.confidence, objective=args.objective,
                      progress=not args.quiet)
    print(result.summary())
    return 0


def _one_bsdf(specs: list, what: str) -> list:
    from ..errors import MiBrdfsError

    if len(specs) != 1:
        raise MiBrdfsError(f"{what} names {len(specs)} BSDFs; give one")
    return specs


def _report_folder(args, filename: str) -> Path:
    """The report folder (created), checked writable for ``filename`` before any work."""
    from ..imageio import output_folder

    return output_folder(args.out, f"--out {args.out}", filename)


def _jit_variant(what: str) -> str:
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
    out = _report_folder(args, kwargs.get("filename", "REPORT.md"))
    variant = _jit_variant(f"the {kwargs.get('title', 'report')}")
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


def _strict_json(value):
    """``value`` for strict JSON: numbers as floats, NaN and infinities (a check without a
    value, a tolerance of inf) as the strings "nan", "inf", "-inf", which JSON has no token
    for."""
    import math

    if isinstance(value, dict):
        return {str(k): _strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_strict_json(v) for v in value]
    if isinstance(value, (str, bool)) or value is None:
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        return str(value)
    return number if math.isfinite(number) else str(number)


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
    in ``kwargs`` says which. An unknown name, or ``--only`` with ``--readme`` (a partial run
    cannot fill every quoted figure), is one error."""
    from ..errors import MiBrdfsError

    if getattr(args, "only", None) is None:
        return sections
    names = _only_names(args.only)
    known = [section_name(s) for s in sections]
    unknown = [n for n in names if n not in known]
    if unknown:
        raise MiBrdfsError(f"--only {args.only}: no section {', '.join(unknown) or 'named'} "
                           f"(sections: {', '.join(known)})")
    if getattr(args, "readme", None):
        raise MiBrdfsError("--only with --readme: a partial run cannot fill every figure the "
                           "documents quote; run without --only")
    kwargs["command"] = kwargs.get("command", "mi-brdfs validate") + f" --only {args.only}"
    return [s for s in sections if section_name(s) in names]


def cmd_audit(args) -> int:
    import os
    import time

    from ..audit import grid, report, run
    from ..errors import MiBrdfsError
    from ..registry import use_variant

    if not args.variant.startswith(("llvm_", "cuda_")):
        raise MiBrdfsError(f"--variant {args.variant}: the audit needs a JIT variant (χ² runs "
                           f"on mitsuba.chi2), e.g. llvm_ad_rgb")
    out = _report_folder(args, "MITSUBA_AUDIT.md")
    use_variant(args.variant, fallback=False)  # fail here, in one line, if it is unusable
    cases = grid.all_cases()
    if args.quick:
        cases = [c for c in cases if c.quick]
    if args.only is not None:
        names = set(_only_names(args.only))
        unknown = names - {c.bsdf for c in grid.all_cases()}
        if unknown:
            raise MiBrdfsError(f"--only {args.only}: no audit configuration for "
                               f"{', '.join(sorted(unknown))} (the audit knows: "
                               f"{', '.join(sorted({c.bsdf for c in grid.all_cases()}))})")
        cases = [c for c in cases if c.bsdf in names]
        if not cases:  # before anything is written: the report stays as it was
            raise MiBrdfsError(f"--only {args.only} --quick: none of these is in the quick "
                               f"audit (its BSDFs: "
                               f"{', '.join(sorted({c.bsdf for c in grid.all_cases() if c.quick}))}"
                               f"); leave --quick out")
    t0 = time.perf_counter()
    records = run.run(cases, args.variant, args.quick, out / "audit" / ".cache",
                      processes=args.processes or min(os.cpu_count() or 1, 4),
                      progress=not args.quiet)
    exits = None
    if not args.quick and not args.only:  # the whole audit reruns its evidence
        from ..audit import reproducers
        exits = reproducers.run_all(processes=args.processes or 2)
    command = "mi-brdfs audit" + (" --quick" if args.quick else "") + \
        (f" --only {args.only}" if args.only else "") + \
        (f" --variant {args.variant}" if args.variant != "llvm_ad_rgb" else "")
    md, js, counts = report.write(records, out, command, time.perf_counter() - t0,
                                  args.variant, args.quick, exits=exits)
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


def cmd_measure(args) -> int:
    import numpy as np

    from ..errors import MiBrdfsError
    from ..imageio import check_writable
    from ..measured.tabulate import measure

    from ..registry import use_variant

    out = check_writable(args.output)
    use_variant(args.variant or "llvm_ad_rgb", fallback=False)
    specs = _bsdfs(args.bsdf)
    if len(specs) != 1:
        raise MiBrdfsError(f"measure: {len(specs)} BSDFs given; give one")
    values = measure(specs[0], out, variant=args.variant, noise=args.noise, seed=args.seed)
    measured = int(np.count_nonzero(~np.isnan(values[0])))
    print(f"wrote {out}: {measured} of {values[0].size} bins measured (the others below the "
          f"horizon), f up to {np.nanmax(values):.4g}")
    return 0


def cmd_tables(args) -> int:
    from .. import albedo_tables as tables
    from ..progress import Progress
    from ..scattering.multiscatter import TABLE_PATH

    from ..imageio import check_writable

    _jit_variant("mi-brdfs tables")
    out = check_writable(args.out or TABLE_PATH)  # before minutes of work, not after
    samples = args.samples or tables.SAMPLES
    samples_dielectric = args.samples or tables.SAMPLES_DIELECTRIC
    rows = len(tables.KINDS) * (len(tables.SHADOWINGS) * tables.N_ALPHA +
                                tables.N_ETA * tables.N_ALPHA_DIELECTRIC)
    progress = Progress(rows, "albedo tables", unit="rows")
    arrays = tables.build(samples=samples, progress=progress)
    arrays.update(tables.build_dielectric(samples=samples_dielectric, progress=progress))
    progress.close()
    tables.write(out, arrays)
    print(f"wrote {out}: E(mu, alpha) on {tables.N_MU} x {tables.N_ALPHA} nodes for "
          f"{', '.join(k[2:] for k in arrays if k.startswith('E_') and 'avg' not in k)} "
          f"({samples} x {samples} samples per node); E(mu, alpha, eta) of the dielectric on "
          f"{tables.N_MU_DIELECTRIC} x {tables.N_ALPHA_DIELECTRIC} x {tables.N_ETA} nodes "
          f"({samples_dielectric} x {samples_dielectric} samples per node)")
    return 0


def cmd_info(args) -> int:
    import drjit as dr
    import mitsuba as mi

    import mi_brdfs
    from .. import _env

    status = _env.find_llvm()
    print(f"mi_brdfs  {mi_brdfs.__version__}")
    print(f"mitsuba   {mi.__version__}   drjit {dr.__version__}   python {sys.version.split()[0]}")
    print(f"libLLVM   {status.path if status.ok else 'none that works'}"
          + (f" (LLVM {'.'.join(map(str, status.version))})" if status.ok else ""))
    for path, verdict in status.tried:
        print(f"          tried {path}: {verdict}")
    if not status.ok:
        print(f"          {status.message}")
    print(f"default   {mi_brdfs.default_variant()}")
    print(f"variants  {', '.join(mi.variants())}")
    print(f"plugins   {', '.join(mi_brdfs.PLUGINS)}")
    return 0
