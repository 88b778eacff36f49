"""
The quantities of Earth observation for any BSDF (mi_brdfs.earth): the BRF in the principal
plane (1 for a white Lambertian surface at every pair; rtls's hot spot on the sun's side, as
its float64 reference has it) and the white-sky albedo (exact for Lambert's constant sample
weight; rtls's against its kernels' published integrals is in tests/plugins/test_rtls_modis.py);
``mi-brdfs plot pp`` and the furnace's white-sky lines in-process.
"""

import math
import warnings

import numpy as np
import pytest

from mi_brdfs import earth
from mi_brdfs.errors import MiBrdfsError, MiBrdfsWarning
from mi_brdfs.reference import rtls as ref

HOTSPOT = {"type": "rtls", "f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.04}


def _direction(theta_deg):
    t = np.radians(theta_deg)
    return np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)


def test01_a_white_lambertian_surface_has_a_brf_of_1(variant_scalar_rgb):
    """BRF = π·eval/cosθo = 1 at every view zenith from −89° to 89° and every sun zenith
    for Lambert's reflectance 1 (f = 1/π), in each channel; the sun zeniths are nodes."""
    plane = earth.principal_plane("lambert reflectance=1", (0.0, 30.0, 72.5))
    assert plane.brf.shape == (3, len(plane.view_zenith_deg), 3)
    assert plane.view_zenith_deg[0] == -89.0 and plane.view_zenith_deg[-1] == 89.0
    assert {0.0, 30.0, 72.5} <= set(plane.view_zenith_deg.tolist())
    np.testing.assert_allclose(plane.brf, 1.0, rtol=1e-6)


def test02_the_hot_spot_is_backward_as_the_reference_has_it(variant_scalar_rgb):
    """rtls (a forest-like hot spot) in the principal plane equals the float64 model's BRF,
    max(BRF, 0), with ωo = (sin v, 0, cos v): v = +θi is exact backscatter (ωo = ωi, the
    hot spot, brighter than the mirror direction v = −θi for this shadow-driven surface)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        plane = earth.principal_plane(HOTSPOT, (30.0, 60.0))
    model = ref.RTLS(0.2, 0.1, 0.04)
    hot = plane.hot_spot()[:, 0]
    wi = _direction(plane.sun_zenith_deg)
    np.testing.assert_allclose(hot, math.pi * model.brdf(wi, wi)[:, 0], rtol=1e-5)
    for k, sun in enumerate(plane.sun_zenith_deg):
        wo = _direction(plane.view_zenith_deg)
        expected = math.pi * model.brdf(np.broadcast_to(wi[k], wo.shape), wo)[:, 0]
        np.testing.assert_allclose(plane.brf[k, :, 0], expected, rtol=1e-5, atol=1e-6)
        mirror = int(np.flatnonzero(plane.view_zenith_deg == -sun)[0])
        assert hot[k] > 1.2 * plane.brf[k, mirror, 0]
    assert hot[1] > hot[0]  # K_geo = sec²θ − secθ at the hot spot


def test03_sun_zeniths_outside_0_90_are_one_line_errors(variant_scalar_rgb):
    for bad in ((90.0,), (-1.0,), ()):
        with pytest.raises(MiBrdfsError, match=r"sun zeniths must lie in \[0, 90\) degrees"):
            earth.principal_plane("lambert", bad)


def test04_white_sky_albedo_of_lambert_is_its_reflectance(variant_scalar_rgb):
    """Lambert's sample weight is its reflectance at every ωi: the white-sky albedo is the
    reflectance per channel with no error; ``line`` says how it was estimated."""
    sky = earth.white_sky_albedo("lambert reflectance=0.3,0.5,0.7", n=200)
    np.testing.assert_allclose(sky.value, [0.3, 0.5, 0.7], rtol=1e-6)
    np.testing.assert_allclose(sky.err, 0.0, atol=1e-7)
    assert sky.line().startswith("white-sky albedo (bihemispherical, isotropic illumination): "
                                 "0.70000 ± 0.00000 (mean sample() weight over 200 ")


def test05_cli_plot_pp_and_the_furnace_white_sky(variant_scalar_rgb, tmp_path, monkeypatch,
                                                 capsys):
    """``mi-brdfs plot pp`` writes its figure; ``furnace`` prints the white-sky albedo and,
    for rtls, the float64 model's from the kernels' integrals (0.219434 for the defaults:
    0.209741 + 0.189184·0.081384 − 1.377622·0.004140)."""
    pytest.importorskip("matplotlib")
    from mi_brdfs.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["plot", "pp", "lambert", "--thetas", "45",
                 "--variant", "scalar_rgb"]) == 0
    assert (tmp_path / "pp.png").stat().st_size > 1000
    assert main(["furnace", "rtls", "--thetas", "30", "-n", "100",
                 "--variant", "scalar_rgb"]) == 0
    out = capsys.readouterr().out
    assert "white-sky albedo (bihemispherical, isotropic illumination): 0.2" in out
    assert "white-sky albedo of the float64 model (mi_brdfs.reference.rtls, unclamped, from " \
           "its kernels' integrals): 0.21943" in out


def test06_the_bundled_scene_renders(variant_llvm_ad_rgb):
    """scenes/earth.xml loads, with the four Earth-observation plugins beside lambert, and
    renders finite and non-negative at 24×8 pixels, 2 spp, lit (the sun reaches the spheres)."""
    import mitsuba as mi

    from mi_brdfs.scenes import load_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)  # the plugins' defaults warn at load
        scene = load_scene("earth", res=8, width=24, spp=2)
    kinds = {type(shape.bsdf()).__name__ for shape in scene.shapes()}
    assert {"RTLS", "RPV", "Hapke", "Ocean"} <= kinds, kinds
    image = np.array(mi.render(scene, seed=0))
    assert image.shape == (8, 24, 3)
    assert np.isfinite(image).all() and (image >= 0).all()
    assert image.max() > 0
