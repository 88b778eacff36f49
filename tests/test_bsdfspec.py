"""
One boundary for BSDF specs (mi_brdfs.bsdfspec): every public function that takes a BSDF takes
it in all four forms — a dict, an XML fragment, a command-line string and a loaded mi.BSDF —
and gets the same answer; what is no BSDF spec gets one clear line.
"""

import mitsuba as mi
import numpy as np
import pytest

import mi_brdfs
from mi_brdfs import bsdfspec, checks, compare, plots, reference, testing
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.scenes import load_scene

FORMS = {
    "dict": lambda: {"type": "lambert", "reflectance": 0.6},
    "xml": lambda: '<bsdf type="lambert"><float name="reflectance" value="0.6"/></bsdf>',
    "cli": lambda: "lambert reflectance=0.6",
    "loaded": lambda: mi.load_dict({"type": "lambert", "reflectance": 0.6}),
}

#: Public entry points that take one BSDF, with small sizes, each returning a number that must be
#: the same for every form of the same BSDF.
ENTRY = {
    "load_bsdf": lambda s: float(np.ravel(bsdfspec.load_bsdf(s).eval_diffuse_reflectance(
        mi.SurfaceInteraction3f()))[0]),
    "check_furnace": lambda s: checks.check_furnace(s, spp=2, res=8, tol=1.0, n=256).value,
    "furnace_render": lambda s: checks.furnace_render(s, spp=2, res=8, predict=False).mean,
    "check_consistency": lambda s: float(checks.check_consistency(s, n=64).passed),
    "check_energy": lambda s: float(checks.check_energy(s, thetas_deg=(0.0, 60.0), n=512).passed),
    "albedo_curve": lambda s: float(checks.albedo_curve(s, (0.0,), n=256).sampled[0, 0]),
    "check_reciprocity": lambda s: float(checks.check_reciprocity(s, n=64).passed),
    "check_positivity": lambda s: float(checks.check_positivity(s, n=64).passed),
    "check_stability": lambda s: float(checks.check_stability([s], n_random=16).passed),
    "check_equal": lambda s: float(checks.check_equal(s, {"type": "diffuse", "reflectance": 0.6},
                                                      n=64).passed),
    "lobe_values": lambda s: float(np.nanmax(plots.lobe_values(s, 30.0, n=31)[1])),
    "slice_values": lambda s: float(np.nanmax(plots.slice_values(s, res=8))),
    "assert_positive": lambda s: float(testing.assert_positive(s, n=64).passed),
    "load_scene": lambda s: float(len(load_scene("furnace", bsdfs={"material": s}).shapes())),
    "reference.for_spec": lambda s: 1.0,  # any form is accepted; see test03 for the values
}


@pytest.mark.parametrize("entry", list(ENTRY))
def test01_every_entry_point_takes_every_form(variant_scalar_rgb, entry):
    values = {form: ENTRY[entry](make()) for form, make in FORMS.items()}
    assert all(np.isfinite(v) for v in values.values()), values
    first = values["dict"]
    for form, value in values.items():
        assert value == pytest.approx(first, rel=1e-6, abs=1e-12), (entry, form, values)


def test02_furnace_render_of_a_loaded_bsdf_in_jit(variant_llvm_ad_rgb):
    """The case that once failed: a loaded mi.BSDF put into the furnace scene (XML)."""
    loaded = mi.load_dict({"type": "lambert", "reflectance": 1.0})
    result = checks.check_furnace(loaded, spp=16, res=16, tol=0.01)
    assert result.passed, result.message  # ρ = 1: the sphere vanishes into the furnace


def test02b_a_scene_does_not_keep_a_loaded_bsdf_alive(variant_llvm_ad_rgb):
    """A loaded Python plugin put into a scene lives while its caller or the scene holds it:
    every BSDF alive in the process is traced into each JIT render, so one that the plugin
    registry kept would slow every later render. Once freed, the XML that named it is one
    line."""
    import gc
    import weakref

    loaded = mi.load_dict({"type": "lambert", "reflectance": 0.5})
    ref = weakref.ref(loaded)
    scene = load_scene("furnace", {"res": "8"}, bsdfs={"material": loaded})
    assert np.all(np.isfinite(np.array(mi.render(scene, spp=1))))
    xml = bsdfspec.to_xml(loaded)
    del scene, loaded
    gc.collect()
    assert ref() is None
    with pytest.raises(RuntimeError, match="the loaded BSDF it stands for has been freed"):
        mi.load_string(f'<scene version="3.0.0">{xml}</scene>')


