"""
The ``rtls`` plugin against Eradiate's: the committed table validation/eradiate/rtls.json
(``make eradiate-values``: Eradiate's ``rtls`` of ``eradiate-mitsuba``, evaluated in a virtual
environment of its own, at fixed pairs and parameter sets, in float32 and float64). Where
Eradiate's value is finite and non-negative the plugin's equals it, within float32 rounding
and Eradiate's cancellation at the hot spot (:func:`cancellation`); where it is negative the
plugin's is 0 (the clamp); where it is not finite the plugin's is finite. The cases of each
kind are counted (the plugin's docstring quotes them); a plugin with f_vol and f_geo swapped
fails the comparison.
"""

import math

import numpy as np
import pytest
from eradiate_table import (UNIT, base_tolerance, compare, counts_against_eradiate,
                            load_table, plugin_values)

from mi_brdfs.reference import rtls as ref
from mi_brdfs.scattering import rtls as kernels

#: Two float32 evaluations of the kernels (Eradiate's and the plugin's), each within 10⁻⁵ of
#: the model away from the horizon (test_rtls.RTOL); the directions' rounding is the
#: conditioning, as in helpers.assert_matches_reference.
RTOL = 2e-5
#: (agree, Eradiate negative, Eradiate not finite) per parameter set and Eradiate variant, of
#: the table's 705 pairs: what the plugin's docstring quotes.
COUNTS = {
    ("defaults", "scalar_rgb"): (691, 0, 14), ("defaults", "scalar_mono_double"): (629, 0, 76),
    ("example", "scalar_rgb"): (559, 132, 14), ("example", "scalar_mono_double"): (497, 132, 76),
    ("crowns", "scalar_rgb"): (510, 181, 14), ("crowns", "scalar_mono_double"): (448, 181, 76),
    ("volume", "scalar_rgb"): (663, 28, 14), ("volume", "scalar_mono_double"): (601, 28, 76),
}


def model(params):
    """The float64 model's f·cosθo, unclamped (mi_brdfs.reference.rtls): the conditioning."""
    m = ref.RTLS(**params)
    return lambda wi, wo: m.brf(wi, wo)[:, 0] / math.pi * wo[:, 2]


def cancellation(params, wi, wo, unit):
    """
    The error of Eradiate's f·cosθo from its D = √(tan²θi' + tan²θo' − 2 tanθi' tanθo' cos φ)
    (src/bsdfs/rtls.cpp), which cancels at the hot spot (D = 0): D² off by δ = 4u(tanθi' +
    tanθo')² (u the unit roundoff; the three terms rounded, cos φ from the azimuths' sines
    and cosines) moves D by √(D² + δ) − D, √δ at the hot spot; cos t = (h/b)√(D² + …)/(secθi'
    + secθo') and |dO/dcos t| ≤ 2(secθi' + secθo')/π move O, and the BRF, by at most
    f_geo (2/π)(h/b) that. The plugin takes D = |pi − po| from the vectors, without it.
    """
    h, r, b = (params.get(k, d) for k, d in (("h", ref.H), ("r", ref.R), ("b", ref.B)))
    f_geo = params.get("f_geo", ref.RTLS().f_geo[0])
    p_i, p_o = ((b / r) * w[:, :2] / w[:, 2:3] for w in (wi, wo))  # |p| = tanθ'
    d = np.linalg.norm(p_i - p_o, axis=1)
    delta = 4 * unit * (np.linalg.norm(p_i, axis=1) + np.linalg.norm(p_o, axis=1)) ** 2
    return f_geo * (2 / np.pi) * (h / b) * (np.sqrt(d ** 2 + delta) - d) * wo[:, 2] / np.pi


def tolerance(params, wi, wo, theirs, variant):
    """Where Eradiate's value is negative by less than this, the plugin's may be that close
    to 0 (the two round differently)."""
    return base_tolerance(RTOL, model(params), wi, wo, theirs) + \
        cancellation(params, wi, wo, UNIT[variant])


def test01_equal_to_eradiate(variant_llvm_ad_rgb):
    """Per parameter set, against Eradiate's float32 and float64 values, with the counts of
    :data:`COUNTS`."""
    table = load_table("rtls")
    _, wi, wo, _, _ = table
    assert counts_against_eradiate("rtls", table, lambda ours, theirs, params, variant, what:
                                   compare(ours, theirs,
                                           tolerance(params, wi, wo, theirs, variant),
                                           wi, wo, what)) == COUNTS


def test02_a_swapped_kernel_fails(variant_llvm_ad_rgb, monkeypatch):
    """A plugin whose f_vol weighs K_geo and f_geo K_vol fails the comparison."""
    def swapped(f_iso, f_vol, f_geo, wi, wo, h_over_b, b_over_r):
        return f_iso + f_geo * kernels.ross_thick(wi, wo) + \
            f_vol * kernels.li_sparse_r(wi, wo, h_over_b, b_over_r)

    monkeypatch.setattr(kernels, "brf", swapped)
    _, wi, wo, sets, columns = load_table("rtls")
    params = sets["example"]
    theirs = columns["example", "scalar_rgb"]
    with pytest.raises(AssertionError, match="differ from Eradiate's"):
        compare(plugin_values("rtls", params, wi, wo), theirs,
                tolerance(params, wi, wo, theirs, "scalar_rgb"), wi, wo, "rtls swapped")
