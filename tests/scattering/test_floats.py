"""
The terms compiled for Python floats (mi_brdfs.scattering.floats) return what the terms return:
same source, rewritten drjit calls, checked function by function on the same floats.
"""

import dis

import mitsuba as mi
import numpy as np
import pytest
from helpers import random_directions

from mi_brdfs.scattering import floats, fresnel, microfacet, orennayar, vector, ward

REWRITTEN = ("select", "maximum", "minimum", "fma", "square", *floats.MATH)
#: Terms that build a direction and compute on with it: the original rounds it to float32 (an
#: mi.Vector3f), the compiled term keeps a floats.Vec3 of float64, so they agree to float32's
#: rounding, which Ward's exp(−tan²θh/α²) amplifies by its exponent (up to ~40 here).
#: (Returned directions are compared after the same rounding: floats.to_mitsuba.)
INTERNAL_VECTOR = {"specular": 1e-4}


def _cases(rng):
    """(function name, argument tuples) for every term, degenerate inputs included."""
    dirs = [mi.Vector3f(*map(float, d)) for d in random_directions(rng, 60)]
    dirs += [mi.Vector3f(0, 0, 1), mi.Vector3f(1, 0, 0), mi.Vector3f(0.6, 0, -0.8)]
    ups = [d for d in dirs if d.z > 0]
    us = [mi.Point2f(*map(float, u)) for u in rng.random((20, 2))] + [mi.Point2f(0, 0)]
    kinds_alphas = [(k, a) for k in microfacet.DISTRIBUTIONS
                    for a in (1e-4, 0.2, 1.5, (0.05, 0.5), (1.5, 1e-4))]
    pairs = list(zip(dirs, dirs[::-1]))
    yield "dot", pairs
    yield "half_vector", [(a, b) for a, b in pairs if (a.z + b.z) != 0 or a.x + b.x != 0]
    yield "reflect", pairs
    for name in ("ndf", "smith_lambda"):
        yield name, [(k, a, v) for k, a in kinds_alphas for v in dirs]
    for name in ("smith_g1", "smith_g1_mitsuba"):
        yield name, [(k, a, v, m) for k, a in kinds_alphas for v, m in zip(dirs, ups * 2)]
    yield "vcavity_g1", list(zip(dirs, ups * 2))
    yield "vcavity_g", [(a, b, m) for (a, b), m in zip(pairs, ups * 3)]
    yield "sample_ndf", [(k, a, u) for k, a in kinds_alphas for u in us]
    yield "sample_vcavity_visible", [(k, a, w, u, 0.3) for k, a in kinds_alphas
                                     for w, u in zip(ups, us)]
    yield "pdf_ndf", [(0.7, m) for m in ups]
    yield "pdf_visible", [(0.7, 0.9, w, m) for w, m in zip(ups, ups[::-1])]
    yield "pdf_visible_reflection", [(0.7, 0.9, w) for w in ups]
    yield "reflection_jacobian", list(zip(dirs, ups * 2))
    yield "refraction_jacobian", [(a, b, m, e) for (a, b), m in zip(pairs, ups * 3)
                                  for e in (1.5, 1 / 1.5)]
    yield "walter_widening", [(c,) for c in (0.0, 0.3, -0.7, 1.0)]
    yield "refract", [(w, m, c, e) for w, m in zip(dirs, ups * 2) for c, e in ((-0.8, 0.66),
                                                                                (0.3, 1.5))]
    yield "generalized_half_vector", [(a, b, e) for a, b in pairs for e in (1.0, 1.5, 0.66)
                                      if a.x + e * b.x != 0 or a.z + e * b.z != 0]
    yield "dielectric", [(c, e) for c in (-1.0, -0.5, -0.05, 0.0, 0.2, 1.0)
                         for e in (1.5, 1 / 1.5, 1.0, 1e3)]
    cos = [0.0, 1e-8, 0.3, 0.999, 1.0, -0.1, 1.1]
    iors = [(1.5, 0.0), (0.2, 3.9), (1.0 + 1e-6, 0.0), (0.0, 1.0), (1e3, 1e3)]
    for name in ("exact", "schlick"):
        yield name, [(c, e, k) for c in cos for e, k in iors]
    yield "r0", iors
    alphas = (1e-4, 0.2, 1.5, (0.05, 0.5))
    yield "specular", [(f, a, w, v) for f in ward.FORMS for a in alphas
                       for w, v in zip(ups, ups[::-1])]
    yield "pdf", [(v, m, 0.7) for v, m in zip(ups, ups[::-1])]
    yield "sample", [(a, u) for a in alphas for u in us]
    yield "coefficients", [(s,) for s in (0.0, 0.3, 1.5)]
    yield "factor", [(f, s, w, v, 0.6) for f in orennayar.FORMS for s in (0.0, 0.4, 1.5)
                     for w, v in zip(ups, ups[::-1])]


def _values(x):
    if isinstance(x, (int, float)):
        return [float(x)]
    return [float(c) for c in x]


