"""
The shape every plugin has (docs/architecture.md, "How to add a plugin"): a ``lobes.Mixture`` of
declared ``lobes.Lobe`` objects, with the mixture's methods; and the mixture itself, which picks
a lobe in proportion to its weight and reports the mixture density.
"""

import inspect

import mitsuba as mi
import numpy as np
import pytest
from helpers import spec as spec_of

from mi_brdfs import registry
from mi_brdfs.checks import batch
from mi_brdfs.plugins import lobes

#: Each plugin with its defaults, and the switches that add lobes
SPECS = [spec_of(name) for name in registry.PLUGINS] + [
    {"type": "cooktorrance", "diffuse_reflectance": 0.3, "multiscatter": True},
    {"type": "cooktorrance", "transmission": True, "multiscatter": True},
    {"type": "lafortune", "exponent_0": 10.0, "cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0},
]
METHODS = ("sample", "eval", "pdf", "eval_pdf", "eval_diffuse_reflectance")


@pytest.mark.parametrize("spec", SPECS, ids=lambda s: "-".join(str(v) for v in s.values()))
def test01_every_plugin_is_a_mixture_of_declared_lobes(variants_rgb, spec):
    """Its methods are the mixture's, each lobe implements what Lobe declares, and the
    components are the lobes' (no plugin re-implements the mixture or calls a hook that the
    interface does not declare)."""
    bsdf = mi.load_dict(spec)
    assert isinstance(bsdf.lobes, lobes.Mixture)
    for name in METHODS:
        assert getattr(type(bsdf), name) is getattr(lobes, name), name
    for lobe in bsdf.lobes.lobes:
        assert isinstance(lobe, lobes.Lobe)
        for name in ("eval_pdf", "sample", "weight"):
            assert getattr(type(lobe), name) is not getattr(lobes.Lobe, name), (lobe, name)
    components, flags = lobes.components(bsdf.lobes.lobes)
    assert list(bsdf.m_components) == components and bsdf.flags() == flags


class Uniform(lobes.Mixture):
    """A broken mixture: every lobe is picked alike, whatever its weight."""

    def probabilities(self, ctx, si, lobes_, active):
        return [1.0 / len(lobes_)] * len(lobes_)


@pytest.mark.parametrize("mixture", [lobes.Mixture, Uniform])
def test02_the_mixture_picks_lobes_by_weight(variant_llvm_ad_rgb, mixture):
    """Two Lambertian lobes ρ = 0.3 (component 0) and 0.1 (component 1): the first is sampled
    3 times in 4, bs.pdf is the mixture density cosθo/π, the weight (ρ0 + ρ1)·cos/π over it
    is 0.4; a mixture that ignores the weights is rejected."""
    bsdf = mixture([lobes.Diffuse(_uniform(0.3), 0),
                    lobes.Diffuse(_uniform(0.1), 1)])
    n = 40_000
    si = batch.interaction([0.3, 0.0, 0.954], n)
    u1 = mi.Float((np.arange(n) + 0.5) / n)
    u2 = mi.Point2f(np.random.default_rng(0).random((2, n)).astype(np.float32))
    bs, weight = bsdf.sample(mi.BSDFContext(), si, u1, u2)
    share = np.mean(np.array(bs.sampled_component) == 0)
    ok = abs(share - 0.75) < 1e-3
    assert ok == (mixture is lobes.Mixture), share
    np.testing.assert_allclose(np.array(bs.pdf), np.array(bs.wo.z) / np.pi, rtol=1e-5)
    np.testing.assert_allclose(np.array(weight), 0.4, rtol=1e-5)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, bs.wo)
    np.testing.assert_allclose(np.array(value)[0], 0.4 * np.array(bs.wo.z) / np.pi, rtol=1e-5)
    np.testing.assert_allclose(np.array(pdf), np.array(bs.pdf), rtol=1e-6)


def _uniform(value):
    return mi.load_dict({"type": "uniform", "value": value})


def test03_lobe_declares_every_method_it_calls():
    """Lobe's methods are documented, and the ones a subclass must give raise until it does."""
    for name, member in inspect.getmembers(lobes.Lobe, inspect.isfunction):
        assert member.__doc__, name
    for name in ("eval_pdf", "sample", "weight"):
        with pytest.raises(NotImplementedError):
            getattr(lobes.Lobe(), name)(*([None] * (len(inspect.signature(
                getattr(lobes.Lobe, name)).parameters) - 1)))
