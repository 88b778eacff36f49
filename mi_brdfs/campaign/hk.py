r"""
Campaign section: Hanrahan & Krueger's layer (``hk``) against Mitsuba's own volumetric path
tracer. The same slab built as a scene — a ``cube`` flattened to a slab of thickness d (1000 d
wide) holding a ``homogeneous`` medium of σs, σa and an ``hg`` phase function of g, behind a
``dielectric`` interface of index η (``null`` where η = 1) — rendered by ``volpath`` and read
by a virtual gonioreflectometer: ``radiancemeter`` sensors reading the radiance leaving a point
of the slab towards a few directions above (reflection) and below (transmission).

The light: a delta light cannot reach the medium through a delta interface in ``volpath``
(a shadow ray stops at the ``dielectric``; a sampled ray never hits a directional emitter), so
the slab is lit by an ``envmap`` bright in a small patch of directions, L(ω), and the plugin's
value is integrated over it, L_o(ωo) = ∫ f(ωo, ω) |cosθ| L(ω) dω, with L(ω) from the very
emitter of the scene (its ``eval``) on a fine grid of directions. A Lambertian plane (Mitsuba's
``diffuse``) under the same light checks this gonioreflectometer itself.

``max_depth`` selects the single scattering. What it counts is measured, not assumed: the
first depth at which a sensor sees any light (every path to a sensor scatters at least once:
with σs = 0 the sensors read 0, also checked) — 2 with ``null`` faces (a null crossing is not
counted: the scattering, then the emitter), 4 under a ``dielectric`` (refraction in, the
scattering, refraction out, the emitter): a path with one more event (a second scattering or
an internal reflection) needs one more. The section renders at that depth and compares the
radiance with the integral of the plugin's ``scattering = single`` value, within Monte Carlo
noise: σ from independent renders (batches of seeds), |volpath − plugin| ≤ 4σ.

Every order: ``volpath`` at ``max_depth`` :data:`ALL_DEPTH` against ``scattering = all``,
within the noise and the error the plugin's tables promise (the two combined in quadrature).
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import batch
from ..reference import hk as ref
from ..scattering.hk_orders import PROMISE
from .core import Context, Row, Section, md_table

#: The environment map's resolution (rows, columns) and its bright patch: the pixels whose
#: centres lie within these zenith angles (from the slab's normal, +y) and azimuths, degrees.
ENV_RES = (32, 64)
PATCH = ((30.0, 50.0), (15.0, 50.0))
#: Sensor directions (zenith from +y, azimuth φ = atan2(x, −z), degrees): three above, two
#: below; none sees the patch by the interface's mirror or the beam through the slab.
SENSORS = ((20.0, 30.0), (65.0, 210.0), (40.0, 120.0), (115.0, 210.0), (160.0, 300.0))
#: The grid: (albedo, optical thickness τ, g, η), thickness 1.
GRID = tuple((a, t, g, eta) for eta in (1.0, 1.5) for a in (0.4, 0.95) for t in (0.25, 2.0)
             for g in (-0.3, 0.7))
QUICK_GRID = ((0.95, 2.0, 0.7, 1.0), (0.4, 0.25, -0.3, 1.5))
#: The agreement: |volpath − plugin| within this many standard errors of volpath's mean.
SIGMAS = 4.0
#: The quadrature's step over the light's directions (degrees).
STEP = 0.2
#: ``scattering = all``: volpath's depth (its Russian roulette ends longer paths without
#: bias), and the error the plugin's tables promise, relative to its value.
ALL_DEPTH, ALL_ERROR = 256, PROMISE


def world(theta, phi) -> np.ndarray:
    """Unit vectors (n, 3) in the scene's frame (normal +y) from zenith and azimuth (degrees)."""
    t, p = np.radians(np.atleast_1d(theta)), np.radians(np.atleast_1d(phi))
    return np.stack([np.sin(t) * np.sin(p), np.cos(t), -np.sin(t) * np.cos(p)], axis=1)


def local(w) -> np.ndarray:
    """The scene's frame (normal +y) to the BSDF's (normal +z), a rotation."""
    w = np.atleast_2d(w)
    return np.stack([w[:, 0], -w[:, 2], w[:, 1]], axis=1)


def env_image() -> np.ndarray:
    """The environment map: 1 in the patch's pixels, 0 elsewhere."""
    rows, cols = ENV_RES
    theta = (np.arange(rows) + 0.5) / rows * 180.0
    phi = (np.arange(cols) + 0.5) / cols * 360.0
    (t0, t1), (p0, p1) = PATCH
    on = ((theta[:, None] >= t0) & (theta[:, None] <= t1)) & \
        ((phi[None, :] >= p0) & (phi[None, :] <= p1))
    return np.repeat(on[:, :, None], 3, axis=2).astype(np.float32)


