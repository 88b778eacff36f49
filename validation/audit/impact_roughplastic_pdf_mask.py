"""
Render impact of roughplastic's unmasked pdf() (see repro_roughplastic_pdf_mask.py).

1. A lit roughplastic plane (GGX α = 0.5, grazing views included), rendered by the `path`
   integrator with the built-in plugin and with a wrapper whose pdf()/eval_pdf()/bs.pdf are masked
   to cos θi > 0 and cos θo > 0 (the fixed expectation), same sampler seed.
2. A mesh whose shading normal is perpendicular to orthographic camera rays, so that the path
   tracer hands the BSDF wi with cos θi = 0 exactly: count NaN pixels, and the NaN pdfs that
   eval_pdf() returns for those interactions.
"""
import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
CFG = {"type": "roughplastic", "distribution": "ggx", "alpha": 0.5}


class Masked(mi.BSDF):
    """The built-in roughplastic with its pdf masked to the hemisphere (the fix)."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.inner = mi.load_dict(CFG)
        self.m_flags = self.inner.flags()
        self.m_components = [self.inner.flags(i) for i in range(self.inner.component_count())]

    @staticmethod
    def _ok(si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def sample(self, ctx, si, s1, s2, active=True):
        bs, w = self.inner.sample(ctx, si, s1, s2, active)
        bs.pdf = dr.select(self._ok(si, bs.wo), bs.pdf, 0.0)
        return bs, w

    def eval(self, ctx, si, wo, active=True):
        return self.inner.eval(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return dr.select(self._ok(si, wo), self.inner.pdf(ctx, si, wo, active), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        v, p = self.inner.eval_pdf(ctx, si, wo, active)
        return v, dr.select(self._ok(si, wo), p, 0.0)

    def to_string(self):
        return "Masked[roughplastic]"


mi.register_bsdf("roughplastic_masked", lambda props: Masked(props))


def scene(bsdf, ortho=False, normals=None):
    s = {"type": "scene", "integrator": {"type": "path", "max_depth": 4},
         "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.3}},
         "light": {"type": "sphere", "center": [1.0, -1.0, 2.0], "radius": 0.2,
                   "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 30.0}}}}
    if ortho:
        s["sensor"] = {"type": "orthographic",
                       "to_world": mi.ScalarTransform4f().look_at([0, 0, 3], [0, 0, 0], [0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": 32, "height": 32,
                                "pixel_format": "rgb"},
                       "sampler": {"type": "independent", "sample_count": 16}}
        mesh = mi.Mesh("quad", 4, 2, has_vertex_normals=True)
        params = mi.traverse(mesh)
        params["vertex_positions"] = dr.ravel(mi.Point3f([-1, 1, 1, -1], [-1, -1, 1, 1], [0] * 4))
        params["faces"] = dr.ravel(mi.Vector3u([0, 0], [1, 2], [2, 3]))
        params["vertex_normals"] = dr.ravel(mi.Normal3f(*normals))
        params.update()
        mesh.set_bsdf(mi.load_dict(bsdf))
        s["shape"] = mesh
    else:
        s["sensor"] = {"type": "perspective", "fov": 60,
                       "to_world": mi.ScalarTransform4f().look_at([0, -3, 0.6], [0, 0, 0],
                                                                  [0, 0, 1]),
                       "film": {"type": "hdrfilm", "width": 96, "height": 64,
                                "pixel_format": "rgb"},
                       "sampler": {"type": "independent", "sample_count": 64}}
        s["shape"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale(4),
                      "bsdf": bsdf}
    return mi.load_dict(s)


# 1. built-in vs masked pdf, same seed
a = np.array(mi.render(scene(CFG), seed=7))
b = np.array(mi.render(scene({"type": "roughplastic_masked"}), seed=7))
a2 = np.array(mi.render(scene(CFG), seed=7))  # the same render again: run-to-run rounding
print(f"[1] lit plane 96x64, 64 spp: mean built-in {a.mean():.6f}, masked {b.mean():.6f}; "
      f"max |Δ| = {np.abs(a - b).max():.3g}, pixels that differ: {(a != b).any(-1).sum()} of "
      f"{a.shape[0] * a.shape[1]} "
      f"(built-in rendered twice: max |Δ| = {np.abs(a - a2).max():.3g}); "
      f"NaN pixels {np.isnan(a).any(-1).sum()}")

# 2. shading normals perpendicular to the rays: wi has cos θi = 0 exactly
sc = scene(CFG, ortho=True, normals=([1.0] * 4, [0.0] * 4, [0.0] * 4))
img = np.array(mi.render(sc, seed=1))
ray = mi.Ray3f(mi.Point3f(0.1, 0.2, 3.0), mi.Vector3f(0, 0, -1))
si = sc.ray_intersect(ray)
bsdf = si.bsdf(ray)
v, p = bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))
print(f"[2] quad with vertex normals (1, 0, 0), orthographic camera along -z: hit wi (local) = "
      f"{np.array(si.wi).ravel().round(6)}, eval_pdf(wo = n_s) = ({np.array(v).ravel()[0]}, "
      f"{np.array(p)[0]}); rendered image: {(img == 0).all(-1).mean():.0%} of the pixels black "
      f"(the quad: eval = 0; the rest is the sphere light), NaN pixels "
      f"{np.isnan(img).any(-1).sum()} of {img.shape[0] * img.shape[1]}")

if __name__ == "__main__" and __import__("os").environ.get("SHOW"):
    print(np.round(img[::4, ::4, 0], 3))
