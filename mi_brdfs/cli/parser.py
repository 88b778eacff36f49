"""
The ``mi-brdfs`` argument parser: one function per subcommand adds its arguments; argument
types and errors in one line (``mi-brdfs: error: ...``, exit status 2).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..fit.optimise import METRICS

from .commands import (
    EXIT_USER_ERROR, cmd_check, cmd_compare, cmd_explore, cmd_fit, cmd_furnace, cmd_info,
    cmd_measure, cmd_plot, cmd_presets, cmd_render, cmd_simplify, cmd_tables,
)
from .reports import cmd_audit, cmd_bench, cmd_validate


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``mi-brdfs: error: ...`` and exit status 2."""

    def error(self, message):
        command = self.prog.split()[-1] if " " in self.prog else None
        where = f"{command}: " if command else ""
        self.exit(EXIT_USER_ERROR, f"mi-brdfs: error: {where}{message} (see --help)\n")



class _Once(argparse.Action):
    """An option that may be given once: a second one is an error (argparse would silently
    keep the last)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if getattr(namespace, self.dest, None) is not None:
            parser.error(f"argument {option_string}: given twice (give it once)")
        setattr(namespace, self.dest, values)

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
_port = _number(int, "a port number", lambda v: 1 <= v <= 65535, "must lie in [1, 65535]")
_positive = _number(float, "a number", lambda v: math.isfinite(v) and v > 0,
                    "must be finite and > 0")
#: A relative error: a relative RMSE of 1 is that of a black image against any other
_relative = _number(float, "a number", lambda v: 0 < v < 1,
                    "must lie in (0, 1) (a relative RMSE; 1 is a black image's)")


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


def _add_force(p: argparse.ArgumentParser, what: str, named: bool = True) -> None:
    """--force: replace the files ``what`` names (without it, each that exists is refused)."""
    p.add_argument("--force", action="store_true",
                   help=f"replace {what} that already exist (without it, such a file is "
                        f"refused before any work" + ("; a file named with -o is replaced)"
                                                      if named else ")"))


def _add_variant(p: argparse.ArgumentParser) -> None:
    p.add_argument("--variant", metavar="V",
                   help="Mitsuba variant (default: llvm_ad_rgb where LLVM works, else scalar_rgb)")


def _parser() -> argparse.ArgumentParser:
    """The parser of ``mi-brdfs`` and its subcommands (each one's ``func``: its command)."""
    from .. import __version__

    parser = _Parser(
        prog="mi-brdfs",
        description="Lecture BRDFs (Lambert, Phong, Cook-Torrance) as Mitsuba 3 plugins: "
                    "render, validate and compare them.")
    parser.add_argument("--version", action="version", version=f"mi-brdfs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    _add_render(sub)
    _add_check(sub)
    _add_furnace(sub)
    _add_plot(sub)
    _add_compare(sub)
    _add_fit(sub)
    _add_simplify(sub)
    _add_validate(sub)
    _add_bench(sub)
    _add_audit(sub)
    _add_tables(sub)
    _add_measure(sub)
    _add_presets(sub)
    _add_explore(sub)
    _add_info(sub)
    return parser


def _add_render(sub) -> None:
    """``mi-brdfs render``."""
    r = sub.add_parser("render", help="render a scene progressively to EXR + PNG",
                       description="Render a scene progressively (passes of independent seeds) "
                                   "and write an EXR with the render's metadata plus an sRGB PNG "
                                   "preview. Ctrl-C keeps and writes what is done.")
    r.add_argument("scene", nargs="?", default="showcase",
                   help="scene XML file or bundled scene name (default: showcase)")
    r.add_argument("-o", "--output", metavar="OUT.exr", type=_output(".exr"),
                   help="output EXR (default: ./<scene name>.exr); the PNG goes beside it")
    _add_force(r, "the default output and the PNG beside the EXR")
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
    r.add_argument("--exposure", type=_finite,
                   help="PNG exposure in stops (default 0; not with --no-png)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_render)


#: The help of the BSDF arguments of check, furnace and plot.
_BSDF_HELP = ("one or more BSDFs: a plugin name followed by its key=value parameters "
              "(e.g. roughconductor alpha=0.3 material=Au diffuse; the same quoted: "
              "'roughconductor alpha=0.3 material=Au' diffuse), an XML file, or a "
              "quoted XML fragment")


def _bsdf_command(sub, name, summary, description, *before):
    """A subcommand taking BSDFs (after the positional arguments ``before``)."""
    cmd = sub.add_parser(name, help=summary, description=description)
    for args, kwargs in before:
        cmd.add_argument(*args, **kwargs)
    cmd.add_argument("bsdf", nargs="+", metavar="BSDF", help=_BSDF_HELP)
    _add_variant(cmd)
    return cmd


def _add_check(sub) -> None:
    """``mi-brdfs check``."""
    c = _bsdf_command(sub, "check", "run every check on one or more BSDFs",
                      "Run the whole battery (consistency, χ² sampling, energy, albedo "
                      "agreement, reciprocity, positivity, stability; optionally the furnace "
                      "render and the gradients) and print a table. Exit status 1 when a check fails.")
    c.add_argument("--quick", action="store_true", help="10× fewer samples")
    c.add_argument("--render", action="store_true", help="also render the white furnace")
    c.add_argument("--gradients", action="store_true",
                   help="also check the derivatives of every differentiable parameter against "
                        "finite differences (AD variants)")
    c.add_argument("--json", metavar="FILE", type=_output(".json"),
                   help="also write the results as JSON")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no messages")
    c.set_defaults(func=cmd_check)


def _add_furnace(sub) -> None:
    """``mi-brdfs furnace``."""
    f = _bsdf_command(sub, "furnace", "directional albedo table; optionally the furnace render",
                      "Directional albedo E(θ) over incident angles by every estimator (sample() "
                      "weights ± error, eval() Monte Carlo, quadrature, float64 reference), and "
                      "with --render the white furnace image (EXR + PNG).")
    f.add_argument("--thetas", metavar="DEG,...", help="incident angles in degrees")
    f.add_argument("-n", "--samples", type=_count, metavar="N", help="samples per angle")
    f.add_argument("--render", action="store_true", help="render the furnace (first BSDF)")
    f.add_argument("-o", "--output", metavar="OUT.exr", type=_output(".exr"),
                   help="furnace image, with --render (default: ./furnace.exr); the PNG goes "
                        "beside it")
    f.add_argument("--spp", type=_count, help="furnace spp, with --render (default 128)")
    f.add_argument("--res", type=_count, help="furnace resolution, with --render (default 64)")
    _add_force(f, "the default output and the PNG beside the EXR (with --render)")
    f.set_defaults(func=cmd_furnace)


def _add_plot(sub) -> None:
    """``mi-brdfs plot``."""
    pl = _bsdf_command(sub, "plot", "lobe, albedo, (θh, θd) slice or principal-plane plots",
                       "Plots like Disney's BRDF Explorer: 'lobe' (polar, plane of incidence, "
                       "several incident angles), 'albedo' (E(θ)), 'slice' (f over θh, θd at "
                       "φd = 90°); and Earth observation's 'pp' (the BRF = π·f against the view "
                       "zenith in the principal plane, backward > 0, forward < 0, one panel per "
                       "sun zenith). Several BSDFs share one figure.",
                       (("kind",), {"choices": ["lobe", "albedo", "slice", "pp"]}))
    pl.add_argument("-o", "--output", metavar="OUT.png", type=_output(".png", ".pdf", ".svg"),
                    help="default: ./<kind>.png")
    _add_force(pl, "the default output")
    pl.add_argument("--thetas", metavar="DEG,...",
                    help="incident angles (lobe, albedo), sun zeniths (pp; default 0,30,60)")
    pl.add_argument("--log", action="store_true", help="logarithmic radius (lobe)")
    pl.add_argument("--no-cos", action="store_true", help="plot f instead of f·cosθo (lobe)")
    pl.add_argument("--res", type=_count, help="slice resolution (slice; default 128)")
    pl.add_argument("-n", "--samples", type=_count, metavar="N",
                    help="samples per angle (albedo)")
    pl.set_defaults(func=cmd_plot)


def _add_compare(sub) -> None:
    """``mi-brdfs compare``."""
    cp = sub.add_parser("compare", help="A | B | difference | FLIP of two renders + noise floor",
                        description="Render two scenes (or one scene and the same scene with a "
                                    "material swapped) with the same spp and seed, and write one "
                                    "figure A | B | signed difference | FLIP error map plus the "
                                    "EXRs, with RMSE, relative MSE, mean FLIP and the noise floor "
                                    "(the same numbers between two seeds of A).")
    cp.add_argument("scenes", nargs="+", metavar="SCENE", help="A.xml [B.xml] (or bundled names)")
    cp.add_argument("--swap", action="append", default=[], metavar="ID=BSDF",
                    help="with one SCENE: B = A with <bsdf id=ID> replaced, e.g. "
                         "--swap \"material=roughconductor alpha=0.3\" (repeatable)")
    _add_variant(cp)
    cp.add_argument("--spp", type=_count, default=64, help="samples per pixel (default 64)")
    cp.add_argument("--seed", type=_seed, default=0)
    cp.add_argument("-D", dest="defines", action="append", default=[], metavar="name=value",
                    help="override a <default> of the scene(s) (repeatable)")
    cp.add_argument("-o", "--output", metavar="OUT.png", type=_output(".png"),
                    help="figure (default ./compare.png); EXRs beside it (OUT-A.exr, OUT-B.exr, "
                         "OUT-diff.exr)")
    _add_force(cp, "the default output and the EXRs beside the figure")
    cp.set_defaults(func=cmd_compare)


def _add_fit(sub) -> None:
    """``mi-brdfs fit``."""
    ft = sub.add_parser("fit", help="fit a model's parameters to another BSDF (JSON, plot)",
                        description="Fit the continuous parameters of MODEL (those of --free, "
                                    "default all) so that its f·cosθo matches TARGET's over "
                                    "direction pairs covering the hemisphere and grazing angles, "
                                    "by automatic differentiation (Adam, cube-root objective; see "
                                    "mi_brdfs.fit). Prints the fitted values, the residual, the "
                                    "albedo error and the fitted BSDF as a command line and XML.")
    ft.add_argument("target", nargs="+", metavar="TARGET",
                    help="the BSDF to match: a plugin name followed by its key=value parameters "
                         "(e.g. cooktorrance material=Au alpha=0.2), a built-in, an XML file, "
                         "a quoted XML fragment, or measured data: a MERL .binary file (compared "
                         "at its own bins)")
    which = ft.add_mutually_exclusive_group(required=True)
    which.add_argument("--model", nargs="+", metavar="MODEL", action=_Once,
                       help="the model to fit: a plugin name with key=value parameters (its "
                            "values are the start; those not in --free stay fixed), e.g. --model "
                            "phong lobe=halfway diffuse_reflectance=0")
    which.add_argument("--models", metavar="all|M1,M2,...",
                       help="fit every lecture model (all: phong, ward, cooktorrance, ashikhmin, "
                            "lafortune, he), or those named, from the lecture's starts (mi_brdfs.fit."
                            "models); write --out DIR/models.md (each scored under every metric "
                            "and ranked), models.json, lobes.png and spheres.png; with several "
                            "TARGET files, a sweep: DIR/sweep.md and sweep.json")
    ft.add_argument("--out", metavar="DIR",
                    help="with --models: the report's folder (default: a new folder "
                         "./<TARGET name>-models; a sweep's: ./sweep)")
    _add_force(ft, "the files of --models' report", named=False)
    ft.add_argument("--compare-published", nargs="?", const="", metavar="MATERIAL",
                    help="with --models and one TARGET: score Ngan et al.'s 2005 published fits "
                         "of MATERIAL (a MERL material's name; default: the TARGET file's name) "
                         "beside ours")
    ft.add_argument("--workers", type=_count, metavar="N",
                    help="a sweep's (several TARGET files and --models): fits run at once, one "
                         "process each (default: one per core)")
    ft.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                    help="a sweep's (several TARGET files and --models): run the fits on this "
                         "Dask cluster (pip install 'mi-brdfs[sweep]'; see mi_brdfs.fit.sweep)")
    ft.add_argument("--free", metavar="P1,P2,...",
                    help="with --model: the parameters to fit, by name (default: all of MODEL's "
                         "continuous ones)")
    ft.add_argument("-o", "--output", metavar="FIT.json", type=_output(".json"),
                    help="with --model: write the result as JSON")
    ft.add_argument("--plot", metavar="FIT.png", type=_output(".png", ".pdf", ".svg"),
                    help="with --model: plot target against fit: lobes in the plane of "
                         "incidence and E(θ)")
    ft.add_argument("--variant", metavar="V", default="llvm_ad_rgb",
                    help="Mitsuba variant with automatic differentiation (default: llvm_ad_rgb)")
    ft.add_argument("--pairs", type=_count, default=16384, metavar="N",
                    help="direction pairs drawn (default 16384; about 3/4 lie above the horizon)")
    ft.add_argument("--steps", type=_count, default=800, metavar="N",
                    help="Adam steps per start (default 800)")
    ft.add_argument("--seed", type=_seed, default=0, metavar="S",
                    help="seed of the direction pairs (default: 0)")
    ft.add_argument("--metric", choices=list(METRICS), default="cuberoot",
                    help="the objective: " + "; ".join(f"{k}: {v}" for k, v in METRICS.items())
                         + " (default: cuberoot)")
    ft.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    ft.set_defaults(func=cmd_fit)


def _add_simplify(sub) -> None:
    """``mi-brdfs simplify``."""
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
    sm.add_argument("--tolerance", type=_relative, default=0.01, metavar="T",
                    help="relative RMSE of the converged image against the original's "
                         "(RMSE over the mean; default 0.01)")
    _add_variant(sm)
    sm.add_argument("-o", "--output", metavar="SIMPLIFIED.xml", type=_output(".xml"),
                    help="the simplified scene (default: ./<scene name>-simplified.xml)")
    _add_force(sm, "the default output and the report's files (--report)")
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
    sm.add_argument("--objective", choices=("simplicity", "speed"), default="simplicity",
                    help="simplicity (default): a simpler candidate within the tolerance and "
                         "not measurably slower replaces a material (the fastest of them); "
                         "speed: only a measurably faster one")
    sm.add_argument("--confidence", type=_finite, default=2.0, metavar="Z",
                    help="standard errors by which a candidate's speed-up must differ from 1 "
                         "to count as measurably faster or slower (default 2; 0: any estimated "
                         "difference)")
    sm.add_argument("--no-cache", action="store_true", help="measure everything again")
    sm.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    sm.set_defaults(func=cmd_simplify)


def _report_command(sub, name, summary, description, quick, target, tag):
    """A subcommand that writes a report into --out (and quotes into --readme)."""
    cmd = sub.add_parser(name, help=summary, description=description)
    cmd.add_argument("--quick", action="store_true", help=quick)
    cmd.add_argument("--out", metavar="DIR", default="validation",
                     help=f"report folder (default: ./validation, as {target})")
    _add_force(cmd, "the report's file in --out DIR", named=False)
    cmd.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    cmd.add_argument("--only", metavar="SECTION[,SECTION]",
                     help="run only these sections (by name, e.g. the plugin's: the list is in "
                          "the error for an unknown name); not with --readme")
    cmd.add_argument("--readme", metavar="FILE", action="append",
                     help=f"also fill in the figures FILE quotes from the run, each marked "
                          f"<!-- {tag}: KEY -->VALUE<!-- /{tag} --> (repeatable; {target}: "
                          f"README.md and docs/*.md)")
    return cmd


def _add_validate(sub) -> None:
    """``mi-brdfs validate``."""
    v = _report_command(sub, "validate", "the validation campaign: REPORT.md with figures",
                        "Run every check on every plugin over its parameter grid, the "
                        "comparisons with Mitsuba's built-ins and the lecture notes' claims, and "
                        "write REPORT.md with its figures.",
                        "CI-sized: fewer samples and parameters", "make validate", "report")
    v.set_defaults(func=cmd_validate)


def _add_bench(sub) -> None:
    """``mi-brdfs bench``."""
    b = _report_command(sub, "bench", "speed vs accuracy: SPEED_ACCURACY.md with plots",
                        "Measure every plugin and sampling choice against the built-ins (ratios "
                        "of medians of interleaved repeats, error against time) and write "
                        "SPEED_ACCURACY.md with its plots. Run it on a quiet machine; it asserts "
                        "nothing.", "tiny sizes (a smoke run; its timings are not judged)",
                        "make bench", "bench")
    b.set_defaults(func=cmd_bench)


def _add_audit(sub) -> None:
    """``mi-brdfs audit``."""
    au = sub.add_parser(
        "audit", help="every BSDF Mitsuba ships through the checks: MITSUBA_AUDIT.md",
        description="Run every BSDF plugin of the installed Mitsuba (and the package's) over a "
                    "grid of configurations through the whole battery of checks and Mitsuba's "
                    "own χ² harness, in worker processes, and write MITSUBA_AUDIT.md and "
                    "audit/findings.json with a triaged verdict for every failure. Results are "
                    "cached per case in OUT/audit/.cache: an interrupted audit resumes. The whole "
                    "audit (no --quick, no --only) also reruns every reproducer of a defect "
                    "(validation/audit/repro_*.py) and reports whether each still fails. Exit "
                    "status 1 when a failure has no verdict yet or a reproducer is broken.")
    au.add_argument("--quick", action="store_true",
                    help="a few configurations, 10× fewer samples (the test suite's run; writes "
                         "MITSUBA_AUDIT-quick.md)")
    au.add_argument("--out", metavar="DIR", default="validation",
                    help="report folder (default: ./validation, as make audit)")
    _add_force(au, "the report's files in --out DIR", named=False)
    au.add_argument("--variant", metavar="V", default="llvm_ad_rgb",
                    help="JIT variant of the audit (default llvm_ad_rgb; cuda_ad_rgb on a "
                         "machine with a CUDA GPU); polarized BSDFs run in the same backend's "
                         "*_ad_spectral_polarized")
    au.add_argument("--processes", type=_count, default=None, metavar="N",
                    help="worker processes (default: one per core)")
    au.add_argument("--only", metavar="BSDF[,BSDF]",
                    help="audit only these plugins (by name as in XML)")
    au.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    au.set_defaults(func=cmd_audit)


def _add_tables(sub) -> None:
    """``mi-brdfs tables``."""
    t = sub.add_parser(
        "tables", help="rebuild the albedo tables of cooktorrance's multiscatter",
        description="Rebuild the directional albedo E(mu, alpha) of cooktorrance's "
                    "single-scattering lobe (F = 1) for each distribution and masking, and "
                    "E(mu, alpha, eta) of its rough dielectric (transmission = true), the "
                    "tables of its energy compensation (multiscatter = true), from the plugin "
                    "itself, deterministically (a few minutes).")
    t.add_argument("-o", "--out", type=_output(".npz"), metavar="FILE.npz",
                   help="where to write them (default: the package's own table file)")
    t.add_argument("--samples", type=_number(int, "--samples", lambda v: v >= 4, "an integer "
                                             ">= 4"), default=None, metavar="N",
                   help="an N x N grid of samples per node (default: 512 for the "
                        "conductor's tables, 256 for the dielectric's)")
    t.set_defaults(func=cmd_tables)


def _add_measure(sub) -> None:
    """``mi-brdfs measure``."""
    m = _bsdf_command(sub, "measure", "tabulate a BSDF in MERL's .binary format",
                      "A virtual gonioreflectometer: the BRDF f = eval/cosθo at the centre of "
                      "every bin of MERL's format (Matusik et al. 2003: 90 θh x 90 θd x 180 φd, "
                      "red, green, blue), the bins below the horizon unmeasured, written as a "
                      ".binary file that the tools reading MERL's data read.")
    # measure tabulates in an RGB JIT variant (mi_brdfs.measured.tabulate): no scalar fallback
    [variant] = [a for a in m._actions if a.dest == "variant"]
    variant.help = "Mitsuba variant: an RGB JIT one, llvm_ad_rgb (default) or cuda_ad_rgb"
    m.add_argument("-o", "--output", required=True, type=_output(".binary"),
                   metavar="FILE.binary", help="where to write it")
    m.add_argument("--noise", type=_noise, metavar="REL[,ABS]",
                   help="measurement noise: f·(1 + REL·ε₁) + ABS·ε₂, ε standard normal per bin "
                        "and channel, clipped at 0 (default: none)")
    m.add_argument("--seed", type=_seed, metavar="S",
                   help="seed of the noise, with --noise (default: 0)")
    m.set_defaults(func=cmd_measure)


def _noise(text: str) -> tuple[float, float]:
    """REL or REL,ABS: two finite numbers ≥ 0."""
    try:
        parts = [float(p) for p in text.split(",")]
    except ValueError:
        parts = []
    if not 1 <= len(parts) <= 2 or not all(math.isfinite(p) and p >= 0 for p in parts):
        raise argparse.ArgumentTypeError(f"'{text}' is not REL or REL,ABS (numbers ≥ 0)")
    return (parts[0], parts[1] if len(parts) == 2 else 0.0)


def _add_presets(sub) -> None:
    """``mi-brdfs presets``."""
    p = sub.add_parser(
        "presets", help="the published fits the plugins take as preset=...",
        description="The presets: Ngan, Durand & Matusik's (2005) fits of the lecture models "
                    "to the MERL materials, which a plugin takes as preset=ngan:MATERIAL "
                    "(docs/presets.md): every material, and which plugins take it; with "
                    "PLUGIN, that plugin's presets, one per line.")
    p.add_argument("plugin", nargs="?", metavar="PLUGIN",
                   help="list this plugin's presets (e.g. ward)")
    p.set_defaults(func=cmd_presets)


def _add_explore(sub) -> None:
    """``mi-brdfs explore``."""
    e = _bsdf_command(sub, "explore", "an interactive BRDF explorer in the browser",
                      "Serve a page on 127.0.0.1 that shows up to four BSDFs computed by their "
                      "own eval, pdf and sample (polar plot, albedo, 3-D lobe, (θh, θd) slice, "
                      "sampling density, progressively rendered spheres, verdicts, their XML "
                      "and Python), with a slider for each parameter mi.traverse exposes and a "
                      "menu for each switch; opens the browser. Ctrl-C stops. "
                      "Needs the explore extra: pip install 'mi-brdfs[explore]'.")
    e.add_argument("--port", type=_port, help="the port (default: a free one)")
    e.add_argument("--host", metavar="ADDRESS",
                   help="listen on this address instead of 127.0.0.1 (others can reach it)")
    e.add_argument("--no-browser", action="store_true", help="do not open a browser")
    e.add_argument("--scene", metavar="SCENE",
                   help="render this scene file (or bundled scene) instead of the sphere, "
                        "with each BSDF in place of the one --scene-bsdf names")
    e.add_argument("--scene-bsdf", metavar="ID", help="the id of the scene's BSDF to replace")
    e.set_defaults(func=cmd_explore)


def _add_info(sub) -> None:
    """``mi-brdfs info``."""
    i = sub.add_parser("info", help="versions, variants, LLVM status and registered plugins")
    i.set_defaults(func=cmd_info)
