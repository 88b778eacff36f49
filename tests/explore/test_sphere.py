"""
The explorer's progressively rendered sphere (mi_brdfs.explorer.sphere): a white-ish Lambertian
sphere under the distant light against the closed form, the running mean's noise falling with
the passes, the light moving the lit side, a parameter change through ``mi.traverse`` showing
after a reset with the kernels reused, and the difference and FLIP against the first BSDF.

The closed form (:func:`lit_sphere`): the camera ray of each point of a pixel (the box filter:
uniform over the pixel) hits the unit sphere at n, whose radiance is ρ·(max(0, n·l) + a) under
a distant light of irradiance π from l and a constant environment of radiance a (the sphere is
convex: each point sees the whole environment above it); a ray that misses sees a.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.bsdfspec import load_bsdf
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.explorer.sphere import CAMERA_DISTANCE, Spheres, camera_fov

RES = 24
AMBIENT = 0.2


def lambert(rho):
    """Our ``lambert`` plugin of albedo ``rho`` (grey)."""
    return load_bsdf({"type": "lambert", "reflectance": rho})


def lit_sphere(rho, theta_deg, phi_deg, res=RES, ambient=AMBIENT, sub=12):
    """The expected image (res × res) of a Lambertian sphere, the mean over ``sub``² points
    of each pixel, computed here from the scene's geometry (camera at z = d looking at the
    origin, x to the image's right, y up)."""
    t = math.tan(math.radians(camera_fov()) / 2)
    offsets = (np.arange(sub) + 0.5) / sub
    u = (np.arange(res)[:, None] + offsets[None, :]).ravel()   # pixel coordinate + offset
    x = (2 * u / res - 1) * t
    y = (1 - 2 * u / res) * t
    dx, dy = np.meshgrid(x, y)                                   # rows: y, columns: x
    d = np.stack([dx, dy, -np.ones_like(dx)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, CAMERA_DISTANCE])
    b = d @ o
    disc = b * b - (o @ o - 1.0)
    hit = disc > 0
    s = -b - np.sqrt(np.where(hit, disc, 0.0))
    n = o + s[..., None] * d
    th, ph = math.radians(theta_deg), math.radians(phi_deg)
    light = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    radiance = np.where(hit, rho * (np.maximum(n @ light, 0.0) + ambient), ambient)
    return radiance.reshape(res, sub, res, sub).mean(axis=(1, 3))


def luminance(image):
    """The mean of the channels, float64 (the images here are grey)."""
    return np.asarray(image, np.float64).mean(axis=2)


def test01_lambert_sphere_is_the_closed_form(variant_llvm_ad_rgb):
    """After 6 passes of 16 spp and one of 32, ρ = 0.8 under the light at (50°, 20°) (the
    passes weighted by their spp, a longer one not counted as one more pass): the mean of the
    image within 1 % of the closed form's (3 times the largest error over eight seeds; a mean over
    one pass too many is 12 % off, a sum 7 times), and each pixel within 0.15 (4 standard
    errors of a pixel on the silhouette, the noisiest: hit or miss, σ ≈ 0.4 per sample, 128
    samples)."""
    spheres = Spheres([lambert(0.8)], res=RES, theta=50, phi=20, ambient=AMBIENT, spp=16)
    for _ in range(6):
        spheres.step()
    assert spheres.step(spp=32) == 7
    got = luminance(spheres.linear(0))
    want = lit_sphere(0.8, 50, 20)
    assert got.mean() == pytest.approx(want.mean(), rel=0.01)
    assert np.max(np.abs(got - want)) < 0.15
    preview = spheres.image(0)
    assert preview.dtype == np.uint8 and preview.shape == (RES, RES, 3)


def test02_the_noise_falls_with_the_passes(variant_llvm_ad_rgb):
    """The error against the closed form after 16 passes is below half that after one (MC:
    a quarter); a render that kept only its last pass keeps the first one's error."""
    spheres = Spheres([lambert(0.8)], res=RES, theta=50, phi=20, ambient=AMBIENT, spp=4)
    want = lit_sphere(0.8, 50, 20)
    errors = []
    for k in range(1, 17):
        spheres.step()
        if k in (1, 16):
            errors.append(np.sqrt(np.mean((luminance(spheres.linear(0)) - want) ** 2)))
    assert errors[1] < 0.5 * errors[0], errors