def test03_reference_for_every_form(variant_scalar_rgb):
    """for_spec parses every form; the float64 model exists for the forms that name parameters."""
    assert reference.for_spec(FORMS["dict"]()).albedo(0.0)[0] == pytest.approx(0.6)
    assert reference.for_spec(FORMS["cli"]()).albedo(0.0)[0] == pytest.approx(0.6)
    assert reference.for_spec(FORMS["loaded"]()) is None
    assert reference.for_spec(FORMS["xml"]()) is None


def test04_compare_swaps_a_loaded_bsdf(variant_scalar_rgb):
    loaded = mi.load_dict({"type": "diffuse", "reflectance": 0.6})
    result = compare.compare("furnace", swap={"material": loaded}, spp=2, with_flip=False,
                             defines={"res": "8"}, swap_a={"material": "lambert reflectance=0.6"})
    assert np.isfinite(result.ab.rmse) and result.ab.rmse < 0.05


BAD = [
    ({"reflectance": 0.5}, "a BSDF dict needs a 'type'"),
    ("nosuchplugin alpha=0.3", "unknown plugin 'nosuchplugin'"),
    ("lambert reflectance=", "malformed parameter"),
    ("alpha=0.3", "comes before any BSDF name"),
    ("lambert diffuse", "names 2 BSDFs, not one"),
    ("sphere", "is a shape, not a BSDF"),
    ("lambert 'unclosed", "cannot read BSDF"),
    (42, "cannot make a BSDF from 42 (int)"),
    ('<bsdf type="lambert"><float name="reflectance" value="2"/></bsdf>',
     'lambert: parameter "reflectance" = 2 is invalid'),
    ("<bsdf type='lambert'", "XML parsing failed"),
]


@pytest.mark.parametrize("spec,message", BAD, ids=[str(i) for i in range(len(BAD))])
def test05_bad_specs_get_one_line(variant_scalar_rgb, spec, message):
    with pytest.raises(MiBrdfsError) as info:
        bsdfspec.load_bsdf(spec)
    text = str(info.value)
    assert message in text and "\n" not in text, text
    assert mi_brdfs is not None


SPLIT = [{"type": "roughconductor", "alpha": 0.3, "material": "Au"}, {"type": "diffuse"}]


@pytest.mark.parametrize("tokens", [
    ["roughconductor", "alpha=0.3", "material=Au", "diffuse"],
    ["roughconductor alpha=0.3 material=Au", "diffuse"],
    ["roughconductor alpha=0.3", "material=Au", "diffuse"],
    ["roughconductor 'alpha=0.3' material=Au diffuse"],
], ids=["words", "quoted", "part-quoted", "one-token"])
def test06_one_grammar_quoted_or_not(variant_scalar_rgb, tokens):
    """A spec reads the same quoted or as words, in parse_cli (the commands) and parse (the
    API): 'mi-brdfs check \"roughconductor alpha=0.3\"' was refused, with a message that told
    the user to write exactly that."""
    assert bsdfspec.parse_cli(tokens) == SPLIT
    assert bsdfspec.parse("roughconductor alpha=0.3 material=Au") == SPLIT[0]


QUOTED_COMMANDS = {
    "check": ["check", "roughconductor alpha=0.3", "diffuse", "-q"],
    "furnace": ["furnace", "roughconductor alpha=0.3", "diffuse", "-n", "16", "--thetas", "0"],
    "plot": ["plot", "slice", "roughconductor alpha=0.3", "diffuse", "--res", "4", "-o", "s.png"],
    "fit": ["fit", "roughconductor alpha=0.3", "--model", "cooktorrance alpha=0.1",
            "--free", "alpha", "--pairs", "256", "--steps", "2", "-q"],
}


@pytest.mark.parametrize("command", list(QUOTED_COMMANDS))
def test07_every_command_takes_a_quoted_spec(variant_scalar_rgb, tmp_path, monkeypatch, capsys,
                                            command):
    """check, furnace, plot and fit take 'roughconductor alpha=0.3' as one argument (check's
    battery stubbed: the spec is what is tested, not the checks)."""
    from mi_brdfs.checks import CheckResult
    from mi_brdfs.cli import main

    seen = []
    monkeypatch.setattr(checks, "run_battery", lambda spec, **kw: seen.append(spec) or [
        CheckResult("stub", True, 0.0, 0.0, "stub")])
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    args = QUOTED_COMMANDS[command]
    if command == "plot":
        pytest.importorskip("matplotlib")
    if command == "fit" and not mi_brdfs.llvm_usable():
        pytest.skip("fit needs llvm_ad_rgb")
    code = main(args + (["--variant", "scalar_rgb"] if command != "fit" else []))
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "error" not in out.err
    if command == "check":
        assert seen == [{"type": "roughconductor", "alpha": 0.3}, {"type": "diffuse"}]
    elif command == "furnace":
        assert "roughconductor(alpha=0.3)" in out.out


