"""
Backends: the cost of each Python plugin against its C++ built-in in each variant, the scalar
render arrangement, the trace overhead per BSDF instance in a scene with many materials, and
the first-render (trace + compile) time.
"""

from __future__ import annotations

from typing import NamedTuple

import drjit as dr
import mitsuba as mi
import numpy as np

from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from ..render import render
from ..scenes import load_scene
from ..timing import interleaved, median, median_ratio, timed

#: Render-time targets against the built-ins: llvm_ad_rgb, and the llvm overhead of many material
#: instances in one scene. The scalar render path is reported without a target: scalar variants
#: are Mitsuba's debugging variants, where a Python plugin costs what calling Python per path
#: vertex costs; the JIT variants are where to render.
TARGET_LLVM, TARGET_TRACE = 1.03, 1.2

#: What the energy compensation (cooktorrance ``multiscatter``) may cost against single
#: scattering, both plugins, in llvm_ad_rgb.
TARGET_MULTISCATTER = 1.10


class Pair(NamedTuple):
    """One scene rendered with a plugin and with its built-in counterpart."""

    label: str
    scene: str
    ours: dict          # defines of the plugin's render
    ref: dict           # defines of the built-in's render
    target: bool | float = True  # the llvm target applies, another (a float), or none (False)

    @property
    def goal(self) -> float | None:
        """The llvm_ad_rgb ratio target, None for a measurement."""
        if self.target is False:
            return None
        return TARGET_LLVM if self.target is True else float(self.target)


PAIRS = [
    Pair("lambert vs diffuse", "cbox", {"material": "lambert"}, {"material": "diffuse"}),
    Pair("cooktorrance (Smith) vs roughconductor", "metalbox", {"metal": "cooktorrance-smith"},
         {"metal": "roughconductor"}),
    Pair("cooktorrance (V-cavity) vs roughconductor", "metalbox", {"metal": "cooktorrance"},
         {"metal": "roughconductor"}, target=False),
    Pair("anisotropic cooktorrance (Smith) vs roughconductor", "brushed",
         {"metal": "cooktorrance-smith"}, {"metal": "roughconductor"}),
    Pair("cooktorrance transmission vs roughdielectric", "glass", {"glass": "cooktorrance"},
         {"glass": "roughdielectric"}),
    # The energy compensation's cost: the same rough gold, with and without it (both plugins;
    # "built-in" is single scattering here). α = 0.6, where it adds visible light.
    Pair("cooktorrance multiscatter on vs off", "metalbox",
         {"metal": "cooktorrance-multiscatter", "alpha": "0.6"},
         {"metal": "cooktorrance-smith", "alpha": "0.6"}, target=TARGET_MULTISCATTER),
    # The dielectric's compensation: measured, in the rough glass sphere at α = 0.6, with and
    # without it; once with every path (the compensated glass loses no energy, so Russian
    # roulette keeps its paths longer), once with one bounce (max_depth 2: the cost per call).
    Pair("cooktorrance transmission multiscatter on vs off", "glass",
         {"glass": "cooktorrance-multiscatter", "alpha": "0.6"},
         {"glass": "cooktorrance", "alpha": "0.6"}, target=False),
    Pair("cooktorrance transmission multiscatter on vs off, one bounce", "glass",
         {"glass": "cooktorrance-multiscatter", "alpha": "0.6", "max_depth": "2"},
         {"glass": "cooktorrance", "alpha": "0.6", "max_depth": "2"}, target=False),
    # The models Mitsuba 3 lacks, against the built-in a user would otherwise take: Ward of
    # the same lobe widths as the brushed roughconductor, Oren-Nayar (σ = 0.2) for diffuse.
    Pair("ward (balanced) vs roughconductor, same widths", "brushed", {"metal": "ward"},
         {"metal": "roughconductor"}, target=False),
    Pair("orennayar vs diffuse", "cbox", {"material": "orennayar"}, {"material": "diffuse"},
         target=False),
    Pair("orennayar vs lambert", "cbox", {"material": "orennayar"}, {"material": "lambert"},
         target=False),
    # What the glossy lobe costs: Phong (ρd = 0.8 and its defaults ks = 0.2, n = 30) against
    # lambert (ρ = 0.8), both plugins, in the white furnace; "built-in" is lambert here.
    Pair("phong vs lambert (furnace)", "furnace",
         {"material": "phong", "reflectance_name": "diffuse_reflectance", "reflectance": "0.8"},
         {"material": "lambert", "reflectance": "0.8"}, target=False),
    # A glossy lobe over a diffuse one against the built-in of that kind, roughplastic (ρd =
    # 0.8, its defaults: Beckmann α = 0.1, η = 1.49, so R0 ≈ 0.04), in the white furnace:
    # Ashikhmin-Shirley with its defaults (n = 100, Rs = 0.04: a Blinn-Phong lobe about as
    # wide, with Schlick's Fresnel), and Lafortune's default lobe, Phong's mirror lobe (n = 30,
    # ρs = 0.2). Not plastic: its specular lobe is a delta, which a path tracer samples but
    # never evaluates, so it would price another computation.
    Pair("ashikhmin vs roughplastic (furnace)", "furnace",
         {"material": "ashikhmin", "reflectance_name": "diffuse_reflectance",
          "reflectance": "0.8"},
         {"material": "roughplastic", "reflectance_name": "diffuse_reflectance",
          "reflectance": "0.8"}, target=False),
    Pair("lafortune (mirror lobe) vs roughplastic (furnace)", "furnace",
         {"material": "lafortune", "reflectance_name": "diffuse_reflectance",
          "reflectance": "0.8"},
         {"material": "roughplastic", "reflectance_name": "diffuse_reflectance",
          "reflectance": "0.8"}, target=False),
]


