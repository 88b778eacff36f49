"""
Campaign section: He, Torrance, Sillion & Greenberg's BRDF (``he``). The battery in the three
regimes of the phase variance (smooth, intermediate, rough), and the energy measured, not
assumed: the directional albedo E(θ) from the plugin's own ``sample()`` (the delta's weight
included) in each reading of the paper, against the float64 reference's quadrature at the same
wavelengths (:meth:`mi_brdfs.reference.he.HTSG.albedo`).
"""

from __future__ import annotations

import math

import numpy as np

from ..checks.albedo import albedo_sampled
from ..checks.battery import run_battery
from ..reference.he import HTSG
from ..scattering.he import READINGS, RGB_WAVELENGTHS
from .core import Context, Row, Section, md_table

#: (label, σ0, τ) in µm: g at normal incidence and 526 nm about 0.2, 2.3 and 150.
REGIMES = (("smooth", 0.01, 1.0), ("intermediate", 0.04, 2.0), ("rough", 0.3, 3.0))
#: The energy's surface: bbm's default roughness on a metal (η = 1, k = 6).
ENERGY = {"sigma0": 0.18, "tau": 3.0, "eta": 1.0, "k": 6.0}
THETAS = (0.0, 45.0, 80.0)
#: The sampled albedo's agreement with the reference: relative, beyond 5 standard errors.
ALBEDO_TOL = 0.01


def _battery(ctx: Context, s: Section) -> list:
    rows = []
    for label, sigma0, tau in REGIMES:
        spec = {"type": "he", "sigma0": sigma0, "tau": tau, "eta": 1.4,
                "diffuse_reflectance": 0.1}
        for r in run_battery(spec, quick=ctx.quick, progress=False):
            if r.skipped:
                continue
            s.rows.append(Row.of("he", r, f"{label}: battery: {r.name}"))
            shown = [f"{v:.4g}" if isinstance(v, float) else str(v)
                     for v in (r.value, r.tolerance)]
            rows.append((label, r.name, *shown, "pass" if r.passed else "FAIL"))
    return rows


def _energy(ctx: Context, s: Section) -> list:
    rows = []
    n = ctx.n(1_000_000, 100_000)
    for reading in READINGS:
        spec = dict(ENERGY, type="he", variant=reading)
        model = HTSG(ENERGY["sigma0"], ENERGY["tau"], list(RGB_WAVELENGTHS), ENERGY["eta"],
                     ENERGY["k"], variant=reading)
        for theta in THETAS:
            mean, err = albedo_sampled(spec, math.radians(theta), n=n)
            want = model.albedo(math.radians(theta))
            off = np.abs(mean - want) - 5.0 * err
            worst = float(np.max(off / want))
            s.values[f"he albedo, {reading}, θ = {theta:g}°"] = f"{float(np.mean(mean)):.4g}"
            s.rows.append(Row("he", f"E(θ = {theta:g}°), {reading}: sample() vs the reference",
                              f"{worst:.2e}", f"≤ {ALBEDO_TOL:g} beyond 5σ",
                              worst <= ALBEDO_TOL))
            rows.append((reading, f"{theta:g}°", ", ".join(f"{x:.4g}" for x in mean),
                         ", ".join(f"{x:.4g}" for x in want)))
        if reading == "westin":
            peak = max(float(np.max(model.albedo(math.radians(t)))) for t in THETAS)
            s.rows.append(Row("he", "westin: E(θ) ≤ 1", f"{peak:.4f}", "≤ 1", peak <= 1.0))
    return rows


def section(ctx: Context) -> Section:
    s = Section("He et al.: he")
    battery = _battery(ctx, s)
    energy = _energy(ctx, s)
    s.markdown = "\n".join([
        "**The battery** (`mi-brdfs check`) on `he` (westin reading, η = 1.4, a = 0.1) in the "
        "three regimes of the phase variance g (at normal incidence and 526 nm): "
        + ", ".join(f"{label} σ0 = {s0:g} µm, τ = {t:g} µm" for label, s0, t in REGIMES)
        + ".", "",
        md_table(["regime", "check", "value", "tolerance", "result"], battery), "",
        "**Energy, measured**: E(θ) = ρ_s + ∫ρ_dd cosθo dωo from the plugin's `sample()` "
        f"({ctx.n(1_000_000, 100_000):,} samples, RGB) against the float64 reference's "
        "quadrature at the same wavelengths (0.645, 0.526, 0.444 µm), on bbm's default "
        f"roughness (σ0 = {ENERGY['sigma0']:g} µm, τ = {ENERGY['tau']:g} µm) of a metal "
        f"(η = {ENERGY['eta']:g}, k = {ENERGY['k']:g}), in each reading. Only westin's stays "
        "under 1: the printed reading of v_xy makes the lobe k² times too strong as the "
        "surface roughens (`mi_brdfs.reference.he`).", "",
        md_table(["reading", "θ", "E(θ) he (R, G, B)", "reference"], energy)])
    return s
