"""The lambert plugin: closed form, equality with Mitsuba's `diffuse`, sampling, rendering, AD."""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from helpers import eval_pdf, random_directions, sample

import mi_brdfs


def test01_create(variants_all):
    bsdf = mi.load_dict({"type": "lambert", "reflectance": 0.3})
    assert type(bsdf).__name__ == "Lambert"
    assert bsdf.component_count() == 1
    assert bsdf.flags() == bsdf.flags(0) == \
        int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
    assert "Lambert[" in str(bsdf) and "reflectance" in str(bsdf)
    # every property is read: an unknown one is reported by Mitsuba, as for built-ins
    with pytest.raises(RuntimeError, match="unreferenced property"):
        mi.load_dict({"type": "lambert", "roughness": 0.3})


def test02_eval_pdf_closed_form(variants_rgb):
    """eval = ρ cosθo/π and pdf = cosθo/π on 20 angles; 0 below the horizon on either side."""
    rho = 0.37
    bsdf = mi.load_dict({"type": "lambert", "reflectance": rho})
    theta = np.linspace(0, np.pi / 2 * 0.999, 20)
    wo = np.stack([np.sin(theta), 0 * theta, np.cos(theta)], axis=1)
    wi = np.tile([0.3, 0.2, np.sqrt(1 - 0.13)], (20, 1))
    f, p, f2, p2 = eval_pdf(bsdf, wi, wo)
    np.testing.assert_allclose(f[:, 0], rho * np.cos(theta) / np.pi, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(p, np.cos(theta) / np.pi, rtol=1e-6, atol=1e-9)
    np.testing.assert_array_equal(f2, f)
    np.testing.assert_array_equal(p2, p)
    below = wo * [1, 1, -1]
    f, p, _, _ = eval_pdf(bsdf, wi, below)
    assert not f.any() and not p.any()
    f, p, _, _ = eval_pdf(bsdf, wi * [1, 1, -1], wo)  # seen from the back side
    assert not f.any() and not p.any()


def test03_equals_diffuse_pointwise(variants_all, np_rng):
    """
    eval, pdf, eval_pdf and sample() equal the built-in's on random inputs: bit for bit in JIT
    variants (the same operations in the same order), and to float rounding in scalar variants,
    where ``mi.warp.square_to_cosine_hemisphere`` called from Python is a separately compiled
    copy of the function: x, y can differ in the last bit, which z = sqrt(1 − x² − y²) amplifies
    near the horizon (a few samples, by a few float32 units).
    """
    n = 64 if mi.variant().startswith("scalar") else 4096
    rgb = {"type": "rgb", "value": [0.2, 0.5, 0.9]}
    ours = mi.load_dict({"type": "lambert", "reflectance": rgb})
    ref = mi.load_dict({"type": "diffuse", "reflectance": rgb})
    wi, wo = random_directions(np_rng, n), random_directions(np_rng, n)
    for a, b in zip(eval_pdf(ours, wi, wo), eval_pdf(ref, wi, wo)):
        np.testing.assert_array_equal(a, b)
    s1, s2 = np_rng.random(n), np_rng.random((n, 2))
    a, b = sample(ours, wi, s1, s2), sample(ref, wi, s1, s2)
    exact = mi.variant().startswith("llvm")
    for key in ("wo", "pdf", "weight", "type", "component"):
        np.testing.assert_allclose(a[key], b[key], rtol=0 if exact else 1e-5,
                                   atol=0 if exact else 1e-6, err_msg=key)


def test04_sample_weight_and_pdf_consistency(variants_rgb, np_rng):
    """weight == eval/pdf and bs.pdf == pdf(bs.wo) for every sample; weight == ρ exactly."""
    n = 200 if mi.variant().startswith("scalar") else 20000
    bsdf = mi.load_dict({"type": "lambert", "reflectance": 0.6})
    wi = random_directions(np_rng, n, lower=False)
    s = sample(bsdf, wi, np_rng.random(n), np_rng.random((n, 2)))
    f, p, _, _ = eval_pdf(bsdf, wi, s["wo"])
    ok = s["pdf"] > 0
    assert ok.mean() > 0.99
    np.testing.assert_allclose(s["pdf"][ok], p[ok], rtol=1e-5)
    np.testing.assert_allclose(s["weight"][ok, 0], f[ok, 0] / p[ok], rtol=1e-5)
    np.testing.assert_allclose(s["weight"][ok], 0.6, rtol=1e-6)


@pytest.mark.parametrize("wi", [[0, 0, 1], [0.6, 0.3, 0.74], [0.99, 0, 0.1]],
                         ids=["normal", "oblique", "grazing"])
def test05_chi2(variant_llvm_ad_rgb, wi):
    from mi_brdfs.checks import chi2_bsdf
    result = chi2_bsdf({"type": "lambert", "reflectance": 0.5}, wi=wi)
    assert result.passed, result.message


def test06_white_furnace_render(variants_rgb):
    """ρ = 1 in the furnace: the sphere vanishes, image mean 1 within 0.005, no NaN/Inf."""
    scalar = mi.variant().startswith("scalar")
    scene = mi_brdfs.scenes.load_scene("furnace", res=16 if scalar else 64)
    img = np.array(mi.render(scene, spp=16 if scalar else 64, seed=7))
    assert np.isfinite(img).all()
    assert abs(img.mean() - 1.0) < 0.005, img.mean()


def test07_render_equals_diffuse(variant_llvm_ad_rgb):
    """
    The Cornell box with every surface lambert renders as with diffuse, same seed: bit for bit on
    one thread; with several, the film's parallel accumulation order varies from run to run
    even for the built-in, so there the difference must stay within that run-to-run noise.
    """
    def cbox(material, seed=3):
        scene = mi_brdfs.scenes.load_scene("cbox", material=material, res=64)
        return np.array(mi.render(scene, spp=16, seed=seed))

    threads = dr.thread_count()
    try:
        dr.set_thread_count(1)
        ours, ref = cbox("lambert"), cbox("diffuse")
    finally:
        dr.set_thread_count(threads)
    assert np.isfinite(ours).all() and ours.mean() > 0.05
    np.testing.assert_array_equal(ours, ref)
    ours, ref, ref2 = cbox("lambert"), cbox("diffuse"), cbox("diffuse")
    noise = max(np.abs(ref - ref2).max(), 1e-6 * ref.max())
    assert np.abs(ours - ref).max() <= 4 * noise


XML = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <bsdf type="{outer}" id="m">{inner}</bsdf>
  <shape type="rectangle"><ref id="m"/></shape>
  <emitter type="constant"/>
  <sensor type="perspective">
    <transform name="to_world"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm">
      <integer name="width" value="16"/><integer name="height" value="16"/>
    </film>
    <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
  </sensor>
</scene>"""


@pytest.mark.parametrize("outer,inner", [
    ("{m}", '<texture type="bitmap" name="reflectance"><string name="filename" value="{tex}"/>'
            "</texture>"),
    ("twosided", '<bsdf type="{m}"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf>'),
    ("blendbsdf", '<float name="weight" value="0.3"/><bsdf type="{m}"/>'
                  '<bsdf type="{m}"><rgb name="reflectance" value="0.9, 0.1, 0.1"/></bsdf>'),
], ids=["bitmap", "twosided", "blendbsdf"])
def test08_xml_textures_and_nesting(variants_rgb, tmp_path, outer, inner):
    """From XML: a bitmap texture and nesting in twosided/blendbsdf render as with diffuse."""
    tex = tmp_path / "tex.png"
    rng = np.random.default_rng(1)
    mi.Bitmap(rng.integers(0, 255, (8, 8, 3), dtype=np.uint8)).write(str(tex))
    images = []
    for m in ("lambert", "diffuse"):
        xml = XML.format(outer=outer.format(m=m), inner=inner.format(m=m, tex=tex))
        images.append(np.array(mi.render(mi.load_string(xml), seed=1)))
    assert np.isfinite(images[0]).all() and images[0].mean() > 0.05
    np.testing.assert_allclose(images[0], images[1], rtol=1e-6, atol=1e-7)


def _sphere_scene(bsdf_type, integrator="prb"):
    return mi.load_dict({
        "type": "scene", "integrator": {"type": integrator, "max_depth": 2},
        "emitter": {"type": "constant"},
        "shape": {"type": "sphere", "bsdf": {"type": bsdf_type, "reflectance": 0.5}},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": 16, "height": 16}}})


def test09_traverse_update_and_gradient(variant_llvm_ad_rgb):
    """mi.traverse exposes reflectance, an update takes effect, d(image)/dρ equals diffuse's."""
    key = "shape.bsdf.reflectance.value"
    result = {}
    for m in ("lambert", "diffuse"):
        scene = _sphere_scene(m)
        params = mi.traverse(scene)
        assert key in params
        params[key] = mi.Float(0.25)
        params.update()
        mean = float(np.array(mi.render(scene, spp=16, seed=2)).mean())
        dr.enable_grad(params[key])
        params.update()
        dr.backward(dr.mean(mi.render(scene, params, spp=16, seed=2), axis=None))
        result[m] = (mean, np.array(dr.grad(params[key])))
    # background 1, sphere ρ·1: the mean drops from about 0.81 (ρ = 0.5) to about 0.72 (0.25)
    assert result["lambert"][0] < 0.75
    assert result["lambert"][0] == pytest.approx(result["diffuse"][0], rel=1e-6)
    assert np.all(result["lambert"][1] > 0)
    np.testing.assert_allclose(result["lambert"][1], result["diffuse"][1], rtol=1e-5)


@pytest.mark.parametrize("value,match", [
    (1.5, r'lambert: parameter "reflectance" = 1.5 is invalid: must be finite and within \[0, 1\]'),
    (-0.1, r'"reflectance" = -0.1 is invalid'),
    (float("nan"), r'"reflectance" = nan is invalid'),
    ({"type": "rgb", "value": [1.5, 0.0, 0.0]}, r'"reflectance" = \[1.5, 0.0, 0.0\] is invalid'),
    ("red", r'"reflectance" = "red" is invalid: must be a float, <rgb>, <spectrum> or a texture'),
], ids=["above1", "negative", "nan", "rgb", "string"])
def test10_bad_reflectance(variants_rgb, value, match):
    with pytest.raises(RuntimeError, match=match):
        mi.load_dict({"type": "lambert", "reflectance": value})


def test11_bad_bitmap_reflectance(variant_scalar_rgb):
    """A texture whose values leave [0, 1] is rejected too (its range is read from the data)."""
    bitmap = mi.Bitmap(np.full((4, 4, 3), 1.7, dtype=np.float32))
    with pytest.raises(RuntimeError, match=r"texture with values in \[1.7, 1.7\]"):
        mi.load_dict({"type": "lambert", "reflectance": {"type": "bitmap", "bitmap": bitmap,
                                                          "raw": True}})


def test12_scalar_constants_follow_updates_and_textures(variant_scalar_rgb, np_rng):
    """
    Scalar RGB reads a constant ρ once as floats (``parameters_changed``): after an update
    through mi.traverse the plugin still equals ``diffuse`` with the new ρ, bit for bit, and a
    bitmap ρ (evaluated per call) equals ``diffuse`` with the same bitmap.
    """
    wi, wo = random_directions(np_rng, 32, lower=False), random_directions(np_rng, 32)
    s1, s2 = np_rng.random(32), np_rng.random((32, 2))
    rgb = {"type": "rgb", "value": [0.2, 0.5, 0.9]}
    bitmap = {"type": "bitmap", "raw": True, "bitmap": mi.Bitmap(
        np.array([[[0.1, 0.2, 0.3], [0.9, 0.8, 0.7]], [[0.4, 0.4, 0.4], [0.6, 0.1, 0.3]]],
                 dtype=np.float32))}
    for reflectance, update in ((rgb, [0.7, 0.1, 0.3]), (bitmap, None)):
        pair = [mi.load_dict({"type": t, "reflectance": reflectance})
                for t in ("lambert", "diffuse")]
        if update is not None:
            for bsdf in pair:
                params = mi.traverse(bsdf)
                params["reflectance.value"] = mi.Color3f(update)
                params.update()
        ours, ref = pair
        for a, b in zip(eval_pdf(ours, wi, wo), eval_pdf(ref, wi, wo)):
            np.testing.assert_array_equal(a, b)
        a, b = sample(ours, wi, s1, s2), sample(ref, wi, s1, s2)
        np.testing.assert_allclose(a["weight"], b["weight"], rtol=1e-6)
