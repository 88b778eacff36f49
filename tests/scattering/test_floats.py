"""
The terms compiled for Python floats (mi_brdfs.scattering.floats) return what the terms return:
same source, rewritten drjit calls, checked function by function on the same floats.
"""

import ast
import contextlib
import dis
import importlib.util
import inspect
import sys
import textwrap

import mitsuba as mi
import numpy as np
import pytest
from helpers import random_directions

from mi_brdfs import registry
from mi_brdfs.scattering import floats, fresnel, microfacet, orennayar, vector, ward


@pytest.fixture(autouse=True)
def _configure_at_once(monkeypatch):
    """Instances get their configured methods when made (not after PROMOTE_AFTER calls), so
    that the tests here check the compiled code."""
    monkeypatch.setattr(floats, "PROMOTE_AFTER", 0)

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


def _module(tmp_path, name, source):
    """A module ``name`` of ``source``, written to ``tmp_path`` and imported (not into
    ``sys.modules``; :func:`floats.specialise` caches it by ``name``: one name per source)."""
    path = tmp_path / f"{name}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _math_module(tmp_path, name):
    """A module of one function per drjit function that :data:`floats.MATH` rewrites."""
    source = "import drjit as dr\n\n" + "".join(
        f"\ndef f_{fn}(x):\n    return dr.{fn}(x)\n" for fn in floats.MATH)
    return _module(tmp_path, name, source)


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


# -------------------------------------------------------------------------------------------------
# Plugin classes compiled for floats (floats.specialise_class): cooktorrance
# -------------------------------------------------------------------------------------------------

CHECKER = {"type": "checkerboard", "color0": 0.1, "color1": 0.4}
#: cooktorrance configurations: both distributions and shadowing terms, visible-normal and D·cos
#: sampling, the three Fresnel terms, isotropic, anisotropic and textured α, textured ks, the
#: diffuse base (grey and per channel), and transmission (int_ior, eta; textured α and kt).
CT_CONFIGS = [
    {"alpha": 0.3},
    {"alpha": 0.2, "sample_visible": False, "fresnel": "schlick", "eta": [0.2, 0.9, 1.4],
     "k": [3.0, 2.5, 2.0]},
    {"distribution": "ggx", "shadowing": "smith", "alpha_u": 0.1, "alpha_v": 0.5,
     "fresnel": "none"},
    {"distribution": "ggx", "alpha_u": 0.6, "alpha_v": 0.05, "material": "Au",
     "diffuse_reflectance": 0.4},
    {"shadowing": "smith", "alpha": 0.15, "sample_visible": False, "fresnel": "schlick",
     "diffuse_reflectance": [0.2, 0.5, 0.3]},
    {"distribution": "ggx", "alpha": 0.4, "sample_visible": False, "fresnel": "none",
     "diffuse_reflectance": 0.3},
    {"shadowing": "smith", "alpha": 0.05, "material": "Al"},
    {"alpha": CHECKER, "shadowing": "smith", "specular_reflectance": CHECKER, "eta": 1.4},
    {"transmission": True, "alpha": 0.2, "int_ior": 1.5},
    {"transmission": True, "distribution": "ggx", "alpha_u": 0.3, "alpha_v": 0.08,
     "sample_visible": False, "int_ior": "water"},
    {"transmission": True, "alpha": CHECKER, "sample_visible": False, "int_ior": 1.33,
     "ext_ior": 1.5, "specular_transmittance": CHECKER},
    {"transmission": True, "distribution": "ggx", "alpha": 0.5, "eta": 1.2},
]


def _properties(config) -> mi.Properties:
    """The mi.Properties of a cooktorrance configuration (a dict is loaded as a texture, a list
    is an RGB colour), for the plugin class's constructor."""
    props = mi.Properties("cooktorrance")
    for key, value in config.items():
        if isinstance(value, dict):
            value = mi.load_dict(value)
        elif isinstance(value, list):
            value = mi.ScalarColor3f(*value)
        props[key] = value
    return props


