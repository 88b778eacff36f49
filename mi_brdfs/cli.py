"""
The ``mi-brdfs`` command line (also ``python -m mi_brdfs``): a thin layer over the library.

User errors (a missing scene, a bad parameter, an unwritable output) print one line
``mi-brdfs: error: ...`` and exit with status 2; no traceback. An interrupted render writes what
it has and exits with status 130.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings
from pathlib import Path

EXIT_USER_ERROR = 2
EXIT_INTERRUPTED = 130


def _one_line_warnings(message, category, filename, lineno, file=None, line=None):
    print(f"mi-brdfs: warning: {message}", file=sys.stderr if file is None else file)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``mi-brdfs: error: ...`` and exit status 2."""

    def error(self, message):
        command = self.prog.split()[-1] if " " in self.prog else None
        where = f"{command}: " if command else ""
        self.exit(EXIT_USER_ERROR, f"mi-brdfs: error: {where}{message} (see --help)\n")


def _number(convert, what: str, valid, allowed: str):
    """An argparse type: ``convert(text)``, which must satisfy ``valid``; else one line."""
    def parse(text: str):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not {what}") from None
        if not valid(value):
            raise argparse.ArgumentTypeError(f"{allowed}, got {text}")
        return value
    return parse


#: Counts (samples, resolution, processes), seeds, finite numbers, durations.
_count = _number(int, "a whole number", lambda v: v >= 1, "must be at least 1")
_seed = _number(int, "a whole number", lambda v: 0 <= v < 2**32, "must lie in [0, 2^32)")
_finite = _number(float, "a number", math.isfinite, "must be finite")
_seconds = _number(float, "a number", lambda v: math.isfinite(v) and v > 0,
                   "must be finite and > 0 seconds")
_positive = _number(float, "a number", lambda v: math.isfinite(v) and v > 0,
                    "must be finite and > 0")


