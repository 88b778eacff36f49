"""
The matrix every plugin joins: in scalar and llvm variants, RGB, mono, spectral and polarized,
each plugin loads with a reflectance of every texture kind (a constant, <rgb>, a spectrum, a
bitmap, a checkerboard, a mesh attribute), evaluates and samples it to finite, non-negative
values at a mesh's hit point, and renders a tiny image of a mesh carrying it, finite and lit.
Whole rows of this matrix were broken before (spectral bitmaps, mesh attributes on multi-lobe
plugins, compensated conductors in polarized variants).
"""

import mitsuba as mi
import numpy as np
import pytest
from conftest import set_variant
from helpers import merl_file

from mi_brdfs import registry

VARIANTS = ["scalar_rgb", "scalar_spectral_polarized", "llvm_ad_rgb", "llvm_ad_mono",
            "llvm_ad_spectral", "llvm_ad_spectral_polarized"]

#: Each plugin, the reflectance the matrix varies, and further parameters (a second lobe or
#: the compensation, so that the mixture and its weights see the texture too)
PLUGINS = {
    "lambert": ("reflectance", {}),
    "orennayar": ("reflectance", {"form": "full"}),
    "phong": ("diffuse_reflectance", {}),
    "ward": ("specular_reflectance", {}),
    "ashikhmin": ("diffuse_reflectance", {}),
    "lafortune": ("specular_reflectance_0", {"cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0}),
    "cooktorrance": ("diffuse_reflectance", {"multiscatter": True, "shadowing": "smith",
                                             "specular_reflectance": 0.5}),
    "merl": ("scale", {"filename": str(merl_file())}),
    "he": ("diffuse_reflectance", {"specular_reflectance": 0.8, "sigma0": 0.05}),
}


def texture_kinds() -> dict:
    """One reflectance of every texture kind, in the current variant."""
    grid = np.linspace(0.1, 0.7, 48).reshape(4, 4, 3).astype(np.float32)
    return {"constant": 0.4,
            "rgb": {"type": "rgb", "value": [0.2, 0.4, 0.6]},
            "spectrum": {"type": "spectrum", "value": [(400.0, 0.2), (700.0, 0.6)]},
            "bitmap": {"type": "bitmap", "bitmap": mi.Bitmap(grid)},
            "checkerboard": {"type": "checkerboard", "color0": 0.2, "color1": 0.6},
            "mesh_attribute": {"type": "mesh_attribute", "name": "vertex_color"}}


def square(bsdf=None):
    """A unit square mesh in z = 0 with uv and a vertex attribute ``vertex_color``."""
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    mesh = mi.Mesh("square", 4, 2, props, has_vertex_normals=False, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = [-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0]
    params["faces"] = [0, 1, 2, 0, 2, 3]
    params["vertex_texcoords"] = [0, 0, 1, 0, 1, 1, 0, 1]
    params.update()
    mesh.add_attribute("vertex_color", 3, [0.3, 0.5, 0.7] * 4)
    return mesh


def test01_every_plugin_is_in_the_matrix():
    assert set(PLUGINS) == set(registry.PLUGINS)


@pytest.mark.parametrize("variant", VARIANTS)
def test02_every_plugin_with_every_texture_kind(variant):
    """Load, eval_pdf and sample at a hit on the mesh: finite, and non-negative where the
    value is a spectrum (a Mueller matrix has negative elements by nature)."""
    set_variant(variant)
    scene = mi.load_dict({"type": "scene", "s": square()})
    si = scene.ray_intersect(mi.Ray3f([0.1, 0.2, 1.0], [0.0, 0.0, -1.0]))
    si.wi = mi.Vector3f(0.3, 0.1, 0.95)
    ctx = mi.BSDFContext()
    for plugin, (param, extra) in PLUGINS.items():
        for kind, texture in texture_kinds().items():
            bsdf = mi.load_dict(dict(extra, type=plugin, **{param: texture}))
            f, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(-0.2, 0.3, 0.93))
            _, weight = bsdf.sample(ctx, si, 0.4, mi.Point2f(0.3, 0.6))
            for value in (f, pdf, weight):
                a = np.array(value)
                assert np.isfinite(a).all(), (plugin, kind)
                assert mi.is_polarized or (a >= 0).all(), (plugin, kind)


@pytest.mark.parametrize("variant", VARIANTS)
def test03_every_plugin_renders(variant):
    """A 4 × 4 render of the mesh under a constant sky, its material every plugin with a
    mesh attribute as the reflectance (the texture kind with no mean): finite and lit."""
    set_variant(variant)
    for plugin, (param, extra) in PLUGINS.items():
        bsdf = mi.load_dict(dict(extra, type=plugin,
                                 **{param: {"type": "mesh_attribute", "name": "vertex_color"}}))
        scene = mi.load_dict({
            "type": "scene", "integrator": {"type": "path", "max_depth": 3},
            "sensor": {"type": "perspective", "fov": 60,
                       "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 2],
                                                                  target=[0, 0, 0], up=[0, 1, 0]),
                       "film": {"type": "hdrfilm", "width": 4, "height": 4,
                                "pixel_format": "luminance" if mi.is_monochromatic else "rgb"}},
            "sky": {"type": "constant", "radiance": 1.0}, "s": square(bsdf)})
        image = np.array(mi.render(scene, spp=1))
        assert np.isfinite(image).all() and image.max() > 0, plugin
