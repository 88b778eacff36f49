"""
Campaign section: model vs measurement. The ``merl`` plugin and the fits to measured data, on
data whose answer is known: Mitsuba's ``roughconductor`` (gold, GGX) tabulated by the virtual
gonioreflectometer (:func:`mi_brdfs.measured.tabulate.measure`) at several roughnesses, read
back by ``merl`` and compared with its source (the interpolation error per α, trilinear and
MERL's nearest bin; the albedo), the whole battery of checks on one file, and ``fit`` of
Cook-Torrance (Smith, GGX) to noisy tabulations under every metric, which must recover α.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from ..bsdfspec import load_bsdf
from ..checks import batch
from ..checks.albedo import albedo_sampled
from ..checks.battery import run_battery
from ..fit import METRICS, direction_pairs, fit
from ..measured.tabulate import measure
from .core import Context, Row, Section, md_table

SOURCE = "roughconductor material=Au distribution=ggx alpha={alpha}"
#: Roughnesses of the round trips; the interpolation is held to 1 % from :data:`HELD` up.
ALPHAS = (0.02, 0.05, 0.1, 0.2, 0.4)
HELD = 0.05
#: Incident angles (degrees) of the albedo comparison, and its tolerance (relative).
ALBEDO_THETAS = (0.0, 60.0, 80.0)
ALBEDO_TOL = 0.02
#: Roughnesses of the fits, the noise of their data (relative, absolute), the tolerance on α.
FIT_ALPHAS = (0.1, 0.25, 0.5)
NOISE = (0.03, 0.0)
FIT_TOL = 0.02
MODEL = "cooktorrance material=Au distribution=ggx shadowing=smith alpha=0.3"


def _projected_error(a, b, wi, wo) -> float:
    """‖Δ(f·cosθi·cosθo)‖/‖b's‖ over the pairs."""
    va = batch.evaluate(a, wi, wo).value * wi[:, 2:3]
    vb = batch.evaluate(b, wi, wo).value * wi[:, 2:3]
    return float(np.linalg.norm(va - vb) / np.linalg.norm(vb))


def _albedos(bsdf, n: int) -> np.ndarray:
    return np.array([albedo_sampled(bsdf, math.radians(t), n=n)[0].mean()
                     for t in ALBEDO_THETAS])


def _round_trips(ctx: Context, s: Section, folder: Path) -> list:
    """The table's rows: interpolation error and albedo per α and filter."""
    wi, wo = direction_pairs(ctx.n(200_000, 20_000), seed=5)
    n = ctx.n(400_000, 40_000)
    rows = []
    for alpha in ALPHAS:
        source = load_bsdf(SOURCE.format(alpha=alpha))
        path = folder / f"ggx-{alpha}.binary"
        measure(SOURCE.format(alpha=alpha), path)
        e_source = _albedos(source, n)
        errors = {}
        for flt in ("trilinear", "nearest"):
            merl = load_bsdf({"type": "merl", "filename": str(path), "filter_type": flt})
            errors[flt] = _projected_error(merl, source, wi, wo)
            e_merl = _albedos(merl, n)
            worst = float(np.max(np.abs(e_merl / e_source - 1.0)))
            rows.append((f"{alpha:g}", flt, f"{errors[flt]:.4f}",
                         ", ".join(f"{x:.4f}" for x in e_merl),
                         ", ".join(f"{x:.4f}" for x in e_source), f"{worst:.4f}"))
            s.values[f"merl round trip α = {alpha:g}, {flt}: error"] = f"{errors[flt]:.4f}"
            if flt == "trilinear" and alpha >= HELD:
                s.rows.append(Row("merl", f"round trip, α = {alpha:g}: rel. error of "
                                  "f·cosθi·cosθo", f"{errors[flt]:.4f}", "≤ 0.01",
                                  errors[flt] <= 0.01))
                s.rows.append(Row("merl", f"round trip, α = {alpha:g}: albedo vs the source",
                                  f"{worst:.4f}", f"≤ {ALBEDO_TOL}", worst <= ALBEDO_TOL))
        s.rows.append(Row("merl", f"round trip, α = {alpha:g}: trilinear closer than nearest",
                          f"{errors['trilinear']:.4f} vs {errors['nearest']:.4f}", "<",
                          errors["trilinear"] < errors["nearest"]))
    return rows