@contextlib.contextmanager
def _generic(cls):
    """``cls`` with the methods it had before floats.specialise_class (``__generic_methods__``),
    and no instance given methods of its own (floats.configure off), while the block runs; the
    compiled ones are put back however it ends."""
    compiled = {name: vars(cls)[name] for name in cls.__generic_methods__}
    configure = floats.configure
    try:
        floats.configure = lambda *args, **kwargs: None
        for name, method in cls.__generic_methods__.items():
            setattr(cls, name, method)
        yield cls
    finally:
        floats.configure = configure
        for name, method in compiled.items():
            setattr(cls, name, method)


def _ct_cases(rng, n=100):
    """(si, wo, sample1, sample2): random directions on the whole sphere (ωi and ωo below the
    surface too), samples and uv, and degenerate pairs (normal incidence, mirror pairs above and
    below, ωo = −ωi, grazing and cosθi = 0, straight through) at samples 0 and near 1."""
    from mi_brdfs.checks.batch import interaction
    pairs = list(zip(random_directions(rng, n), random_directions(rng, n)))
    samples = [tuple(u) for u in rng.random((n, 5))]
    edges = [((0, 0, 1), (0, 0, 1)), ((0.6, 0, 0.8), (-0.6, 0, 0.8)),
             ((0.6, 0, 0.8), (-0.6, 0, -0.8)), ((1, 0, 0), (0, 0, 1)),
             ((0, 0.6, -0.8), (0, -0.6, -0.8)), ((0.6, 0, 0.8), (-0.4, 0, -0.84 ** 0.5)),
             ((0, 0, -1), (0, 0, 1)), ((0.28, 0.96, 0), (0.6, 0, 0.8))]
    for u in ((0.0, 0.0, 0.0, 0.0, 0.0), (0.5, 0.999999, 0.25, 0.5, 0.5),
              (0.999999, 0.3, 0.999999, 0.9, 0.1)):
        pairs += edges
        samples += [u] * len(edges)
    return [(interaction(wi, uv=u[3:]), mi.Vector3f(*map(float, wo)), float(u[0]),
             mi.Point2f(float(u[1]), float(u[2]))) for (wi, wo), u in zip(pairs, samples)]


def _contexts(config) -> list:
    """Radiance transport with every lobe, with ctx.component 0 and 1, and importance transport
    (with transmission, where it changes the refraction's weight)."""
    contexts = [mi.BSDFContext()]
    for component in (0, 1):
        ctx = mi.BSDFContext()
        ctx.component = component
        contexts.append(ctx)
    if config.get("transmission"):
        contexts.append(mi.BSDFContext(mi.TransportMode.Importance))
    return contexts


#: The columns of :func:`_observe`'s rows.
COLUMNS = ("value.r", "value.g", "value.b", "pdf", "bs.wo.x", "bs.wo.y", "bs.wo.z", "bs.pdf",
           "bs.eta", "bs.sampled_component", "bs.sampled_type", "weight.r", "weight.g",
           "weight.b")


def _observe(bsdf, contexts, cases):
    """What ``bsdf``'s methods return, per (context, case): rows of eval_pdf (value, pdf) and
    sample (bs.wo, bs.pdf, bs.eta, bs.sampled_component, bs.sampled_type, weight) as float64,
    the types of value, pdf and weight; eval_diffuse_reflectance per case; to_string."""
    rows, types = [], []
    for ctx in contexts:
        for si, wo, sample1, sample2 in cases:
            value, pdf = bsdf.eval_pdf(ctx, si, wo)
            bs, weight = bsdf.sample(ctx, si, sample1, sample2)
            # (spectra of any length; Mueller matrices in polarized variants: every entry)
            value, weight = np.ravel(np.array(value)), np.ravel(np.array(weight))
            rows.append([*value, pdf, *bs.wo, bs.pdf, bs.eta, bs.sampled_component,
                         bs.sampled_type, *weight])
            types.append((type(value), type(pdf), type(weight)))
    diffuse = [list(bsdf.eval_diffuse_reflectance(si)) for si, *_ in cases]
    return np.array(rows, dtype=np.float64), types, np.array(diffuse), bsdf.to_string()


