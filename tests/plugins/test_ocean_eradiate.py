"""
The ``ocean`` plugin against Eradiate's ``ocean_mishchenko``: the committed table
validation/eradiate/ocean.json (``make eradiate-values``: ``eradiate-mitsuba`` 0.5.0 in a
virtual environment of its own, at fixed pairs, the mirror direction included, and parameter
sets, in float32 and float64). Eradiate computes Smith's Λ by Walter's rational approximation
(Mitsuba's ``microfacet.h``, < 0.35 % in G1), the plugin exactly (the paper's erfc): the
plugin's value times S_approx/S_exact, in float64 (:func:`approximation`), equals Eradiate's
within float32 rounding (and, where a direction is within 4.5·10⁻⁴ rad of the normal, the
4.9·10⁻⁴ rad by which Eradiate moves it: it clamps μ at 0.9999999). At exact backscatter
ωo = ωi Eradiate's Fresnel matrix (Mishchenko & Travis's amplitude matrix over
|ωi × ωo|⁴, a plane of scattering that is undefined there) is 0/0: its values are 0, tiny or
off by factors; the plugin's equal the float64 reference there. Each kind is counted (the
plugin's docstring quotes them); a plugin with α² = σ²/2 fails.
"""

import math

import numpy as np
import pytest
from eradiate_table import (base_tolerance, compare, counts_against_eradiate,
                            load_table, plugin_values)

from mi_brdfs.reference import ocean as ref
from mi_brdfs.scattering import ocean as terms

#: Two float32 evaluations (Eradiate's and the plugin's), each within a few 10⁻⁶.
RTOL = 2e-5
#: Where Eradiate moves a direction off the normal (μ > 0.9999999): the value's change by a
#: 4.9·10⁻⁴ rad move, at most 5·10⁻⁴ relative on the table.
NADIR_RTOL = 1e-3
#: (agree, exact backscatter where Eradiate's Fresnel is 0/0) per set and Eradiate variant,
#: of the table's 840 pairs: what the plugin's docstring quotes.
COUNTS = {
    ("defaults", "scalar_rgb"): (832, 8), ("defaults", "scalar_mono_double"): (831, 9),
    ("example", "scalar_rgb"): (807, 33), ("example", "scalar_mono_double"): (807, 33),
    ("calm", "scalar_rgb"): (833, 7), ("calm", "scalar_mono_double"): (832, 8),
    ("storm", "scalar_rgb"): (789, 51), ("storm", "scalar_mono_double"): (790, 50),
}


def model(params):
    """The float64 model's f·cosθo (mi_brdfs.reference.ocean): the conditioning."""
    m = ref.Ocean(**params)
    return lambda wi, wo: m.brdf(wi, wo)[:, 0] * wo[:, 2]


def _lambda_rational(w, alpha):
    """Λ as Mitsuba's microfacet.h computes it for Beckmann: (1 − 1.259a + 0.396a²)/(3.535a
    + 2.181a²), 0 for a ≥ 1.6, a = 1/(α tanθ)."""
    tan = np.hypot(w[:, 0], w[:, 1]) / w[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        a = 1 / (alpha * tan)
        out = (1 - 1.259 * a + 0.396 * a * a) / (3.535 * a + 2.181 * a * a)
    return np.where(a >= 1.6, 0.0, out)


def approximation(params, wi, wo):
    """S_approx/S_exact = (1 + Λ(ωi) + Λ(ωo))/(1 + Λ~(ωi) + Λ~(ωo)) in float64."""
    m = ref.Ocean(**params)
    alpha = math.sqrt(terms.ISOTROPIC[0] + terms.ISOTROPIC[1] * params.get("wind_speed", 0.1))
    return (1 + m.lam(wi) + m.lam(wo)) / \
        (1 + _lambda_rational(wi, alpha) + _lambda_rational(wo, alpha))


def compare_ocean(ours, theirs, params, kind, wi, wo, what):
    """The rules of the module's docstring (eradiate_table's, on the plugin's value times
    S_approx/S_exact, exact backscatter excused where the plugin's equals the float64
    reference's); (agree, backscatter 0/0) counts."""
    f = model(params)
    reference = f(wi, wo)
    paper = np.abs(ours - reference) <= base_tolerance(RTOL, f, wi, wo, reference)
    nadir = (wi[:, 2] > 0.9999999) | (wo[:, 2] > 0.9999999)
    tol = base_tolerance(np.where(nadir, NADIR_RTOL, RTOL), f, wi, wo, theirs)
    agree, negative, missing = compare(ours * approximation(params, wi, wo), theirs, tol, wi,
                                       wo, what, excused=(kind == "backscatter") & paper)
    assert negative == missing == 0, what  # Eradiate's ocean values are all finite, ≥ 0
    return agree, len(theirs) - agree


def test01_equal_to_eradiate(variant_llvm_ad_rgb):
    """Per parameter set, against Eradiate's float32 and float64 values, with the counts of
    :data:`COUNTS`; finite and non-negative everywhere."""
    table = load_table("ocean")
    kind, wi, wo, _, _ = table
    assert counts_against_eradiate("ocean", table, lambda ours, theirs, params, variant, what:
                                   compare_ocean(ours, theirs, params, kind, wi, wo,
                                                 what)) == COUNTS


def test02_a_wrong_roughness_fails(variant_llvm_ad_rgb, monkeypatch):
    """A plugin with α² = σ²/2 (the variance of one axis) fails the comparison."""
    right = terms.roughness
    monkeypatch.setattr(terms, "roughness",
                        lambda u, aniso: (right(u, aniso)[0] / math.sqrt(2), None))
    kind, wi, wo, sets, columns = load_table("ocean")
    params = sets["example"]
    with pytest.raises(AssertionError, match="differ from Eradiate's"):
        compare_ocean(plugin_values("ocean", params, wi, wo), columns["example", "scalar_rgb"],
                      params, kind, wi, wo, "ocean halved")