def _interface(eta: float) -> dict:
    if eta == 1.0:
        return {"type": "null"}
    return {"type": "dielectric", "int_ior": eta, "ext_ior": 1.0}


def _sensors(thickness: float) -> dict:
    """Radiancemeters aimed at a point of the top face (reflection) or of the bottom one
    (transmission), off the faces' triangle diagonals (a ray through a mesh edge can slip
    between its triangles)."""
    import mitsuba as mi

    out = {}
    target = np.array([0.31, 0.0, 0.17])
    for k, w in enumerate(world(*np.array(SENSORS).T)):
        at = target - (0.0 if w[1] > 0 else np.array([0.0, thickness, 0.0]))
        out[f"sensor{k}"] = {
            "type": "radiancemeter", "origin": mi.ScalarPoint3f(*(at + w)),
            "direction": mi.ScalarVector3f(*(-w)),
            "film": {"type": "hdrfilm", "width": 1, "height": 1, "pixel_format": "rgb",
                     "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 1}}
    return out


def slab_scene(albedo: float, tau: float, g: float, eta: float, max_depth: int,
               thickness: float = 1.0):
    """The slab as a Mitsuba scene rendered by ``volpath`` at ``max_depth``."""
    import mitsuba as mi

    half, wide = 0.5 * thickness, 1000.0 * thickness
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "volpath", "max_depth": max_depth},
        "light": {"type": "envmap", "bitmap": mi.Bitmap(env_image())},
        "slab": {"type": "cube", "bsdf": _interface(eta),
                 "to_world": mi.ScalarTransform4f().translate([0.0, -half, 0.0])
                 .scale([wide, half, wide]),
                 "interior": {"type": "homogeneous", "albedo": albedo,
                              "sigma_t": tau / thickness, "phase": {"type": "hg", "g": g}}},
        **_sensors(thickness)})


def plane_scene():
    """A Lambertian plane (``diffuse``, ρ = 0.5) at y = 0 under the same light, ``path``."""
    import mitsuba as mi

    return mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 2},
        "light": {"type": "envmap", "bitmap": mi.Bitmap(env_image())},
        "plane": {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": 0.5},
                  "to_world": mi.ScalarTransform4f().rotate([1.0, 0.0, 0.0], -90.0)
                  .scale(1000.0)},
        **{k: v for k, v in _sensors(1.0).items() if int(k[6:]) < 3}})


#: Non-finite radiance samples ``volpath`` returned, and all samples taken, this process:
#: a few in 10⁷ are NaN; they are left out.
DROPPED = {"nan": 0, "all": 0}


def measure(scene, sensor: int, spp: int, batches: int, seed: int = 0) -> tuple[float, float]:
    """(the radiance a sensor reads, its standard error): ``batches`` × ``spp`` samples of the
    scene's integrator along the sensor's rays (what ``mi.render`` does for a one-pixel film),
    the red channel (every parameter here is grey); non-finite samples left out
    (:data:`DROPPED`)."""
    import mitsuba as mi

    camera, integrator = scene.sensors()[sensor], scene.integrator()
    values = []
    for b in range(batches):
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(seed * 7919 + b, spp)
        ray, _ = camera.sample_ray(0.0, sampler.next_1d(), sampler.next_2d(),
                                   sampler.next_2d())
        radiance, _, _ = integrator.sample(scene, sampler, ray)
        values.append(np.asarray(radiance)[0])
    x = np.concatenate(values)
    finite = np.isfinite(x)
    DROPPED["nan"] += int(np.sum(~finite))
    DROPPED["all"] += x.size
    x = x[finite]
    return float(np.mean(x)), float(np.std(x) / math.sqrt(x.size))


def light_directions() -> tuple[np.ndarray, np.ndarray]:
    """(directions ω (n, 3) where the environment map shines, L(ω) dω): a midpoint grid of
    :data:`STEP` over the upper hemisphere, L from the emitter's own ``eval``."""
    import drjit as dr
    import mitsuba as mi

    emitter = mi.load_dict({"type": "envmap", "bitmap": mi.Bitmap(env_image())})
    t = np.arange(0.5 * STEP, 90.0, STEP)
    p = np.arange(0.5 * STEP, 360.0, STEP)
    tt, pp = (a.ravel() for a in np.meshgrid(t, p, indexing="ij"))
    w = world(tt, pp)
    si = dr.zeros(mi.SurfaceInteraction3f, len(w))
    si.wi = mi.Vector3f(*(-w.T))
    radiance = np.asarray(emitter.eval(si))[0]
    keep = radiance > 0
    solid = np.sin(np.radians(tt[keep])) * math.radians(STEP) ** 2
    return w[keep], radiance[keep] * solid