def _check_class_equals_generic(cls, rng, configs=CT_CONFIGS):
    """cooktorrance class ``cls``, compiled, returns bit for bit what its generic methods
    return, for each configuration (an instance built in each state)."""
    cases = _ct_cases(rng)
    for config in configs:
        contexts = _contexts(config)
        got = _observe(cls(_properties(config)), contexts, cases)
        with _generic(cls):
            want = _observe(cls(_properties(config)), contexts, cases)
        rows, want_rows = got[0], want[0]
        # equal, NaN where NaN, and the same sign of every zero
        same = ((rows == want_rows) & (np.signbit(rows) == np.signbit(want_rows))) | \
            (np.isnan(rows) & np.isnan(want_rows))
        if not same.all():
            i = int(np.argwhere(~same.all(axis=1))[0, 0])
            ctx, (si, wo, sample1, sample2) = contexts[i // len(cases)], cases[i % len(cases)]
            differ = [c for c, ok in zip(COLUMNS, same[i]) if not ok]
            raise AssertionError(
                f"{config}, {ctx}, wi={list(si.wi)}, wo={list(wo)}, sample1={sample1}, "
                f"sample2={list(sample2)}: {differ} differ; compiled {rows[i].tolist()}, "
                f"generic {want_rows[i].tolist()} ({(~same.all(axis=1)).sum()} rows differ)")
        assert got[1] == want[1], config
        np.testing.assert_array_equal(got[2], want[2], err_msg=str(config))
        assert got[3] == want[3], config


def test07_compiled_class_equals_the_generic_class(variant_scalar_rgb, np_rng):
    """cooktorrance's methods compiled by floats.specialise_class return what its generic methods
    (``__generic_methods__``) return, bit for bit: eval_pdf, sample (bs.wo, bs.pdf, bs.eta, the
    sampled component and type, the weight), eval_diffuse_reflectance and to_string, for every
    configuration of CT_CONFIGS, at random and degenerate directions on the whole sphere and
    random samples, in radiance and importance transport and with ctx.component 0 and 1.

    No tolerance: both run the same compiled terms (``V.terms`` in a scalar variant), and the
    class's own rewrites are exact in float64 (select, maximum, square, abs, sqrt, rcp,
    V.select/choose, and the bodies of terms taken in: the same operations in the same order).
    Only a ``dr.fma`` in a method, which the rewrite makes ``a*b + c`` (two roundings), could
    change a last bit; the methods have none (3000 random pairs × the 12 configurations, every
    context: 0 bits differ). Should one be added, compare with rtol = 2⁻²³ (float32's last
    bit)."""
    cls = floats.compiled_class(registry.plugin_class("cooktorrance"))
    compiled_file = f"<{cls.__module__}.{cls.__name__} for floats>"
    assert {"eval_pdf", "sample", "parameters_changed"} <= set(cls.__generic_methods__)
    assert cls.sample.__code__.co_filename == compiled_file
    with _generic(cls):
        assert cls.sample.__code__.co_filename == inspect.getsourcefile(cls.__generic_methods__[
            "sample"])
    assert cls.sample.__code__.co_filename == compiled_file  # (restored)
    with pytest.raises(ZeroDivisionError), _generic(cls):
        1 / 0
    assert cls.sample.__code__.co_filename == compiled_file  # (restored after an error too)
    _check_class_equals_generic(cls, np_rng)


@pytest.mark.parametrize("variant", ["scalar_spectral", "scalar_spectral_polarized"])
def test07b_compiled_class_equals_the_generic_class_in_other_variants(np_rng, variant):
    """As test07, in the spectral and the polarized scalar variant (spectra evaluated at each
    call's wavelengths, no per-channel constants; Mueller matrices), for five
    configurations."""
    from conftest import set_variant
    set_variant(variant)
    try:
        cls = floats.compiled_class(registry.plugin_class("cooktorrance"))
        _check_class_equals_generic(cls, np_rng, configs=[*CT_CONFIGS[:4], CT_CONFIGS[8]])
    finally:
        set_variant("scalar_rgb")


def _fresh_plugin_class(monkeypatch, module="mi_brdfs.plugins.cooktorrance",
                        name="CookTorrance"):
    """The plugin module executed afresh, as registry._load_for_variant does, so that its class
    is compiled by floats as it is now (monkeypatched); not registered, and in sys.modules only
    for the test."""
    spec = importlib.util.find_spec(module)
    fresh = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, module, fresh)
    spec.loader.exec_module(fresh)
    return floats.compiled_class(getattr(fresh, name))


