"""
The ``rpv`` plugin against Eradiate's: the committed table validation/eradiate/rpv.json
(``make eradiate-values``). Eradiate's values are finite and non-negative at all its pairs
(θ ≤ 89°), and the plugin's equal them within float32 rounding, the directions' conditioning
and Eradiate's cancellation of G at the hot spot (:func:`cancellation`); the counts are
asserted (the plugin's docstring quotes them); a plugin with g's sign flipped fails.
"""

import math

import numpy as np
import pytest
from eradiate_table import (UNIT, base_tolerance, compare, counts_against_eradiate,
                            load_table, plugin_values)

from mi_brdfs.reference import rpv as ref
from mi_brdfs.scattering import rpv as scattering

#: Two float32 evaluations (Eradiate's and the plugin's, each within 10⁻⁶ of the model away
#: from the hot spot's cancellation: test_rpv.RTOL) of the same model.
RTOL = 4e-6
#: (agree, Eradiate negative, Eradiate not finite) per parameter set and Eradiate variant, of
#: the table's 705 pairs.
COUNTS = {(name, variant): (705, 0, 0) for name in ("defaults", "example", "bowl", "bell")
          for variant in UNIT}


def model(params):
    """The float64 model's f·cosθo (mi_brdfs.reference.rpv): the conditioning."""
    m = ref.RPV(**params)
    return lambda wi, wo: m.brdf(wi, wo)[:, 0] * wo[:, 2]


def cancellation(params, wi, wo, unit):
    """
    The error of Eradiate's f·cosθo from its G = √(tan²θi + tan²θo − 2 tanθi tanθo cos φ)
    (src/bsdfs/rpv.cpp), which cancels near the hot spot (G = 0): G² off by δ = 4u(tanθi +
    tanθo)² (u the unit roundoff) moves G by √(G² + δ) − G and H = 1 + (1 − ρc)/(1 + G) by
    |1 − ρc| that over (1 + G)²; relative to H, the value's. The plugin takes G = |pi − po|
    from the vectors, without it. Eradiate's parameters are float32 (0.1f): a relative 10⁻⁷
    in the float64 variant.
    """
    rho_c = params.get("rho_c", params.get("rho_0", ref.RHO_0))
    m = ref.RPV(**params)
    _, _, big_g = m.factors(wi, wo)
    tan_sum = np.linalg.norm(wi[:, :2], axis=1) / wi[:, 2] + \
        np.linalg.norm(wo[:, :2], axis=1) / wo[:, 2]
    delta = 4 * unit * tan_sum ** 2
    shift = np.sqrt(big_g ** 2 + delta) - big_g
    h = 1 + (1 - rho_c) / (1 + big_g)
    value = m.brdf(wi, wo)[:, 0] * wo[:, 2]
    return value * (abs(1 - rho_c) * shift / (1 + big_g) ** 2 / h + 1e-7)


def tolerance(params, wi, wo, theirs, variant):
    return base_tolerance(RTOL, model(params), wi, wo, theirs) + \
        cancellation(params, wi, wo, UNIT[variant])


def test01_equal_to_eradiate(variant_llvm_ad_rgb):
    """Per parameter set, against Eradiate's float32 and float64 values, with the counts of
    :data:`COUNTS`."""
    table = load_table("rpv")
    _, wi, wo, _, _ = table
    assert counts_against_eradiate("rpv", table, lambda ours, theirs, params, variant, what:
                                   compare(ours, theirs,
                                           tolerance(params, wi, wo, theirs, variant),
                                           wi, wo, what)) == COUNTS


def test02_a_flipped_asymmetry_fails(variant_llvm_ad_rgb, monkeypatch):
    """A plugin reading g as −g (forward for backward) fails the comparison."""
    hg = scattering.henyey_greenstein
    monkeypatch.setattr(scattering, "henyey_greenstein", lambda g, wi, wo: hg(-g, wi, wo))
    _, wi, wo, sets, columns = load_table("rpv")
    params = sets["bell"]
    theirs = columns["bell", "scalar_rgb"]
    with pytest.raises(AssertionError, match="differ from Eradiate's"):
        compare(plugin_values("rpv", params, wi, wo), theirs,
                tolerance(params, wi, wo, theirs, "scalar_rgb"), wi, wo, "rpv flipped")
    assert math.isfinite(theirs.sum())
