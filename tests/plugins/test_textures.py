"""
Textured parameters: values out of a parameter's range are rejected at load where the texture's
range can be known (constants, bitmaps, checkerboards of them), and clipped into range where
the model evaluates it where it cannot (mesh_attribute: the values live on the shape).
"""

import mitsuba as mi
import numpy as np
import pytest

import mi_brdfs
from conftest import set_variant


def checker(value, other=0.2):
    return {"type": "checkerboard", "color0": value, "color1": other}


OUT_OF_RANGE = [
    ("lambert", "reflectance", checker(1.5)),
    ("lambert", "reflectance", checker(-0.5)),
    ("lambert", "reflectance", checker(checker(1.2))),  # nested
    ("phong", "specular_reflectance", checker(-0.3)),
    ("phong", "diffuse_reflectance", checker(2.0)),
    ("phong", "exponent", checker(-5.0)),
    ("phong", "exponent", checker(1e35)),
    ("cooktorrance", "eta", checker(-1.0)),
    ("cooktorrance", "k", checker(-1.0)),
    ("cooktorrance", "alpha", checker(-0.1)),
    ("cooktorrance", "specular_reflectance", checker(1.5)),
]


@pytest.mark.parametrize("plugin,param,tex", OUT_OF_RANGE,
                         ids=[f"{p}-{q}-{i}" for i, (p, q, _) in enumerate(OUT_OF_RANGE)])
def test01_procedural_texture_out_of_range_is_rejected(variants_rgb, plugin, param, tex):
    spec = {"type": plugin, param: tex}
    if param == "k":
        spec["eta"] = 1.5
    with pytest.raises(RuntimeError) as info:
        mi.load_dict(spec)
    last = str(info.value).strip().splitlines()[-1]
    assert f'{plugin}: parameter "{param}"' in last and "a texture with values in" in last, last


def test02_procedural_texture_in_range_is_kept(variants_rgb):
    bsdf = mi.load_dict({"type": "lambert", "reflectance": checker(0.9, 0.1)})
    assert "Checkerboard" in str(bsdf)
    assert mi.load_dict({"type": "phong", "exponent": checker(100.0, 5.0)}) is not None


