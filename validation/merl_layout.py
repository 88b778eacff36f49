#!/usr/bin/env python3
"""
What the layout of merl's table buys: the render time of ``merl`` against the ``cooktorrance``
it tabulates (the pair of ``mi-brdfs bench``'s render-cost row: every sphere of the showcase,
``llvm_ad_rgb``) with the same half-precision bins stored three ways:

* MERL's order (φd fastest) starting 16 bytes past a cache line: NumPy's alignment, which
  drjit's CPU backend uses as it is (the plugin without ``plugins.merl._aligned``);
* MERL's order on a cache line: the plugin's layout;
* blocks of 2 × 2 × 2 bins on a cache line, one block of half-precision RGBA per line, so that
  the 8 corners of an interpolation fall in (1 + ½)³ ≈ 3.4 lines on average instead of 4.5:
  an alternative this script builds for the comparison.

Each layout renders in a process of its own (a JIT render traces every BSDF alive in the
process), the layouts taking turns round after round, so that each sees the machine in the
same states; within a process the pair is rendered interleaved after a first render of each,
and the process reports the median of the per-repeat ratios. The script prints, per layout,
the median, the range and how many rounds exceeded the bench's target (1.3×), with the row of
bin (0, 1, 0) and the table's offset past a cache line as the process found them. It asserts
nothing; run it on an otherwise idle machine.

    python validation/merl_layout.py              # 8 rounds of 15 repeats, 128², 32 spp
    python validation/merl_layout.py --quick      # a smoke run (the test suite runs this)

The smoke run measures every layout in one process, in turn (its timings mean nothing; each
process imports Mitsuba and reads the table again).
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from mi_brdfs.measured.merl import RES

LAYOUTS = ("MERL's order, 16 bytes past a line", "MERL's order on lines (the plugin's)",
           "blocks of 2 × 2 × 2 on lines")
TARGET = 1.3


def _block_row(i, j, k, res=RES):
    """The row of bin (i, j, k) in blocks of 2 × 2 × 2 bins, φd fastest (NumPy or drjit
    integers)."""
    block = ((i >> 1) * (res[1] // 2) + (j >> 1)) * (res[2] // 2) + (k >> 1)
    return block * 8 + (i & 1) * 4 + (j & 1) * 2 + (k & 1)


def _use_layout(layout: str) -> None:
    """Make the merl plugin of this process store and look up its bins as ``layout``."""
    import mitsuba as mi

    from mi_brdfs.measured import lookup
    from mi_brdfs.plugins import merl as plugin

    aligned = plugin._aligned
    if layout == LAYOUTS[0]:
        plugin._aligned = lambda rows: aligned(rows, offset=16)
    elif layout == LAYOUTS[2]:
        i, j, k = np.meshgrid(*(np.arange(n) for n in RES), indexing="ij")
        order = np.empty(i.size, np.int64)
        order[_block_row(i, j, k).ravel()] = np.arange(i.size)  # the bin each row holds
        plugin._aligned = lambda rows: aligned(rows[order])
        lookup._flat = lambda i, j, k: mi.UInt32(_block_row(mi.UInt32(i), mi.UInt32(j),
                                                            mi.UInt32(k)))


@contextlib.contextmanager
def _layout(layout: str):
    """Within: the merl plugin of this process stores and looks up its bins as ``layout``;
    the tables it built before, and the layout, are dropped on the way out."""
    from mi_brdfs.measured import lookup
    from mi_brdfs.plugins import merl as plugin

    saved = plugin._aligned, lookup._flat
    plugin._tables.clear()
    _use_layout(layout)
    try:
        yield
    finally:
        plugin._aligned, lookup._flat = saved
        plugin._tables.clear()
        gc.collect()  # the renders' BSDFs: a JIT render traces every BSDF alive


def worker(layouts: list, filename: str, res: int, spp: int, repeats: int) -> list:
    """One process's measurement of each of ``layouts`` in turn: the median ratio and the
    times per sample."""
    import mi_brdfs

    mi_brdfs.use_variant("llvm_ad_rgb")
    import mitsuba as mi

    from mi_brdfs.benchmark.measured import render_cost
    from mi_brdfs.measured import lookup

    out = []
    for layout in layouts:
        with _layout(layout):
            ratio, per = render_cost(f"merl filename={filename}", res, spp, repeats)
            bsdf = mi.load_dict({"type": "merl", "filename": filename})
            _check(bsdf, filename, layout)
            out.append({"ratio": ratio, "ns": per,
                        "start": int(np.from_dlpack(bsdf.table.buffer).ctypes.data % 64),
                        "row": int(lookup._flat(0, 1, 0)[0])})  # 180 in MERL's order, 2 in blocks
            del bsdf
    return out


def _check(bsdf, filename, layout: str) -> None:
    """Exit unless ``bsdf`` evaluates the file's float64 interpolation (within half
    precision's rounding and float32's angles) at random direction pairs: a layout that looks
    its bins up wrong is not timed."""
    import drjit as dr
    import mitsuba as mi

    from mi_brdfs.measured import merl

    rng = np.random.default_rng(1)
    v = rng.normal(size=(2, 4000, 3))
    v[..., 2] = np.abs(v[..., 2])  # both directions above the surface
    wi, wo = v / np.linalg.norm(v, axis=-1, keepdims=True)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(wi.T.astype(np.float32))
    got = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(wo.T.astype(np.float32)))).T
    want = merl.interpolate(np.nan_to_num(merl.read(filename)), wi, wo) * wo[:, 2:]
    if not np.allclose(got, want, rtol=2e-3, atol=1e-6 * want.max()):
        sys.exit(f"merl_layout.py: {layout!r} does not evaluate the file's values")


def _run(layouts, filename, args) -> list:
    """The measurements of ``layouts``, in turn in one worker process."""
    cmd = [sys.executable, __file__, "--worker", *layouts, "--file", str(filename),
           "--res", str(args.res), "--spp", str(args.spp), "--repeats", str(args.repeats)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        sys.exit(f"merl_layout.py: the worker for {', '.join(map(repr, layouts))} failed:"
                 f"\n{p.stderr}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def _table(results: dict) -> str:
    lines = [f"| layout | merl / cooktorrance (median of rounds) | range | rounds > {TARGET}× "
             f"| merl per sample | cooktorrance per sample | row of bin (0, 1, 0) | table's "
             f"start past a line |", "|---|---|---|---|---|---|---|---|"]
    for layout, runs in results.items():
        ratios = [r["ratio"] for r in runs]
        merl = statistics.median(r["ns"]["bsdf"] for r in runs)
        ct = statistics.median(r["ns"]["against"] for r in runs)
        high = sum(x > TARGET for x in ratios)
        lines.append(f"| {layout} | {statistics.median(ratios):.3f}× | {min(ratios):.3f}–"
                     f"{max(ratios):.3f}× | {high} of {len(ratios)} | {merl:.1f} ns | "
                     f"{ct:.1f} ns | {runs[0]['row']} | {runs[0]['start']} bytes |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny sizes, one round")
    parser.add_argument("--rounds", type=int, default=8, help="turns of every layout")
    parser.add_argument("--repeats", type=int, default=15, help="interleaved renders per turn")
    parser.add_argument("--res", type=int, default=128)
    parser.add_argument("--spp", type=int, default=32)
    parser.add_argument("--file", help="a MERL file (default: the bench's tabulation)")
    parser.add_argument("--worker", choices=LAYOUTS, nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:
        args.rounds, args.repeats, args.res, args.spp = 1, 2, 16, 2
    if args.worker:
        print(json.dumps(worker(args.worker, args.file, args.res, args.spp, args.repeats)))
        return
    with tempfile.TemporaryDirectory() as folder:
        filename = args.file or _tabulate(Path(folder) / "cost.binary")
        results = {layout: [] for layout in LAYOUTS}
        turns = [LAYOUTS] if args.quick else [[layout] for layout in LAYOUTS] * args.rounds
        for layouts in turns:
            for layout, measured in zip(layouts, _run(layouts, filename, args)):
                results[layout].append(measured)
    print(f"merl against the cooktorrance it tabulates, llvm_ad_rgb, showcase {args.res}², "
          f"{args.spp} spp; {args.rounds} round(s) of {args.repeats} interleaved repeats "
          f"({os.cpu_count()} cores):\n")
    print(_table(results))


def _tabulate(path: Path) -> Path:
    """The bench's source BSDF tabulated in MERL's format (``mi-brdfs measure``)."""
    from mi_brdfs.benchmark.measured import COST_SOURCE
    from mi_brdfs.measured.tabulate import measure

    measure(COST_SOURCE, path, variant="llvm_ad_rgb")
    return path


if __name__ == "__main__":
    main()