def test08_a_wrong_class_rewrite_is_caught(variant_scalar_rgb, np_rng, monkeypatch):
    """test07 rejects a cooktorrance class compiled afresh with V.select's branches swapped:
    its values differ."""
    original = floats._Rewrite._tools_call

    def swapped(self, node):
        out = original(self, node)
        if out is not None and node.func.attr == "select":
            out.body, out.orelse = out.orelse, out.body
        return out

    monkeypatch.setattr(floats._Rewrite, "_tools_call", swapped)
    with pytest.raises(AssertionError, match="differ"):
        _check_class_equals_generic(_fresh_plugin_class(monkeypatch), np_rng)


#: Calls that compiled cooktorrance makes no more: terms inlined or taken in, variant tools
#: rewritten.
NOT_CALLED = {"mf.ndf", "mf.smith_g1_mitsuba", "vec.half_vector", "V.select", "V.choose"}


def _calls(source: str) -> set:
    """The callees ``f`` and ``ns.f`` of every call in ``source``."""
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call):
            func = node.func
            if isinstance(func, ast.Name):
                names.add(func.id)
            elif isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
                names.add(f"{func.value.id}.{func.attr}")
    return names


def _functions(source: str) -> dict:
    """The source of each top-level function of ``source``, by name."""
    return {node.name: ast.unparse(node) for node in ast.parse(source).body
            if isinstance(node, ast.FunctionDef)}


def _check_vector_inlined(compiled):
    """vector.reflect and vector.refract, compiled, compute ωi·m in place: no call of dot."""
    functions = _functions(floats.compiled_source(compiled))
    for name in ("reflect", "refract"):
        assert "dot" in _calls(inspect.getsource(getattr(vector, name)))  # (in the original)
        assert "dot" not in _calls(functions[name]), functions[name]
        assert "dot" not in getattr(compiled, name).__code__.co_names  # (the code that runs)
        assert all(f"wi.{c} * m.{c}" in functions[name] for c in "xyz"), functions[name]


def _check_class_inlined(cls):
    """The compiled cooktorrance calls none of :data:`NOT_CALLED`, which its source calls."""
    assert NOT_CALLED <= _calls(inspect.getsource(sys.modules[cls.__module__]))
    left = NOT_CALLED & _calls(floats.compiled_source(cls))
    assert not left, sorted(left)


def test09_terms_are_inlined(variant_scalar_rgb):
    """The compiled terms inline what they call (vector.reflect: the dot product), and the
    compiled cooktorrance calls neither the terms mf.ndf, mf.smith_g1_mitsuba, vec.half_vector
    (their expressions or bodies are in place) nor V.select, V.choose (conditionals)."""
    _check_vector_inlined(floats.specialise(vector))
    _check_class_inlined(floats.compiled_class(registry.plugin_class("cooktorrance")))


@pytest.mark.parametrize("rewrite", ["_inlined", "_body_of", "_tools_call"])
def test10_a_missing_rewrite_is_caught(variant_scalar_rgb, monkeypatch, rewrite):
    """test09 rejects code compiled with one rewrite off: vector without inlined terms, a
    cooktorrance without the terms' bodies or with the calls of V left."""
    monkeypatch.setattr(floats._Rewrite, rewrite, lambda self, node: None)
    monkeypatch.setattr(floats, "_cache", {})
    with pytest.raises(AssertionError):
        if rewrite == "_inlined":
            _check_vector_inlined(floats.specialise(vector))
        else:
            _check_class_inlined(_fresh_plugin_class(monkeypatch))