def test01_compiled_terms_equal_the_terms(variant_scalar_rgb, np_rng):
    """Every term, compiled for floats, returns the terms' own value on the same floats (to
    float64 rounding: a*b + c where dr.fma rounds once)."""
    modules = {m: floats.specialise(m) for m in (vector, microfacet, fresnel, ward, orennayar)}
    seen = set()
    for name, cases in _cases(np_rng):
        module = next(m for m in modules if hasattr(m, name) and
                      getattr(m, name).__module__ == m.__name__)
        original, compiled = getattr(module, name), getattr(modules[module], name)
        assert compiled is not original
        assert cases
        for args in cases:
            want, got = _values(original(*args)), _values(floats.to_mitsuba(compiled(*args)))
            np.testing.assert_allclose(got, want, rtol=INTERNAL_VECTOR.get(name, 1e-12),
                                       atol=1e-300, err_msg=f"{name}{args}")
        seen.add(name)
    # every function a plugin uses is among them
    assert {"ndf", "smith_g1_mitsuba", "vcavity_g", "exact", "half_vector", "reflect",
            "dielectric", "refract", "generalized_half_vector", "refraction_jacobian",
            "specular", "factor"} <= seen


def _drjit_calls(fn) -> set:
    """The names X of every ``dr.X`` that ``fn``'s bytecode reads."""
    ops = list(dis.get_instructions(fn))
    return {b.argval for a, b in zip(ops, ops[1:])
            if a.opname == "LOAD_GLOBAL" and a.argval == "dr" and b.opname == "LOAD_ATTR"}


def test02_no_drjit_call_left(variant_scalar_rgb):
    """The compiled functions no longer call the rewritten drjit functions, and the terms they
    call from sibling modules (microfacet -> vector.dot) are the compiled ones."""
    for module in (vector, microfacet, fresnel, ward, orennayar):
        compiled = floats.specialise(module)
        for name, fn in vars(compiled).items():
            if callable(fn) and getattr(fn, "__code__", None) and \
                    fn.__code__.co_filename.startswith("<"):
                assert not _drjit_calls(fn) & set(REWRITTEN), (module.__name__, name)
    compiled = floats.specialise(microfacet)
    assert compiled.smith_g1.__globals__["dot"] is floats.specialise(vector).dot


def test03_a_wrong_rewrite_is_caught(variant_scalar_rgb, np_rng, monkeypatch):
    """test01 rejects a rewrite that swaps dr.select's branches."""
    original = floats._Rewrite.visit_Call

    def swapped(self, node):
        out = original(self, node)
        if isinstance(out, floats.ast.IfExp) and not isinstance(out.test, floats.ast.Compare):
            out.body, out.orelse = out.orelse, out.body
        return out

    monkeypatch.setattr(floats._Rewrite, "visit_Call", swapped)
    monkeypatch.setattr(floats, "_cache", {})
    with pytest.raises(AssertionError):
        test01_compiled_terms_equal_the_terms(None, np_rng)


EDGES = [-800.0, -1.0, -1e-300, -0.0, 0.0, 1e-300, 1e-30, 0.5, 2.0, 700.0, 709.5, 709.9, 1e300,
         float("inf"), float("-inf"), float("nan")]


def _math_module(tmp_path, name):
    """A module of one function per drjit function that :data:`floats.MATH` rewrites."""
    import importlib.util
    source = "import drjit as dr\n\n" + "".join(
        f"\ndef f_{fn}(x):\n    return dr.{fn}(x)\n" for fn in floats.MATH)
    path = tmp_path / f"{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _check_math(module):
    compiled = floats.specialise(module)
    for fn in floats.MATH:
        original, rewritten = getattr(module, f"f_{fn}"), getattr(compiled, f"f_{fn}")
        assert not _drjit_calls(rewritten)
        for x in EDGES:
            want, got = original(x), rewritten(x)
            np.testing.assert_allclose(got, want, rtol=1e-15, atol=0, err_msg=f"{fn}({x})")
            if not np.isnan(want):  # (the sign of a NaN means nothing)
                assert np.signbit(got) == np.signbit(want), f"{fn}({x}): {got} vs {want}"


def test04_math_rewrites_return_drjits_values(variant_scalar_rgb, tmp_path):
    """abs, sqrt, rsqrt, rcp, exp and log by ``math`` give drjit's values where ``math`` would
    raise (below 0, at ±0, on overflow) and elsewhere, NaN and infinities included."""
    _check_math(_math_module(tmp_path, "mi_brdfs_floats_math_case"))


def test05_a_wrong_guard_is_caught(variant_scalar_rgb, tmp_path, monkeypatch):
    """test04 rejects a guard that takes sqrt of |x| (no NaN below 0)."""
    monkeypatch.setitem(floats.MATH, "sqrt", "_math.sqrt(abs({x}))")
    with pytest.raises(AssertionError):
        _check_math(_math_module(tmp_path, "mi_brdfs_floats_math_wrong"))


def test06_directions_leave_as_mitsuba_vectors(variant_scalar_rgb):
    """The compiled terms build floats.Vec3; to_mitsuba and to_vec3 convert both ways, and a
    term that hands a direction to Mitsuba (microfacet.sample_visible) converts it."""
    v = floats.Vec3(0.6, 0.0, 0.8)
    assert type(floats.to_mitsuba(v)) is mi.Vector3f and list(floats.to_mitsuba(v)) == \
        pytest.approx([0.6, 0.0, 0.8])
    assert list(floats.to_vec3(mi.Vector3f(0.6, 0.0, 0.8))) == pytest.approx([0.6, 0.0, 0.8])
    compiled = floats.specialise(microfacet)
    m = compiled.sample_visible("beckmann", 0.3, v, mi.Point2f(0.3, 0.7))
    want = microfacet.sample_visible("beckmann", 0.3, mi.Vector3f(0.6, 0.0, 0.8),
                                     mi.Point2f(0.3, 0.7))
    assert list(m) == list(want)
