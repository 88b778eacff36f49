"""
mi_brdfs.checks.batch, the layer the checks, plots, campaign and benchmark share: values against
closed forms (a Lambertian BSDF), shapes, and directions that are unit vectors.
"""

import math

import numpy as np
import pytest

from mi_brdfs.checks import batch

RHO = 0.6


def test01_random_directions(np_rng):
    for sphere in (True, False):
        d = batch.random_directions(np_rng, 5000, sphere=sphere)
        assert d.shape == (5000, 3)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-12)
        assert (d[:, 2].min() < 0) == sphere
        # uniform: the mean of z over the sphere is 0, over the hemisphere 1/2
        assert d[:, 2].mean() == pytest.approx(0.0 if sphere else 0.5, abs=0.03)


def test02_direction():
    theta = math.radians(30)
    np.testing.assert_allclose(batch.direction(theta), [math.sin(theta), 0, math.cos(theta)])


def test03_evaluate_is_lambert(variants_rgb, np_rng):
    """eval = ρ/π·cosθo, pdf = cosθo/π above the surface, 0 below; eval_pdf agrees."""
    n = 64 if not batch.is_jit() else 4096
    wi = batch.random_directions(np_rng, n, sphere=False)
    wo = batch.random_directions(np_rng, n)
    e = batch.evaluate({"type": "diffuse", "reflectance": RHO}, wi, wo)
    cos = np.where(wo[:, 2] > 0, wo[:, 2], 0.0)
    assert e.value.shape == (n, 3) and e.pdf.shape == (n,)
    np.testing.assert_allclose(e.value, RHO / np.pi * cos[:, None] * np.ones(3), atol=2e-7)
    np.testing.assert_allclose(e.pdf, cos / np.pi, atol=2e-7)
    np.testing.assert_array_equal(e.eval_pdf_value, e.value)
    np.testing.assert_array_equal(e.eval_pdf_pdf, e.pdf)


def test04_sample_is_lambert(variants_rgb, np_rng):
    """Sampled directions lie above the surface with pdf cosθo/π and weight ρ."""
    n = 64 if not batch.is_jit() else 4096
    s = batch.sample({"type": "diffuse", "reflectance": RHO}, batch.direction(0.3),
                     np_rng.random(n), np_rng.random((n, 2)))
    assert s.wo.shape == (n, 3)
    np.testing.assert_allclose(np.linalg.norm(s.wo, axis=1), 1.0, atol=1e-6)
    assert (s.wo[:, 2] >= 0).all()
    np.testing.assert_allclose(s.pdf, s.wo[:, 2] / np.pi, atol=2e-7)
    np.testing.assert_allclose(s.weight, RHO, atol=2e-7)


def test05_a_wrong_value_is_seen(variants_rgb, np_rng):
    """The closed-form comparisons of test03 tell ρ = 0.6 from ρ = 0.61."""
    wi = batch.random_directions(np_rng, 16, sphere=False)
    e = batch.evaluate({"type": "diffuse", "reflectance": 0.61}, wi, wi)
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(e.value, RHO / np.pi * wi[:, 2:3] * np.ones(3), atol=2e-7)


def test09_floats_compile_one_kernel_whatever_the_numpy_address(variant_llvm_ad_rgb):
    """
    batch.floats: the same kernel (by hash) for the same data at four addresses (4-byte steps
    from a 64-byte boundary), so the on-disk kernel cache serves it; drjit's own conversion of
    the arrays at those addresses, mi.Float(a), compiles different kernels (the cause).
    """
    import drjit as dr
    import mitsuba as mi

    from mi_brdfs.timing import traced_kernels

    values = np.linspace(0.1, 0.9, 1000, dtype=np.float32)
    base = np.empty(values.nbytes + 128, dtype=np.uint8)
    start = (-base.ctypes.data) % 64

    def at(offset):
        a = base[start + offset:start + offset + values.nbytes].view(np.float32)
        a[:] = values
        return a

    def irs(convert):
        return {k["hash"] for offset in (0, 4, 8, 12)
                for k in traced_kernels(lambda: dr.sin(convert(at(offset))) * 2.0)[1]
                if "hash" in k}

    assert len(irs(batch.floats)) == 1
    assert len(irs(mi.Float)) > 1
    np.testing.assert_array_equal(np.array(batch.floats(values)), values)
