"""
Model choices: what each switch of the plugins costs per evaluation, and what it buys in
accuracy; and that a disabled lobe costs nothing measurable.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..bsdfspec import load_bsdf
from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from ..checks import batch
from ..materials import conductor_ior
from ..reference import cooktorrance as ref
from ..timing import interleaved, kernel_timed, median, median_ratio

#: (choice, A, B): eval cost of A relative to B.
CHOICES = [
    ("Schlick vs exact Fresnel", {"type": "cooktorrance", "fresnel": "schlick", "material": "Au"},
     {"type": "cooktorrance", "fresnel": "exact", "material": "Au"}),
    ("V-cavity vs Smith", {"type": "cooktorrance", "shadowing": "vcavity"},
     {"type": "cooktorrance", "shadowing": "smith"}),
    ("GGX vs Beckmann", {"type": "cooktorrance", "distribution": "ggx"},
     {"type": "cooktorrance", "distribution": "beckmann"}),
    ("V-cavity: its visible normals vs D·cos (sample)", {"type": "cooktorrance"},
     {"type": "cooktorrance", "sample_visible": False}),
    ("Smith: its visible normals vs D·cos (sample)", {"type": "cooktorrance", "shadowing": "smith"},
     {"type": "cooktorrance", "shadowing": "smith", "sample_visible": False}),
    ("Phong normalized vs lecture", {"type": "phong", "form": "normalized"},
     {"type": "phong", "form": "lecture"}),
    ("Phong halfway vs mirror lobe", {"type": "phong", "lobe": "halfway"}, {"type": "phong"}),
    ("cooktorrance vs roughconductor", {"type": "cooktorrance", "shadowing": "smith",
                                        "material": "Au"},
     {"type": "roughconductor", "material": "Au"}),
    ("Ward (balanced, αu = 0.05, αv = 0.3) vs roughconductor of the same widths",
     {"type": "ward", "alpha_u": 0.05, "alpha_v": 0.3, "diffuse_reflectance": 0.0,
      "specular_reflectance": 0.9},
     {"type": "roughconductor", "alpha_u": 0.05, "alpha_v": 0.3, "material": "Al"}),
    ("Ward original vs balanced form", {"type": "ward", "form": "original"}, {"type": "ward"}),
    ("Oren-Nayar qualitative vs lambert", {"type": "orennayar"}, {"type": "lambert"}),
    ("Oren-Nayar full vs qualitative", {"type": "orennayar", "form": "full"},
     {"type": "orennayar"}),
]

#: (disabled lobe, A, B): A has the lobe disabled; it must cost what B costs.
DISABLED = [
    ("Phong with ks = 0 vs lambert", {"type": "phong", "specular_reflectance": 0.0,
                                      "diffuse_reflectance": 0.5},
     {"type": "lambert", "reflectance": 0.5}),
    ("Phong with ρd = 0 vs Phong glossy lobe only", {"type": "phong", "diffuse_reflectance": 0.0},
     {"type": "phong", "diffuse_reflectance": 0.0, "specular_reflectance": 0.2}),
    ("Cook-Torrance without vs with a diffuse base", {"type": "cooktorrance"},
     {"type": "cooktorrance", "diffuse_reflectance": 0.3}),
    ("Ward with ρd = 0 vs with a diffuse base", {"type": "ward", "diffuse_reflectance": 0.0},
     {"type": "ward"}),
]

#: A disabled lobe "costs nothing measurable": within this of the configuration without it.
NOTHING = 1.05
#: Removing a lobe must not cost more than keeping it: at most this ratio (timing noise).
NO_MORE = 1.02


def _eval_call(bsdf, n: int, seed: int = 0, sample: bool = False):
    """A function tracing ``eval_pdf`` (or ``sample``) at n random lanes, unevaluated."""
    rng = np.random.default_rng(seed)
    wi = batch.random_directions(rng, n, sphere=False)
    si = batch.interaction(wi, n)
    ctx = mi.BSDFContext()
    if sample:
        s1 = batch.floats(rng.random(n, dtype=np.float32))
        s2 = mi.Point2f(batch.floats(rng.random(n, dtype=np.float32)),
                        batch.floats(rng.random(n, dtype=np.float32)))
        return lambda: bsdf.sample(ctx, si, s1, s2)
    wo = batch.random_directions(rng, n, sphere=False).astype(np.float32)
    w = batch.vectors(wo)
    return lambda: bsdf.eval_pdf(ctx, si, w)


def _kernel_seconds(fn) -> float:
    """The kernels' execution time of one call of ``fn`` (DrJit's kernel history): the cost
    per evaluation, without the tracing of the Python code, a fixed cost per launch (different
    for every plugin; a render traces once)."""
    return kernel_timed(fn)[1]


def jit_seconds(spec, ctx: Context, sample: bool = False) -> float:
    """Kernel seconds per 1e7 evaluations of ``spec`` in the JIT variant (median of repeats)."""
    n = ctx.n(10_000_000, 100_000)
    times = interleaved({"a": _eval_call(load_bsdf(spec), n, sample=sample)},
                        repeats=ctx.n(5, 2), timer=_kernel_seconds)
    return median(times["a"]) * 1e7 / n


def jit_cost(a, b, ctx: Context, sample: bool = False):
    """(kernel seconds per 1e7 evaluations of A, of B, median ratio) in the JIT variant."""
    n = ctx.n(10_000_000, 100_000)
    funcs = {"a": _eval_call(load_bsdf(a), n, sample=sample),
             "b": _eval_call(load_bsdf(b), n, sample=sample)}
    times = interleaved(funcs, repeats=ctx.n(9, 3), timer=_kernel_seconds)
    scale = 1e7 / n
    return median(times["a"]) * scale, median(times["b"]) * scale, median_ratio(times, "a", "b")


def scalar_cost(a, b, ctx: Context):
    """(µs per eval_pdf call of A, of B, ratio) in the scalar variant (per ray in a render);
    called within ``ctx.scalar()``."""
    n = ctx.n(20_000, 200)
    calls = {}
    for key, spec in (("a", a), ("b", b)):
        bsdf = load_bsdf(spec)
        si = batch.interaction([0.3, 0.2, 0.932738])
        w = mi.Vector3f(0.1, 0.4, 0.910465)
        c = mi.BSDFContext()

        def call(bsdf=bsdf, si=si, w=w, c=c):
            for _ in range(n):
                bsdf.eval_pdf(c, si, w)
        calls[key] = call
    times = interleaved(calls, repeats=ctx.n(5, 2))
    return (median(times["a"]) / n * 1e6, median(times["b"]) / n * 1e6,
            median_ratio(times, "a", "b"))


def _costs(ctx: Context) -> tuple[dict, dict]:
    """({label: jit_cost}, {label: scalar_cost}) of every pair of CHOICES and DISABLED: the JIT
    ones first, then the scalar ones in one switch of variant (each switch reloads Mitsuba's
    Python modules); sample() choices have no scalar cost. Quick: the first of each
    (:data:`SKIPPED`)."""
    pairs = CHOICES + DISABLED if not ctx.quick else CHOICES[:1] + DISABLED[:1]
    jit = {label: jit_cost(a, b, ctx, sample=label.endswith("(sample)"))
           for label, a, b in pairs}
    with ctx.scalar():
        scalar = {label: scalar_cost(a, b, ctx) for label, a, b in pairs
                  if not label.endswith("(sample)")}
    return jit, scalar


def fresnel_error() -> list:
    """What Schlick's approximation costs in accuracy: |ΔF| and the albedo it changes."""
    rows = []
    cos = np.cos(np.radians(np.linspace(0, 89.9, 900)))
    for label, eta, k in (("glass η 1.5", 1.5, 0.0), ("water η 1.33", 1.33, 0.0),
                          ("gold (RGB)", *conductor_ior("Au")),
                          ("aluminium (RGB)", *conductor_ior("Al"))):
        err = np.abs(ref.fresnel_schlick(cos, eta, k) - ref.fresnel_exact(cos, eta, k))
        e_exact = ref.CookTorrance(alpha=0.2, eta=eta, k=k).albedo(math.radians(75.0))
        e_schlick = ref.CookTorrance(alpha=0.2, eta=eta, k=k, fresnel="schlick").albedo(
            math.radians(75.0))
        rows.append((label, f"{err.max():.4f}", f"{err.mean():.4f}",
                     f"{np.max(np.abs(e_schlick - e_exact)):.4f}"))
    return rows