def jit_ratios(ctx: Context, s: Section, pairs=PAIRS, measured: int | None = None) -> list:
    """JIT: mi.render of each pair, plugin vs built-in, per sample; first renders apart. With
    ``measured``, the first that many pairs alone are rendered, the others' scenes loaded
    (:data:`SKIPPED`)."""
    res, spp, repeats = ctx.n(256, 64), ctx.n(64, 8), ctx.n(15, 2)
    table = []
    for i, pair in enumerate(pairs):
        scenes = {k: load_scene(pair.scene, dict(d, res=str(res))) for k, d in
                  (("plugin", pair.ours), ("built-in", pair.ref))}
        if measured is not None and i >= measured:
            s.values[f"{ctx.variant}: {pair.label}"] = SKIPPED
            table.append((pair.label, ctx.variant, "—", "—", SKIPPED, "—", "—"))
            continue
        first = {k: timed(lambda sc=sc: mi.render(sc, spp=spp))[0] for k, sc in scenes.items()}
        times = interleaved({k: (lambda sc=sc: mi.render(sc, spp=spp)) for k, sc in
                             scenes.items()}, repeats=repeats, warmup=0)
        ratio = median_ratio(times, "plugin", "built-in")
        per = {k: median(t) / (res * res * spp) * 1e9 for k, t in times.items()}
        s.values[f"{ctx.variant}: {pair.label}"] = f"{ratio:.3f}×"
        goal = f"≤ {pair.goal}" if pair.goal else "—"
        table.append((pair.label, ctx.variant, f"{per['plugin']:.1f} ns",
                      f"{per['built-in']:.1f} ns", f"**{ratio:.3f}×**", goal,
                      f"{first['plugin']:.2f} s / {first['built-in']:.2f} s"))
        if pair.goal:
            s.rows.append(Row(pair.label, f"{ctx.variant} render time ratio", f"{ratio:.3f}×",
                              f"≤ {pair.goal}×", ratio <= pair.goal))
    return table


