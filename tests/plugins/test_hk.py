"""
The ``hk`` plugin (Hanrahan & Krueger 1993's layer): eval against the float64 reference at
random pairs over the sphere (index-matched, under an interface, from below, over a base, per
channel) in scalar_rgb; its components (scattered, the unscattered beam as a null
interaction, the mirror where η ≠ 1) and their sample weights against the closed forms;
one-line errors (``scattering = all``: tests/plugins/test_hk_all.py). The battery (χ²,
reciprocity, energy) runs in ``mi-brdfs check hk``; the slow tier runs it on a forward-scattering layer under glass.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from earth_helpers import assert_load_error
from helpers import assert_matches_reference, eval_pdf, random_directions, sample

from mi_brdfs.reference import hk as ref
from mi_brdfs.testing import assert_sampling_matches_pdf

SETS = [
    {"sigma_s": 0.8, "sigma_a": 0.2, "thickness": 1.0, "g": 0.5},
    {"sigma_s": [1.5, 0.3, 4.0], "sigma_a": 0.5, "thickness": 0.7, "g": -0.3, "eta": 1.5},
    {"sigma_s": 0.6, "sigma_a": 0.2, "thickness": 2.0, "g": 0.8, "eta": 1.33,
     "diffuse_reflectance": [0.7, 0.2, 0.5]},
]


def _spec(params):
    return {"type": "hk", **{k: ({"type": "rgb", "value": v} if isinstance(v, list) else v)
                             for k, v in params.items()}}


def test01_eval_equals_the_reference(variant_scalar_rgb):
    """f·|cosθo| at 300 random pairs per set (ωi over the whole sphere without a base, the
    upper hemisphere over one) within float32 rounding of the float64 model."""
    rng = np.random.default_rng(5)
    for params in SETS:
        base = "diffuse_reflectance" in params
        wi = random_directions(rng, 300, lower=not base)
        wo = random_directions(rng, 300)
        value, pdf, _, _ = eval_pdf(mi.load_dict(_spec(params)), wi, wo)
        model = ref.HK(**params)

        def f(a, b):
            out = model.brdf(a, b) * np.abs(b[:, 2:3])
            return out if not base else np.where((a[:, 2:3] > 0), out, 0.0)

        assert_matches_reference(value, f, wi, wo, 2e-5, str(params))
        assert np.all(pdf[value.max(axis=1) > 0] > 0)


def test02_components_and_delta_weights(variant_scalar_rgb):
    """Under glass without a base: 3 components (glossy reflection and transmission, null,
    delta reflection); the null sample's weight over its probability is T² e^{−τ/μ'}, the
    mirror's F(μ), both as the reference computes them."""
    params = SETS[1]
    bsdf, model = mi.load_dict(_spec(params)), ref.HK(**params)
    assert bsdf.component_count() == 3
    F = mi.BSDFFlags
    assert bsdf.flags(1) == int(F.Null | F.FrontSide | F.BackSide)
    assert bsdf.flags(2) & int(F.DeltaReflection)
    wi = np.array([0.6, 0.0, 0.8])
    s = sample(bsdf, np.tile(wi, (2000, 1)), np.linspace(0, 1, 2000, endpoint=False),
               np.full((2000, 2), 0.3))
    null, mirror = s["component"] == 1, s["component"] == 2
    assert null.any() and mirror.any()
    np.testing.assert_allclose(s["weight"][null][0] * s["pdf"][null][0],
                               model.unscattered(0.8)[0], rtol=2e-5)
    np.testing.assert_allclose(s["weight"][mirror][0] * s["pdf"][mirror][0],
                               model.specular(0.8)[0], rtol=2e-5)
    np.testing.assert_allclose(s["wo"][null][0], -wi, atol=1e-6)


@pytest.mark.parametrize("spec,message", [
    ({"scattering": "double"}, 'parameter "scattering" = "double" is invalid: must be one of'),
    ({"g": 1.0}, 'hk: parameter "g" = 1 is invalid'),
    ({"eta": 0.8}, 'hk: parameter "eta" = 0.8 is invalid'),
    ({"thickness": 0.0}, 'hk: parameter "thickness" = 0 is invalid'),
    ({"sigma_s": -1.0}, 'hk: parameter "sigma_s" = -1 is invalid'),
])
def test03_one_line_errors(variant_scalar_rgb, spec, message):
    assert_load_error({"type": "hk", **spec}, message)


def test04_sampler_matches_its_pdf_under_glass(variant_llvm_ad_rgb):
    """χ² of the sampler (the HG lobe about −ωi and the two cosines) against its pdf for a
    strongly forward-scattering layer under glass, at grazing and normal incidence."""
    spec = {"type": "hk", "g": 0.9, "eta": 1.5, "sigma_s": 3.0, "thickness": 0.5}
    for wi in ([0.0, 0.0, 1.0], [0.985, 0.0, 0.174]):
        assert_sampling_matches_pdf(spec, wi=wi)
