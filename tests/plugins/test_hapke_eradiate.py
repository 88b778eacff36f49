"""
The ``hapke`` plugin against Eradiate's: the committed table validation/eradiate/hapke.json
(``make eradiate-values``). Where Eradiate's value is finite the plugin's equals it within
float32 rounding, the directions' conditioning and Eradiate's own angles (:func:`eradiate`):
it takes g = acos(cos g) and ψ = acos(cos ψ) from the vectors' components, which near g = 0
and ψ = 0 turn the inputs' rounding into angles of √(2ε). Where Eradiate's value is NaN (the
defaults' h = 0 at g = 0: 0·∞ in B_0/(1 + tan(g/2)/h)) the plugin's is finite. The counts are
asserted (the plugin's docstring quotes them); a plugin whose phase function has its lobes
swapped (c weighting the forward one) fails.
"""

import numpy as np
import pytest
from eradiate_table import (UNIT, base_tolerance, compare, counts_against_eradiate,
                            load_table, plugin_values)

from mi_brdfs.reference import hapke as ref
from mi_brdfs.scattering import hapke as scattering

#: Two float32 evaluations of the model (Eradiate's and the plugin's, each within 10⁻⁵ of the
#: float64 model: test_hapke.RTOL).
RTOL = 2e-5
#: (agree, Eradiate negative, Eradiate not finite) per parameter set and Eradiate variant, of
#: the table's 705 pairs.
COUNTS = {
    ("defaults", "scalar_rgb"): (599, 0, 106), ("defaults", "scalar_mono_double"): (632, 0, 73),
    **{(name, variant): (705, 0, 0) for name in ("example", "smooth", "bright")
       for variant in UNIT},
}


def model(params):
    """The float64 model's f·cosθo (mi_brdfs.reference.hapke): the conditioning."""
    m = ref.Hapke(**params)
    return lambda wi, wo: m.brdf(wi, wo)[:, 0] * wo[:, 2]


def eradiate(params, wi, wo, unit):
    """
    How far Eradiate's angles move its value: it takes cos g = cosθi cosθo + sinθi sinθo cos ψ
    with the sines from the components (sin²θ = x² + y²), so that for directions of |ω|² ≠ 1
    (the table's are rounded to float32: 1 − |ω|² up to 6·10⁻⁸) and its own rounding cos g is
    off by ε = |1 − |ωi|²| + |1 − |ωo|²| + 8u, and g = acos(cos g) by up to acos(cos g − ε) −
    g (√(2ε) at g = 0, where B = B_0/(1 + tan(g/2)/h) is steepest); likewise ψ = acos(cos ψ),
    cos ψ off by 8u; both ways (acos is steep at −1 too). And it takes cos i = cos(atan(tan
    i)), whose angle is off by 2u·i: relative 2u·i/cos i near grazing. The float64 model's
    change of f·cosθo under each, summed.
    """
    m = ref.Hapke(**params)
    i, e, psi, g = ref.angles(wi, wo)
    eps = np.abs(1 - np.sum(wi * wi, 1)) + np.abs(1 - np.sum(wo * wo, 1)) + 8 * unit
    base = m.reflectance_at(i, e, psi, g)[:, 0]
    shift = np.zeros_like(base)
    for sign in (-1, 1):  # acos is steep at both ends: g, ψ near 0 and near π
        g2 = np.arccos(np.clip(np.cos(g) + sign * eps, -1, 1))
        psi2 = np.arccos(np.clip(np.cos(psi) + sign * 8 * unit, -1, 1))
        i2, e2 = i * (1 + sign * 2 * unit), e * (1 + sign * 2 * unit)
        moved = [m.reflectance_at(*a)[:, 0] for a in
                 ((i, e, psi, g2), (i, e, psi2, g), (i2, e, psi, g), (i, e2, psi, g))]
        shift = np.maximum(shift, sum(np.abs(x - base) for x in moved))
    return shift * wo[:, 2] / wi[:, 2]


def tolerance(params, wi, wo, theirs, variant):
    return base_tolerance(RTOL, model(params), wi, wo, theirs) + \
        2 * eradiate(params, wi, wo, UNIT[variant])


def test01_equal_to_eradiate(variant_llvm_ad_rgb):
    """Per parameter set, against Eradiate's float32 and float64 values, with the counts of
    :data:`COUNTS`; the plugin finite and non-negative at every pair."""
    table = load_table("hapke")
    kind, wi, wo, _, columns = table
    assert counts_against_eradiate("hapke", table, lambda ours, theirs, params, variant, what:
                                   compare(ours, theirs,
                                           tolerance(params, wi, wo, theirs, variant),
                                           wi, wo, what)) == COUNTS
    for (name, _), theirs in columns.items():  # NaN where g rounds to 0: backscatter, nadir
        if name == "defaults":
            assert set(kind[~np.isfinite(theirs)]) <= {"backscatter", "grid"}


def test02_swapped_lobes_fail(variant_llvm_ad_rgb, monkeypatch):
    """A plugin whose c weighs the forward lobe (Hapke 2012's other convention read wrongly)
    fails the comparison."""
    phase = scattering.phase
    monkeypatch.setattr(scattering, "phase", lambda b, c, cos_g: phase(b, 1.0 - c, cos_g))
    _, wi, wo, sets, columns = load_table("hapke")
    params = sets["example"]
    theirs = columns["example", "scalar_rgb"]
    with pytest.raises(AssertionError, match="differ from Eradiate's"):
        compare(plugin_values("hapke", params, wi, wo), theirs,
                tolerance(params, wi, wo, theirs, "scalar_rgb"), wi, wo, "hapke swapped")
