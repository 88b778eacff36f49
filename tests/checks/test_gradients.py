"""
The gradient check (:mod:`mi_brdfs.checks.gradients`): it rejects a BSDF with a wrong or
detached derivative in eval, pdf or the sample weights, reports a weight detached on purpose,
and every plugin of the package passes it, the compensated glass's ∂/∂η included.
"""

import mitsuba as mi
import pytest
from broken import GRADIENT_DEFECTS, register_broken_gradients
from helpers import spec as spec_of

from mi_brdfs import checks, registry
from mi_brdfs.scattering import multiscatter
from mi_brdfs.testing import assert_gradients

#: defect -> the status of (eval, pdf, weight): a defect in eval reaches the weight (eval/pdf)
EXPECTED = {"none": ("ok", "ok", "ok"), "eval_detached": ("detached", "ok", "mismatch"),
            "eval_sign": ("mismatch", "ok", "mismatch"), "pdf_scaled": ("ok", "mismatch", "ok"),
            "weight_detached": ("ok", "ok", "detached"), "weight_sign": ("ok", "ok", "mismatch")}


@pytest.mark.parametrize("defect", GRADIENT_DEFECTS)
def test01_a_broken_derivative_is_found(variant_llvm_ad_rgb, defect):
    """Each defect gets its status on the quantities it reaches, the others stay ok; the check
    fails on all but the control and the weight detached on purpose."""
    register_broken_gradients()
    result = checks.check_gradients({"type": "gradbroken", "defect": defect}, n=256)
    status = tuple({g.quantity: g.status for g in result.details["rows"]}[q]
                   for q in ("eval", "pdf", "weight"))
    assert status == EXPECTED[defect]
    assert result.passed == (defect in ("none", "weight_detached")), result.message


PLUGINS = [spec_of(name) for name in registry.PLUGINS] + [
    {"type": "phong", "form": "original", "lobe": "halfway"},
    {"type": "cooktorrance", "diffuse_reflectance": 0.3, "shadowing": "smith",
     "distribution": "ggx", "specular_reflectance": 0.6},
    {"type": "cooktorrance", "multiscatter": True, "alpha": 0.5, "material": "Au"},
    {"type": "cooktorrance", "transmission": True, "alpha": 0.5},
    # α between two nodes of the albedo tables (α = 0.5 sits 0.2 steps from one, a kink of
    # their interpolation, where finite differences and AD part by design)
    {"type": "cooktorrance", "transmission": True, "multiscatter": True, "alpha": 0.45},
    {"type": "orennayar", "form": "full"},
    {"type": "ashikhmin", "nu": 10.0, "nv": 200.0},
    {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3},
    {"type": "lafortune", "exponent_0": 20.0, "cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0},
    # every order: through the tables' interpolation in albedo and optical depth
    {"type": "hk", "scattering": "all", "sigma_s": 1.3, "sigma_a": 0.4, "g": 0.6, "eta": 1.5},
]


#: The pdfs detached by design, per plugin: he's, rtls's, rpv's and hapke's sampling densities
#: are tabulated from their parameters when they are set (a table has no derivative), and he's
#: sampling probabilities are detached from them alike.
DETACHED_PDF = {"he": {"sigma0", "tau", "eta.value", "k.value"},
                "rtls": {"f_iso.value", "f_vol.value", "f_geo.value"},
                "rpv": {"rho_0.value", "k.value", "g.value"},
                "hapke": {f"{k}.value" for k in ("w", "b", "c", "theta", "B_0", "h")}}


@pytest.mark.parametrize("spec", PLUGINS, ids=lambda s: "-".join(str(v) for v in s.values()))
def test02_every_plugin_passes(variant_llvm_ad_rgb, spec):
    """Every differentiable parameter of every plugin: AD = finite differences in eval, pdf
    and the sample weights (the testing assertion); a pdf detached by design is reported so."""
    result = assert_gradients(spec, n=256)
    allowed = DETACHED_PDF.get(spec["type"], set())
    for g in result.details["rows"]:
        detached = g.status == "detached" and g.quantity == "pdf" and g.parameter in allowed
        assert g.status in ("ok", "constant") or detached, result.message


def test03_the_compensated_glass_carries_eta_into_its_tables(variant_llvm_ad_rgb,
                                                             monkeypatch):
    """Without the tables' slope in η (looked up at a number taken from η, as before) the
    derivative of eval and pdf in η misses the compensation's part and the check fails."""
    tables = multiscatter.dielectric_tables
    monkeypatch.setattr(multiscatter, "dielectric_tables",
                        lambda kind, eta, alpha=None: tables(kind, float(eta[0]), alpha))
    result = checks.check_gradients({"type": "cooktorrance", "transmission": True,
                                     "multiscatter": True, "alpha": 0.45}, n=256)
    status = {(g.parameter, g.quantity): g.status for g in result.details["rows"]}
    assert status[("eta", "eval")] == "mismatch" and not result.passed


def test04_an_ad_variant_is_needed(variant_scalar_rgb):
    with pytest.raises(Exception, match="need an AD variant"):
        checks.check_gradients("lambert")
    assert mi.variant() == "scalar_rgb"
