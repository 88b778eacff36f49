"""
Campaign section: the Earth-observation plugins ``rtls``, ``rpv``, ``hapke`` and ``ocean``, each
at its defaults (Eradiate's) and at one parameter set its docstring documents. The battery of
checks, eval against the float64 reference (:mod:`mi_brdfs.reference`) at random pairs, the
three findings ``mi-brdfs check`` makes on Eradiate's plugins checked on ours (rtls below 0,
rpv infinite at grazing backscatter, hapke NaN at the opposition), and the directional albedo
E(θ) from each plugin's ``sample()`` against the reference's quadrature.
"""

from __future__ import annotations

import math

import numpy as np

from .. import checks
from ..bsdfspec import load_bsdf
from ..checks import batch
from ..checks.battery import CHI2_THETAS
from ..checks.reciprocity import RTOL
from ..reference import for_spec
from .core import Context, Row, Section, md_table

#: (plugin, label, parameters, checks the model itself fails there: the docstring's words).
SETS = (
    ("rtls", "defaults", {}, {}),
    ("rtls", "f_iso = 0.2, f_vol = 0.1, f_geo = 0.03",
     {"f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.03}, {}),
    ("rpv", "defaults (k = 0.1)", {},
     {"energy": "k < 1: E(θi) grows without bound towards grazing incidence (the model's)"}),
    ("rpv", "ρ0 = 0.2, k = 1.4, g = −0.3, ρc = 0.05",
     {"rho_0": 0.2, "k": 1.4, "g": -0.3, "rho_c": 0.05}, {}),
    ("hapke", "defaults", {}, {}),
    ("hapke", "lunar-like: w = 0.3, b = 0.25, c = 0.7, θ̄ = 20°, B_0 = 1, h = 0.06",
     {"w": 0.3, "b": 0.25, "c": 0.7, "theta": 20.0, "B_0": 1.0, "h": 0.06}, {}),
    ("ocean", "defaults (U = 0.1 m/s)", {}, {}),
    ("ocean", "U = 10 m/s, ext_ior = 1", {"wind_speed": 10.0, "ext_ior": 1.0}, {}),
)
#: Incident angles (degrees) of the albedo table (and of the energy and agreement checks).
THETAS = (0.0, 30.0, 60.0, 80.0, 89.0)
#: eval against the float64 reference: relative, over values above 10⁻⁶ of the largest.
REFERENCE_RTOL = 1e-3
#: Reciprocity's relative tolerance where it is not the check's own: rtls's BRF is a sum of
#: terms of either sign (f_geo K_geo ≈ −0.3 towards grazing), so where it nears 0 float32
#: rounding of the terms, 6·10⁻⁸ of each, is a larger share of it (f_iso = 0.2, f_vol = 0.1,
#: f_geo = 0.03: 2.5·10⁻⁴ at a BRF of 6·10⁻⁵, θ = 13°, 86°, 200,000 pairs).
RECIPROCITY_RTOL = {"rtls": 1e-3}


def _spec(plugin: str, params: dict) -> dict:
    return dict(params, type=plugin)


def _named(result, name: str):
    result.name = name
    return result


def _battery(ctx: Context, s: Section, plugin: str, label: str, params: dict,
             expected: dict) -> tuple[list, checks.AlbedoCurve]:
    """The battery's checks on one parameter set as rows; returns (table rows, the albedo
    curve at :data:`THETAS`)."""
    spec, n = _spec(plugin, params), ctx.n(1_000_000, 50_000)
    curve = checks.albedo_curve(spec, THETAS, n=n, estimators=("eval", "reference"))
    thetas = ctx.n(CHI2_THETAS, (45.0,))
    results = [checks.check_consistency(spec, n=n // 10)]
    results += [_named(checks.chi2_bsdf(spec, wi=batch.direction(math.radians(t)), res=None,
                                        ires=None, test_count=len(thetas), sample_count=n),
                       f"chi2 θ={t:g}°") for t in thetas]
    results += [checks.check_energy(spec, curve=curve),
                checks.check_albedo_agreement(spec, curve=curve),
                checks.check_reciprocity(spec, n=n // 5,
                                         rtol=RECIPROCITY_RTOL.get(plugin, RTOL)),
                checks.check_positivity(spec, n=n // 5),
                checks.check_stability(spec, n_random=ctx.n(20_000, 1_000))]
    table = []
    for r in results:
        s.rows.append(Row.of(f"{plugin} ({label})", r, expected_fail=r.name in expected))
        verdict = s.rows[-1].verdict
        table.append((plugin, label, r.name, f"{r.value:.4g}" if isinstance(r.value, float)
                      else str(r.value), str(r.tolerance), verdict))
    return table, curve


def _against_reference(ctx: Context, s: Section) -> list:
    """eval (f·cosθo) against the float64 reference's f·cosθo at random pairs above the
    surface: the largest relative error."""
    rng = np.random.default_rng(7)
    n = ctx.n(200_000, 10_000)
    wi, wo = (batch.random_directions(rng, n, sphere=False) for _ in range(2))
    table = []
    for plugin, label, params, _ in SETS:
        spec = _spec(plugin, params)
        value = batch.evaluate(load_bsdf(spec), wi, wo).value
        want = for_spec(spec).brdf(wi, wo) * wo[:, 2:3]
        rel = np.abs(value - want) / np.maximum(np.abs(want), 1e-6 * np.abs(want).max())
        worst = float(rel.max())
        s.rows.append(Row(f"{plugin} ({label})", f"eval = float64 reference, {n:,} random pairs",
                          f"{worst:.2e}", f"≤ {REFERENCE_RTOL:g} relative",
                          worst <= REFERENCE_RTOL))
        table.append((plugin, label, f"{worst:.2e}"))
    return table


def _grazing(theta_deg, phi: float = 0.0) -> np.ndarray:
    """Unit vectors at zenith angles ``theta_deg`` (degrees; 90 exactly: cosθ = 0)."""
    degrees = np.asarray(theta_deg, dtype=np.float64)
    t = np.radians(degrees)
    z = np.where(degrees == 90.0, 0.0, np.cos(t))
    return np.stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), z], axis=1)


def _rtls_finding(ctx: Context, s: Section) -> list:
    """rtls non-negative where Eradiate's is negative: at normal incidence towards the
    horizon (eval), and the sample weights from normal to grazing incidence."""
    rows = []
    for plugin, label, params, _ in SETS[:2]:
        spec = _spec(plugin, params)
        bsdf = load_bsdf(spec)
        phi = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
        wo = np.concatenate([_grazing(np.linspace(80.0, 90.0, 201), p) for p in phi])
        e = batch.evaluate(bsdf, (0.0, 0.0, 1.0), wo)
        model = float(for_spec(spec).brf(np.broadcast_to([0.0, 0.0, 1.0], wo.shape), wo).min())
        rng = np.random.default_rng(3)
        m = ctx.n(200_000, 10_000)
        weights = [batch.sample(bsdf, batch.direction(math.radians(t)), rng.random(m),
                                rng.random((m, 2))).weight
                   for t in (0.0, 60.0, 85.0, 89.0, 89.9)]
        low_eval = float(min(e.value.min(), e.eval_pdf_value.min()))
        low_weight = float(min(w.min() for w in weights))
        finite = bool(np.all(np.isfinite(e.value)) and all(np.all(np.isfinite(w))
                                                           for w in weights))
        ok = finite and low_eval >= 0.0 and low_weight >= 0.0
        shown = (f"min eval {low_eval:.3g}, min weight {low_weight:.3g} (the model's BRF down "
                 f"to {model:.3g})")
        s.rows.append(Row(f"rtls ({label})", "non-negative: eval at θi = 0° towards the "
                          "horizon, sample weights at θi = 0°-89.9°", shown, "≥ 0, finite", ok))
        rows.append((f"rtls, {label}", "eval at θi = 0°, θo = 80°-90°; sample weights at θi = "
                     "0°, 60°, 85°, 89°, 89.9°", shown, "✓" if ok else "✗"))
    return rows


def _rpv_finding(s: Section, curves: dict) -> list:
    """rpv finite at grazing backscatter, and its albedo at 89° the model's own."""
    spec = _spec("rpv", {})
    w = _grazing([89.0, 89.9, 89.99, 90.0])
    bsdf = load_bsdf(spec)
    values = np.stack([batch.evaluate(bsdf, wi, wi[None]).value[0] for wi in w])
    ok = bool(np.all(np.isfinite(values)) and np.all(values >= 0))
    shown = ", ".join(f"{v:.3g}" for v in values[:, 0])
    s.rows.append(Row("rpv (defaults (k = 0.1))", "finite at grazing backscatter ωo = ωi, "
                      "θ = 89°, 89.9°, 89.99°, 90°", shown, "finite, ≥ 0", ok))
    rows = [("rpv, defaults", "eval at ωo = ωi, θ = 89°, 89.9°, 89.99°, 90°", shown,
             "✓" if ok else "✗")]
    curve = curves[("rpv", SETS[2][1])]
    i = THETAS.index(89.0)
    got, err, want = curve.sampled[i, 0], curve.sampled_err[i, 0], curve.reference[i, 0]
    off = abs(got - want) / want
    ok = abs(got - want) <= 5 * err + 0.005 * want
    s.rows.append(Row("rpv (defaults (k = 0.1))", "E(89°) from sample() = the model's "
                      "(reference quadrature)", f"{got:.4g} ± {err:.2g} vs {want:.4g}",
                      "5σ + 0.5 %", bool(ok)))
    s.values["rpv: E(89°), defaults"] = f"{got:.3g}"
    rows.append(("rpv, defaults", "E(89°): sample() against the model's quadrature",
                 f"{got:.4g} ± {err:.2g} against {want:.4g} ({100 * off:.2g} %)",
                 "✓" if ok else "✗"))
    return rows


def _hapke_finding(s: Section) -> list:
    """hapke finite at the opposition at normal incidence (h = 0: Eradiate's NaN)."""
    spec = _spec("hapke", {})
    up = np.array([[0.0, 0.0, 1.0]])
    e = batch.evaluate(load_bsdf(spec), up[0], up)
    want = float(for_spec(spec).brdf(up, up)[0, 0])
    got, pdf = float(e.value[0, 0]), float(e.pdf[0])
    ok = math.isfinite(got) and math.isfinite(pdf) and abs(got - want) <= 1e-5 * want
    shown = f"f·cosθo = {got:.6g} (reference {want:.6g}), pdf {pdf:.4g}"
    s.rows.append(Row("hapke (defaults)", "finite at ωo = ωi = normal (h = 0), = reference",
                      shown, "finite, 10⁻⁵ relative", ok))
    return [("hapke, defaults (h = 0)", "eval and pdf at ωo = ωi = the normal", shown,
             "✓" if ok else "✗")]


def _albedo_table(curves: dict) -> list:
    rows = []
    for (plugin, label), curve in curves.items():
        for i, theta in enumerate(THETAS):
            rows.append((plugin, label, f"{theta:g}°",
                         f"{curve.sampled[i, 0]:.4g} ± {curve.sampled_err[i, 0]:.1g}",
                         f"{curve.reference[i, 0]:.4g}"))
    return rows


def section(ctx: Context) -> Section:
    s = Section("Earth observation: rtls, rpv, hapke, ocean")
    battery, curves = [], {}
    for plugin, label, params, expected in SETS:
        table, curves[(plugin, label)] = _battery(ctx, s, plugin, label, params, expected)
        battery += table
    reference = _against_reference(ctx, s)
    findings = _rtls_finding(ctx, s) + _rpv_finding(s, curves) + _hapke_finding(s)
    n = ctx.n(1_000_000, 50_000)
    s.markdown = "\n".join([
        "The plugins of Earth observation and planetary science (`mi_brdfs/plugins/rtls.py`, "
        "`rpv.py`, `hapke.py`, `ocean.py`), each at its defaults (Eradiate's) and at one "
        "parameter set its docstring documents, against their float64 references "
        "(`mi_brdfs/reference/`). Expected to fail, as the docstrings say: "
        + "; ".join(f"{p} {label}: {check} ({why})" for p, label, _, exp in SETS
                    for check, why in exp.items()) + ".", "",
        f"**The battery** (χ² at θi = {', '.join(f'{t:g}°' for t in ctx.n(CHI2_THETAS, (45.0,)))};"
        f" energy and the sample()/reference albedo agreement at θi = "
        f"{', '.join(f'{t:g}°' for t in THETAS)}, {n:,} samples each; reciprocity within "
        f"{RECIPROCITY_RTOL['rtls']:g} for rtls, whose BRF, a sum of terms of either sign, "
        "loses float32 digits where it nears 0):", "",
        md_table(["plugin", "parameters", "check", "value", "tolerance", "verdict"], battery),
        "",
        "**eval against the float64 reference** (f·cosθo at random pairs above the surface; "
        "relative error over values above 10⁻⁶ of the largest):", "",
        md_table(["plugin", "parameters", "largest relative error"], reference), "",
        "**The findings on Eradiate's plugins, checked on ours** (`mi-brdfs check` under "
        "`eradiate-mitsuba` finds rtls negative towards grazing, rpv infinite at grazing "
        "backscatter with a white-furnace albedo of 21 at θi = 89°, hapke NaN at ωo = ωi; "
        "the albedo of 21 is the model's own, and rpv keeps it, with a warning at load):", "",
        md_table(["plugin", "where", "measured", "as documented"], findings), "",
        "**Directional albedo** E(θ) = ∫ f cosθo dωo: the mean sample() weight (± its standard "
        f"error, {n:,} samples) against the reference's quadrature (first channel; the "
        "parameters are grey):", "",
        md_table(["plugin", "parameters", "θ", "E(θ) sample()", "reference"],
                 _albedo_table(curves))])
    return s
