#!/usr/bin/env python3
"""
Render-time benchmark: each mi_brdfs plugin against its Mitsuba built-in on the same scene, and
phong against lambert (what its glossy lobe costs per sample).

Every pair is rendered interleaved in one process (A, B, B, A, A, B, ...), after a warm-up render
of each that is excluded (it holds the JIT compilation), and the script reports medians and the
median of the per-repeat ratios. Run it on a quiet machine; it asserts nothing.

    python validation/bench_render.py            # the figures in README.md
    python validation/bench_render.py --quick    # a smoke run (the test suite runs this)
    python validation/bench_render.py --pairs phong   # only the pairs whose label says phong

Targets (TARGETS): lambert (issue #2) llvm_ad_rgb ratio ≤ 1.03, scalar_rgb through the
package's render path (mi_brdfs.render.render, which picks one thread per process) ≤ 12×;
cooktorrance with shadowing=smith against roughconductor on scenes/metalbox.xml (issue #4)
llvm_ad_rgb ≤ 1.03. The other rows (the textbook V-cavity model, scalar cooktorrance) are for
information.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from typing import NamedTuple

import mi_brdfs  # first: it chooses the libLLVM before drjit loads

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

from mi_brdfs.render import render  # noqa: E402
from mi_brdfs.scenes import load_scene  # noqa: E402

class Pair(NamedTuple):
    """Two renders of one scene, timed against each other."""

    label: str
    scene: str
    ours: dict        # defines of the plugin's render
    ref: dict         # defines of the reference render
    targets: dict | None = None  # the largest acceptable ratio per variant; None: a measurement
    processes: int | None = None  # scalar render path's worker processes (None: its choice)


PAIRS = [
    Pair("lambert vs diffuse", "cbox", {"material": "lambert"}, {"material": "diffuse"},
         {"llvm_ad_rgb": 1.03, "scalar_rgb": 12.0}),
    # What Phong's glossy lobe costs per sample over a Lambert (ρd 0.8 and the defaults ks 0.2,
    # n 30), on the furnace sphere: one BSDF sample and one emitter sample per hit. In scalar
    # variants both render on one thread in-process, so that the ratio is the per-sample cost
    # (the render path would give the slower one worker processes, the other not).
    Pair("phong vs lambert (furnace)", "furnace",
         {"material": "phong", "reflectance_name": "diffuse_reflectance", "reflectance": "0.8"},
         {"material": "lambert", "reflectance": "0.8"}, processes=1),
    Pair("cooktorrance smith vs roughconductor", "metalbox", {"metal": "cooktorrance-smith"},
         {"metal": "roughconductor"}, {"llvm_ad_rgb": 1.03}),
    Pair("cooktorrance (V-cavity) vs roughconductor", "metalbox", {"metal": "cooktorrance"},
         {"metal": "roughconductor"}),
]


def _time_jit(scene, spp, seed):
    t0 = time.perf_counter()
    image = mi.render(scene, spp=spp, seed=seed)
    dr.eval(image)
    dr.sync_thread()
    return time.perf_counter() - t0


def bench_jit(pair, res, spp, repeats):
    """Both scenes loaded once; mi.render timed directly, warm-up excluded."""
    scenes = [load_scene(pair.scene, dict(d, res=str(res))) for d in (pair.ours, pair.ref)]
    first = [_time_jit(s, spp, 0) for s in scenes]  # includes tracing + compiling the kernel
    times = ([], [])
    for r in range(repeats):
        order = (0, 1) if r % 2 == 0 else (1, 0)
        for i in order:
            times[i].append(_time_jit(scenes[i], spp, r + 1))
    return first, times


def bench_render_path(pair, res, spp, repeats):
    """Scalar: both through mi_brdfs.render.render (the package's arrangement), interleaved."""
    times, arrangement = ([], []), ["", ""]
    for r in range(repeats + 1):
        order = (0, 1) if r % 2 == 0 else (1, 0)
        for i in order:
            defines = dict((pair.ours, pair.ref)[i], res=str(res))
            result = render(pair.scene, spp=spp, seed=r, defines=defines,
                            processes=pair.processes, progress=False)
            arrangement[i] = result.arrangement
            if r > 0:  # the first round warms caches (and starts nothing we want to time)
                times[i].append(result.wall_time)
    return arrangement, times


def summarize(times):
    ratios = [a / b for a, b in zip(*times)]
    return statistics.median(times[0]), statistics.median(times[1]), statistics.median(ratios)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes, 2 repeats (smoke test)")
    parser.add_argument("--repeats", type=int, default=None)
    parser.add_argument("--variants", default="llvm_ad_rgb,scalar_rgb")
    parser.add_argument("--pairs", default="", metavar="TEXT",
                        help="only the pairs whose label contains TEXT (e.g. phong)")
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    args = parser.parse_args(argv)

    settings = {  # variant: (res, spp, repeats)
        "llvm_ad_rgb": (32, 4, 2) if args.quick else (256, 64, 15),
        "scalar_rgb": (16, 2, 2) if args.quick else (128, 16, 5),
    }
    rows, results = [], []
    for variant in args.variants.split(","):
        if variant.startswith("llvm") and not mi_brdfs.llvm_usable():
            print(f"skipping {variant}: no working libLLVM", file=sys.stderr)
            continue
        mi_brdfs.use_variant(variant, fallback=False)
        res, spp, repeats = settings[variant]
        repeats = args.repeats or repeats
        for pair in (p for p in PAIRS if args.pairs in p.label):
            if dr.is_jit_v(mi.Float):
                first, times = bench_jit(pair, res, spp, repeats)
                how = (f"mi.render; first render (trace + compile): {first[0]:.2f} s "
                       f"vs {first[1]:.2f} s")
            else:
                arrangement, times = bench_render_path(pair, res, spp, repeats)
                how = f"mi_brdfs render path ({arrangement[0]}) vs ({arrangement[1]})"
            ours, ref, ratio = summarize(times)
            target = (pair.targets or {}).get(variant)
            verdict = ("—" if target is None else
                       f"≤ {target:g}× ({'meets' if ratio <= target else 'misses'})")
            rows.append(f"| {pair.label} | {variant} | {res}×{res}, {spp} spp | {ours:.3f} s | "
                        f"{ref:.3f} s | **{ratio:.2f}×** | {verdict} | {how} |")
            results.append(dict(pair=pair.label, variant=variant, res=res, spp=spp, repeats=repeats,
                                plugin_s=times[0], builtin_s=times[1], median_ratio=ratio,
                                target=target, how=how))
    print(f"Render time (Cornell box; phong on the furnace sphere; the metals on metalbox), "
          f"median of interleaved repeats "
          f"({platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Mitsuba {mi.__version__}):\n")
    print("| pair | variant | size | plugin | reference | ratio | target | how |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