def _triangle_si(colour):
    """A hit on a triangle whose vertices carry ``colour`` as the attribute vertex_color."""
    mesh = mi.Mesh("triangle", 3, 1, has_vertex_normals=False, has_vertex_texcoords=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = [-1, -1, 0, 1, -1, 0, 0, 1, 0]
    params["faces"] = [0, 1, 2]
    params.update()
    mesh.add_attribute("vertex_color", 3, list(colour) * 3)
    scene = mi.load_dict({"type": "scene", "mesh": mesh})
    si = scene.ray_intersect(mi.Ray3f([0, 0, 1], [0, 0, -1]))
    si.wi = [0, 0, 1]
    return si, scene  # the scene must outlive si, which points at its mesh


ATTRIBUTE = {"type": "mesh_attribute", "name": "vertex_color"}


def test03_unknowable_texture_is_clamped_at_evaluation(variants_rgb):
    """A mesh attribute of (1.5, −0.5, 0.7) as lambert's reflectance acts as (1, 0, 0.7): no
    sample weight above 1, no negative eval."""
    si, _scene = _triangle_si([1.5, -0.5, 0.7])
    ctx = mi.BSDFContext()
    bsdf = mi.load_dict({"type": "lambert", "reflectance": ATTRIBUTE})
    f = np.ravel(np.array(bsdf.eval(ctx, si, [0, 0, 1])))
    np.testing.assert_allclose(f, np.array([1.0, 0.0, 0.7]) / np.pi, rtol=1e-6)
    _, w = bsdf.sample(ctx, si, 0.5, [0.3, 0.4])
    np.testing.assert_allclose(np.ravel(np.array(w)), [1.0, 0.0, 0.7], rtol=1e-6)


def test04_clamped_eta_gives_a_valid_cooktorrance(variants_rgb):
    """η from a mesh attribute of −1 is clipped to 0 where it is evaluated (with k = 1: a
    mirror's Fresnel, as η = 0 gives), so eval and pdf stay finite, non-negative and
    consistent."""
    si, _scene = _triangle_si([-1.0, -1.0, -1.0])
    bsdf = mi.load_dict({"type": "cooktorrance", "eta": ATTRIBUTE, "k": 1.0, "alpha": 0.3})
    ctx = mi.BSDFContext()
    f, pdf = bsdf.eval_pdf(ctx, si, [0.1, 0.0, 0.994987])
    f, pdf = np.ravel(np.array(f)), float(np.ravel(np.array(pdf))[0])
    assert np.isfinite(f).all() and f.min() > 0 and pdf > 0
    mirror = mi.load_dict({"type": "cooktorrance", "eta": 0.0, "k": 1.0, "alpha": 0.3})
    g, q = mirror.eval_pdf(ctx, si, [0.1, 0.0, 0.994987])
    np.testing.assert_allclose(f, np.ravel(np.array(g)), rtol=1e-6)
    assert pdf == pytest.approx(float(np.ravel(np.array(q))[0]), rel=1e-6)
    assert mi_brdfs is not None


@pytest.mark.parametrize("plugin,param", [
    ("phong", "diffuse_reflectance"), ("ward", "specular_reflectance"),
    ("ashikhmin", "diffuse_reflectance"), ("lafortune", "specular_reflectance_0"),
    ("cooktorrance", "diffuse_reflectance"),
])
def test05_a_mesh_attribute_weighs_the_lobes_where_it_is_evaluated(variants_rgb, plugin, param):
    """A mesh attribute (no Texture::mean()) as a reflectance of a model with several lobes:
    the lobes' sampling weights read it at the hit point, clipped, so the plugin loads, and
    sample() agrees with eval/pdf there (an attribute of 1.5 acts as 1)."""
    si, _scene = _triangle_si([1.5, 0.3, 0.7])
    ctx = mi.BSDFContext()
    bsdf = mi.load_dict({"type": plugin, param: ATTRIBUTE})
    bs, weight = bsdf.sample(ctx, si, 0.3, [0.3, 0.4])
    value, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    weight, value = np.ravel(np.array(weight)), np.ravel(np.array(value))
    pdf = float(np.ravel(np.array(pdf))[0])
    assert float(np.ravel(np.array(bs.pdf))[0]) == pytest.approx(pdf, rel=1e-5) and pdf > 0
    np.testing.assert_allclose(weight, value / pdf, rtol=1e-5)
    clipped = mi.load_dict({"type": plugin, param: {"type": "rgb", "value": [1.0, 0.3, 0.7]}})
    np.testing.assert_allclose(value, np.ravel(np.array(clipped.eval(ctx, si, bs.wo))),
                               rtol=1e-5)


#: Every reflectance parameter of every plugin
REFLECTANCES = [("lambert", "reflectance"), ("orennayar", "reflectance"),
                ("phong", "diffuse_reflectance"), ("phong", "specular_reflectance"),
                ("ward", "diffuse_reflectance"), ("ward", "specular_reflectance"),
                ("ashikhmin", "diffuse_reflectance"), ("ashikhmin", "specular_reflectance"),
                ("lafortune", "diffuse_reflectance"), ("lafortune", "specular_reflectance_0"),
                ("cooktorrance", "specular_reflectance"), ("cooktorrance", "diffuse_reflectance")]


@pytest.mark.parametrize("variant", ["scalar_spectral", "llvm_ad_spectral"])
def test06_spectral_variants_take_a_bitmap_reflectance(variant, tmp_path):
    """A 20 % grey bitmap as every reflectance, in spectral variants, where Mitsuba stores its
    texels as spectral upsampling coefficients (values like −0.75, which are no reflectance):
    each plugin loads it, as diffuse does, and a lambert of it evaluates as diffuse of it; a
    raw bitmap's values are still checked."""
    set_variant(variant)
    path = str(tmp_path / "grey.exr")
    mi.Bitmap(np.full((4, 4, 3), 0.2, np.float32)).write(path)
    texture = {"type": "bitmap", "filename": path}
    for plugin, param in REFLECTANCES:
        assert mi.load_dict({"type": plugin, param: texture}) is not None, (plugin, param)
    si = mi.SurfaceInteraction3f()
    si.wi, si.uv = mi.Vector3f(0, 0, 1), mi.Point2f(0.5, 0.5)
    si.wavelengths = mi.UnpolarizedSpectrum([450, 520, 600, 680])
    wo = mi.Vector3f(0.3, 0.0, 0.954)
    ours = mi.load_dict({"type": "lambert", "reflectance": texture})
    theirs = mi.load_dict({"type": "diffuse", "reflectance": texture})
    np.testing.assert_allclose(np.ravel(np.array(ours.eval(mi.BSDFContext(), si, wo))),
                               np.ravel(np.array(theirs.eval(mi.BSDFContext(), si, wo))),
                               rtol=1e-6)
    bright = str(tmp_path / "bright.exr")
    mi.Bitmap(np.full((4, 4, 1), 1.7, np.float32)).write(bright)
    with pytest.raises(RuntimeError, match=r"texture with values in \[1.7, 1.7\]"):
        mi.load_dict({"type": "lambert", "reflectance": {"type": "bitmap", "filename": bright,
                                                          "raw": True}})


@pytest.mark.parametrize("spec,key,value", [
    ({"type": "ashikhmin"}, "specular_reflectance.value", 3.0),
    ({"type": "lambert"}, "reflectance.value", -0.5),
    ({"type": "cooktorrance", "eta": 1.5, "k": 1.0}, "eta.value", -1.0),
    ({"type": "cooktorrance", "eta": 1.5, "k": 1.0}, "k.value", 1e12),
    ({"type": "cooktorrance", "transmission": True, "multiscatter": True}, "eta", -1.0),
])
def test07_values_set_through_traverse_are_clipped(variant_llvm_ad_rgb, np_rng, spec, key,
                                                   value):
    """mi.traverse does not run the load-time checks: the lobes clip what they read into the
    parameter's range (a reflectance into [0, 1], η and k into [0, 1e6], a dielectric's η
    into [1e-6, 1e6]), so no value is negative, NaN or raises (ashikhmin's Rs = 3 gave
    negative f, glass at η = −1 a ValueError, k = 1e12 NaN)."""
    from helpers import eval_pdf, random_directions

    bsdf = mi.load_dict(spec)
    params = mi.traverse(bsdf)
    params[key] = value
    params.update()
    wi, wo = random_directions(np_rng, 2000), random_directions(np_rng, 2000)
    f, pdf = eval_pdf(bsdf, wi, wo)[:2]
    assert np.isfinite(f).all() and np.isfinite(pdf).all() and f.min() >= 0 and pdf.min() >= 0