def scalar_ratios(ctx: Context, s: Section, pairs=PAIRS, measured: int | None = None) -> list:
    """Scalar: both through the package's render path (which picks the arrangement). With
    ``measured``, the first that many pairs alone (:data:`SKIPPED`)."""
    res, spp, repeats = ctx.n(128, 16), ctx.n(16, 2), ctx.n(5, 2)
    table = []
    with ctx.scalar():
        for i, pair in enumerate(pairs):
            if measured is not None and i >= measured:
                s.values[f"{ctx.scalar_variant}: {pair.label}"] = SKIPPED
                table.append((pair.label, ctx.scalar_variant, "—", "—", SKIPPED, "—", "—"))
                continue
            results = {}

            def run(key, defines, pair=pair):
                results[key] = render(pair.scene, spp=spp, defines=dict(defines, res=str(res)),
                                      progress=False)
                if results[key].interrupted:  # render keeps a partial image; the bench stops
                    raise KeyboardInterrupt
            times = interleaved({"plugin": lambda: run("plugin", pair.ours),
                                 "built-in": lambda: run("built-in", pair.ref)}, repeats=repeats)
            ratio = median_ratio(times, "plugin", "built-in")
            per = {k: median(t) / (res * res * spp) * 1e9 for k, t in times.items()}
            s.values[f"{ctx.scalar_variant}: {pair.label}"] = f"{ratio:.2f}×"
            table.append((pair.label, f"{ctx.scalar_variant} ({results['plugin'].arrangement})",
                          f"{per['plugin']:.0f} ns", f"{per['built-in']:.0f} ns",
                          f"**{ratio:.2f}×**", "—", "—"))
    return table


def scalar_threads(ctx: Context) -> list:
    """Why the arrangement: a plugin in scalar on 1 and 2 render threads, in-process."""
    res, spp = ctx.n(64, 16), ctx.n(8, 2)
    rows = []
    with ctx.scalar():
        for material in ("lambert", "diffuse"):
            scene = load_scene("cbox", {"res": str(res), "material": material})
            for n in (1, 2):
                dr.set_thread_count(n)
                seconds = median([timed(lambda: mi.render(scene, spp=spp))[0]
                                  for _ in range(ctx.n(3, 1))])
                rows.append((material, n, f"{seconds:.3f} s"))
    return rows


FORWARD = "mi_brdfs_bench_forward"


