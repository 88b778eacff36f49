"""
Render impact of hair's residual-lobe sampling defect (see repro_hair_pmax_sampling.py).

The fixed expectation is a wrapper around the built-in plugin whose sample() moves each sample
of the residual lobe (recognised by wo.y == 0 exactly) to where the fixed code would put it:
the same random numbers (cos theta from sample2.x with variance v[P_MAX], cos phi from
sample2.y, the azimuth phi_o of the built-in sample, which is already uniform) with the
untilted incident angle, then pdf() and eval() of the built-in plugin at that direction.

1. Direct estimates of I(wi) = integral of eval(wi, wo) L(wo) dwo with L(wo) = wo.y^2 (light
   arriving along the fibre): by sample() as a path tracer does (built-in and fixed), and by
   uniform sphere sampling of eval() (the reference, independent of sample()).
2. A render: 40 straight fibres (bsplinecurve, whose shading frame has the tangent on local +y as
   hair expects; linearcurve puts it on local x) along world x under an environment brighter along
   x, `path` integrator, built-in vs. fixed plugin, same seed.
Uses only mitsuba, drjit and numpy.
"""
import os
import tempfile

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
BLONDE = {"type": "hair", "eumelanin": 0.2, "pheomelanin": 0.4}
LR = 0.3
V3 = 4 * (0.726 * LR + 0.812 * LR ** 2 + 3.7 * LR ** 20) ** 2


class FixedHair(mi.BSDF):
    """The built-in hair with residual-lobe samples moved to where the fixed code puts them."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        cfg = {"type": "hair"}
        for k in ("eumelanin", "pheomelanin"):
            if props.has_property(k):
                cfg[k] = props[k]
        self.inner = mi.load_dict(cfg)
        self.m_flags = self.inner.flags()
        self.m_components = [self.inner.flags(i) for i in range(self.inner.component_count())]

    def sample(self, ctx, si, s1, s2, active=True):
        bs, w = self.inner.sample(ctx, si, s1, s2, active)
        residual = bs.wo.y == 0
        sin_i = si.wi.y
        cos_i = dr.safe_sqrt(1 - sin_i * sin_i)
        cos_t = dr.clip(1 + V3 * dr.log(s2.x + (1 - s2.x) * dr.exp(-2 / V3)), -1, 1)
        sin_t = dr.safe_sqrt(1 - cos_t * cos_t)
        sin_o = -cos_t * sin_i + sin_t * dr.cos(2 * dr.pi * s2.y) * cos_i
        cos_o = dr.safe_sqrt(1 - sin_o * sin_o)
        phi_o = dr.atan2(bs.wo.z, bs.wo.x)
        wo = mi.Vector3f(cos_o * dr.cos(phi_o), sin_o, cos_o * dr.sin(phi_o))
        v, p = self.inner.eval_pdf(ctx, si, wo, active)
        bs.wo = dr.select(residual, wo, bs.wo)
        bs.pdf = dr.select(residual, p, bs.pdf)
        w = dr.select(residual, dr.select(p > 0, v / p, 0), w)
        return bs, w

    def eval(self, ctx, si, wo, active=True):
        return self.inner.eval(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return self.inner.pdf(ctx, si, wo, active)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.inner.eval_pdf(ctx, si, wo, active)

    def to_string(self):
        return "FixedHair"


mi.register_bsdf("hair_fixed", lambda props: FixedHair(props))


def interaction(wi, n):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f([float(x) for x in wi])
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def direct(cfg, wi, n=4_000_000, seed=3):
    rng = np.random.default_rng(seed)
    ctx = mi.BSDFContext()
    out = []
    for plugin in (mi.load_dict(cfg), mi.load_dict(dict(cfg, type="hair_fixed"))):
        u = rng.random((n, 3), dtype=np.float32)
        bs, w = plugin.sample(ctx, interaction(wi, n), mi.Float(u[:, 0]),
                              mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
        est = np.array(w)[0].astype(np.float64) * np.array(bs.wo.y, dtype=np.float64) ** 2
        out.append((est.mean(), est.std() / np.sqrt(n)))
    z = 2 * rng.random(n) - 1
    ph = 2 * np.pi * rng.random(n)
    r = np.sqrt(1 - z * z)
    d = np.stack([r * np.cos(ph), r * np.sin(ph), z], 1).astype(np.float32)
    f = np.array(mi.load_dict(cfg).eval(ctx, interaction(wi, n),
                                        mi.Vector3f(*[mi.Float(d[:, k]) for k in range(3)])))[0]
    ref = f.astype(np.float64) * d[:, 1].astype(np.float64) ** 2 * 4 * np.pi
    out.append((ref.mean(), ref.std() / np.sqrt(n)))
    return out


def scene(bsdf, curves, env):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 8},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at([0, 0, 4], [0, 0, 0], [0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 64, "height": 48, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": 256}},
        "env": {"type": "envmap", "filename": env},
        "hair": {"type": "bsplinecurve", "filename": curves, "bsdf": bsdf},
    })


def main():
    print("1. I(wi) = integral of f(wi, wo) L(wo) with L = wo.y^2 (light along the fibre), red")
    for cfg, name in (({"type": "hair"}, "brown"), (BLONDE, "blonde")):
        for wi in ((0.0, 0.0, 1.0), (0.995037, 0.0, 0.0995037), (0.6, 0.6, 0.5291503)):
            (b, sb), (f, sf), (r, sr) = direct(cfg, wi)
            print(f"   {name:6s} wi = {tuple(round(x, 3) for x in wi)}: sample() built-in "
                  f"{b:.5f} +- {sb:.5f}, fixed {f:.5f} +- {sf:.5f}, reference {r:.5f} +- {sr:.5f}"
                  f"  (built-in {100 * (b / r - 1):+.1f} %)")

    tmp = tempfile.mkdtemp()
    curves = os.path.join(tmp, "fibres.txt")
    rng = np.random.default_rng(1)
    with open(curves, "w") as fh:
        for i in range(40):
            y, z = -0.9 + 1.8 * i / 39, rng.uniform(-0.3, 0.3)
            for x in np.linspace(-1.5, 1.5, 6):
                fh.write(f"{x} {y} {z} 0.02\n")
            fh.write("\n")
    # environment: 0.2 + 5 x^2 in world directions (bright along the fibres' axis x)
    h, w = 128, 256
    theta = (np.arange(h) + 0.5) / h * np.pi
    phi = (np.arange(w) + 0.5) / w * 2 * np.pi
    T, P = np.meshgrid(theta, phi, indexing="ij")
    dx = np.sin(T) * np.sin(P)   # the envmap's x for its lat-long parameterisation
    img = np.repeat((0.2 + 5 * dx ** 2)[..., None], 3, axis=2).astype(np.float32)
    env = os.path.join(tmp, "env.exr")
    mi.Bitmap(img).write(env)
    out = []
    for bsdf in (BLONDE, dict(BLONDE, type="hair_fixed")):
        out.append(np.array(mi.render(scene(bsdf, curves, env), seed=11)))
    again = np.array(mi.render(scene(BLONDE, curves, env), seed=12))
    hit = out[1].sum(-1) > 0
    a, b = out[0][hit].mean(), out[1][hit].mean()
    print(f"2. 40 blonde fibres, 64x48, 256 spp, path tracer: mean over the fibres' pixels "
          f"built-in {a:.5f}, fixed {b:.5f} ({100 * (a / b - 1):+.2f} %); built-in with "
          f"another seed {again[hit].mean():.5f} ({100 * (again[hit].mean() / a - 1):+.2f} %)")


if __name__ == "__main__":
    main()
