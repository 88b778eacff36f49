"""
The Python API as a new user misuses it: every public entry point leaves the Mitsuba variant as
it found it (also when it raises), and bad arguments to the checks' public functions end in one
MiBrdfsError naming the function, the parameter, the value and what is allowed (no raw
ValueError, IndexError or TypeError from NumPy or DrJit).
"""

import mitsuba as mi
import pytest

import mi_brdfs
from mi_brdfs.cli import main
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.fit import fit

TINY_FIT = dict(pairs=256, steps=2, thetas_deg=(0.0,), starts="given")

SCENE = """<scene version="3.0.0">
    <default name="res" value="8"/>
    <integrator type="path"/>
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="$res"/>
        <integer name="height" value="$res"/></film></sensor>
    <emitter type="constant"/>
    <shape type="sphere"><bsdf type="lambert" id="ball"/></shape>
</scene>"""


def test01_failed_fit_leaves_the_variant_as_it_found_it(variant_llvm_ad_rgb):
    """fit(variant='scalar_rgb') fails (no AD there); the process stays in llvm_ad_rgb, and the
    next fit, without a variant, works."""
    with pytest.raises(MiBrdfsError, match="fit needs an RGB variant with automatic"):
        fit("lambert reflectance=0.3", "lambert", variant="scalar_rgb", **TINY_FIT)
    assert mi.variant() == "llvm_ad_rgb"
    result = fit("lambert reflectance=0.3", "lambert", **TINY_FIT)
    assert result.variant == "llvm_ad_rgb"


def test02_fit_in_another_variant_hands_the_callers_back(variant_scalar_rgb):
    if not mi_brdfs.llvm_usable():
        pytest.skip("no working libLLVM")
    result = fit("lambert reflectance=0.3", "lambert", variant="llvm_ad_rgb", **TINY_FIT)
    assert result.variant == "llvm_ad_rgb" and mi.variant() == "scalar_rgb"


def test03_simplify_that_raises_leaves_the_variant(variant_llvm_ad_rgb, tmp_path):
    from mi_brdfs.simplify import simplify

    path = tmp_path / "tiny.xml"
    path.write_text(SCENE)
    with pytest.raises(MiBrdfsError, match="declares no <default> for nosuch"):
        simplify(path, variant="scalar_rgb", defines={"nosuch": 1}, cache=False)
    assert mi.variant() == "llvm_ad_rgb"


def test04_the_command_line_in_process_leaves_the_variant(variant_llvm_ad_rgb, tmp_path,
                                                          monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["fit", "lambert", "--model", "lambert", "--variant", "scalar_rgb"]) == 2
    assert "fit needs an RGB variant" in capsys.readouterr().err
    assert mi.variant() == "llvm_ad_rgb"
