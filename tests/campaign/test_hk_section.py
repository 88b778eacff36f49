"""
The report's section on ``hk`` against Mitsuba's ``volpath`` at quick size: the virtual
gonioreflectometer reads a Lambertian plane right, ``max_depth`` counts what the section says it
measures (2 with ``null`` faces, 4 under a ``dielectric``: measured in Mitsuba 3.9), no sensor
sees unscattered light, single scattering agrees within 4σ and every order within 4σ with the
tables' promised error; the same comparison fails on a
plugin without the n² law of radiance (1/η²). The full grid runs in
``mi-brdfs validate --only hk``.
"""

from mi_brdfs.campaign import hk
from mi_brdfs.campaign.core import Context, Section
from mi_brdfs.scattering import hk as layer


def test01_quick_section_rows(variant_llvm_ad_rgb, tmp_path):
    s = hk.section(Context(tmp_path, quick=True))
    assert all(r.ok for r in s.rows), [(r.plugin, r.check, r.result) for r in s.rows
                                       if not r.ok]
    assert s.values["hk: single-scattering max_depth, η = 1"] == "2"
    assert s.values["hk: single-scattering max_depth, η = 1.5"] == "4"
    assert sum("single scattering = volpath" in r.check for r in s.rows) == len(hk.QUICK_GRID)
    assert sum("all orders = volpath" in r.check for r in s.rows) == len(hk.QUICK_GRID)
    assert sum("diffuse plane" in r.check for r in s.rows) == 3


def test02_without_the_n2_law_the_comparison_fails(variant_llvm_ad_rgb, tmp_path, monkeypatch):
    """The plugin's single term times η² (the 1/η² of both crossings removed): the slab under
    glass disagrees with volpath, the index-matched one still agrees."""
    single = layer.single
    monkeypatch.setattr(layer, "single", lambda wi, wo, a, tau, g, eta, rho, base:
                        single(wi, wo, a, tau, g, eta, rho, base) * eta * eta)
    s = Section("hk")
    hk._grid(Context(tmp_path, quick=True), s, {1.0: 2, 1.5: 4})
    verdicts = {r.plugin: r.ok for r in s.rows}
    assert verdicts == {"hk (a = 0.95, τ = 2, g = 0.7, η = 1)": True,
                        "hk (a = 0.4, τ = 0.25, g = -0.3, η = 1.5)": False}, verdicts