def expected(spec: dict, directions: np.ndarray, light: np.ndarray) -> np.ndarray:
    """L_o at each sensor: ∫ f(ωo, ω)|cosθ| L(ω) dω of ``spec`` by its own ``eval``."""
    out = []
    for w in world(*np.array(SENSORS).T):
        value = batch.evaluate(spec, local(w)[0], local(directions)).value[:, 0]
        out.append(float(np.sum(value * light)))
    return np.array(out)


def expected_reference(model: ref.HK, directions: np.ndarray, light: np.ndarray) -> np.ndarray:
    """The same integral of the float64 model."""
    wl = local(directions)
    out = []
    for w in world(*np.array(SENSORS).T):
        wo = np.tile(local(w), (len(wl), 1))
        out.append(float(np.sum(model.brdf(wo, wl)[:, 0] * np.abs(wl[:, 2]) * light)))
    return np.array(out)


def single_depth(eta: float, spp: int, limit: int = 8) -> tuple[int, list]:
    """The first ``max_depth`` at which the first sensor reads any light, and its readings
    from depth 1 to that depth + 1 (one render each)."""
    readings = []
    for depth in range(1, limit + 1):
        reading = measure(slab_scene(0.9, 1.0, 0.3, eta, depth), 0, spp, 1)[0]
        readings.append(reading)
        if len(readings) >= 2 and readings[-2] > 0:
            return depth - 1, readings
    raise RuntimeError(f"hk validation: no light reached the sensor by max_depth {limit}")


def spec_of(albedo: float, tau: float, g: float, eta: float) -> dict:
    """The ``hk`` plugin's spec of a grid point (thickness 1)."""
    return {"type": "hk", "sigma_s": albedo * tau, "sigma_a": (1.0 - albedo) * tau,
            "thickness": 1.0, "g": g, "eta": eta}


def _label(albedo, tau, g, eta) -> str:
    return f"a = {albedo:g}, τ = {tau:g}, g = {g:g}, η = {eta:g}"


def _sensor_label(k: int) -> str:
    theta, phi = SENSORS[k]
    return f"{'R' if theta < 90 else 'T'} θ = {theta:g}°, φ = {phi:g}°"


def _calibration(ctx: Context, s: Section) -> list:
    """The gonioreflectometer on a Lambertian plane: ρ/π ∫ |cosθ| L dω at each sensor above."""
    scene = plane_scene()
    directions, light = light_directions()
    want = 0.5 / math.pi * float(np.sum(directions[:, 1] * light))
    rows = []
    for k in range(3):
        mean, err = measure(scene, k, ctx.n(200_000, 50_000), ctx.n(8, 4), seed=k + 1)
        z = (mean - want) / err
        s.rows.append(Row("hk (gonioreflectometer)", f"diffuse plane, {_sensor_label(k)}: path "
                          "vs quadrature", f"z = {z:+.2f}", f"|z| ≤ {SIGMAS:g}",
                          abs(z) <= SIGMAS))
        rows.append((_sensor_label(k), f"{mean:.6g} ± {err:.2g}", f"{want:.6g}", f"{z:+.2f}"))
    return rows


def _depths(ctx: Context, s: Section) -> tuple[dict, list]:
    """The single-scattering depth of each interface, measured; and the dark check: with
    σs = 0 every sensor reads 0 up to that depth + 2 (no unscattered light reaches one)."""
    depths, rows = {}, []
    for eta in (1.0, 1.5):
        depth, readings = single_depth(eta, ctx.n(100_000, 20_000))
        depths[eta] = depth
        rows.append((_interface(eta)["type"], str(depth),
                     ", ".join(f"{r:.3g}" for r in readings)))
        s.values[f"hk: single-scattering max_depth, η = {eta:g}"] = str(depth)
        dark = slab_scene(0.0, 1.0, 0.3, eta, depth + 2)
        seen = max(measure(dark, k, 10_000, 1)[0] for k in range(len(SENSORS)))
        s.rows.append(Row("hk (gonioreflectometer)", f"σs = 0, η = {eta:g}, max_depth "
                          f"{depth + 2}: no sensor sees unscattered light", f"{seen:.3g}",
                          "0", seen == 0.0))
    return depths, rows