def test08_a_check_loads_its_spec_once(variant_llvm_ad_rgb, monkeypatch):
    """One check call loads its BSDF once, however many helpers it hands the spec to (the
    battery runs a dozen); outside a check, each load_bsdf is a fresh object, as a caller
    that changes its BSDF through mi.traverse expects."""
    loads = []
    load_dict = mi.load_dict
    monkeypatch.setattr(mi, "load_dict", lambda d, *a, **k: loads.append(d) or load_dict(d))
    spec = "roughconductor alpha=0.3"
    assert checks.run_battery(spec, quick=True)
    assert len(loads) == 1, loads
    assert bsdfspec.load_bsdf(spec) is not bsdfspec.load_bsdf(spec)
    with bsdfspec.loaded_once():
        assert bsdfspec.load_bsdf(spec) is bsdfspec.load_bsdf(spec)
        other = bsdfspec.load_bsdf("roughconductor alpha=0.4")
        assert other is not bsdfspec.load_bsdf(spec)


def test09_a_file_path_with_blanks_or_as_path(variant_scalar_rgb, tmp_path):
    """The Python API takes a BSDF file as the CLI does: a str whose path has a blank (it was
    split as 'type key=value'), and a pathlib.Path (it was refused)."""
    folder = tmp_path / "my materials"
    folder.mkdir()
    path = folder / "gold metal.xml"
    path.write_text('<bsdf type="roughconductor"><string name="material" value="Au"/></bsdf>')
    for spec in (str(path), path):
        bsdf = bsdfspec.load_bsdf(spec)
        assert "RoughConductor" in str(bsdf) and "0.143036" in str(bsdf)  # gold's eta
        assert checks.check_consistency(spec, n=50).passed


def test10_an_xml_bsdf_is_named_by_its_type_and_parameters(variant_scalar_rgb):
    """Tables and legends name an XML BSDF as they name a dict (it was its first 60
    characters: '<bsdf type="roughconductor"> <float name="alpha" value="0.').."""
    xml = ('<bsdf type="roughconductor"><float name="alpha" value="0.3"/>'
           '<string name="material" value="Au"/>'
           '<texture type="bitmap" name="specular_reflectance"/></bsdf>')
    assert bsdfspec.describe(xml) == \
        "roughconductor(alpha=0.3, material=Au, specular_reflectance=bitmap)"
    assert bsdfspec.describe('<bsdf type="diffuse"/>') == "diffuse"


def test11_an_object_of_another_variant_or_no_bsdf_is_one_line(variant_scalar_rgb):
    """A BSDF loaded in scalar_rgb handed to a call that works in llvm_ad_rgb (fit, measure
    switch to it) was refused as "cannot make a BSDF from" its multi-line repr: one line now,
    naming both variants; a loaded texture is no BSDF, in one line too."""
    from conftest import LLVM_OK

    if not LLVM_OK:
        pytest.skip("no working libLLVM")
    texture = mi.load_dict({"type": "checkerboard"})
    with pytest.raises(MiBrdfsError, match="^a Checkerboard is not a BSDF$"):
        bsdfspec.parse(texture)
    loaded = [mi.load_dict({"type": "diffuse"}), mi.load_dict({"type": "lambert"})]
    mi_brdfs.use_variant("llvm_ad_rgb")
    for bsdf, name in zip(loaded, ("SmoothDiffuse", "Lambert")):
        with pytest.raises(MiBrdfsError) as info:
            bsdfspec.load_bsdf(bsdf)
        text = str(info.value)
        assert text.startswith(f"a {name} loaded in scalar_rgb cannot be used in llvm_ad_rgb")
        assert "\n" not in text, text


def test12_the_kind_of_a_plugin_warns_nothing(variants_rgb):
    """``plugin_kind`` instantiates a plugin at its defaults where Mitsuba cannot say (a Python
    plugin in the variant registered second): rpv's defaults create energy and warn at load, a
    warning about a BSDF the user did not give. It says BSDF and warns nothing, in both
    variants (one of them takes the instantiating path)."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert bsdfspec.plugin_kind("rpv") == "BSDF"
    assert not caught, [str(w.message) for w in caught]
