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


def _one_line(load) -> str:
    """The one line a loader's error becomes (as the CLI and bsdfspec show it)."""
    from mi_brdfs.errors import mitsuba_error_line

    with pytest.raises(RuntimeError) as info:
        load()
    return mitsuba_error_line(info.value)


@pytest.mark.parametrize("plugin", list(mi_brdfs.PLUGINS))
def test06_a_misspelt_parameter_names_the_closest(variants_rgb, plugin):
    """A parameter of ours misspelt (its two last letters swapped), from a dict and from XML,
    in both variants: one line naming the plugin, the parameter and the documented name it is
    closest to, where Mitsuba said 'Found 1 unreferenced property in unknown plugin of type'
    (in the variant registered second) without a suggestion."""
    from helpers import spec as spec_of

    from mi_brdfs.plugins.properties import documented

    # the first documented name long enough to misspell (hapke's first ones are single letters)
    right = next(n for n in documented(mi_brdfs.plugin_class(plugin).__doc__) if len(n) > 2)
    wrong = right[:-2] + right[-1] + right[-2]
    spec = dict(spec_of(plugin), **{wrong: 0.25})
    xml = "".join(f'<string name="{k}" value="{v}"/>' for k, v in spec_of(plugin).items()
                  if k != "type")
    xml = (f'<bsdf version="3.0.0" type="{plugin}">{xml}<float name="{wrong}" value="0.25"/>'
           f'</bsdf>')
    for load in (lambda: mi.load_dict(spec), lambda: mi.load_string(xml)):
        text = _one_line(load)
        head = f'{plugin}: parameter "{wrong}" = 0.25 is invalid: an unreferenced property in ' \
               f'{plugin}, which has no such parameter; did you mean '
        assert head in text, text  # right among the closest (rpv's rho_c ties with rho_0)
        assert right in text.split(head)[1].rstrip("?").replace(",", " or").split(" or "), \
            text
        assert "unknown plugin" not in text, text


def test07_an_unknown_parameter_lists_the_plugins_parameters(variant_llvm_ad_rgb, tmp_path,
                                                             monkeypatch):
    """No close name: the line lists the plugin's parameters; the command line says the same
    (it said 'unknown plugin of type "cooktorrance"')."""
    from helpers import cli_one_line_error

    text = _one_line(lambda: mi.load_dict({"type": "ward", "zzz": 1.0, "qqq": 2.0}))
    assert text.endswith('ward: parameter "zzz" = 1 is invalid: an unreferenced property in '
                         'ward, which has no such parameter; its parameters: alpha, alpha_u, '
                         'alpha_v, specular_reflectance, diffuse_reflectance, form, preset '
                         '(also unreferenced: qqq)'), text
    monkeypatch.chdir(tmp_path)
    cli_one_line_error(["check", "cooktorrance", "alpah=0.2", "--quick"],
                       'cooktorrance: parameter "alpah" = 0.2 is invalid: an unreferenced '
                       'property in cooktorrance, which has no such parameter; did you mean '
                       'alpha, alpha_v or alpha_u?')
    text = _one_line(lambda: mi.load_dict({"type": "lafortune", "exponnet_1": 3.0}))
    assert "lafortune, which has no such parameter; did you mean exponent_1 or exponent_0?" \
        in text, text


def test08_a_documented_parameter_left_unread_is_not_called_unknown(variant_scalar_rgb):
    """check_all_read on its own: a property the docstring's table documents but the plugin
    left unread is unused with the others given, not "no such parameter; did you mean" itself;
    every property read, nothing is said."""
    from mi_brdfs.errors import ParameterError
    from mi_brdfs.plugins.properties import check_all_read

    doc = "Doc.\n\n    .. pluginparameters::\n\n     * - alpha, beta\n       - |float|\n"
    props = mi.Properties("demo")
    props["beta"] = 0.5
    with pytest.raises(ParameterError, match=r'^demo: parameter "beta" = 0.5 is invalid: an '
                                             r'unreferenced property in demo, which does not '
                                             r'use it with the other parameters given$'):
        check_all_read(props, "demo", doc)
    props = mi.Properties("demo")
    props["alpha"] = 0.5
    assert props["alpha"] == 0.5  # read
    check_all_read(props, "demo", doc)