def _grid(ctx: Context, s: Section, depths: dict, scattering: str = "single") -> list:
    """volpath against the plugin's integral at each point of the grid and each sensor: at
    the single-scattering depth for ``single``, at :data:`ALL_DEPTH` for ``all``, where the
    plugin may also differ by the tables' error, :data:`ALL_ERROR` of its value."""
    rows, worst, worst_rel = [], 0.0, 0.0
    spp, batches = ctx.n(250_000, 100_000), ctx.n(12, 4)
    directions, light = light_directions()
    every = scattering == "all"
    for i, (albedo, tau, g, eta) in enumerate(ctx.n(GRID, QUICK_GRID)):
        spec = {**spec_of(albedo, tau, g, eta), "scattering": scattering}
        plugin = expected(spec, directions, light)
        model = expected_reference(ref.HK(**{k: v for k, v in spec_of(albedo, tau, g, eta)
                                             .items() if k != "type"}), directions, light)
        depth = ALL_DEPTH if every else depths[eta]
        scene = slab_scene(albedo, tau, g, eta, depth)
        zs, rel = [], []
        for k in range(len(SENSORS)):
            mean, err = measure(scene, k, spp, batches, seed=100 * (i + 1) + k + 50 * every)
            slack = ALL_ERROR * abs(plugin[k]) if every else 0.0
            zs.append((mean - plugin[k]) / math.hypot(err, slack / SIGMAS))
            rel.append(abs(mean - plugin[k]) / max(abs(mean), 1e-30))
            rows.append((_label(albedo, tau, g, eta), _sensor_label(k),
                         f"{mean:.4g} ± {err:.2g}", f"{plugin[k]:.4g}",
                         f"{model[k]:.4g}" if not every else f"{rel[-1]:.2%}",
                         f"{zs[-1]:+.2f}"))
        top = float(np.max(np.abs(zs)))
        worst, worst_rel = max(worst, top), max(worst_rel, max(rel))
        what = (f"all orders = volpath (max_depth {depth}), tables within {ALL_ERROR:.1%}"
                if every else f"single scattering = volpath (max_depth {depth})")
        s.rows.append(Row(f"hk ({_label(albedo, tau, g, eta)})",
                          f"{what}, {len(SENSORS)} sensors: largest |z|", f"{top:.2f}",
                          f"≤ {SIGMAS:g}", top <= SIGMAS))
    s.values[f"hk: volpath ({scattering}), largest |z|"] = f"{worst:.2f}"
    if every:
        s.values["hk: volpath (all), largest relative difference"] = f"{worst_rel:.2%}"
    return rows


def section(ctx: Context) -> Section:
    s = Section("Hanrahan-Krueger: hk against volpath")
    DROPPED.update(nan=0, all=0)
    calibration = _calibration(ctx, s)
    depths, depth_rows = _depths(ctx, s)
    grid = _grid(ctx, s, depths)
    grid_all = _grid(ctx, s, depths, "all")
    (t0, t1), (p0, p1) = PATCH
    s.markdown = "\n".join([
        "The `hk` slab (`scattering = single`) against Mitsuba's `volpath` on the same slab "
        "built as a scene (a `homogeneous` medium with an `hg` phase function in a flattened "
        "`cube`, behind a `dielectric` interface, `null` for η = 1; thickness 1), read by "
        "`radiancemeter` sensors (R: reflected, T: transmitted; zenith from the normal) under "
        "an `envmap` lit in the pixels of zenith "
        f"{t0:g}°-{t1:g}° and azimuth {p0:g}°-{p1:g}° ({ENV_RES[1]} × {ENV_RES[0]}); the "
        "plugin's value integrated over that light by quadrature "
        f"({STEP:g}° grid, the light's radiance from the emitter's own `eval`). "
        f"σ: the standard error of volpath's mean over {ctx.n(12, 4)} renders of "
        f"{ctx.n(250_000, 100_000):,} samples; z = (volpath − hk)/σ. Method: "
        "`mi_brdfs.campaign.hk`.", "",
        "**The gonioreflectometer** on a Lambertian plane (`diffuse`, ρ = 0.5, `path`):", "",
        md_table(["sensor", "path", "ρ/π ∫ cosθ L dω", "z"], calibration), "",
        "**What `max_depth` counts**, measured: the first depth at which a sensor sees light "
        "(every path to one scatters at least once; with σs = 0 they all read 0), and the "
        "readings from depth 1 on (a = 0.9, τ = 1, g = 0.3, sensor 0):", "",
        md_table(["interface", "single scattering at max_depth", "readings"], depth_rows), "",
        "**Single scattering**:", "",
        md_table(["slab", "sensor", "volpath ± σ", "hk (plugin)", "float64 model", "z"],
                 grid), "",
        f"**All orders** (`scattering = all`, volpath's `max_depth` {ALL_DEPTH}); z = "
        f"(volpath − hk)/√(σ² + (ε·hk/{SIGMAS:g})²) with ε = {ALL_ERROR:.1%}, the error the "
        "tables promise:", "",
        md_table(["slab", "sensor", "volpath ± σ", "hk (plugin)", "|volpath − hk|/volpath",
                  "z"], grid_all), "",
        f"`volpath` returned {DROPPED['nan']} non-finite (NaN) samples of "
        f"{DROPPED['all']:,}, left out."])
    return s
