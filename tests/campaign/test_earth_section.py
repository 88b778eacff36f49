"""
The report's section on the Earth-observation plugins (rtls, rpv, hapke, ocean) at quick size:
every row as expected (rpv's energy at its defaults the one expected failure: the model's own),
each plugin's battery, reference comparison and the three findings of Eradiate's plugins
checked on ours. The full size runs in ``mi-brdfs validate --only earth``.
"""

from mi_brdfs.campaign import earth
from mi_brdfs.campaign.core import Context


def test01_quick_section_rows(variant_llvm_ad_rgb, tmp_path):
    s = earth.section(Context(tmp_path, quick=True))
    assert all(r.ok for r in s.rows), [(r.plugin, r.check, r.result) for r in s.rows
                                       if not r.ok]
    expected = [r for r in s.rows if r.expected_fail]
    assert [(r.plugin, r.check) for r in expected] == [("rpv (defaults (k = 0.1))", "energy")]
    for plugin in ("rtls", "rpv", "hapke", "ocean"):
        rows = [r for r in s.rows if r.plugin.startswith(plugin)]
        assert any("reference" in r.check for r in rows), plugin
        assert any(r.check.startswith("chi2") for r in rows), plugin
    assert any("finite at ωo = ωi = normal" in r.check for r in s.rows)
    assert float(s.values["rpv: E(89°), defaults"]) > 20  # the model's own energy, kept