ONCE_SOURCE = '''
def twice(x):
    return x + x


def minus(a, b):
    return a - b


def doubled(x):
    y = x + x
    return y


def difference(a, b):
    d = a - b
    return d


def tick(calls):
    calls.append(len(calls))
    return float(len(calls))


def inlined(calls):
    return twice(tick(calls))


def inlined_in_order(calls):
    return minus(tick(calls), tick(calls))


def taken_in(calls):
    r = doubled(tick(calls))
    return r


def taken_in_in_order(calls):
    r = difference(tick(calls), tick(calls))
    return r


def simple(calls, v):
    return twice(v) + minus(v, -1.0)
'''


def _check_once(module):
    """Each function of ONCE_SOURCE, compiled, returns what it returns and calls ``tick`` as
    often and in the same order; the calls with simple arguments are inlined."""
    compiled = floats.specialise(module)
    for name in ("inlined", "inlined_in_order", "taken_in", "taken_in_in_order"):
        calls, compiled_calls = [], []
        want, got = getattr(module, name)(calls), getattr(compiled, name)(compiled_calls)
        assert (got, compiled_calls) == (want, calls), name
    assert compiled.simple([], 2.0) == module.simple([], 2.0)
    assert not _calls(_functions(floats.compiled_source(compiled))["simple"])


def test11_an_argument_that_is_not_simple_is_evaluated_once(variant_scalar_rgb, tmp_path):
    """A term called with an argument that is not simple (a call with a side effect) is not
    inlined, and a body taken in binds it once: it is evaluated once, in order."""
    _check_once(_module(tmp_path, "mi_brdfs_floats_once_case", ONCE_SOURCE))


def test12_an_argument_evaluated_twice_is_caught(variant_scalar_rgb, tmp_path, monkeypatch):
    """test11 rejects a compiler that takes every argument for simple."""
    monkeypatch.setattr(floats, "_simple", lambda node: True)
    monkeypatch.setattr(floats, "_cache", {})
    with pytest.raises(AssertionError):
        _check_once(_module(tmp_path, "mi_brdfs_floats_once_wrong", ONCE_SOURCE))


CONSTANT_SOURCE = '''
import contextlib

SCALE = 2.0


def reads(x):
    return SCALE * x


def nested_reads(x):
    def inner():
        return SCALE * x
    return inner()


def assigns(x):
    SCALE = 3.0
    return SCALE * x


def parameter(x, SCALE=5.0):
    return SCALE * x


def keyword(x, *, SCALE=5.0):
    return SCALE * x


def loop(x):
    total = 0.0
    for SCALE in (1.0, 4.0):
        total += SCALE * x
    return total


def walrus(x):
    return (SCALE := 7.0) * x


def comprehension(x):
    return sum([SCALE * x for SCALE in (1.0, 3.0)])


def closure(x):
    SCALE = 3.0

    def inner():
        return SCALE * x
    return inner()


def nested_keyword(x):
    def inner(*, SCALE=9.0):
        return SCALE * x
    return inner()


def with_as(x):
    with contextlib.nullcontext(6.0) as SCALE:
        return SCALE * x


def lambda_keyword(x):
    f = lambda *, SCALE=9.0: SCALE * x
    return f()


def lambda_varargs(x):
    f = lambda *SCALE: len(SCALE) * x
    return f(1.0, 2.0, 3.0)


def except_as(x):
    try:
        raise ValueError(4.0)
    except ValueError as SCALE:
        return SCALE.args[0] * x


def import_as(x):
    import math as SCALE
    return SCALE.pi * x
'''
#: The functions of CONSTANT_SOURCE that read the module's SCALE, and those that bind it.
READ_SCALE = ("reads", "nested_reads")
BIND_SCALE = ("assigns", "parameter", "keyword", "loop", "walrus", "comprehension", "closure",
              "nested_keyword", "with_as")


