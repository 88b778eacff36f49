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


#: (function, its dotted name in the message, arguments, the parameter, the value as shown).
MISUSE = [
    ("chi2_bsdf", {"wi": "0.6,0,0.8"}, "wi", '"0.6,0,0.8"'),
    ("chi2_bsdf", {"wi": (0.6, 0.8)}, "wi", "(0.6, 0.8)"),
    ("chi2_bsdf", {"wi": []}, "wi", "[]"),
    ("chi2_bsdf", {"wi": (0, 0, 0)}, "wi", "(0, 0, 0)"),
    ("chi2_bsdf", {"seed": -1}, "seed", "-1"),
    ("check_consistency", {"seed": -1, "n": 16}, "seed", "-1"),
    ("check_consistency", {"seed": 1.5, "n": 16}, "seed", "1.5"),
    ("check_reciprocity", {"seed": -1, "n": 16}, "seed", "-1"),
    ("check_positivity", {"seed": -1, "n": 16}, "seed", "-1"),
    ("check_lobes", {"n": 0}, "n", "0"),
    ("check_pdf_integral", {"seed": -1, "n": 16}, "seed", "-1"),
    ("check_equal", {"spec_b": "diffuse", "seed": -1, "n": 16}, "seed", "-1"),
    ("albedo_curve", {"thetas_deg": [], "n": 16}, "thetas_deg", "[]"),
    ("albedo_curve", {"thetas_deg": "0,30", "n": 16}, "thetas_deg", '"0,30"'),
    ("albedo_curve", {"thetas_deg": (0.0,), "seed": -1, "n": 16}, "seed", "-1"),
    ("check_energy", {"thetas_deg": (0.0,), "sigmas": -1, "n": 16}, "sigmas", "-1"),
    ("furnace_render", {"seed": -1, "spp": 1, "res": 4}, "seed", "-1"),
    ("check_stability", {"n_random": 4, "seed": -1}, "seed", "-1"),
    ("eval_precision", {"seed": -1, "n": 16}, "seed", "-1"),
]


@pytest.mark.parametrize("name,kwargs,parameter,shown", MISUSE,
                         ids=[f"{m[0]}-{m[2]}={m[3]}" for m in MISUSE])
def test05_checks_refuse_misuse_in_one_line(variant_llvm_ad_rgb, name, kwargs, parameter,
                                            shown):
    """One MiBrdfsError naming the function, the parameter, the value and what is allowed,
    where NumPy's ValueError or IndexError (or DrJit's TypeError) came out."""
    from mi_brdfs import checks

    with pytest.raises(MiBrdfsError) as info:
        getattr(checks, name)("lambert", **kwargs)
    text = str(info.value)
    assert "\n" not in text and f"{name}: " in text, text
    assert (f'parameter "{parameter}" = {shown} is invalid: must' in text
            or f"{parameter} = {shown} is invalid: must" in text), text


def test06_check_stability_of_no_spec(variant_scalar_rgb):
    from mi_brdfs import checks

    with pytest.raises(MiBrdfsError, match=r'check_stability: parameter "specs" = \[\] is '
                                           r'invalid: must be one BSDF spec or a non-empty'):
        checks.check_stability([])


@pytest.mark.parametrize("output", ["x.exr", "x.json", "x"])
def test07_simplify_refuses_an_output_that_is_no_xml(variant_llvm_ad_rgb, tmp_path, output):
    """simplify(..., output='x.exr') wrote the XML scene into an .exr file."""
    from mi_brdfs.simplify import simplify

    path = tmp_path / "tiny.xml"
    path.write_text(SCENE)
    with pytest.raises(MiBrdfsError, match=f'simplify: parameter "output" = ".*{output}" is '
                                           f'invalid: must end in .xml'):
        simplify(path, output=tmp_path / output, cache=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.xml"]


def test08_write_json_refuses_another_extension(variant_llvm_ad_rgb, tmp_path):
    from mi_brdfs.fit import write_json

    result = fit("lambert reflectance=0.3", "lambert", **TINY_FIT)
    with pytest.raises(MiBrdfsError, match='fit.write_json: parameter "path" = ".*x.exr" is '
                                           'invalid: must end in .json'):
        write_json(result, tmp_path / "x.exr")
    assert not list(tmp_path.iterdir())


@pytest.mark.skipif(bool(__import__("drjit").has_backend(__import__("drjit").JitBackend.CUDA)),
                    reason="a CUDA device is there")
def test09_use_variant_cuda_without_a_device(variant_scalar_rgb):
    with pytest.raises(MiBrdfsError) as info:
        mi_brdfs.use_variant("cuda_ad_rgb")
    text = str(info.value)
    assert text.startswith("variant 'cuda_ad_rgb' needs a CUDA device, and this machine has "
                           "none") and "usable here: scalar_rgb" in text and "\n" not in text
    assert mi.variant() == "scalar_rgb"


@pytest.mark.parametrize("call,message", [
    (lambda: fit("lambert", "lambert", seed=-1, **TINY_FIT),
     'fit.fit: parameter "seed" = -1 is invalid: must be a whole number in [0, 2^32)'),
    (lambda: fit("lambert", "lambert", pairs=256, steps=2, thetas_deg="0,30"),
     "fit: thetas_deg = '0,30' is invalid: must be one or more angles within [0, 90]"),
    (lambda: __import__("mi_brdfs.simplify").simplify.simplify({"type": "scene"}),
     'simplify: parameter "scene" = {\'type\': \'scene\'} is invalid: must be a scene file'),
    (lambda: __import__("mi_brdfs.simplify").simplify.simplify("showcase", defines=["res=4"]),
     'simplify: parameter "defines" = [\'res=4\'] is invalid: must be a dict'),
], ids=["fit-seed", "fit-thetas-str", "simplify-scene-dict", "simplify-defines-list"])
def test10_fit_and_simplify_arguments(variant_llvm_ad_rgb, call, message):
    """Raw ValueError, TypeError or AttributeError from NumPy or Python once."""
    with pytest.raises(MiBrdfsError) as info:
        call()
    assert message in str(info.value) and "\n" not in str(info.value), str(info.value)
