"""
Render impact of roughdielectric's sample_visible=false weight (see
repro_roughdielectric_widened_weight.py): the same scenes rendered with sample_visible=true
(unbiased) and =false, which must agree in expectation.

  * a rough glass sphere (alpha 0.3, bk7/air) in a constant environment of radiance 1, path
    tracer (max_depth 64, no Russian roulette): mean radiance in rings of the sphere's image;
  * a rough glass pane (one interface, a 2000 x 2000 rectangle) seen 3 deg above its plane
    (incidence about 87 deg), same environment: the pixel value is the directional albedo in
    radiance transport, R + T/eta^2.

Prints visible / widened and the difference with its standard error over independent seeds.
Only mitsuba, drjit and numpy (llvm_ad_rgb). Exits 0 (a measurement).
"""
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
T = mi.ScalarTransform4f
SEEDS = 4


def render(shape, sensor, visible, kind, spp=256):
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "path", "max_depth": 64, "rr_depth": 1000},
        "sensor": dict(sensor, film={"type": "hdrfilm", "width": 96, "height": 96,
                                     "rfilter": {"type": "box"}},
                       sampler={"type": "independent", "sample_count": spp}),
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "obj": dict(shape, bsdf={"type": "roughdielectric", "distribution": kind, "alpha": 0.3,
                                 "sample_visible": visible})})
    return np.array([np.array(mi.render(scene, seed=s))[..., 0] for s in range(SEEDS)])


def compare(what, a, b):
    """a, b: (seeds,) means of the same region."""
    diff = b - a
    err = diff.std(ddof=1) / np.sqrt(len(diff))
    print(f"{what}: visible {a.mean():.4f}  widened {b.mean():.4f}  ratio {b.mean() / a.mean():.4f}"
          f"  difference {diff.mean():+.4f} +- {err:.4f}")


sphere = {"type": "sphere"}
cam_sphere = {"type": "perspective", "fov": 30,
              "to_world": T().look_at(origin=[0, 0, 4.2], target=[0, 0, 0], up=[0, 1, 0])}
th = np.radians(87)
pane = {"type": "rectangle", "to_world": T().scale([1000, 1000, 1])}
cam_pane = {"type": "perspective", "fov": 4,
            "to_world": T().look_at(origin=[0, -np.sin(th) * 10, np.cos(th) * 10],
                                    target=[0, 0, 0], up=[0, 0, 1])}
y, x = np.mgrid[0:96, 0:96]
radius = np.tan(np.arcsin(1 / 4.2)) / np.tan(np.radians(15)) * 48     # sphere's image, pixels
r = np.hypot(x - 47.5, y - 47.5) / radius
for kind in ("beckmann", "ggx"):
    A, B = render(sphere, cam_sphere, True, kind), render(sphere, cam_sphere, False, kind)
    for lo, hi in ((0, 0.5), (0.5, 0.8), (0.8, 0.95), (0.95, 0.99)):
        m = (r >= lo) & (r < hi)
        compare(f"{kind:8s} sphere, ring {lo:.2f}-{hi:.2f} (incidence "
                f"{np.degrees(np.arcsin(lo)):.0f}-{np.degrees(np.arcsin(hi)):.0f} deg)",
                A[:, m].mean(1), B[:, m].mean(1))
    A, B = render(pane, cam_pane, True, kind), render(pane, cam_pane, False, kind)
    compare(f"{kind:8s} pane seen at 87 deg incidence", A.mean((1, 2)), B.mean((1, 2)))
