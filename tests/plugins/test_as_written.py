"""
The plugins run as written in every variant: an exception inside a term, called by a plugin in
scalar_rgb, reports that term's own file, line and source text (no code is generated or
rewritten at run time).
"""

import traceback

import mitsuba as mi
import pytest

from mi_brdfs.plugins import properties
from mi_brdfs.scattering import microfacet


def _raise_in_ndf(monkeypatch):
    """A roughness of 0 (which the plugin's clamp never lets through) divides by zero in D."""
    monkeypatch.setattr(properties, "roughness_at", lambda *args: (0.0, None))


def test01_a_term_raises_with_its_own_file_line_and_source(variant_scalar_rgb, monkeypatch):
    bsdf = mi.load_dict({"type": "cooktorrance", "material": "Au", "alpha": 0.2})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.2, 0.932738)
    _raise_in_ndf(monkeypatch)
    with pytest.raises(ZeroDivisionError) as info:
        bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(-0.2, 0.1, 0.97467943))
    last = traceback.extract_tb(info.tb)[-1]
    assert last.filename == microfacet.__file__
    assert last.name == "ndf"
    assert "m.x / au" in last.line
    source = open(microfacet.__file__, encoding="utf-8").read().splitlines()
    assert source[last.lineno - 1].strip() == last.line


def test02_the_check_sees_a_frame_from_elsewhere(variant_scalar_rgb, monkeypatch):
    """The check can fail: an exception raised outside the terms names another file."""
    def elsewhere(*args):
        raise ZeroDivisionError("not in a term")

    monkeypatch.setattr(microfacet.Distribution, "ndf", elsewhere)
    bsdf = mi.load_dict({"type": "cooktorrance", "material": "Au", "alpha": 0.2})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0.3, 0.2, 0.932738)
    with pytest.raises(ZeroDivisionError) as info:
        bsdf.eval_pdf(mi.BSDFContext(), si, mi.Vector3f(-0.2, 0.1, 0.97467943))
    assert traceback.extract_tb(info.tb)[-1].filename != microfacet.__file__