def section(ctx: Context) -> Section:
    s = Section("Model choices")
    rows = []
    jit, scalar = _costs(ctx)
    for label, _, _ in CHOICES:
        if label not in jit:
            s.values[f"model: {label}"] = SKIPPED
            rows.append((label, "—", "—", "—", SKIPPED, "—"))
            continue
        ta, tb, ratio = jit[label]
        s.values[f"model: {label}"] = f"{ratio:.2f}×"
        per_call = "—"  # sample() choices: no scalar cost
        if label in scalar:
            sa, sb, sratio = scalar[label]
            per_call = f"{sa:.1f} / {sb:.1f} µs ({sratio:.2f}×)"
        rows.append((label, "eval_pdf()" if label in scalar else "sample()", f"{ta:.3f} s",
                     f"{tb:.3f} s", f"**{ratio:.2f}×**", per_call))
    schlick = fresnel_error()
    for label, max_f, _, albedo in schlick:
        s.values[f"schlick: {label}, max ΔF"] = max_f
        s.values[f"schlick: {label}, ΔE(75°)"] = albedo
    lobes = []
    for label, _, _ in DISABLED:
        if label not in jit:
            s.values[f"disabled: {label}"] = SKIPPED
            lobes.append((label, "—", "—", SKIPPED, "—"))
            continue
        (ta, tb, ratio), (sa, sb, sratio) = jit[label], scalar[label]
        s.values[f"disabled: {label}"] = f"{ratio:.2f}×"
        lobes.append((label, f"{ta:.3f} s", f"{tb:.3f} s", f"**{ratio:.2f}×**",
                      f"{sa:.1f} / {sb:.1f} µs ({sratio:.2f}×)"))
        if "vs lambert" in label:
            s.rows.append(Row(label, "eval_pdf cost ratio (JIT)", f"{ratio:.2f}×",
                              f"≤ {NOTHING}×", ratio <= NOTHING))
        elif "without vs with" in label:
            s.rows.append(Row(label, "the base's cost when disabled (JIT, ≤ 1 = none)",
                              f"{ratio:.2f}×", f"≤ {NO_MORE}×", ratio <= NO_MORE))
    s.markdown = "\n".join([
        "Cost per 1e7 evaluations (`eval_pdf`, or `sample` where the choice is the sampler) in "
        f"`{ctx.variant}` on random direction pairs: the kernels' execution time (DrJit's kernel "
        "history; tracing the Python code is a fixed cost per launch, left out as in Sampling "
        "strategies), medians of interleaved repeats, and per "
        f"call in `{ctx.scalar_variant}` (where Mitsuba calls the plugin once per ray):", "",
        md_table(["choice", "call", "A per 1e7", "B per 1e7", "A / B (JIT)",
                  "A / B per call (scalar)"], rows), "",
        "What Schlick's approximation buys: its largest and mean |F − F_exact| over θ ∈ [0, 90°) "
        "and the change of the Cook-Torrance albedo (α = 0.2) at 75° (float64 reference):", "",
        md_table(["interface", "max |ΔF|", "mean |ΔF|", "|ΔE(75°)|"], schlick), "",
        "Disabled lobes: a lobe whose reflectance is the constant 0 is left out entirely, so it "
        "must cost nothing measurable:", "",
        md_table(["disabled lobe", "A per 1e7", "B per 1e7", "A / B (JIT)",
                  "A / B per call (scalar)"], lobes)])
    return s
