"""
What ``mi-brdfs fit`` and ``mi-brdfs simplify`` cost a user: a default fit, and ``simplify`` on
the bundled showcase (``--quick`` and full), from an empty cache, then again with the cache
(another tolerance), wall time on this machine.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from ..campaign.core import Context, Row, Section, md_table

#: The costs the tools promise (seconds): a fit, simplify on the showcase (full and --quick).
TARGET_FIT, TARGET_SIMPLIFY, TARGET_SIMPLIFY_QUICK = 60.0, 300.0, 60.0


def section(ctx: Context) -> Section:
    from ..fit import fit
    from ..simplify import simplify

    s = Section("Fit and simplify on the user's scene")
    rows = []
    t0 = time.perf_counter()
    steps = ctx.n(800, 40)
    result = fit("cooktorrance material=Au alpha=0.2", "phong lobe=halfway",
                 steps=steps, pairs=ctx.n(16384, 1024), progress=False)
    t_fit = time.perf_counter() - t0
    s.values["fit: residual"] = f"{result.residual:.3f}"
    rows.append(("fit: phong (halfway) to cooktorrance Au α = 0.2", f"{steps} steps",
                 f"{t_fit:.1f} s", f"≤ {TARGET_FIT:g} s"))
    s.values["fit: seconds"] = f"{t_fit:.1f}"
    s.rows.append(Row("fit", "a default fit, wall time", f"{t_fit:.1f} s",
                      f"≤ {TARGET_FIT:g} s", t_fit <= TARGET_FIT))
    runs = [("--quick", True, TARGET_SIMPLIFY_QUICK)] + ([] if ctx.quick else
                                                         [("full", False, TARGET_SIMPLIFY)])
    for label, quick, target in runs if not ctx.quick else []:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            first = simplify("showcase", 0.01, variant=ctx.variant, quick=quick,
                             cache=Path(tmp), progress=False)
            t_first = time.perf_counter() - t0
            t0 = time.perf_counter()
            simplify("showcase", 0.02, variant=ctx.variant, quick=quick, cache=Path(tmp),
                     progress=False)
            t_again = time.perf_counter() - t0
        replaced = sum(1 for m in first.materials if m.chosen)
        rows.append((f"simplify showcase {label}", f"{len(first.materials)} materials, "
                     f"{replaced} replaced", f"{t_first:.0f} s (again, cached, other tolerance: "
                     f"{t_again:.0f} s)", f"≤ {target:g} s"))
        s.values[f"simplify {label}: seconds"] = f"{t_first:.0f}"
        s.rows.append(Row("simplify", f"showcase {label}, wall time", f"{t_first:.0f} s",
                          f"≤ {target:g} s", t_first <= target))
    s.markdown = "\n".join([
        "What the user-scene tools cost on this machine, wall time: `mi_brdfs.fit.fit` with its "
        "defaults, and `mi_brdfs.simplify.simplify` on the bundled showcase from an empty cache, "
        "then rerun with another tolerance from the cache it left "
        f"({ctx.variant}).", "",
        md_table(["what", "size", "time", "target"], rows)])
    return s