def _fits(ctx: Context, s: Section, folder: Path) -> list:
    """The table's rows: α recovered from noisy tabulations under every metric."""
    sizes = dict(pairs=ctx.n(16384, 2048), steps=ctx.n(800, 150), starts="given",
                 thetas_deg=(0.0, 60.0))
    rows = []
    for alpha in FIT_ALPHAS:
        path = folder / f"noisy-{alpha}.binary"
        measure(SOURCE.format(alpha=alpha), path, noise=NOISE, seed=1)
        found = {}
        for metric in METRICS:
            result = fit(str(path), MODEL, "alpha", metric=metric, **sizes)
            found[metric] = float(result.parameters["alpha"])
            off = abs(found[metric] / alpha - 1.0)
            s.rows.append(Row("fit", f"α = {alpha:g} from noisy data, {metric}",
                              f"{found[metric]:.4f}", f"within {FIT_TOL:.0%}", off <= FIT_TOL))
        rows.append((f"{alpha:g}", *[f"{found[m]:.4f}" for m in METRICS]))
    return rows


def _battery(ctx: Context, s: Section, folder: Path) -> list:
    """Every check of the battery on merl of the α = 0.1 tabulation."""
    path = folder / "ggx-0.1.binary"
    results = run_battery({"type": "merl", "filename": str(path)}, quick=ctx.quick,
                          progress=False)
    rows = []
    for r in results:
        if r.skipped:
            continue
        s.rows.append(Row.of("merl", r, f"battery: {r.name}"))
        shown = [f"{v:.4g}" if isinstance(v, float) else str(v) for v in (r.value, r.tolerance)]
        rows.append((r.name, *shown, "pass" if r.passed else "FAIL"))
    return rows


def section(ctx: Context) -> Section:
    s = Section("Model vs measurement: merl")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        trips = _round_trips(ctx, s, folder)
        battery = _battery(ctx, s, folder)
        fits = _fits(ctx, s, folder)
    s.markdown = "\n".join([
        f"`{SOURCE.format(alpha='α')}` tabulated in MERL's format by `mi-brdfs measure` "
        "(f at the centre of every bin), read back by the `merl` plugin and compared with its "
        "source. **Interpolation error**: ‖Δ(f·cosθi·cosθo)‖/‖·‖ over "
        f"{ctx.n(200_000, 20_000):,} pairs drawn as the fits draw them (dense about the peak); "
        f"**albedo** E(θ) at θ = {', '.join(f'{t:g}°' for t in ALBEDO_THETAS)} from each "
        "one's own `sample()` (mean of RGB), and the largest relative difference. The peak of "
        "a narrow lobe falls between MERL's θh bins: the error grows as α shrinks, and MERL's "
        "nearest-bin lookup is about ten times the trilinear interpolation's.", "",
        md_table(["α", "lookup", "interpolation error", "E(θ) merl", "E(θ) source",
                  "albedo rel. diff."], trips), "",
        "**The battery** on `merl` of the α = 0.1 tabulation (`mi-brdfs check`):", "",
        md_table(["check", "value", "tolerance", "result"], battery), "",
        f"**Fits to measured data**: the tabulations with {NOISE[0]:.0%} relative noise "
        f"(`measure --noise {NOISE[0]:g}`), `{MODEL}` fitted with α free from α = 0.3, at "
        "the files' own bins, under each metric (`fit --metric`); the α found:", "",
        md_table(["true α", *METRICS], fits)])
    return s