def _output(*suffixes: str):
    """An output path with one of ``suffixes`` (not empty, not a directory name)."""
    def parse(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError("the output path is empty")
        if text.endswith(("/", "\\")) or Path(text).suffix.lower() not in suffixes:
            raise argparse.ArgumentTypeError(
                f"'{text}' must end in {' or '.join(suffixes)}")
        return text
    return parse


def _add_variant(p: argparse.ArgumentParser) -> None:
    p.add_argument("--variant", metavar="V",
                   help="Mitsuba variant (default: llvm_ad_rgb where LLVM works, else scalar_rgb)")


def _parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = _Parser(
        prog="mi-brdfs",
        description="Lecture BRDFs (Lambert, Phong, Cook-Torrance) as Mitsuba 3 plugins: "
                    "render, validate and compare them.")
    parser.add_argument("--version", action="version", version=f"mi-brdfs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    r = sub.add_parser("render", help="render a scene progressively to EXR + PNG",
                       description="Render a scene progressively (passes of independent seeds) "
                                   "and write an EXR with the render's metadata plus an sRGB PNG "
                                   "preview. Ctrl-C keeps and writes what is done.")
    r.add_argument("scene", nargs="?", default="showcase",
                   help="scene XML file or bundled scene name (default: showcase)")
    r.add_argument("-o", "--output", metavar="OUT.exr", type=_output(".exr"),
                   help="output EXR (default: ./<scene name>.exr); the PNG goes beside it")
    r.add_argument("--spp", type=_count, metavar="N",
                   help="samples per pixel (default: the scene's sampler; unlimited with "
                        "--time-budget)")
    _add_variant(r)
    r.add_argument("--seed", type=_seed, default=0, metavar="S", help="base seed (default: 0)")
    r.add_argument("--time-budget", type=_seconds, metavar="SECONDS",
                   help="stop starting passes that would end after this many seconds")
    r.add_argument("-D", dest="defines", action="append", default=[], metavar="name=value",
                   help="override a <default> of the scene (repeatable)")
    r.add_argument("--pass-spp", type=_count, metavar="N",
                   help="samples per pixel in each pass")
    r.add_argument("--processes", type=_count, metavar="N",
                   help="render processes for scalar scenes with Python plugins, this one "
                        "included (default: one per core when it pays)")
    r.add_argument("--no-png", action="store_true", help="write no PNG preview")
    r.add_argument("--exposure", type=_finite, default=0.0,
                   help="PNG exposure in stops (default 0)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_render)

    bsdf_help = ("one or more BSDFs: a plugin name followed by its key=value parameters "
                 "(e.g. roughconductor alpha=0.3 material=Au diffuse), an XML file, or a "
                 "quoted XML fragment")

    def bsdf_command(name, summary, description, *before):
        """A subcommand taking BSDFs (after the positional arguments ``before``)."""
        cmd = sub.add_parser(name, help=summary, description=description)
        for args, kwargs in before:
            cmd.add_argument(*args, **kwargs)
        cmd.add_argument("bsdf", nargs="+", metavar="BSDF", help=bsdf_help)
        _add_variant(cmd)
        return cmd

    c = bsdf_command("check", "run every check on one or more BSDFs",
                     "Run the whole battery (consistency, χ² sampling, energy, albedo agreement, "
                     "reciprocity, positivity, stability; optionally the furnace render) and "
                     "print a table. Exit status 1 when a check fails.")
    c.add_argument("--quick", action="store_true", help="10× fewer samples")
    c.add_argument("--render", action="store_true", help="also render the white furnace")
    c.add_argument("--json", metavar="FILE", type=_output(".json"),
                   help="also write the results as JSON")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no messages")
    c.set_defaults(func=cmd_check)

    f = bsdf_command("furnace", "directional albedo table; optionally the furnace render",
                     "Directional albedo E(θ) over incident angles by every estimator (sample() "
                     "weights ± error, eval() Monte Carlo, quadrature, float64 reference), and "
                     "with --render the white furnace image (EXR + PNG).")
    f.add_argument("--thetas", metavar="DEG,...", help="incident angles in degrees")
    f.add_argument("-n", "--samples", type=_count, metavar="N", help="samples per angle")
    f.add_argument("--render", action="store_true", help="render the furnace (first BSDF)")
    f.add_argument("-o", "--output", metavar="OUT.exr", default="furnace.exr",
                   type=_output(".exr"),
                   help="furnace image (default: ./furnace.exr)")
    f.add_argument("--spp", type=_count, default=128, help="furnace spp (default 128)")
    f.add_argument("--res", type=_count, default=64, help="furnace resolution (default 64)")
    f.set_defaults(func=cmd_furnace)

    pl = bsdf_command("plot", "lobe, albedo or (θh, θd) slice plots (PNG)",
                      "Plots like Disney's BRDF Explorer: 'lobe' (polar, plane of incidence, "
                      "several incident angles), 'albedo' (E(θ)), 'slice' (f over θh, θd at "
                      "φd = 90°). Several BSDFs share one figure.",
                      (("kind",), {"choices": ["lobe", "albedo", "slice"]}))
    pl.add_argument("-o", "--output", metavar="OUT.png", type=_output(".png", ".pdf", ".svg"),
                    help="default: ./<kind>.png")
    pl.add_argument("--thetas", metavar="DEG,...", help="incident angles (lobe, albedo)")
    pl.add_argument("--log", action="store_true", help="logarithmic radius (lobe)")
    pl.add_argument("--no-cos", action="store_true", help="plot f instead of f·cosθo (lobe)")
    pl.add_argument("--res", type=_count, default=128, help="slice resolution (default 128)")
    pl.add_argument("-n", "--samples", type=_count, metavar="N",
                    help="samples per angle (albedo)")
    pl.set_defaults(func=cmd_plot)

    cp = sub.add_parser("compare", help="A | B | difference | FLIP of two renders + noise floor",
                        description="Render two scenes (or one scene and the same scene with a "
                                    "material swapped) with the same spp and seed, and write one "
                                    "figure A | B | signed difference | FLIP error map plus the "
                                    "EXRs, with RMSE, relative MSE, mean FLIP and the noise floor "
                                    "(the same numbers between two seeds of A).")
    cp.add_argument("scenes", nargs="+", metavar="SCENE", help="A.xml [B.xml] (or bundled names)")
    cp.add_argument("--swap", action="append", default=[], metavar="ID=BSDF",
                    help="B = A with <bsdf id=ID> replaced, e.g. "
                         "--swap \"material=roughconductor alpha=0.3\" (repeatable)")
    _add_variant(cp)
    cp.add_argument("--spp", type=_count, default=64, help="samples per pixel (default 64)")
    cp.add_argument("--seed", type=_seed, default=0)
    cp.add_argument("-D", dest="defines", action="append", default=[], metavar="name=value",
                    help="override a <default> of the scene(s) (repeatable)")
    cp.add_argument("-o", "--output", metavar="OUT.png", default="compare.png",
                    type=_output(".png"),
                    help="figure (default ./compare.png); EXRs beside it")
    cp.set_defaults(func=cmd_compare)

    ft = sub.add_parser("fit", help="fit a model's parameters to another BSDF (JSON, plot)",
                        description="Fit the continuous parameters of MODEL (those of --free, "
                                    "default all) so that its f·cosθo matches TARGET's over "
                                    "direction pairs covering the hemisphere and grazing angles, "
                                    "by automatic differentiation (Adam, cube-root objective; see "
                                    "mi_brdfs.fit). Prints the fitted values, the residual, the "
                                    "albedo error and the fitted BSDF as a command line and XML.")
    ft.add_argument("target", nargs="+", metavar="TARGET",
                    help="the BSDF to match: a plugin name followed by its key=value parameters "
                         "(e.g. cooktorrance material=Au alpha=0.2), a built-in, an XML file or "
                         "a quoted XML fragment")
    ft.add_argument("--model", nargs="+", required=True, metavar="MODEL",
                    help="the model to fit: a plugin name with key=value parameters (its values "
                         "are the start; those not in --free stay fixed), e.g. --model phong "
                         "lobe=halfway diffuse_reflectance=0")
    ft.add_argument("--free", metavar="P1,P2,...",
                    help="the parameters to fit, by name (default: all of MODEL's continuous ones)")
    ft.add_argument("-o", "--output", metavar="FIT.json", type=_output(".json"),
                    help="write the result as JSON")
    ft.add_argument("--plot", metavar="FIT.png", type=_output(".png", ".pdf", ".svg"),
                    help="plot target against fit: lobes in the plane of incidence and E(θ)")
    ft.add_argument("--variant", metavar="V", default="llvm_ad_rgb",
                    help="Mitsuba variant with automatic differentiation (default: llvm_ad_rgb)")
    ft.add_argument("--pairs", type=_count, default=16384, metavar="N",
                    help="direction pairs drawn (default 16384; about 3/4 lie above the horizon)")
    ft.add_argument("--steps", type=_count, default=800, metavar="N",
                    help="Adam steps per start (default 800)")
    ft.add_argument("--seed", type=_seed, default=0, metavar="S",
                    help="seed of the direction pairs (default: 0)")
    ft.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    ft.set_defaults(func=cmd_fit)

    sm = sub.add_parser("simplify", help="cheaper materials within a tolerance: table, plot, "
                                         "simplified scene",
                        description="For every BSDF of SCENE, render cheaper candidates (switches "
                                    "of the plugins, the built-in with the same model, fitted "
                                    "cheaper models) in the scene itself; measure each one's bias "
                                    "against the original (relative RMSE, 2 to 16 seeds, common "
                                    "random numbers), its cost per sample and variance, and so "
                                    "its time to reach the tolerance; write the scene with each "
                                    "material replaced by its cheapest candidate within the "
                                    "tolerance (every other byte kept) and verify it by one more "
                                    "render (see mi_brdfs.simplify).")
    sm.add_argument("scene", metavar="SCENE", help="scene XML file or bundled scene name")
    sm.add_argument("--tolerance", type=_positive, default=0.01, metavar="T",
                    help="relative RMSE of the converged image against the original's "
                         "(RMSE over the mean; default 0.01)")
    _add_variant(sm)
    sm.add_argument("-o", "--output", metavar="SIMPLIFIED.xml", type=_output(".xml"),
                    help="the simplified scene (default: ./<scene name>-simplified.xml)")
    sm.add_argument("--report", metavar="DIR",
                    help="write SIMPLIFY.md and simplify.png there (and keep the cache in "
                         "DIR/cache)")
    sm.add_argument("--quick", action="store_true",
                    help="small renders (-D res=128 where the scene declares res, 16 spp) and "
                         "short fits")
    sm.add_argument("--spp", type=_count, metavar="N",
                    help="samples per pixel of each render (default 64; --quick: 16)")
    sm.add_argument("-D", dest="defines", action="append", default=[], metavar="name=value",
                    help="override a <default> of the scene (repeatable)")
    sm.add_argument("--confidence", type=_finite, default=2.0, metavar="Z",
                    help="standard errors by which a candidate's speed-up must exceed 1 to "
                         "replace a material (default 2; 0: any estimated gain)")
    sm.add_argument("--no-cache", action="store_true", help="measure everything again")
    sm.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    sm.set_defaults(func=cmd_simplify)

    def report_command(name, summary, description, quick, target, tag):
        """A subcommand that writes a report into --out (and quotes into --readme)."""
        cmd = sub.add_parser(name, help=summary, description=description)
        cmd.add_argument("--quick", action="store_true", help=quick)
        cmd.add_argument("--out", metavar="DIR", default=".",
                         help=f"report folder (default: the current directory; {target}: "
                              f"validation)")
        cmd.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
        cmd.add_argument("--readme", metavar="FILE", action="append",
                         help=f"also fill in the figures FILE quotes from the run, each marked "
                              f"<!-- {tag}: KEY -->VALUE<!-- /{tag} --> (repeatable; {target}: "
                              f"README.md and docs/*.md)")
        return cmd

    v = report_command("validate", "the validation campaign: REPORT.md with figures",
                       "Run every check on every plugin over its parameter grid, the "
                       "comparisons with Mitsuba's built-ins and the lecture notes' claims, and "
                       "write REPORT.md with its figures.",
                       "CI-sized: fewer samples and parameters", "make validate", "report")
    v.set_defaults(func=cmd_validate)

    b = report_command("bench", "speed vs accuracy: SPEED_ACCURACY.md with plots",
                       "Measure every plugin and sampling choice against the built-ins (ratios "
                       "of medians of interleaved repeats, error against time) and write "
                       "SPEED_ACCURACY.md with its plots. Run it on a quiet machine; it asserts "
                       "nothing.", "tiny sizes (a smoke run; its timings are not judged)",
                       "make bench", "bench")
    b.set_defaults(func=cmd_bench)

    au = sub.add_parser(
        "audit", help="every BSDF Mitsuba ships through the checks: MITSUBA_AUDIT.md",
        description="Run every BSDF plugin of the installed Mitsuba (and the package's) over a "
                    "grid of configurations through the whole battery of checks and Mitsuba's "
                    "own χ² harness, in worker processes, and write MITSUBA_AUDIT.md and "
                    "audit/findings.json with a triaged verdict for every failure. Results are "
                    "cached per case in OUT/audit/.cache: an interrupted audit resumes. Exit "
                    "status 1 when a failure has no verdict yet.")
    au.add_argument("--quick", action="store_true",
                    help="a few configurations, 10× fewer samples (the test suite's run; writes "
                         "MITSUBA_AUDIT-quick.md)")
    au.add_argument("--out", metavar="DIR", default=".",
                    help="report folder (default: the current directory; make audit: "
                         "validation)")
    au.add_argument("--variant", metavar="V", default="llvm_ad_rgb",
                    help="JIT variant of the audit (default llvm_ad_rgb; polarized BSDFs run in "
                         "llvm_ad_spectral_polarized)")
    au.add_argument("--processes", type=_count, default=None, metavar="N",
                    help="worker processes (default: one per core)")
    au.add_argument("--only", metavar="BSDF[,BSDF]",
                    help="audit only these plugins (by name as in XML)")
    au.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    au.set_defaults(func=cmd_audit)

    i = sub.add_parser("info", help="versions, variants, LLVM status and registered plugins")
    i.set_defaults(func=cmd_info)
    return parser


def _bsdfs(tokens):
    from .bsdfspec import load_bsdf, parse_cli

    specs = parse_cli(tokens)
    for spec in specs:
        load_bsdf(spec)  # reject bad parameters before any long work, in one line
    return specs


def _thetas(text):
    from .errors import MiBrdfsError

    if text is None:
        return None
    try:
        values = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise MiBrdfsError(f"--thetas expects degrees separated by commas, got '{text}'") from None
    if not values or any(not 0 <= v <= 90 for v in values):
        raise MiBrdfsError(f"--thetas: angles must lie in [0, 90] degrees, got '{text}'")
    return values


def cmd_check(args) -> int:
    import json

    import mi_brdfs
    from .bsdfspec import describe
    from .checks import format_table, run_battery

    from .imageio import check_writable

    json_path = check_writable(args.json) if args.json else None
    variant = mi_brdfs.use_variant(args.variant)
    specs = _bsdfs(args.bsdf)
    failed, report = 0, []
    for spec in specs:
        results = run_battery(spec, quick=args.quick, render=args.render,
                              progress=not args.quiet)
        failed += sum(not r.passed for r in results)
        print(f"\n{describe(spec)} ({variant})")
        print(format_table(results, messages=not args.quiet))
        report.append({"bsdf": describe(spec), "variant": variant, "checks": [
            {"name": r.name, "passed": r.passed, "value": r.value, "tolerance": str(r.tolerance),
             "message": r.message} for r in results]})
    if json_path:
        from .imageio import atomic_path
        with atomic_path(json_path, ".json") as tmp:
            with open(tmp, "w") as f:
                json.dump(report, f, indent=1, default=float)
    print(f"\n{failed} check(s) failed" if failed else "\nall checks passed")
    return 1 if failed else 0


def cmd_furnace(args) -> int:
    import mi_brdfs
    from .bsdfspec import describe
    from .checks.albedo import DEFAULT_THETAS, albedo_curve
    from .checks.furnace import check_furnace
    from .imageio import check_writable, write_exr, write_png

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
    from . import plots
    from .imageio import check_writable

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
    from .imageio import check_writable, write_exr, write_png
    from .render import render
    from .scenes import parse_defines, scene_path

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
    from .compare import compare, parse_swaps, write_outputs
    from .errors import MiBrdfsError
    from .imageio import check_writable
    from .scenes import parse_defines, scene_path

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


def _spec_tokens(tokens) -> list:
    """Command-line BSDF tokens, a quoted 'plugin key=value ...' split into its words."""
    import shlex

    words = []
    for token in tokens:
        words += [token] if token.lstrip().startswith("<") else shlex.split(token)
    return words


def cmd_fit(args) -> int:
    import mi_brdfs
    from .bsdfspec import parse_cli
    from .errors import MiBrdfsError
    from .fit import fit, plot_fit, write_json
    from .imageio import check_writable

    json_path = check_writable(args.output) if args.output else None
    plot_path = check_writable(args.plot) if args.plot else None
    if plot_path:
        from .plots import pyplot
        pyplot()  # matplotlib missing: say so before the fit
    try:
        target_tokens, model_tokens = _spec_tokens(args.target), _spec_tokens(args.model)
    except ValueError as e:
        raise MiBrdfsError(f"cannot read the BSDF: {e}") from None
    mi_brdfs.use_variant(args.variant, fallback=False)
    (target,), (model,) = _one_bsdf(parse_cli(target_tokens), "TARGET"), \
        _one_bsdf(parse_cli(model_tokens), "--model")
    result = fit(target, model, args.free, pairs=args.pairs, steps=args.steps, seed=args.seed,
                 variant=args.variant, progress=not args.quiet)
    print(result.summary())
    written = []
    if json_path:
        written.append(write_json(result, json_path))
    if plot_path:
        written.append(plot_fit(result, plot_path))
    if written:
        print("wrote " + " and ".join(written))
    return 0


def cmd_simplify(args) -> int:
    import mi_brdfs
    from .imageio import check_writable
    from .scenes import parse_defines, scene_path
    from .simplify import simplify

    path = scene_path(args.scene)
    out = check_writable(Path(args.output) if args.output
                         else Path.cwd() / f"{path.stem}-simplified.xml")
    defines = parse_defines(args.defines)
    mi_brdfs.use_variant(args.variant)
    result = simplify(path, args.tolerance, output=out, report=args.report, quick=args.quick,
                      spp=args.spp, defines=defines, cache=not args.no_cache,
                      confidence=args.confidence, progress=not args.quiet)
    print(result.summary())
    return 0


def _one_bsdf(specs: list, what: str) -> list:
    from .errors import MiBrdfsError

    if len(specs) != 1:
        raise MiBrdfsError(f"{what} names {len(specs)} BSDFs; give one")
    return specs


def _report_folder(args, filename: str) -> Path:
    """The report folder (created), checked writable for ``filename`` before any work."""
    from .imageio import output_folder

    return output_folder(args.out, f"--out {args.out}", filename)


def _jit_variant(what: str) -> str:
    import mi_brdfs
    from .errors import MiBrdfsError

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
    from .campaign import Context, run
    from .campaign.core import fill_quotes
    from .errors import MiBrdfsError

    readmes = getattr(args, "readme", None) or []
    for readme in readmes:
        if not Path(readme).is_file():
            raise MiBrdfsError(f"--readme {readme}: no such file")
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


def cmd_audit(args) -> int:
    import os
    import time

    from .audit import grid, report, run
    from .errors import MiBrdfsError
    from .registry import use_variant

    if not args.variant.startswith(("llvm_", "cuda_")):
        raise MiBrdfsError(f"--variant {args.variant}: the audit needs a JIT variant (χ² runs "
                           f"on mitsuba.chi2), e.g. llvm_ad_rgb")
    out = _report_folder(args, "MITSUBA_AUDIT.md")
    use_variant(args.variant, fallback=False)  # fail here, in one line, if it is unusable
    cases = grid.all_cases()
    if args.quick:
        cases = [c for c in cases if c.quick]
    if args.only:
        names = {n.strip() for n in args.only.split(",") if n.strip()}
        unknown = names - {c.bsdf for c in grid.all_cases()}
        if unknown:
            raise MiBrdfsError(f"--only {args.only}: no audit configuration for "
                               f"{', '.join(sorted(unknown))} (the audit knows: "
                               f"{', '.join(sorted({c.bsdf for c in grid.all_cases()}))})")
        cases = [c for c in cases if c.bsdf in names]
    t0 = time.perf_counter()
    records = run.run(cases, args.variant, args.quick, out / "audit" / ".cache",
                      processes=args.processes or min(os.cpu_count() or 1, 4),
                      progress=not args.quiet)
    command = "mi-brdfs audit" + (" --quick" if args.quick else "") + \
        (f" --only {args.only}" if args.only else "")
    md, js, counts = report.write(records, out, command, time.perf_counter() - t0,
                                  args.variant, args.quick)
    print(f"wrote {md} and {js}: " + ", ".join(f"{n} {v}" for v, n in sorted(counts.items())))
    return 1 if counts.get("untriaged") else 0


def cmd_validate(args) -> int:
    from .campaign import sections

    return 1 if _run_report(args, sections(), "checks", quotes="report") else 0


def cmd_bench(args) -> int:
    from .benchmark import sections

    _run_report(args, sections(), "measurements", quotes="bench",
                title="mi_brdfs speed vs accuracy",
                filename="SPEED_ACCURACY.md", command="mi-brdfs bench", make_target="make bench",
                quick_note="tiny renders whose timings are too short to judge the targets",
                judge_quick=False)
    return 0  # a benchmark reports targets met or missed; it does not fail


def cmd_info(args) -> int:
    import drjit as dr
    import mitsuba as mi

    import mi_brdfs
    from . import _env

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


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    warnings.showwarning = _one_line_warnings
    try:
        import mi_brdfs  # noqa: F401  (preflight: libatomic, libLLVM)
        from .errors import MiBrdfsError
    except ImportError as e:
        print(f"mi-brdfs: error: {e}", file=sys.stderr)
        return EXIT_USER_ERROR
    try:
        return args.func(args)
    except MiBrdfsError as e:
        print(f"mi-brdfs: error: {e}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("mi-brdfs: interrupted; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (| head): stop quietly, as cat does
        import os
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