def _register_forward() -> None:
    """
    Register :data:`FORWARD` in the current variant: a Python BSDF that hands every call to a
    built-in ``diffuse`` of its reflectance. It renders ``diffuse``'s image at the cost of
    Mitsuba calling into Python and Python calling back: the least any Python plugin pays.
    """
    class Forward(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.inner = mi.load_dict({"type": "diffuse",
                                       "reflectance": props.get_texture("reflectance", 0.5)})
            self.m_flags = int(self.inner.flags())
            self.m_components = [int(self.inner.flags(0))]

        def eval(self, ctx, si, wo, active=True):
            return self.inner.eval(ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):
            return self.inner.pdf(ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.inner.eval_pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            return self.inner.sample(ctx, si, sample1, sample2, active)

    mi.register_bsdf(FORWARD, Forward)


def scalar_floor(ctx: Context, s: Section) -> list:
    """
    The Cornell box in-process on one render thread with ``diffuse``, :data:`FORWARD` and
    ``lambert``, interleaved: what calling Python costs, apart from what the plugin computes.
    """
    res, spp = ctx.n(64, 16), ctx.n(8, 2)
    with ctx.scalar(threads=1):
        _register_forward()
        labels = {"diffuse": "`diffuse` (C++)",
                  FORWARD: "a Python BSDF forwarding each call to `diffuse`",
                  "lambert": "`lambert`"}
        scenes = {m: load_scene("cbox", {"res": str(res), "material": m}) for m in labels}
        times = interleaved({m: (lambda sc=sc: mi.render(sc, spp=spp))
                             for m, sc in scenes.items()}, repeats=ctx.n(7, 2))
        rows = []
        for m, label in labels.items():
            ratio = f"{median_ratio(times, m, 'diffuse'):.2f}×"
            s.values[f"floor: {label}"] = ratio
            rows.append((label, f"{median(times[m]):.3f} s", f"**{ratio}**"))
        return rows


#: BSDFs whose calls the scalar per-call profile times (the metal of the metalbox pair: Au).
CALLS = [("lambert", {"type": "lambert"}), ("diffuse", {"type": "diffuse"}),
         ("cooktorrance (Smith)", {"type": "cooktorrance", "shadowing": "smith",
                                   "material": "Au", "alpha": 0.2}),
         ("roughconductor", {"type": "roughconductor", "material": "Au", "alpha": 0.2})]


def scalar_calls(ctx: Context) -> list:
    """
    µs per call from Python of eval_pdf and sample (what Mitsuba calls per path vertex) of each
    of :data:`CALLS`, interleaved.
    """
    from ..bsdfspec import load_bsdf
    with ctx.scalar():
        n = ctx.n(20_000, 1_000)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(0.3, 0.2, 0.932738)
        wo, c, u = mi.Vector3f(0.1, 0.4, 0.910465), mi.BSDFContext(), mi.Point2f(0.3, 0.6)
        calls = {}
        for label, spec in CALLS:
            b = load_bsdf(spec)
            calls[(label, "eval_pdf")] = lambda b=b: [b.eval_pdf(c, si, wo) for _ in range(n)]
            calls[(label, "sample")] = lambda b=b: [b.sample(c, si, 0.4, u) for _ in range(n)]
        times = interleaved(calls, repeats=ctx.n(5, 2))
        return [(label, call, f"{median(t) / n * 1e6:.2f} µs")
                for (label, call), t in times.items()]


#: (label, the plugin's material dict given index i of K, the built-in's)
INSTANCES = [
    ("lambert vs diffuse",
     lambda i, k: {"type": "lambert", "reflectance": 0.1 + 0.8 * i / k},
     lambda i, k: {"type": "diffuse", "reflectance": 0.1 + 0.8 * i / k}),
    ("cooktorrance (Smith) vs roughconductor",
     lambda i, k: {"type": "cooktorrance", "shadowing": "smith", "material": "Au",
                   "alpha": 0.05 + 0.5 * i / k},
     lambda i, k: {"type": "roughconductor", "material": "Au", "alpha": 0.05 + 0.5 * i / k}),
]


def _spheres(k: int, material, res: int):
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": 4},
         "light": {"type": "constant"},
         "sensor": {"type": "perspective", "fov": 40,
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=[0, 0, 12], target=[0, 0, 0], up=[0, 1, 0]),
                    "film": {"type": "hdrfilm", "width": res, "height": res}}}
    side = int(np.ceil(np.sqrt(k)))
    for i in range(k):
        x, y = i % side - (side - 1) / 2, i // side - (side - 1) / 2
        d[f"s{i}"] = {"type": "sphere", "radius": 0.4 * 8 / max(side, 1) / 2,
                      "center": [x * 8 / side, y * 8 / side, 0], "bsdf": material(i, k)}
    return mi.load_dict(d)


