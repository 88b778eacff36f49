"""
The ``mi-brdfs`` subcommands: one ``cmd_*`` function each, which takes the parsed arguments
(:mod:`mi_brdfs.cli.parser`) and returns the exit status, and the helpers they share.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..bsdfspec import loaded_once
from .reports import jit_variant as _jit_variant
from .reports import report_folder as _report_folder

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

    from ..imageio import planned_outputs

    json_path = planned_outputs("check", named=[args.json])[0] if args.json else None
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
    from ..imageio import write_exr, write_png

    thetas = _thetas(args.thetas) or DEFAULT_THETAS
    out, png = _exr_and_png(args, "furnace.exr", "name another EXR with -o") if args.render \
        else (None, None)
    variant = mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    for spec in specs:
        curve = albedo_curve(spec, thetas, n=args.samples, progress=True)
        print(f"\ndirectional albedo of {describe(spec)} (the black-sky albedo at sun zenith "
              f"θ; {variant}; brightest channel)")
        print(curve.table())
        for note in curve.notes:
            print(f"note: {note}")
        _white_sky(spec, args.samples)
    if args.render:
        result = check_furnace(specs[0], spp=args.spp, res=args.res, n=args.samples)
        r = result.details["render"]
        meta = {"mi_brdfs.check": "white furnace", "furnace.bsdf": describe(specs[0]),
                "furnace.mean": f"{r.mean:.6f}", "furnace.expected": str(r.expected),
                "furnace.nonfinite": r.nonfinite, "render.variant": variant,
                "render.spp": r.spp, "mi_brdfs.version": mi_brdfs.__version__}
        write_exr(out, r.image, meta)
        write_png(png, r.image)
        print(f"\n{result.message}\nwrote {out} and {png}")
        return 0 if result.passed else 1
    return 0


def _white_sky(spec, samples) -> None:
    """``furnace``'s white-sky albedo lines: the estimate, and the float64 model's own where
    it has one in closed form (``rtls``: its kernels' published integrals)."""
    from .. import reference
    from ..earth import white_sky_albedo

    print(white_sky_albedo(spec, n=samples).line())
    model = reference.for_spec(spec)
    if hasattr(model, "white_sky"):
        value = float(max(model.white_sky()))
        print(f"white-sky albedo of the float64 model ({type(model).__module__}, unclamped, "
              f"from its kernels' integrals): {value:.5f}")


def cmd_plot(args) -> int:
    import mi_brdfs
    from .. import plots
    from ..errors import MiBrdfsError

    thetas = _thetas(args.thetas)
    if args.kind == "pp" and thetas and max(thetas) >= 90:
        raise MiBrdfsError(f"plot pp: --thetas {args.thetas}: sun zeniths must lie in [0, 90) "
                           f"degrees (the BRF needs the sun above the horizon)")
    (out,) = _planned(args, args.output, f"{args.kind}.png")
    mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    if args.kind == "lobe":
        plots.plot_lobe(specs, out, thetas or (0.0, 30.0, 60.0, 80.0), log=args.log,
                        cosine=not args.no_cos)
    elif args.kind == "albedo":
        plots.plot_albedo(specs, out, thetas, n=args.samples)
    elif args.kind == "pp":
        plots.plot_principal_plane(specs, out, thetas)
    else:
        plots.plot_slice(specs, out, res=args.res)
    print(f"wrote {out}")
    return 0


def cmd_render(args) -> int:
    import mi_brdfs
    from ..imageio import write_exr, write_png
    from ..render import render
    from ..scenes import parse_defines, scene_path

    path = scene_path(args.scene)
    out, png = _exr_and_png(args, f"{path.stem}.exr", "name another EXR with -o, pass --no-png")
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
    from ..compare import compare, exr_paths, parse_swaps, write_outputs
    from ..errors import MiBrdfsError
    from ..scenes import parse_defines, scene_path

    if len(args.scenes) > 2:  # (one scene without --swap: cli.modes)
        raise MiBrdfsError("compare takes A.xml B.xml, or one scene with --swap ID=BSDF")
    paths = [scene_path(s) for s in args.scenes]
    out = Path(args.output or "compare.png")
    beside = [(p, "an EXR beside the figure", "name another figure with -o")
              for p in exr_paths(out).values()]
    (out, *_) = _planned(args, args.output, "compare.png", beside)
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
    from ..fit.models import chosen
    from ..imageio import planned_outputs
    from .modes import bsdf_count

    # the mode and its options are checked (cli.modes); --models '' or a typo, before any work
    names = chosen(args.models) if args.models is not None else None
    if names is not None and bsdf_count(args.target) > 1:
        mi_brdfs.use_variant(args.variant, fallback=False)
        return _sweep(args, parse_cli(args.target))
    json_path, plot_path = (planned_outputs("fit", named=[p])[0] if p else None
                            for p in (args.output, args.plot))
    if plot_path or names is not None:
        from ..plots import pyplot
        pyplot()  # matplotlib missing: say so before the fit
    mi_brdfs.use_variant(args.variant, fallback=False)
    (target,) = _one_bsdf(parse_cli(args.target), "TARGET")
    if names is not None:
        return _fit_models(args, target, names)
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


def _fit_models(args, target, names: list) -> int:
    """``mi-brdfs fit TARGET --models ...``: the report in --out DIR (cli.modes: by default a
    new folder named after TARGET)."""
    from ..fit.models import fit_models, published_table, ranking_table
    from ..fit.optimise import METRICS
    from ..markdown import md_table

    material = _published_material(args.compare_published, target)
    out = _report_folder(args, "models.md")
    done = fit_models(target, names, args.metric, out, pairs=args.pairs, steps=args.steps,
                      seed=args.seed, progress=not args.quiet, compare_published=material)
    print(md_table(["model", *METRICS], ranking_table(done["scores"])))
    if done["published"] is not None:
        print(md_table(["model", f"ours ({args.metric})", "published", "published / ours"],
                       published_table(done["scores"], done["published"], args.metric)))
    print("wrote " + ", ".join(done["written"]))
    return 0


def _published_material(material: str | None, target) -> str | None:
    """The MERL material of --compare-published (given, or the TARGET file's name), checked
    against the materials of the published fits before any fit runs."""
    import difflib

    from .. import presets
    from ..errors import MiBrdfsError

    if material is None:
        return None
    given = material != ""
    if not given:  # the name of the MERL file
        if not (isinstance(target, dict) and target["type"] == "merl"):
            raise MiBrdfsError("--compare-published without a MATERIAL needs a MERL .binary "
                               "TARGET, whose file name is the material's")
        material = Path(target["filename"]).stem
    known = presets.materials()
    if material not in known:
        close = difflib.get_close_matches(material, known, n=3, cutoff=0.6)
        hint = f"did you mean {' or '.join(close)}? " if close else ""
        among = f"among the {len(known)} materials of Ngan et al.'s published fits"
        if given:
            raise MiBrdfsError(f"--compare-published {material}: not {among} ({hint}mi-brdfs "
                               f"presets lists them)")
        raise MiBrdfsError(f"--compare-published: the TARGET file's name, {material}, is not "
                           f"{among}; name the material: --compare-published MATERIAL ({hint}"
                           f"mi-brdfs presets lists them)")
    return material


def _sweep(args, targets) -> int:
    """``mi-brdfs fit A.binary B.binary ... --models ...``: one task per (file, model)."""
    from ..bsdfspec import describe
    from ..errors import MiBrdfsError
    from ..fit.models import chosen
    from ..fit.sweep import check_files, sweep
    from ..runner import reach, scheduler_address

    address = scheduler_address(args.scheduler, "--scheduler") \
        if args.scheduler is not None else None
    merl = [isinstance(t, dict) and t["type"] == "merl" and set(t) == {"type", "filename"}
            for t in targets]
    if not all(merl):
        raise MiBrdfsError("fit: a sweep (several TARGETs with --models) takes MERL .binary "
                           "files only, not " + ", ".join(
                               describe(t) for t, m in zip(targets, merl) if not m))
    names = chosen(args.models)
    files = check_files([t["filename"] for t in targets])  # before the report folder: nothing
    if address is not None:                                 # made for a bad file or scheduler
        reach(address)
    out = _report_folder(args, "sweep.md")
    done = sweep(files, names, args.metric, out, pairs=args.pairs, steps=args.steps,
                 seed=args.seed, workers=args.workers, scheduler=address,
                 progress=not args.quiet)
    print(Path(done["written"][0]).read_text())
    print(f"{done['computed']} fits computed, {done['cached']} from the cache; wrote "
          + ", ".join(done["written"]))
    return 0


def cmd_simplify(args) -> int:
    import mi_brdfs
    from ..scenes import parse_defines, scene_path
    from ..simplify import simplify

    path = scene_path(args.scene)
    report = [(Path(args.report) / name, "", "name another folder with --report")
              for name in ("SIMPLIFY.md", "simplify.png")] if args.report else []
    (out, *_) = _planned(args, args.output, f"{path.stem}-simplified.xml", report)
    defines = parse_defines(args.defines)
    mi_brdfs.use_variant(args.variant)
    result = simplify(path, args.tolerance, output=out, report=args.report, quick=args.quick,
                      spp=args.spp, defines=defines, cache=not args.no_cache,
                      confidence=args.confidence, objective=args.objective,
                      progress=not args.quiet)
    print(result.summary())
    return 0


def _planned(args, named, default: str, beside=()) -> list[Path]:
    """
    The output the user named (``named``: -o's value, replaced if it exists) or else
    ``default`` in the current folder, then the files written ``beside`` it, as (path, what it
    is, advice): all checked before any work by :func:`mi_brdfs.imageio.planned_outputs`,
    which refuses a default or a file beside that exists unless --force. Absolute paths.
    """
    from ..imageio import planned_outputs

    if named:
        return planned_outputs(args.command, named=[named], unnamed=beside, force=args.force)
    return planned_outputs(args.command, unnamed=[(default, "", "name another with -o"),
                                                  *beside], force=args.force)


def _exr_and_png(args, default: str, advice: str) -> tuple:
    """(EXR, PNG preview beside it or None with --no-png): -o or ``default``, planned."""
    if getattr(args, "no_png", False):
        return _planned(args, args.output, default)[0], None
    png = Path(args.output or default).with_suffix(".png")
    return tuple(_planned(args, args.output, default,
                          [(png, "the PNG preview beside the EXR", advice)]))


def _one_bsdf(specs: list, what: str) -> list:
    from ..errors import MiBrdfsError

    if len(specs) != 1:
        raise MiBrdfsError(f"{what} names {len(specs)} BSDFs; give one")
    return specs


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


def cmd_measure(args) -> int:
    import numpy as np

    from ..errors import MiBrdfsError
    from ..imageio import planned_outputs
    from ..measured.tabulate import measure

    from ..registry import use_variant

    (out,) = planned_outputs("measure", named=[args.output])
    use_variant(args.variant or "llvm_ad_rgb", fallback=False)
    specs = _bsdfs(args.bsdf)
    if len(specs) != 1:
        raise MiBrdfsError(f"measure: {len(specs)} BSDFs given; give one")
    values = measure(specs[0], out, variant=args.variant, noise=args.noise or (0.0, 0.0),
                     seed=args.seed or 0)  # (--seed goes with --noise: cli.modes)
    measured = int(np.count_nonzero(~np.isnan(values[0])))
    print(f"wrote {out}: {measured} of {values[0].size} bins measured (the others below the "
          f"horizon), f up to {np.nanmax(values):.4g}")
    return 0


def cmd_tables(args) -> int:
    from .. import albedo_tables as tables
    from ..progress import Progress
    from ..scattering.multiscatter import TABLE_PATH

    from ..imageio import planned_outputs

    _jit_variant("mi-brdfs tables")
    # before minutes of work; without -o, the package's own tables, which it exists to rebuild
    (out,) = planned_outputs("tables", named=[args.out or TABLE_PATH])
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


def cmd_presets(args) -> int:
    """The materials of the published fits and the plugins that take each as a preset."""
    from .. import presets
    from ..errors import MiBrdfsError

    plugins = sorted(presets.DEFAULT_MODEL)
    if args.plugin is not None:
        if args.plugin not in plugins:
            raise MiBrdfsError(f"presets {args.plugin}: no presets; the plugins that take "
                               f"preset=... are {', '.join(plugins)}")
        names = presets.names(args.plugin)
        if not names:
            raise MiBrdfsError(f"presets {args.plugin}: no published fit converts exactly to "
                               f"{args.plugin}'s parameters (docs/presets.md says why)")
        print("\n".join(names))
        return 0
    takes = {p: set(presets.names(p)) for p in plugins}
    columns = [(p, prefix) for p in plugins
               for prefix in sorted({n.split(":")[0] for n in takes[p]})]
    print(f"Presets: Ngan, Durand & Matusik's (2005) fits to {len(presets.materials())} MERL "
          f"materials, as <string name=\"preset\" value=\"ngan:MATERIAL\"/> or preset=ngan:"
          f"MATERIAL (docs/presets.md); x: the plugin takes that material's fit exactly.")
    for model, _, plugin, _, how in presets.table():
        print(f"  {plugin:<12} {model:<17} {how}")
    width = max(map(len, presets.materials()))
    heads = [p if prefix == presets.SOURCE else f"{p} ({prefix}:)" for p, prefix in columns]
    print("\n" + f"{'material':<{width}}  " + "  ".join(heads))
    for material in presets.materials():
        marks = ["x" if f"{prefix}:{material}" in takes[p] else "-" for p, prefix in columns]
        print(f"{material:<{width}}  " + "  ".join(f"{m:<{len(h)}}" for m, h in
                                                  zip(marks, heads)).rstrip())
    return 0


def cmd_explore(args) -> int:
    from ..errors import MiBrdfsError

    try:
        import panel  # noqa: F401
    except ImportError:
        raise MiBrdfsError("explore needs Panel: pip install 'mi-brdfs[explore]'") from None
    from ..explorer import _scene, jit_variant
    from ..explorer.app import spheres
    from ..explorer.server import LOCALHOST, free_port, serve
    from ..explorer.session import MAX_BSDFS, Session

    jit_variant(args.variant)
    if len(args.bsdf) > MAX_BSDFS:
        raise MiBrdfsError(f"explore: at most {MAX_BSDFS} BSDFs, got {len(args.bsdf)}")
    specs = _bsdfs(args.bsdf)
    scene = _scene(args.scene, args.scene_bsdf)
    host = args.host or LOCALHOST
    port = free_port(host, args.port)  # a port in use ends here, before the server starts
    # the BSDFs (and the scene) load here, so that what the plugins refuse ends in one line
    # before the server starts
    bsdfs = [e.bsdf for e in Session(specs).entries]
    if scene is not None:
        spheres(bsdfs, scene, None)
    return serve(specs, port, host, browser=not args.no_browser, scene=scene)


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
