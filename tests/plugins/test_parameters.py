"""
Parameter forms across the plugins: a roughness is one value per point (an <rgb> is refused, not
averaged), the energy warnings of models that can reflect more than they receive, η of a rough
dielectric as a uniform <spectrum>, and roughconductor's material "none" (a perfect conductor).
"""

import warnings

import mitsuba as mi
import numpy as np
import pytest
from helpers import eval_pdf, random_directions

import mi_brdfs

RGB = {"type": "rgb", "value": [0.1, 0.2, 0.3]}


@pytest.mark.parametrize("plugin", ["cooktorrance", "ward"])
@pytest.mark.parametrize("name", ["alpha", "alpha_u"])
def test01_an_rgb_roughness_is_refused(variant_scalar_rgb, plugin, name):
    spec = {"type": plugin, name: RGB}
    if name == "alpha_u":
        spec["alpha_v"] = 0.2
    with pytest.raises(RuntimeError, match=rf'{plugin}: parameter "{name}" = \[0.1, 0.2, 0.3\] '
                                           r'is invalid: must be a float or a texture, one value '
                                           r'per point'):
        mi.load_dict(spec)
    with pytest.raises(RuntimeError, match=r'"alpha" = "x" is invalid: must be a float or a '
                                           r'texture$'):
        mi.load_dict({"type": plugin, "alpha": "x"})


def test02_a_uniform_spectrum_roughness_is_its_value(variant_scalar_rgb, np_rng):
    wi, wo = random_directions(np_rng, 16, lower=False), random_directions(np_rng, 16, lower=False)
    uniform = mi.load_dict({"type": "cooktorrance", "alpha": {"type": "spectrum", "value": 0.3}})
    plain = mi.load_dict({"type": "cooktorrance", "alpha": 0.3})
    np.testing.assert_array_equal(eval_pdf(uniform, wi, wo)[0], eval_pdf(plain, wi, wo)[0])


def _warned(spec) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mi.load_dict(spec)
    return [str(w.message) for w in caught if issubclass(w.category, mi_brdfs.MiBrdfsWarning)]


def test03_energy_warnings(variant_scalar_rgb):
    """Unnormalised Phong forms and Cook-Torrance's added diffuse base warn where they can
    reflect more than they receive (values kept); within bounds they do not."""
    lecture = dict(type="phong", form="lecture", exponent=1.0, diffuse_reflectance=0.5,
                   specular_reflectance=0.5)
    # ρd + ks·2π/(n+2) at n = 1 (mirror lobe, lecture form)
    assert _warned(lecture) == ["phong: form = lecture reflects 1.5472 > 1 of the light at normal "
                                "incidence (ρd + ks·E(0) at n = 1: the form is not normalised); "
                                "values kept"]
    assert "reflects 2.07" in _warned(dict(lecture, form="original"))[0]  # 2π/(n+1)
    assert _warned(dict(lecture, exponent=30.0)) == []
    base = dict(type="cooktorrance", fresnel="none", diffuse_reflectance=0.9)
    assert "diffuse_reflectance + specular_reflectance reaches 1.9 > 1" in _warned(base)[0]
    assert _warned(dict(base, specular_reflectance=0.1)) == []
    assert _warned(dict(base, diffuse_reflectance=0.0)) == []  # no base, no warning


def test04_transmission_eta_as_a_uniform_spectrum(variant_scalar_rgb, np_rng):
    wi, wo = random_directions(np_rng, 16), random_directions(np_rng, 16)
    glass = {"type": "cooktorrance", "transmission": True}
    spectrum = mi.load_dict(dict(glass, eta={"type": "spectrum", "value": 1.5}))
    number = mi.load_dict(dict(glass, eta=1.5))
    np.testing.assert_array_equal(eval_pdf(spectrum, wi, wo)[0], eval_pdf(number, wi, wo)[0])
    with pytest.raises(RuntimeError, match=r'"eta" .* is invalid: must be one number with '
                                           r'transmission = true'):
        mi.load_dict(dict(glass, eta={"type": "spectrum", "value": [(400, 1.5), (700, 1.4)]}))


def test05_material_none_is_a_perfect_conductor(variants_rgb, np_rng):
    """material="none" is roughconductor's η = 0, k = 1 (F ≡ 1): equal to roughconductor's,
    and to fresnel = none."""
    wi, wo = random_directions(np_rng, 256, lower=False), random_directions(np_rng, 256, lower=False)
    ours = mi.load_dict({"type": "cooktorrance", "material": "none", "shadowing": "smith"})
    theirs = mi.load_dict({"type": "roughconductor", "material": "none", "alpha": 0.1})
    unit = mi.load_dict({"type": "cooktorrance", "fresnel": "none", "shadowing": "smith"})
    a = eval_pdf(ours, wi, wo)[0]
    np.testing.assert_allclose(a, eval_pdf(theirs, wi, wo)[0], rtol=1e-5, atol=1e-7)
    np.testing.assert_allclose(a, eval_pdf(unit, wi, wo)[0], rtol=1e-5, atol=1e-7)
    with pytest.raises(RuntimeError, match=r'"material" = "nothing" is invalid: .* or none'):
        mi.load_dict({"type": "cooktorrance", "material": "nothing"})
