"""Campaign section: every plugin parameter swept to its extremes; NaN/Inf/negative counts and
where float32 stops following the float64 reference."""

from __future__ import annotations

import numpy as np

from .. import checks
from ..checks.precision import BREAK
from ..plots import pyplot, save_figure
from .core import Context, Row, Section, image, md_table

#: (plugin, parameter, base spec, values): each sweep varies one parameter.
SWEEPS = [
    ("lambert", "reflectance", {"type": "lambert"}, [0.0, 1e-6, 0.5, 1.0]),
    ("phong (mirror)", "exponent",
     {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0},
     [0.0, 1.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e10, 1e12]),
    ("phong (halfway)", "exponent",
     {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 1.0,
      "lobe": "halfway"}, [0.0, 1.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e10, 1e12]),
    ("cooktorrance (V-cavity)", "alpha", {"type": "cooktorrance", "eta": 1.5},
     [1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0, 10.0]),
    ("cooktorrance (Smith)", "alpha", {"type": "cooktorrance", "eta": 1.5, "shadowing": "smith"},
     [1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0, 3.0, 10.0]),
    ("cooktorrance", "eta (k = 0)", {"type": "cooktorrance", "alpha": 0.3, "k": 0.0},
     [1.0 + 1e-6, 1.0 + 1e-4, 1.01, 1.5, 10.0, 100.0, 1e3]),
    ("cooktorrance", "k (η = 1.5)", {"type": "cooktorrance", "alpha": 0.3, "eta": 1.5},
     [0.0, 1.0, 10.0, 100.0, 1e3]),
]


def param_name(name: str) -> str:
    """The parameter of a sweep label ('alpha (GGX)' -> 'alpha')."""
    return name.split(" ")[0]


def section(ctx: Context) -> Section:
    s = Section("The extremes matrix")
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    panels = {"reflectance": axes[0], "exponent": axes[0], "alpha": axes[1], "eta": axes[2],
              "k": axes[2]}
    rows = []
    n = ctx.n(20_000, 3_000)
    for plugin, name, base, values in SWEEPS:
        key = param_name(name)
        values = values if not ctx.quick else values[:: max(1, len(values) // 4)] + values[-1:]
        values = sorted(set(values))
        p99, bad, breakpoint = [], 0, None
        for v in values:
            spec = dict(base, **{key: v})
            p = checks.eval_precision(spec, n=n)
            stab = checks.check_stability(spec, n_random=ctx.n(2_000, 200))
            bad += int(stab.value)
            p99.append(p.p99)
            if breakpoint is None and p.p99 > BREAK:
                breakpoint = v
            rows.append((plugin, name, f"{v:.7g}", int(stab.value), f"{p.median:.1e}",
                         f"{p.p99:.1e}", f"{p.max:.1e}"))
        s.rows.append(Row(plugin, f"no NaN/Inf/negative over {name} ∈ [{values[0]:g}, "
                          f"{values[-1]:g}]", f"{bad} bad values", "0", bad == 0))
        s.rows.append(Row(plugin, f"float32 follows float64 (p99 ≤ {BREAK:g}), {name}",
                          "everywhere" if breakpoint is None else f"up to < {breakpoint:g}",
                          "measured", True))
        ax = panels[key]
        x = np.array(values, dtype=np.float64)
        if key == "eta":
            x = x - 1.0  # η − 1: the distance from index matching
        ax.loglog(np.maximum(x, 1e-7), np.maximum(p99, 1e-9), "o-", ms=3,
                  label=f"{plugin}: {name}")
    for ax, label in ((axes[0], "exponent n (reflectance for lambert)"), (axes[1], "α"),
                      (axes[2], "η − 1 (k = 0) or k (η = 1.5)")):
        ax.axhline(BREAK, color="0.5", ls=":", lw=0.8)
        ax.set_xlabel(label)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("99th percentile of |f32 − f64| / f64")
    fig.suptitle("float32 eval against the float64 reference at the directions the BSDF "
                 f"samples (dotted: {BREAK:g})", fontsize=9)
    path = save_figure(fig, ctx.figure("extremes_precision.png"))
    s.markdown = "\n".join([
        "Each plugin with one parameter swept to its extremes. For every value: the stability "
        "sweep (NaN, Inf or negative eval, pdf or sample weight at the stress directions: "
        "normal, grazing down to cosθ = 6e-17, back-facing, V = −L, at and beside the mirror "
        "direction, plus random pairs), and the relative error of the plugin's float32 `eval` "
        "against the float64 reference at the same directions, drawn by the plugin's own "
        "sampler at 0°, 45° and 80° incidence (`checks.eval_precision`). The breakpoint is the "
        f"first value where the 99th percentile of that error exceeds {BREAK:g}.", "",
        image(ctx, path, "float32 against float64"), "",
        md_table(["plugin", "parameter", "value", "NaN/Inf/negative", "median rel. error",
                  "99th percentile", "max"], rows), "",
        "Reading the matrix: Phong's mirror lobe follows float64 far beyond where the textbook "
        "pow(R·V, n) breaks (see the `phong` section of the README); its halfway lobe is "
        "limited by the half-vector of two float32 directions. For Cook-Torrance, η → 1 is a "
        "limit of the *parameter*, not of the arithmetic: float32 cannot hold η closer to 1 "
        "than 1.2e-7, and F ∝ (η − 1)² there, so the relative error of a vanishing "
        "reflectance grows while the reflectance itself goes to 0."])
    return s
