"""
The interaction latency of ``mi-brdfs explore`` in ``make bench``: a page's :class:`Explorer`
(:mod:`mi_brdfs.explorer.app`) is driven in-process as the browser's events drive it, by a
scripted series of parameter changes, and each change is timed in two parts: the 2-D plots
redrawn (the views of the changed BSDF computed and their Bokeh sources updated) and the first
pass of the spheres (64 × 64). The time the browser then takes to draw is not in these
figures (it is the browser's, on the user's machine).
"""

from __future__ import annotations

import time

import numpy as np

from ..campaign.core import SKIPPED, Context, Row, Section, md_table

#: The BSDFs of the page (the plugin against its Mitsuba twin), and the changes: α of the first.
PAGES = [
    ("one BSDF", ["cooktorrance alpha=0.3 material=Au distribution=ggx"]),
    ("two BSDFs", ["cooktorrance alpha=0.3 material=Au distribution=ggx",
                   "roughconductor alpha=0.3 material=Au distribution=ggx"]),
    ("four BSDFs", ["cooktorrance alpha=0.3 material=Au distribution=ggx",
                    "roughconductor alpha=0.3 material=Au distribution=ggx",
                    "phong exponent=40", "lambert"]),
]
ALPHAS = (0.1, 0.2, 0.35, 0.5, 0.25, 0.15)
#: Changes made before the timed ones (the kernels of the values' first changes compile).
WARM_UP = 4
#: The targets (seconds): the 2-D plots, and the spheres' first pass.
TARGETS = {"plots": 0.100, "sphere": 0.300}


def latency(specs, changes: int) -> dict:
    """{'plots': [s, ...], 'sphere': [s, ...]}: each of ``changes`` changes of the first BSDF's
    α timed (after :data:`WARM_UP` changes that compile the kernels)."""
    from ..explorer.app import Explorer

    page = Explorer(specs)
    times = {"plots": [], "sphere": []}
    for k in range(changes + WARM_UP):
        assert page.set_parameter(0, "alpha.value", ALPHAS[k % len(ALPHAS)])
        if k >= WARM_UP:
            for key in times:
                times[key].append(page.latency[key])
    return times


def _stats(values) -> tuple[float, float]:
    return float(np.median(values)), float(np.percentile(values, 95))


def section(ctx: Context) -> Section:
    s = Section("Interaction latency of mi-brdfs explore")
    try:
        import panel  # noqa: F401
    except ImportError:
        s.markdown = "Not measured: the explore extra (Panel) is not installed."
        return s
    rows = []
    for label, specs in PAGES:
        if ctx.quick and len(specs) > 1:
            rows.append((label, SKIPPED, SKIPPED, SKIPPED, SKIPPED))
            continue
        clock = time.perf_counter()
        times = latency(specs, ctx.n(30, 4))
        stats = {key: _stats(v) for key, v in times.items()}
        for key, target in TARGETS.items():
            median, p95 = stats[key]
            s.values[f"explore, {label}: {key}, median"] = f"{1e3 * median:.0f} ms"
            s.values[f"explore, {label}: {key}, p95"] = f"{1e3 * p95:.0f} ms"
            s.rows.append(Row(f"explore, {label}", f"{key} after a change (p95)",
                              f"{1e3 * p95:.0f} ms", f"≤ {1e3 * target:.0f} ms",
                              p95 <= target, judged=not ctx.quick))
        rows.append((label, *(f"{1e3 * v:.0f} ms" for key in TARGETS for v in stats[key])))
        s.values[f"explore, {label}: seconds"] = f"{time.perf_counter() - clock:.0f}"
    s.markdown = "\n".join([
        f"A page of `mi-brdfs explore` driven in-process ({ctx.variant}), α of the first BSDF "
        f"changed {ctx.n(30, 4)} times after {WARM_UP} changes that compile the kernels; each "
        "change timed until the 2-D plots' data are updated (the changed BSDF's polar plot, "
        "albedo, 3-D lobe, (θh, θd) slice and sampling density) and until the spheres' first "
        "pass (64 × 64) is drawn. Targets: plots ≤ 100 ms, first pass ≤ 300 ms (95th "
        "percentile). The browser's own drawing is not included.", "",
        md_table(["page", "plots: median", "plots: p95", "first pass: median",
                  "first pass: p95"], rows)])
    return s
