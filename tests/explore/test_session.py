"""
What ``mi-brdfs explore`` shows, without the page (mi_brdfs.explorer.session): the controls
generated from ``mi.traverse``, a change of a parameter through it (the view's kernels reused,
not traced anew), a value the plugin refuses (its own message, the BSDF unchanged), the XML
and dict that reproduce the BSDF as it is now, and the polar view against the BSDF's eval.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.bsdfspec import load_bsdf
from mi_brdfs.checks import batch
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.explorer.session import Session

GOLD = {"type": "cooktorrance", "alpha": 0.3, "material": "Au"}


def test01_controls_from_traverse(variant_llvm_ad_rgb):
    """cooktorrance: α on a log slider within [1e-3, 2], η and k as colours whose ranges hold
    gold's values; lambert's reflectance a colour in [0, 1]; at most four BSDFs."""
    session = Session([GOLD, {"type": "lambert", "reflectance": {"type": "rgb",
                                                                 "value": [0.5, 0.2, 0.1]}}])
    gold, white = (e.controls for e in session.entries)
    alpha = gold["alpha.value"]
    assert alpha.log and (alpha.lo, alpha.hi) == (1e-3, 2.0) and alpha.channels == 1
    for key in ("eta.value", "k.value"):
        c = gold[key]
        assert c.channels == 3 and c.lo <= min(c.value) and max(c.value) <= c.hi
    assert white["reflectance.value"].channels == 3
    rpv = Session(["rpv rho_0=0.05 k=0.6 g=-0.1"]).entries[0].controls
    assert (rpv["k.value"].lo, rpv["k.value"].hi) == (0.0, 3.0)  # rpv's own range, not k's 10
    with pytest.raises(MiBrdfsError, match="1 to 4 BSDFs"):
        Session([GOLD] * 5)


def test02_a_change_goes_through_traverse_and_reuses_the_kernels(variant_llvm_ad_rgb):
    """Setting α keeps the same plugin object, changes the polar view as eval at the new α
    does (against a BSDF loaded at it), and the second change launches only kernels the first
    one compiled (the value is an input of the kernels, not part of their code)."""
    session = Session([GOLD])
    entry = session.entries[0]
    bsdf = entry.bsdf
    entry.set("alpha.value", 0.1)
    theta_o, (values,) = session.polar(30.0, n=91)
    assert entry.bsdf is bsdf
    t = np.radians(theta_o)
    wo = np.stack([np.sin(t), 0 * t, np.cos(t)], axis=1)
    want = batch.evaluate(load_bsdf(dict(GOLD, alpha=0.1)), batch.direction(math.radians(-30.0)),
                          wo).value.mean(axis=1)
    np.testing.assert_allclose(values, want, rtol=1e-5, atol=1e-7)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        dr.kernel_history_clear()
        entry.set("alpha.value", 0.2)
        session.polar(30.0, n=91)
        first = {k["hash"] for k in dr.kernel_history() if "hash" in k}
        entry.set("alpha.value", 0.25)
        session.polar(30.0, n=91)
        second = {k["hash"] for k in dr.kernel_history() if "hash" in k}
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert first and second <= first, second - first


def test03_a_refused_value_keeps_the_bsdf(variant_llvm_ad_rgb):
    """α = −1 is refused in cooktorrance's own words, text is no number, an unknown key is
    named; the BSDF keeps α = 0.3."""
    entry = Session([GOLD]).entries[0]
    with pytest.raises(MiBrdfsError, match=r"cooktorrance: parameter \"alpha\" = -1") as e:
        entry.set("alpha.value", -1.0)
    assert len(str(e.value).splitlines()) == 1
    with pytest.raises(MiBrdfsError, match="expected a number"):
        entry.set("alpha.value", "rough")
    with pytest.raises(MiBrdfsError, match="no parameter 'beta'"):
        entry.set("beta", 1.0)
    assert entry.controls["alpha.value"].value == pytest.approx(0.3)
    assert float(entry.params["alpha.value"][0]) == pytest.approx(0.3)


def test04_dict_and_xml_reproduce_the_bsdf_now(variant_llvm_ad_rgb):
    """After α and η change, the dict (η and k as rgb, material dropped) and the XML fragment
    load into BSDFs whose eval equals the explored one's."""
    entry = Session([GOLD]).entries[0]
    entry.set("alpha.value", 0.12)
    entry.set("eta.value", (0.2, 0.4, 1.4))
    spec = entry.as_dict()
    assert "material" not in spec and spec["eta"]["type"] == "rgb"
    wi = batch.direction(math.radians(-40.0))
    wo = np.array([[0.3, 0.1, 0.95], [0.6, 0.0, 0.8]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    want = batch.evaluate(entry.bsdf, wi, wo).value
    for other in (spec, entry.xml()):
        got = batch.evaluate(load_bsdf(other), wi, wo).value
        np.testing.assert_allclose(got, want, rtol=1e-5)
    assert '<float name="alpha" value="0.12"/>' in entry.xml()


def test05_switches_are_menus_that_reload_the_plugin(variant_llvm_ad_rgb):
    """cooktorrance's switches as it reads them (distribution, fresnel, multiscatter, ...),
    a built-in's from the audit's table, a preset's as its parameters; a switch set loads the
    plugin anew with the parameters as they were (eval equals the dict's with both), the
    Python shown loads the same BSDF, and a value the plugin refuses changes nothing."""
    session = Session([GOLD, "roughplastic alpha=0.2", "ward preset=ngan:gold-metallic-paint"])
    gold, plastic, ward = session.entries
    assert gold.switches["distribution"] == ("beckmann", ("beckmann", "ggx"))
    assert gold.switches["multiscatter"] == (False, (False, True))
    assert plastic.switches["nonlinear"] == (False, (False, True))
    assert ward.switches["form"][0] == "original"  # the preset's, not the plugin's default
    gold.set("alpha.value", 0.15)
    old = gold.bsdf
    gold.switch("distribution", "ggx")
    assert gold.bsdf is not old and gold.switches["distribution"][0] == "ggx"
    wi = batch.direction(math.radians(-30.0))
    wo = np.array([[0.2, 0.1, 0.97], [0.5, 0.0, 0.86]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    want = batch.evaluate(load_bsdf(dict(GOLD, alpha=0.15, distribution="ggx")), wi, wo).value
    np.testing.assert_allclose(batch.evaluate(gold.bsdf, wi, wo).value, want, rtol=1e-5)
    assert gold.python().startswith("mi.load_dict(")
    shown = eval(gold.python()[len("mi.load_dict("):-1])  # the dict the page shows
    np.testing.assert_allclose(batch.evaluate(load_bsdf(shown), wi, wo).value, want, rtol=1e-5)
    with pytest.raises(MiBrdfsError, match='"distribution" = "foo"'):
        gold.switch("distribution", "foo")
    assert gold.switches["distribution"][0] == "ggx"


def test06_a_merl_file_and_an_xml_fragment(variant_llvm_ad_rgb):
    """A MERL file (its path, as on the command line) is explored through the merl plugin,
    with its interpolation switch as a menu; an XML fragment as given (no menus, its XML
    shown as it came); the polar view of each is its eval."""
    from helpers import merl_file

    path = str(merl_file())
    fragment = '<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>'
    session = Session([path, fragment])
    measured, xml = session.entries
    assert measured.spec["type"] == "merl" and "filter_type" in measured.switches
    assert xml.switches == {} and xml.xml() == fragment
    theta_o, curves = session.polar(40.0, n=31)
    t = np.radians(theta_o)
    wo = np.stack([np.sin(t), 0 * t, np.cos(t)], axis=1)
    for spec, values in ((path, curves[0]), (fragment, curves[1])):
        want = batch.evaluate(load_bsdf(spec), batch.direction(math.radians(-40.0)),
                              wo).value.mean(axis=1)
        np.testing.assert_allclose(values, want, rtol=1e-5, atol=1e-7)


def test07_what_the_plugin_says_is_kept_for_the_page(variant_llvm_ad_rgb):
    """Ward with ρd + ρs = 1.1 > 1: its plugin's warning is the entry's (for the page), not
    printed; a value that brings the sum below 1 clears it, one above brings it back; a
    warning of another kind passes on."""
    import warnings

    from mi_brdfs.errors import MiBrdfsWarning

    with warnings.catch_warnings(record=True) as outside:
        warnings.simplefilter("always")
        entry = Session(["ward diffuse_reflectance=0.6 specular_reflectance=0.5"]).entries[0]
        (said,) = entry.warnings
        assert said.startswith("ward: ") and "1.1 > 1" in said
        entry.set("specular_reflectance.value", 0.2)
        assert entry.warnings == []
        entry.set("specular_reflectance.value", 0.6)
        assert len(entry.warnings) == 1 and "1.2 > 1" in entry.warnings[0]
        from mi_brdfs.explorer import session

        _, heard = session._heard(lambda: warnings.warn("other", DeprecationWarning))
    assert heard == []
    assert [str(w.message) for w in outside] == ["other"]
    assert not any(issubclass(w.category, MiBrdfsWarning) for w in outside)
