"""
The float64 Phong reference (mi_brdfs.reference.phong): its lobe-aligned albedo quadrature against
the closed forms at normal incidence (which verifies every normalisation, Giesen's included) and
against brute-force quadrature of its own brdf(), and its transport-mode convention.
"""

import math

import numpy as np
import pytest
from helpers import closed_form

from mi_brdfs.reference import Phong, for_spec, hemisphere_albedo

FORMS = ("normalized", "lecture", "original")
LOBES = ("mirror", "halfway")


@pytest.mark.parametrize("lobe", LOBES)
@pytest.mark.parametrize("form", FORMS)
def test01_albedo_at_normal_incidence_equals_closed_form(form, lobe):
    """n from 0 (uniform lobe) to 1e8: the quadrature reproduces the closed forms to 1e-10."""
    for n in (0.0, 1.0, 10.0, 100.0, 1e4, 1e8):
        model = Phong(0.0, 1.0, n, form, lobe)
        assert model.specular_albedo(0.0) == pytest.approx(closed_form(form, lobe, n), rel=1e-10)


def test02_a_wrong_normalization_is_caught():
    """
    The check above can fail: the halfway lobe with the NDF normalisation (n+2)/(2π) (right for
    ∫ D cosθh dωh, wrong for the BRDF) reflects 4(n + 2^-n/2)/(n+4) at normal incidence, not 1.
    """
    class NDFNormalized(Phong):
        normalization = property(lambda self: (self.n + 2) / (2 * math.pi))

    albedo = NDFNormalized(0.0, 1.0, 10.0, "normalized", "halfway").specular_albedo(0.0)
    assert albedo == pytest.approx(4 * (10 + 2 ** -5) / 14, rel=1e-10)
    assert abs(albedo - 1) > 1.0


@pytest.mark.parametrize("lobe", LOBES)
@pytest.mark.parametrize("form", FORMS)
def test03_albedo_curve_equals_brute_force_quadrature(form, lobe):
    """
    The lobe-aligned quadrature against a plain 512² Gauss-Legendre × midpoint grid of brdf()
    (which resolves lobes up to n ≈ 10): equal to 2e-6 at normal, oblique and grazing incidence.
    The tolerance is the plain grid's own error (its difference from a 1024² grid). n = 1 or 10
    here, alternating over form × lobe (both for each: make validate, section "Phong: three
    forms, two lobes").
    """
    for n in ((1.0,) if (FORMS.index(form) + LOBES.index(lobe)) % 2 == 0 else (10.0,)):
        model = Phong(0.3, 0.7, n, form, lobe)
        for theta in np.radians([0.0, 45.0, 84.26]):
            brute = hemisphere_albedo(model.brdf, theta, 512, 512)
            np.testing.assert_allclose(model.albedo(theta), brute, rtol=2e-6,
                                       err_msg=f"n={n}, θ={np.degrees(theta):.2f}°")


def test04_quadrature_resolves_sharp_lobes():
    """n = 1e4 and 1e8, where a plain grid sees nothing: E → ks·cosθ (mirror, normalized)."""
    for n in (1e4, 1e8):
        model = Phong(0.0, 1.0, n)
        for theta in np.radians([30.0, 60.0, 84.26]):
            assert model.specular_albedo(theta) == pytest.approx(
                math.cos(theta) * (n + 2) / (n + 1), rel=1e-3)
    plain = hemisphere_albedo(Phong(0.0, 1.0, 1e8).brdf, math.radians(30), 256, 256)
    assert plain[0] < 0.1  # the reason for the lobe-aligned quadrature


def test05_transport_modes():
    """original: f in importance transport is f with the arguments swapped (L = ωi there)."""
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(100, 3)), rng.normal(size=(100, 3))
    a[:, 2], b[:, 2] = np.abs(a[:, 2]), np.abs(b[:, 2])
    for form in FORMS:
        model = Phong(0.2, 0.5, 5.0, form, "mirror")
        np.testing.assert_allclose(model.brdf(a, b, "importance"), model.brdf(b, a), rtol=1e-12)
        same = np.allclose(model.brdf(a, b), model.brdf(b, a), rtol=1e-12)
        assert same == (form != "original")


def test06_for_spec(variant_scalar_rgb):
    """The reference for a spec (parsed by mi_brdfs.bsdfspec, which needs a variant)."""
    model = for_spec({"type": "phong", "exponent": 12.0, "form": "lecture", "lobe": "halfway",
                      "specular_reflectance": 0.3})
    assert (model.n, model.form, model.lobe) == (12.0, "lecture", "halfway")
    assert model.k_s.tolist() == [0.3] and model.rho_d.tolist() == [0.5]
    default = for_spec({"type": "phong"})
    assert (default.n, default.form, default.lobe) == (30.0, "normalized", "mirror")
    assert for_spec({"type": "phong", "exponent": {"type": "checkerboard"}}) is None
