#!/usr/bin/env python3
"""
Render-time ratios of each mi_brdfs plugin against its Mitsuba built-in: the "Backends" table
of ``mi-brdfs bench`` (mi_brdfs/benchmark/backends.py), on its own.

Every pair is rendered interleaved in one process (A, B, B, A, ...), after a first render of each
that is excluded (it holds the JIT compilation); the script prints medians and the median of the
per-repeat ratios. Run it on a quiet machine; it asserts nothing.

    python validation/bench_render.py            # the full sizes
    python validation/bench_render.py --quick    # a smoke run (the test suite runs this)
    python validation/bench_render.py --jit-only --pair Smith   # llvm_ad_rgb, the Smith pairs

Targets: llvm_ad_rgb ≤ 1.03×; scalar_rgb through the package's render path is reported without a
target (scalar variants are for debugging).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
from pathlib import Path

import mi_brdfs  # first: it chooses the libLLVM before drjit loads

import mitsuba as mi  # noqa: E402

from mi_brdfs.benchmark import backends  # noqa: E402
from mi_brdfs.campaign.core import Context, Section, md_table  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes, few repeats")
    parser.add_argument("--json", metavar="FILE", help="also write the table rows as JSON")
    parser.add_argument("--jit-only", action="store_true",
                        help="only the llvm_ad_rgb pairs (the scalar render path takes long)")
    parser.add_argument("--pair", action="append", default=[], metavar="TEXT",
                        help="only the pairs whose label contains TEXT (repeatable)")
    args = parser.parse_args(argv)
    pairs = [p for p in backends.PAIRS
             if not args.pair or any(t in p.label for t in args.pair)]
    variant = mi_brdfs.use_variant(None)
    ctx = Context(out=Path("."), quick=args.quick, variant=variant)
    section = Section("render-time ratios")
    rows = []
    if variant.startswith("llvm"):
        rows += backends.jit_ratios(ctx, section, pairs)
    if not args.jit_only:
        rows += backends.scalar_ratios(ctx, section, pairs)
    print(f"Render time, plugin vs built-in, medians of interleaved repeats "
          f"({platform.machine()}, {os.cpu_count()} cores, Mitsuba {mi.__version__}):\n")
    print(md_table(["pair", "variant", "plugin per sample", "built-in per sample", "ratio",
                    "target", "first render plugin / built-in"], rows))
    if args.json:
        with open(args.json, "w") as f:
            json.dump([{"pair": r.plugin, "measure": r.check, "ratio": r.result,
                        "target": r.tolerance, "met": r.passed} for r in section.rows], f,
                      indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