def _check_constants(module, names=READ_SCALE + BIND_SCALE):
    """The functions ``names`` of CONSTANT_SOURCE, compiled, return what they return; where
    they read the module's SCALE, its value is in place."""
    compiled = floats.specialise(module)
    for name in names:
        want = getattr(module, name)(1.5)
        try:
            got = getattr(compiled, name)(1.5)
        except Exception as e:  # (a constant where the function binds the name)
            raise AssertionError(f"{name}: {e!r}, not {want}") from e
        assert got == want, (name, got, want)
    for name in READ_SCALE:
        assert "2.0 * x" in _functions(floats.compiled_source(compiled))[name], name


def test13_constants_are_not_put_in_where_the_function_binds_the_name(variant_scalar_rgb,
                                                                      tmp_path):
    """An upper-case module constant is put in by value where a function reads the module's
    name, and not where the function (or a function nested in it) binds that name: assigns it,
    takes it as a parameter, a loop, walrus, comprehension or with target."""
    _check_constants(_module(tmp_path, "mi_brdfs_floats_constant_case", CONSTANT_SOURCE))


@pytest.mark.parametrize("name", ["lambda_keyword", "lambda_varargs", "except_as", "import_as"])
def test14_constants_where_other_forms_bind_the_name(variant_scalar_rgb, tmp_path, name):
    """As test13, for the other forms that bind a name in a function."""
    _check_constants(_module(tmp_path, "mi_brdfs_floats_constant_case", CONSTANT_SOURCE),
                     (name,))


def test15_a_constant_put_in_everywhere_is_caught(variant_scalar_rgb, tmp_path, monkeypatch):
    """test13 rejects a compiler that puts constants in whatever the function binds."""
    monkeypatch.setattr(floats, "_bound_names", lambda fn: set())
    monkeypatch.setattr(floats, "_cache", {})
    with pytest.raises(AssertionError):
        _check_constants(_module(tmp_path, "mi_brdfs_floats_constant_wrong", CONSTANT_SOURCE))


def test16_a_body_taken_in_reads_its_own_globals(variant_scalar_rgb, tmp_path):
    """A body taken in from the caller's own module reads that module's globals, also where
    the caller binds a local of the same name."""
    module = _module(tmp_path, "mi_brdfs_floats_capture_case", textwrap.dedent('''
        offset = 1.0


        def shifted(x):
            y = x + offset
            return y


        def caller(x):
            offset = 100.0
            r = shifted(x)
            return r + offset
        '''))
    assert floats.specialise(module).caller(1.5) == module.caller(1.5)


def test17_an_argument_is_read_before_the_body_runs(variant_scalar_rgb, tmp_path):
    """A body taken in sees its arguments as they were at the call, also an attribute that the
    body's statements assign."""
    module = _module(tmp_path, "mi_brdfs_floats_attribute_case", textwrap.dedent('''
        class Box:
            def __init__(self, v):
                self.v = v


        def bump(box, old):
            box.v = box.v + 1.0
            return old * 1.0


        def caller(box):
            r = bump(box, box.v)
            return r
        '''))
    assert floats.specialise(module).caller(module.Box(1.0)) == module.caller(module.Box(1.0))


def test18_a_rewrite_in_a_comprehension_iterable(variant_scalar_rgb, tmp_path):
    """dr.maximum of an attribute in a comprehension's iterable compiles and returns the
    original's value."""
    module = _module(tmp_path, "mi_brdfs_floats_iterable_case", textwrap.dedent('''
        import drjit as dr


        def largest(v, w):
            return [y for y in (dr.maximum(v.real, w), 0.0)]
        '''))
    assert floats.specialise(module).largest(1.5, 2.0) == module.largest(1.5, 2.0)