def many_materials(ctx: Context, s: Section) -> list:
    """Trace overhead per BSDF instance: K spheres, each with its own material instance."""
    res, spp = ctx.n(128, 32), ctx.n(16, 4)
    rows, ratios = [], []
    for label, ours, ref in INSTANCES if not ctx.quick else INSTANCES[:1]:
        for k in ctx.n((1, 16, 64), (4,)):
            scenes = {"plugin": _spheres(k, ours, res), "built-in": _spheres(k, ref, res)}
            first = {w: timed(lambda sc=sc: mi.render(sc, spp=spp))[0] for w, sc in scenes.items()}
            times = interleaved({w: (lambda sc=sc: mi.render(sc, spp=spp)) for w, sc in
                                 scenes.items()}, repeats=ctx.n(7, 2), warmup=0)
            ratio = median_ratio(times, "plugin", "built-in")
            ratios.append(ratio)
            rows.append((label, k, f"{first['plugin']:.2f} s", f"{first['built-in']:.2f} s",
                         f"{median(times['plugin']):.3f} s", f"{median(times['built-in']):.3f} s",
                         f"**{ratio:.3f}×**"))
            s.rows.append(Row(label, f"{k} material instances, render time", f"{ratio:.3f}×",
                              f"≤ {TARGET_TRACE}×", ratio <= TARGET_TRACE))
    s.values["instances: range"] = f"{min(ratios):.3f}–{max(ratios):.3f}×"
    return rows


def section(ctx: Context) -> Section:
    s = Section("Backends")
    first = 1 if ctx.quick else None  # quick: the first pair measured, the others named
    table = jit_ratios(ctx, s, measured=first) + scalar_ratios(ctx, s, measured=first)
    threads = scalar_threads(ctx)
    floor = scalar_floor(ctx, s)
    calls = scalar_calls(ctx)
    many = many_materials(ctx, s)
    s.values.update({f"threads: {m}, {n}": t for m, n, t in threads})
    s.values.update({f"call: {label}, {call}": t for label, call, t in calls})
    s.markdown = "\n".join([
        "Render time with every surface (Cornell box: `scenes/cbox.xml`), every metal "
        "(`scenes/metalbox.xml`; brushed: `scenes/brushed.xml`) or the glass sphere "
        "(`scenes/glass.xml`) the plugin, against the built-in (for Phong: against "
        "`lambert`, both plugins, in the white furnace `scenes/furnace.xml`, which prices its "
        "glossy lobe; for Ashikhmin-Shirley and Lafortune: against `roughplastic`, a glossy "
        "lobe over a diffuse one too, in the same furnace), same spp and seeds, medians "
        "of interleaved repeats in one process. In the JIT variant both go through `mi.render`, "
        "after a first render each that traces and compiles (its time is the last column); in "
        "the scalar variant through the package's render path `mi_brdfs.render.render`, which "
        "renders scenes with Python plugins on one thread per process.", "",
        md_table(["pair", "variant", "plugin per sample", "built-in per sample", "ratio",
                  "target", "first render plugin / built-in"], table), "",
        "Why one thread per process in scalar variants: Mitsuba calls a Python plugin once per "
        "ray from its render threads, and those calls serialise on the GIL "
        f"(Cornell box, in-process `mi.render`, {ctx.scalar_variant}):", "",
        md_table(["material", "render threads", "time"], threads), "",
        "The least a Python plugin costs in a scalar variant: the same Cornell box, in-process "
        "on one render thread, with a Python BSDF that computes nothing and hands every call "
        "to a built-in `diffuse` (the same image as `diffuse`), medians of interleaved repeats. "
        "The package's render path adds the start of its helper processes to this (once in "
        "a session: they are kept for the next render):", "",
        md_table(["BSDF", "time", "ratio to `diffuse`"], floor), "",
        "What the scalar ratios are made of: Mitsuba calls `eval_pdf` (towards the sampled "
        "light) and `sample` once each per path vertex. Time per call from Python (the table "
        f"above prices the call from C++), {ctx.scalar_variant}, medians of interleaved "
        "repeats after a warm-up that has cooktorrance compiled for its configuration, as in "
        "a render:", "",
        md_table(["BSDF", "call", "time per call"], calls), "",
        "Trace overhead per BSDF instance (JIT): K spheres, each with its own material "
        "instance (a different parameter value). Every Python instance is traced into the "
        "kernel once per render; the first render also compiles:", "",
        md_table(["pair", "K", "first render plugin", "built-in", "render plugin",
                  "render built-in", "ratio"], many)])
    return s