def test03_the_lit_side_follows_the_light(variant_llvm_ad_rgb):
    """The light from the right (θ 70°, φ 0), then the left (φ 180°), then above (φ 90°):
    the half of the sphere towards it is the brighter; a light that is no light is refused."""
    spheres = Spheres([lambert(0.8)], res=RES, theta=70, phi=0, spp=4)

    def halves():
        """One more pass: the means of the left, right, top and bottom halves."""
        spheres.step()
        image = luminance(spheres.linear(0))
        h = RES // 2
        return (image[:, :h].mean(), image[:, h:].mean(), image[:h].mean(), image[h:].mean())

    left, right, top, bottom = halves()
    assert right > 2 * left and abs(top - bottom) < 0.1 * right
    spheres.set_light(70, 180)
    assert spheres.passes == 0
    left, right, top, bottom = halves()
    assert left > 2 * right
    spheres.set_light(70, 90)
    left, right, top, bottom = halves()
    assert top > 2 * bottom
    with pytest.raises(MiBrdfsError, match="sphere light 'sun' is unknown"):
        Spheres([lambert(0.8)], light="sun")


@pytest.mark.parametrize("light", ["point", "envmap"])
def test04_other_lights_light_the_side_towards_them(variant_llvm_ad_rgb, light):
    """The point light and the envmap's sun at (70°, 0) light the right half."""
    spheres = Spheres([lambert(0.8)], res=16, light=light, theta=70, phi=0, spp=4)
    spheres.step()
    image = luminance(spheres.linear(0))
    assert image[:, 8:].mean() > 2 * image[:, :8].mean()


def _kernels(action):
    """The hashes of the kernels that ``action`` launches."""
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history_clear()
        action()
        return {k["hash"] for k in dr.kernel_history() if "hash" in k}
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)


def test05_a_parameter_change_shows_and_reuses_the_kernels(variant_llvm_ad_rgb):
    """ρ set through the BSDF's own ``mi.traverse`` (the object the scene holds, no new
    scene): after reset the first pass is the image at ρ = 0.8 scaled by ρ / 0.8 (the same
    seeds, the same paths; no environment, which the camera would see unscaled), and a second
    change launches only kernels of the first."""
    bsdf = lambert(0.8)
    params = mi.traverse(bsdf)
    spheres = Spheres([bsdf], res=16, spp=2, ambient=0.0)
    spheres.step()
    before = spheres.linear(0)

    def change(rho):
        """ρ set through mi.traverse, then the first pass after a reset."""
        params["reflectance.value"] = type(params["reflectance.value"])(rho)
        params.update()
        spheres.reset()
        spheres.step()

    warm = _kernels(lambda: change(0.5))
    np.testing.assert_allclose(spheres.linear(0), before * 0.5 / 0.8, rtol=1e-4, atol=1e-6)
    again = _kernels(lambda: change(0.3))
    assert warm and again <= warm, again - warm
    np.testing.assert_allclose(spheres.linear(0), before * 0.3 / 0.8, rtol=1e-4, atol=1e-6)


def test06_difference_and_flip_against_the_first(variant_llvm_ad_rgb):
    """Two equal BSDFs (two objects) give equal images (the same seeds): FLIP 0 and a white
    difference; a darker albedo gives FLIP > 0.05 and a blue sphere in the difference."""
    pytest.importorskip("flip_evaluator")
    spheres = Spheres([lambert(0.6), lambert(0.6), lambert(0.2)], res=16, spp=4)
    spheres.step()
    assert spheres.flip(1) == 0.0
    same = spheres.difference(1).astype(int)
    assert same.shape == (16, 16, 3) and np.all(same > 240)
    assert spheres.flip(2) > 0.05
    centre = spheres.difference(2)[8, 8].astype(int)
    assert centre[2] > centre[0] + 50  # blue: darker than the first


def test07_a_scene_file_with_the_bsdf_swapped(variant_llvm_ad_rgb):
    """The bundled ``material`` scene (16² px) with its BSDF ``material`` replaced by two of
    ours: the scene holds the objects themselves (ρ from 0.2 to 0.6 through ``mi.traverse``
    triples the sphere's middle in the first pass: the same seeds, the same paths; light
    that came by the floor, by more), its lights do not move, a wrong id is named."""
    dark, bright = lambert(0.2), lambert(0.8)
    spheres = Spheres.from_scene("material", [dark, bright], "material", {"res": "16"}, spp=2)
    assert spheres.bsdfs[0] is dark and spheres.shape == (16, 16)
    spheres.step()
    before = luminance(spheres.linear(0))
    assert luminance(spheres.linear(1)).mean() > before.mean()
    params = mi.traverse(dark)
    params["reflectance.value"] = type(params["reflectance.value"])(0.6)
    params.update()
    spheres.reset()
    spheres.step()
    middle = (slice(6, 10), slice(6, 10))
    np.testing.assert_allclose(luminance(spheres.linear(0))[middle] / before[middle], 3.0,
                               rtol=0.05)
    with pytest.raises(MiBrdfsError, match="do not move"):
        spheres.set_light(10, 0)
    with pytest.raises(MiBrdfsError, match='no <bsdf id="floor">'):
        Spheres.from_scene("material", [dark], "floor", {"res": "16"})