def test19_directions_kept_as_floats(variant_scalar_rgb):
    """The compiled eval_pdf of cooktorrance keeps ωo, and the half vector it builds, as three
    local floats (floats._unbox): it makes no Vec3 of them and reads no component of an object
    for them; where a direction is also handed on whole (ωi), its components are read once
    into locals (floats._scalarise)."""
    cls = floats.compiled_class(registry.plugin_class("cooktorrance"))
    tree = ast.parse(_functions(floats.compiled_source(cls))["eval_pdf"])
    components, objects = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            for target in node.targets:
                for t in (target.elts if isinstance(target, ast.Tuple) else [target]):
                    if isinstance(t, ast.Name) and t.id.endswith("__x"):
                        components.add(t.id[:-3])
                    elif isinstance(t, ast.Name):
                        objects.add(t.id)
    reads = [f"{n.value.id}.{n.attr}" for n in ast.walk(tree) if isinstance(n, ast.Attribute)
             and isinstance(n.value, ast.Name) and n.attr in ("x", "y", "z")]
    unboxed, scalarised = components - objects, components & objects
    # the microfacet branch's ωo and m: three names each, no object made, none read
    assert any(n.endswith("_wo") for n in unboxed) and any(n.endswith("_m") for n in unboxed)
    assert not [r for r in reads if r.split(".")[0] in unboxed], reads
    # a direction also handed on whole is read once per component
    assert scalarised and all(reads.count(f"{n}.{c}") <= 1 for n in scalarised for c in "xyz")


@pytest.mark.parametrize("step", ["_unbox", "_scalarise"])
def test20_a_wrong_unboxing_is_caught(variant_scalar_rgb, np_rng, monkeypatch, step):
    """test07 rejects a cooktorrance compiled with the components of an unboxed or scalarised
    direction swapped (x read as y): its values differ."""
    original = getattr(floats, step)

    def swapped(fn, *args):
        out = original(fn, *args)
        for node in ast.walk(out):  # the reads only: the assignments stay as they were
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load):
                if node.id.endswith("__x"):
                    node.id = node.id[:-3] + "__y"
                elif node.id.endswith("__y"):
                    node.id = node.id[:-3] + "__x"
        return out

    monkeypatch.setattr(floats, step, swapped)
    if step == "_scalarise":  # (unboxed names then keep their order: only scalarised swap)
        monkeypatch.setattr(floats, "_unbox", lambda fn, *args: fn)
    with pytest.raises(AssertionError, match="differ"):
        _check_class_equals_generic(_fresh_plugin_class(monkeypatch), np_rng)


def test21_instances_compiled_for_their_configuration(variant_scalar_rgb):
    """A cooktorrance instance gets its own eval_pdf and sample, compiled for its switches
    (floats.configure), in which no switch is tested any more; instances of the same
    configuration share them, and a parameter update that keeps the configuration keeps
    them."""
    from mi_brdfs.bsdfspec import load_bsdf
    a = load_bsdf({"type": "cooktorrance", "shadowing": "smith", "material": "Au"})
    b = load_bsdf({"type": "cooktorrance", "shadowing": "smith", "material": "Al"})
    for name in ("eval_pdf", "sample"):
        assert name in vars(a) and vars(a)[name].__func__ is vars(b)[name].__func__
    cls = type(a)
    key = next(k for k in cls.__configured__ if ("self.m_shadowing", "smith") in k[0])
    source = ast.unparse(_configured_tree(cls, key, "eval_pdf"))
    assert "m_shadowing" in inspect.getsource(sys.modules[cls.__module__])
    for switch in CONFIGURATION_TESTED:
        assert switch not in source, (switch, source[:2000])
    # a new α: the same configuration, the same methods (α is read by parameters_changed)
    params = mi.traverse(a)
    before = vars(a)["eval_pdf"].__func__
    params["alpha.value"] = 0.3
    params.update()
    assert vars(a)["eval_pdf"].__func__ is before  # (the same configuration)


#: The switches whose tests a configured cooktorrance no longer makes.
CONFIGURATION_TESTED = ("m_shadowing", "m_distribution", "m_fresnel", "m_sample_visible",
                        "m_transmission", "_channels is", "_alpha_const is")


def _configured_tree(cls, key, name):
    """The syntax tree floats.configure compiled ``name`` from, for configuration ``key``."""
    config, known, _ = key
    tree, kinds, tools, _ = cls.__taken__
    node = next(n for n in tree.body if n.name == name)
    return floats._scalarise(floats._unbox(floats._fold(floats._copy(node), dict(config),
                                                        dict(known)), kinds, tools))


