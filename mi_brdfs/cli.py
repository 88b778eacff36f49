"""
The ``mi-brdfs`` command line (also ``python -m mi_brdfs``): a thin layer over the library.

User errors (a missing scene, a bad parameter, an unwritable output) print one line
``mi-brdfs: error: ...`` and exit with status 2; no traceback. An interrupted render writes what
it has and exits with status 130.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

EXIT_USER_ERROR = 2
EXIT_INTERRUPTED = 130


def _one_line_warnings(message, category, filename, lineno, file=None, line=None):
    print(f"mi-brdfs: warning: {message}", file=sys.stderr if file is None else file)


def _add_variant(p: argparse.ArgumentParser) -> None:
    p.add_argument("--variant", metavar="V",
                   help="Mitsuba variant (default: llvm_ad_rgb where LLVM works, else scalar_rgb)")


def _parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(
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
    r.add_argument("-o", "--output", metavar="OUT.exr",
                   help="output EXR (default: ./<scene name>.exr); the PNG goes beside it")
    r.add_argument("--spp", type=int, metavar="N",
                   help="samples per pixel (default: the scene's sampler; unlimited with "
                        "--time-budget)")
    _add_variant(r)
    r.add_argument("--seed", type=int, default=0, metavar="S", help="base seed (default: 0)")
    r.add_argument("--time-budget", type=float, metavar="SECONDS",
                   help="stop starting passes that would end after this many seconds")
    r.add_argument("-D", dest="defines", action="append", default=[], metavar="name=value",
                   help="override a <default> of the scene (repeatable)")
    r.add_argument("--pass-spp", type=int, metavar="N", help="samples per pixel in each pass")
    r.add_argument("--processes", type=int, metavar="N",
                   help="worker processes for scalar scenes with Python plugins "
                        "(default: one per core when it pays)")
    r.add_argument("--no-png", action="store_true", help="write no PNG preview")
    r.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops (default 0)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_render)

    i = sub.add_parser("info", help="versions, variants, LLVM status and registered plugins")
    i.set_defaults(func=cmd_info)
    return parser


def cmd_render(args) -> int:
    import mi_brdfs
    from .errors import MiBrdfsError
    from .imageio import check_writable, write_exr, write_png
    from .render import render
    from .scenes import parse_defines, scene_path

    path = scene_path(args.scene)
    out = Path(args.output) if args.output else Path.cwd() / f"{path.stem}.exr"
    if out.suffix.lower() != ".exr":
        raise MiBrdfsError(f"output must be an .exr file, got {out}")
    out = check_writable(out)
    png = out.with_suffix(".png")
    if not args.no_png:
        check_writable(png)
    if args.spp is not None and args.spp < 1:
        raise MiBrdfsError(f"--spp must be at least 1, got {args.spp}")
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