def test22_a_wrong_fold_is_caught(variant_scalar_rgb, np_rng, monkeypatch):
    """test07 rejects instances compiled with every constant 'if' taking the other branch."""

    def wrong(self, node):
        node = self.generic_visit(node)
        known, value = floats._truth(node.test)
        if not known:
            return node
        self.changed = True
        kept = node.orelse if value else node.body
        return kept or ast.Pass()

    monkeypatch.setattr(floats._Folder, "visit_If", wrong)
    cls = _fresh_plugin_class(monkeypatch)
    with pytest.raises((AssertionError, AttributeError, NameError, TypeError)):
        _check_class_equals_generic(cls, np_rng, configs=CT_CONFIGS[:3])


def test23_configured_after_another_variant_loaded(variant_scalar_rgb):
    """The plugin module is loaded afresh for each variant: an instance made in scalar_rgb after
    another variant's module was loaded is compiled in scalar_rgb's module (its globals: the
    scalar variant tools), and evaluates."""
    from conftest import set_variant

    from mi_brdfs.bsdfspec import load_bsdf
    spec = {"type": "cooktorrance", "shadowing": "smith", "material": "Au", "alpha": 0.37}
    set_variant("scalar_spectral")  # (its own module of cooktorrance, now in sys.modules)
    set_variant("scalar_rgb")
    bsdf = load_bsdf(spec)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.2, 0.932738)
    value, pdf = bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(0.1, 0.4, 0.910465))
    with _generic(type(bsdf)):
        want = load_bsdf(spec).eval_pdf(mi.BSDFContext(), si, mi.Vector3f(0.1, 0.4, 0.910465))
    assert list(value) == list(want[0]) and pdf == want[1] and pdf > 0


def test24_promoted_after_calls_and_renders_the_same(variant_scalar_rgb, monkeypatch):
    """With PROMOTE_AFTER = 50, an instance first runs the class's methods through counting
    stand-ins, then its configured methods; a scalar render of the brushed and the glass scene
    through Mitsuba (which finds the instance's methods) is the same image, bit for bit, as
    with the generic methods throughout."""
    from mi_brdfs.bsdfspec import load_bsdf
    from mi_brdfs.scenes import load_scene
    monkeypatch.setattr(floats, "PROMOTE_AFTER", 50)
    cls = floats.compiled_class(registry.plugin_class("cooktorrance"))
    monkeypatch.setattr(cls, "__configured__", {})  # (no configuration compiled yet)
    bsdf = load_bsdf({"type": "cooktorrance", "shadowing": "smith", "material": "Cr"})
    si, ctx = mi.SurfaceInteraction3f(), mi.BSDFContext()
    si.wi = mi.Vector3f(0.3, 0.2, 0.932738)
    assert vars(bsdf)["eval_pdf"].__name__ == "eval_pdf"  # (a stand-in)
    assert not hasattr(vars(bsdf)["eval_pdf"], "__func__")
    for _ in range(50):
        bsdf.eval_pdf(ctx, si, mi.Vector3f(0.1, 0.4, 0.910465))
    assert "configured" in vars(bsdf)["eval_pdf"].__func__.__code__.co_filename
    import drjit as dr
    threads = dr.thread_count()
    dr.set_thread_count(1)  # (two render threads add overlapping blocks in either order)
    try:
        _render_both(floats, registry, load_scene)
    finally:
        dr.set_thread_count(threads)


def _render_both(floats, registry, load_scene):
    """test24's renders: configured and generic, the same image."""
    for scene, defines in (("brushed", {"metal": "cooktorrance-smith"}),
                           ("glass", {"glass": "cooktorrance"})):
        images = []
        for generic in (False, True):
            with contextlib.ExitStack() as stack:
                if generic:
                    stack.enter_context(_generic(floats.compiled_class(
                        registry.plugin_class("cooktorrance"))))
                loaded = load_scene(scene, dict(defines, res="12", max_depth="4"))
                images.append(np.array(mi.render(loaded, spp=4, seed=3)))
        assert np.isfinite(images[0]).all() and images[0].max() > 0
        np.testing.assert_array_equal(images[0], images[1], err_msg=scene)
