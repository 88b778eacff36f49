"""
mi_brdfs.simplify and ``mi-brdfs simplify`` on a tiny scene (16² pixels, 8 spp): the BSDF
elements and their byte spans (nested, self-closing, in comments), a simplification re-measured
independently (the original and the simplified file rendered at other seeds and compared), the
bytes outside the replaced elements, lambert → diffuse at zero bias, a wrong candidate that
the measurement rejects and the independent re-measurement catches, the cache, and one-line
errors.
"""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import cli_one_line_error

import mi_brdfs
from mi_brdfs.cli import main
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.scenes import load_scene
from mi_brdfs.simplify import pipeline as simplify_pipeline  # simplify() calls candidates_for
from mi_brdfs.simplify import scene_bsdfs, simplify, splice

TOLERANCE = 0.05

#: A sphere under a white sky; in the llvm test also a card behind it, whose material is a
#: phong with a faint glossy lobe nested in a twosided.
TINY = """<?xml version="1.0" encoding="utf-8"?>
<!-- A tiny scene: <bsdf type="phong"> in this comment is no material -->
<scene version="3.0.0">
    <default name="res" value="24"/>
    <integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="28"/>
        <transform name="to_world">
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
    <shape type="sphere">
      <bsdf type="lambert" id="ball">
        <rgb name="reflectance" value="0.2, 0.5, 0.7"/>
      </bsdf>
    </shape>
CARD</scene>
"""

CARD = """    <shape type="rectangle">
        <transform name="to_world"><scale value="1.2"/><translate z="-1.5"/></transform>
        <bsdf type="twosided" id="card">
            <bsdf type="phong">
                <rgb name="diffuse_reflectance" value="0.6, 0.5, 0.4"/>
                <float name="specular_reflectance" value="0.01"/>
                <float name="exponent" value="20"/>
            </bsdf>
        </bsdf>
    </shape>
"""

SMALL = {"quick": True, "spp": 8, "defines": {"res": "16"}}


def write_scene(tmp_path, card: bool = False):
    path = tmp_path / "tiny.xml"
    path.write_text(TINY.replace("CARD", CARD if card else ""))
    return path


def remeasure(original, simplified, seeds=(11, 12), spp=256, res=32) -> tuple[float, float]:
    """
    (relative RMSE of the simplified file's render against the original's, the same between
    two seeds of the original: the noise floor), in llvm_ad_rgb, independent of
    mi_brdfs.simplify: plain renders of both files, seeds it never uses.
    """
    mi_brdfs.use_variant("llvm_ad_rgb")
    import mitsuba as mi

    def render(path, seed):
        scene = mi.load_file(str(path), res=str(res))
        return np.array(mi.render(scene, seed=seed, spp=spp), dtype=np.float64)

    a, a2, b = render(original, seeds[0]), render(original, seeds[1]), render(simplified, seeds[1])
    mean = float(np.mean(a))
    rel = lambda x, y: float(np.sqrt(np.mean((x - y) ** 2))) / mean
    return rel(a, b), rel(a, a2)


def outermost(data: bytes) -> list:
    """The BSDF elements not nested in another, in file order."""
    materials, _ = scene_bsdfs(data)
    out, end = [], -1
    for m in materials:
        if m.start >= end:
            out.append(m)
            end = m.end
    return out


def assert_rest_identical(original: bytes, simplified: bytes, replaced: set):
    """
    Every byte outside the outermost <bsdf> elements is the same in both files, and those
    elements are too, but for the ``replaced`` ones (by label of their outermost element).
    """
    old, new = outermost(original), outermost(simplified)
    assert [m.label for m in old] == [m.label for m in new]
    cuts = lambda data, ms: [data[a.end:b.start] for a, b in zip(ms, ms[1:])]
    assert original[:old[0].start] == simplified[:new[0].start]
    assert original[old[-1].end:] == simplified[new[-1].end:]
    assert cuts(original, old) == cuts(simplified, new)
    for a, b in zip(old, new):
        assert (a.text != b.text) == (a.label in replaced), a.label


def test01_bsdf_spans_nested_self_closing_and_comments():
    data = b"""<scene version="3.0.0">
    <!-- <bsdf type="lambert" id="commented"/> -->
    <bsdf type="diffuse" id="a&gt;b"/>
    <shape type="sphere">
        <bsdf type="blendbsdf" id="blend">
            <float name="weight" value="0.5"/>
            <bsdf type="phong" name="one"><float name="exponent" value="$n"/></bsdf>
            <bsdf type="twosided"><bsdf type="lambert"/></bsdf>
        </bsdf>
    </shape>
    <default name="n" value="7"/>
</scene>"""
    materials, defaults = scene_bsdfs(data)
    assert defaults == {"n": "7"}
    labels = [m.label for m in materials]
    assert labels == ["a>b", "blend", "phong in blend", "twosided in blend",
                      "lambert in twosided in blend"]
    assert [m.leaf for m in materials] == [True, False, True, False, True]
    for m in materials:
        assert data[m.start:m.end].decode() == m.text
        assert m.text.startswith("<bsdf") and m.text.endswith(("/>", "</bsdf>"))
        assert ET.fromstring(m.text).tag == "bsdf"
    assert materials[2].indent == " " * 12
    lam = materials[-1]
    assert splice(data, {(lam.start, lam.end): '<bsdf type="diffuse"/>'}) == \
        data.replace(b'<bsdf type="lambert"/>', b'<bsdf type="diffuse"/>')
    with pytest.raises(MiBrdfsError, match="not valid XML"):
        scene_bsdfs(b"<scene><bsdf></scene>")


def test02_scalar_lambert_to_diffuse_remeasured_independently(tmp_path):
    """
    scalar_rgb, where the Python lambert costs several times the built-in diffuse: the
    simplification replaces it (zero bias, faster), writes a file whose other bytes are the
    original's and that loads, and an independent render of it is within the tolerance.
    """
    mi_brdfs.use_variant("scalar_rgb")
    path = write_scene(tmp_path)
    out = tmp_path / "simplified.xml"
    result = simplify(path, TOLERANCE, output=out, cache=tmp_path / "cache", repeats=7, **SMALL)
    (ball,) = result.materials
    diffuse = next(c for c in ball.candidates if c.label == "diffuse")
    assert diffuse.bias < 1e-5 and diffuse.measured["noise"] < 1e-5
    assert ball.candidates[ball.chosen] is diffuse, result.summary()
    assert diffuse.measured["cost_ratio"] < 1
    assert result.verification.bias_hi < TOLERANCE and result.verification.speedup > 1

    original, simplified = path.read_bytes(), out.read_bytes()
    assert_rest_identical(original, simplified, {"ball"})
    (element,) = outermost(simplified)
    assert ET.fromstring(element.text).attrib == {"type": "diffuse", "id": "ball"}
    import mitsuba as mi
    mi.load_file(str(out), res="16")  # loads

    error, noise = remeasure(path, out)
    assert error <= TOLERANCE and noise <= TOLERANCE / 3, (error, noise)


def test03_llvm_cli_report_nested_and_cache(tmp_path, capsys, monkeypatch):
    """
    The command line in llvm_ad_rgb: the tables (nested phong included), SIMPLIFY.md, the plot
    and the simplified file; a rerun with another tolerance renders nothing new.
    """
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    path = write_scene(tmp_path, card=True)
    out, report = tmp_path / "out.xml", tmp_path / "report"
    code = main(["simplify", str(path), "--tolerance", str(TOLERANCE), "--quick", "--spp", "8",
                 "-D", "res=16", "-o", str(out), "--report", str(report), "--variant",
                 "llvm_ad_rgb"])
    printed = capsys.readouterr().out
    assert code == 0
    assert "### ball (`lambert`" in printed and "### phong in card (`phong`" in printed
    # (the row is in bold when timing noise makes the built-in measurably faster and chosen)
    assert "| diffuse | built-in | 0.0000" in printed.replace(" — the same model (lambert "
                                                            "computes what diffuse computes)",
                                                            "").replace("**", "")
    assert "diffuse: the glossy lobe left out" in printed
    text = (report / "SIMPLIFY.md").read_text()
    assert "## Materials" in text and "simplify.png" in text
    assert (report / "simplify.png").stat().st_size > 1000
    original, simplified = path.read_bytes(), out.read_bytes()
    replaced = {m.label for m in outermost(original)} - {"ball", "card"}
    assert not replaced
    changed = {a.label for a, b in zip(outermost(original), outermost(simplified))
               if a.text != b.text}
    assert_rest_identical(original, simplified, changed)
    import mitsuba as mi
    mi.load_file(str(out), res="16")
    error, _ = remeasure(path, out)
    assert error <= TOLERANCE, error

    # another tolerance: every candidate's measurement comes from the cache (as the module
    # promises, a candidate renders again only where its bounds straddle the new tolerance,
    # and the verification only where the choice changed: which it may, since the choice
    # depends on the timings' significance); the cache the command kept in the report's
    # folder, without a second report (its plot alone takes seconds)
    result = simplify(path, 0.1, cache=report / "cache", variant="llvm_ad_rgb", **SMALL)
    for c in (c for m in result.materials for c in m.candidates if c.ok and c.kind != "original"):
        assert c.cached or c.bias_lo <= 0.1 < c.bias_hi, c.label
    if result.renders:
        assert result.verification is not None and not result.verification.cached, \
            result.renders
    lobe = next(c for m in result.materials for c in m.candidates
                if c.label == "diffuse: the glossy lobe left out")
    assert lobe.cached and lobe.bias < 0.1


def test04_wrong_candidate_rejected_and_caught(tmp_path, monkeypatch):
    """
    A deliberately wrong candidate (lambert's "diffuse" with another reflectance): the
    simplification measures its bias above the tolerance and keeps the original, even when any
    speed-up would do (confidence 0); and the independent re-measurement of a file with that
    candidate exceeds the tolerance, so it would have caught it.
    """
    mi_brdfs.use_variant("scalar_rgb")
    real = simplify_pipeline.candidates_for

    def wrong(material, values, fit_fn):
        out = []
        for label, kind, element, note in real(material, values, fit_fn):
            if label == "diffuse":
                for child in element:
                    if child.get("name") == "reflectance":
                        child.set("value", "0.9, 0.9, 0.9")
            out.append((label, kind, element, note))
        return out

    monkeypatch.setattr(simplify_pipeline, "candidates_for", wrong)
    path = write_scene(tmp_path)
    out = tmp_path / "simplified.xml"
    result = simplify(path, TOLERANCE, output=out, cache=False, confidence=0, **SMALL)
    (ball,) = result.materials
    diffuse = next(c for c in ball.candidates if c.label == "diffuse")
    assert diffuse.bias_lo > TOLERANCE and diffuse.verdict == "over tolerance"
    assert ball.chosen == 0 and out.read_bytes() == path.read_bytes()

    (element,) = outermost(path.read_bytes())
    wrong_file = tmp_path / "wrong.xml"
    wrong_file.write_bytes(splice(path.read_bytes(), {(element.start, element.end):
                                                      diffuse.xml}))
    error, noise = remeasure(path, wrong_file)
    assert error > TOLERANCE > noise, (error, noise)


NO_BSDF = """<scene version="3.0.0"><integrator type="path"/>
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
    <integer name="height" value="8"/></film></sensor>
    <emitter type="constant"/><shape type="sphere"/></scene>"""

BAD = [
    (["simplify", "nosuch.xml"], "scene file nosuch.xml does not exist"),
    (["simplify", "nobsdf.xml"], "nobsdf.xml has no <bsdf>: nothing to simplify"),
    (["simplify", "tiny.xml", "--tolerance", "0"], "argument --tolerance: must lie in (0, 1)"),
    (["simplify", "tiny.xml", "--tolerance", "-0.01"], "--tolerance: must lie in (0, 1)"),
    (["simplify", "tiny.xml", "--tolerance", "nan"], "--tolerance: must lie in (0, 1)"),
    (["simplify", "tiny.xml", "--tolerance", "inf"], "--tolerance: must lie in (0, 1)"),
    (["simplify", "tiny.xml", "-o", "/nonexistent/x.xml"], "folder /nonexistent does not exist"),
    (["simplify", "tiny.xml", "-o", "x.txt"], "'x.txt' must end in .xml"),
    (["simplify", "tiny.xml", "--report", "/proc/x"], "report /proc/x: cannot create the folder"),
    (["simplify", "tiny.xml", "-D", "spp=4"], "tiny.xml declares no <default> for spp"),
    (["simplify", "tiny.xml", "--spp", "0"], "argument --spp: must be at least 1"),
    (["simplify", "tiny.xml", "-D", "res=0"], "tiny.xml: the film's width is 0"),
    (["simplify", "tiny.xml", "--confidence", "-1"], "confidence = -1.0 is invalid: must be a "
                                                     "finite number >= 0"),
]


@pytest.mark.parametrize("args,message", BAD, ids=[" ".join(a[1:]) for a, _ in BAD])
def test05_bad_input_one_line_exit_2(tmp_path, tmp_path_factory, monkeypatch, args, message):
    write_scene(tmp_path)
    (tmp_path / "nobsdf.xml").write_text(NO_BSDF)
    monkeypatch.chdir(tmp_path)
    xdg = tmp_path_factory.mktemp("xdg")
    monkeypatch.setenv("XDG_CACHE_HOME", str(xdg))
    cli_one_line_error(args, message)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nobsdf.xml", "tiny.xml"]
    assert not (xdg / "mi_brdfs" / "simplify").exists()  # no cache either


def test05b_one_line_after_many_variant_switches(tmp_path, monkeypatch):
    """drjit's warning after 1000 @dr.syntax decorations (Mitsuba's, at every JIT variant
    switch) once came out in the middle of a test session as a second line: the command line
    silences it (registry.quiet_drjit_syntax), even where the caller reset the filters."""
    import drjit.ast

    mi_brdfs.use_variant("scalar_rgb")  # the command switches to llvm_ad_rgb and back
    monkeypatch.setattr(drjit.ast, "_syntax_counter", 1000)
    cli_one_line_error(["simplify", str(write_scene(tmp_path)), "-D", "res=0"],
                       "tiny.xml: the film's width is 0")


@pytest.mark.parametrize("tolerance", [0, -1, math.nan, math.inf, "0.01", True])
def test06_api_tolerance(tmp_path, tolerance):
    with pytest.raises(MiBrdfsError, match=r"tolerance .* is invalid: must lie in \(0, 1\)"):
        simplify(write_scene(tmp_path), tolerance, cache=False)


def _fake_timings(monkeypatch, ratios):
    """Renders as they are, but the timing repeats (seeds 1000, 1001, ...) take 1 s for the
    original and ``ratios`` in turn for a candidate."""
    from mi_brdfs.simplify import measure

    mi_brdfs.use_variant("llvm_ad_rgb")
    real = measure._Engine._render

    def faked(self, scene, text, seed, spp):
        image, seconds = real(self, scene, text, seed, spp)
        if seed >= 1000:
            seconds = 1.0 if text == self.data else ratios[(seed - 1000) % len(ratios)]
        return image, seconds

    monkeypatch.setattr(measure._Engine, "_render", faked)


@pytest.mark.parametrize("ratios,kept", [((0.99, 0.991, 1.10), False), ((0.5, 0.52, 0.51), True)],
                         ids=["noisy-around-1", "consistently-faster"])
def test07_speedup_bars_from_the_spread_of_repeats(tmp_path, monkeypatch, ratios, kept):
    """
    Faked timings (the interleaved timing renders' seconds replaced; the images are real): the
    candidate/original ratio of each repeat is ``ratios``. Noisy around 1, two repeats agreeing
    by chance once gave bars far narrower than the spread, and a replacement that a rerun found
    slower: now the bars follow the spread of the repeats, and the candidate is not kept. A
    candidate consistently twice as fast is. (The objective speed: only a measurably faster
    candidate replaces; test21 runs the default, simplicity.)
    """
    _fake_timings(monkeypatch, ratios)
    result = simplify(write_scene(tmp_path), TOLERANCE, cache=False, fits=False, repeats=3,
                      objective="speed", **SMALL)
    (ball,) = result.materials
    diffuse = next(c for c in ball.candidates if c.label == "diffuse")
    assert diffuse.within and diffuse.measured["timing_ratios"] == pytest.approx(ratios)
    spread = float(np.std(np.log(ratios), ddof=1))
    assert diffuse.measured["cost_ratio_se"] >= spread / math.sqrt(3), diffuse.measured
    assert (ball.chosen != 0) == kept, result.summary()
    if not kept:
        assert diffuse.verdict == "within, not measurably faster", diffuse.verdict


def test08_a_flagged_fit_is_no_candidate(variant_llvm_ad_rgb):
    """A ward whose glossy lobe is the weaker gets a fitted lambert as a candidate; that fit
    ends at ρ = 1 (flagged: at the bound of its range), so it is listed as not offered, with
    the flag, instead of being measured as a replacement."""
    from mi_brdfs.simplify import FIT_SIZES, candidates, candidates_for, measure

    data = (b'<scene version="3.0.0"><bsdf type="ward" id="w">'
            b'<rgb name="diffuse_reflectance" value="0.4"/></bsdf></scene>')
    (material,), _ = scene_bsdfs(data)
    fit_fn = candidates._cached_fit(measure._Cache(None), FIT_SIZES[1])
    fits = [c for c in candidates_for(material, {}, fit_fn) if c[1] == "fit"]
    assert len(fits) == 1, fits
    label, _, element, note = fits[0]
    assert element is None and note.startswith("fit not offered: reflectance = 1 is at the "
                                               "upper bound 1"), (label, note)


#: Every form Mitsuba's XML allows for a material's parameters and place: rgb, spectrum,
#: textures, <ref>s to textures and to BSDFs, $defaults, wrappers (twosided, blendbsdf, mask),
#: a type chosen by a <default>, a built-in.
FORMS = b"""<scene version="3.0.0">
    <default name="a" value="0.3"/>
    <default name="mat" value="lambert"/>
    <texture type="checkerboard" id="checks"/>
    <bsdf type="cooktorrance" id="ct_rgb">
        <rgb name="diffuse_reflectance" value="0.2, 0.3, 0.4"/>
        <float name="alpha" value="$a"/>
    </bsdf>
    <bsdf type="cooktorrance" id="ct_spectrum">
        <spectrum name="diffuse_reflectance" value="0.2"/>
        <spectrum name="specular_reflectance" value="400:0.5, 700:0.7"/>
    </bsdf>
    <bsdf type="phong" id="ph_texture">
        <texture type="checkerboard" name="diffuse_reflectance"/>
        <rgb name="specular_reflectance" value="0.3"/>
    </bsdf>
    <bsdf type="ward" id="ward_ref"><ref name="diffuse_reflectance" id="checks"/></bsdf>
    <bsdf type="twosided" id="two"><ref id="ct_rgb"/></bsdf>
    <bsdf type="blendbsdf" id="blend">
        <float name="weight" value="0.5"/>
        <bsdf type="orennayar"><rgb name="reflectance" value="0.5"/></bsdf>
        <bsdf type="mask"><float name="opacity" value="0.5"/><bsdf type="lambert"/></bsdf>
    </bsdf>
    <bsdf type="$mat" id="chosen"/>
    <bsdf type="diffuse" id="builtin"/>
</scene>"""


def test09_every_xml_form_gets_candidates_or_a_reason(variant_llvm_ad_rgb):
    """
    simplify's candidates of every material of FORMS (no rendering): a cooktorrance whose
    diffuse_reflectance is an <rgb> once ended in a TypeError; now every material gets its
    candidates (the fits included), or the reason it has none.
    """
    materials, defaults = scene_bsdfs(FORMS)
    fits = []
    notes = []
    plans = simplify_pipeline._plans(materials, defaults,
                                     lambda *job: fits.append(job) or "fit skipped", notes)
    assert not notes, notes
    got = {mat.label: (cands, reason) for mat, cands, reason in plans}
    for label in ("ct_rgb", "ct_spectrum", "ph_texture", "orennayar in blend",
                  "lambert in mask in blend"):
        cands, reason = got[label]
        assert cands and not reason, (label, reason)
    assert {c[0] for c in got["ct_rgb"][0]} >= {"fresnel=schlick", "phong (fit)"}
    rho = next(model for target, model, _ in fits if target.get("alpha") == 0.3)
    assert rho["diffuse_reflectance"] == {"type": "rgb", "value": [0.2, 0.3, 0.4]}
    reasons = {label: reason for label, (cands, reason) in got.items() if not cands}
    assert reasons["two"].startswith("a wrapper of ct_rgb (<ref>)"), reasons
    assert reasons["blend"].startswith("a wrapper") and reasons["mask in blend"].startswith(
        "a wrapper"), reasons
    assert "its type is $mat, chosen by a <default>" in reasons["chosen"], reasons
    assert reasons["builtin"] == "a built-in of Mitsuba: no cheaper candidate", reasons
    assert "cannot read checks (a <ref> to an object defined apart)" in reasons["ward_ref"]


MATERIAL_FILE = """<scene version="3.0.0">
    <bsdf type="lambert" id="inc"><rgb name="reflectance" value="0.5, 0.4, 0.3"/></bsdf>
</scene>"""


def test10_materials_of_included_files_are_simplified(tmp_path, monkeypatch):
    """The materials of a file the scene <include>s (from a subfolder, as the bundled scenes
    do) are simplified too: the simplified file is written beside the output, every other byte
    kept, and the output includes it instead of the original, which is untouched (they were
    only named in the notes). A scene with no <bsdf> of its own is simplified through it."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "mat.xml").write_text(MATERIAL_FILE)
    text = TINY.replace("CARD", '    <include filename="sub/$m.xml"/>\n').replace(
        '<default name="res" value="24"/>', '<default name="res" value="24"/><default name="m" '
        'value="missing"/>')
    only = tmp_path / "only.xml"
    only.write_text(text.replace('<bsdf type="lambert" id="ball">', '<ref id="inc"/><!--')
                    .replace("</bsdf>\n    </shape>", "-->\n    </shape>"))
    out = tmp_path / "out.xml"
    _fake_timings(monkeypatch, (1.0, 1.0, 1.0))  # the choice, not a noisy timing, is tested
    # -D m=mat names the file: merged, nothing references $m, which Mitsuba would refuse
    result = simplify(only, TOLERANCE, output=out, cache=False, fits=False, repeats=3,
                      variant="scalar_rgb", **dict(SMALL, defines={"res": "16", "m": "mat"}))
    assert [m.label for m in result.materials] == ["inc"]
    material = result.materials[0]
    assert material.candidates[material.chosen].label.startswith("diffuse"), result.summary()
    assert (tmp_path / "sub" / "mat.xml").read_text() == MATERIAL_FILE
    written = (tmp_path / "out.mat.xml").read_text()
    element = MATERIAL_FILE[MATERIAL_FILE.index("<bsdf"):MATERIAL_FILE.index("</scene>") - 1]
    assert written.replace(written[written.index("<bsdf"):written.rindex("</bsdf>") + 7],
                           element) == MATERIAL_FILE
    assert 'type="diffuse"' in written and 'id="inc"' in written
    assert out.read_text() == only.read_text().replace('"sub/$m.xml"', '"out.mat.xml"')
    assert f"wrote {out} and {tmp_path / 'out.mat.xml'}" in result.summary()
    load_scene(out)  # as the command checks it


def test10b_included_files_left_alone_are_named(tmp_path):
    """A file included from another folder that names a file (its relative names would
    resolve elsewhere) is left alone and named in the notes; an output whose included file
    would overwrite a file the scene reads is refused before any work."""
    import mitsuba as mi

    (tmp_path / "sub").mkdir()
    mi_brdfs.use_variant("llvm_ad_rgb")
    mi.Bitmap(np.full((2, 2, 3), 0.5, dtype=np.float32)).write(str(tmp_path / "grey.exr"))
    (tmp_path / "sub" / "mat.xml").write_text(MATERIAL_FILE.replace(
        '<rgb name="reflectance" value="0.5, 0.4, 0.3"/>',
        f'<texture type="bitmap" name="reflectance"><string name="filename" '
        f'value="{tmp_path / "grey.exr"}"/></texture>'))
    mixed = tmp_path / "mixed.xml"
    mixed.write_text(TINY.replace("CARD", '    <include filename="sub/mat.xml"/>\n'))
    result = simplify(mixed, TOLERANCE, cache=False, fits=False, variant="llvm_ad_rgb", **SMALL)
    assert [m.label for m in result.materials] == ["ball"] and result.included == {}
    assert "note: materials in included file sub/mat.xml (inc (lambert)): left alone " \
           "(a file included from another folder that names files relative to it, or by an " \
           "included file, is not edited" in result.summary()
    for name in ("m.xml", "o.m.xml"):
        (tmp_path / name).write_text(MATERIAL_FILE.replace("inc", name))
    scene = tmp_path / "s.xml"
    scene.write_text(TINY.replace("CARD", '    <include filename="m.xml"/>\n'
                                          '    <include filename="o.m.xml"/>\n'))
    with pytest.raises(MiBrdfsError, match=r"the simplified m.xml would be written to "
                                           r"o.m.xml, which the scene reads"):
        simplify(scene, TOLERANCE, output=tmp_path / "o.xml", cache=False)
    assert not (tmp_path / "o.xml").exists()


def test10c_unmerge_puts_each_replacement_back_in_its_file(tmp_path):
    """merge_includes, locate and unmerge on bytes alone: the materials before, inside and
    after two included files are found where they are written (file and line, in the labels
    of unnamed ones), and replacements land in the file each came from, every other byte
    kept."""
    from mi_brdfs.simplify.scene import locate, merge_includes, unmerge

    (tmp_path / "a.xml").write_bytes(b'<?xml version="1.0"?>\n<scene version="3.0.0">'
                                     b'<bsdf type="diffuse"/></scene>\n')
    (tmp_path / "b.xml").write_bytes(b"<scene>\n<bsdf id='b' type='diffuse'/>\n<!-- b --></scene>")
    data = (b'<scene version="3.0.0"><bsdf id="m" type="diffuse"/>\n<include filename="a.xml"/>'
            b'<bsdf id="n" type="diffuse"/><include filename=\'$f\'></include>'
            b'<bsdf type="diffuse"/></scene>')
    merged, parts = merge_includes(tmp_path, data, {"f": "b.xml"})
    materials, _ = scene_bsdfs(merged)
    locate(materials, parts, data)
    assert [(m.label, m.file, m.line) for m in materials] == [
        ("m", None, 1), ("diffuse (line 2 of a.xml)", "a.xml", 2), ("n", None, 2),
        ("b", "b.xml", 2), ("diffuse (line 2)", None, 2)]
    new = {(m.start, m.end): f"<bsdf id='{i}' type='X'/>" for i, m in enumerate(materials)}
    scene, files = unmerge(data, parts, new, {p.file: "new-" + p.file.name for p in parts})
    assert scene == data.replace(b'id="m" type="diffuse"', b"id='0' type='X'").replace(
        b'id="n" type="diffuse"', b"id='2' type='X'").replace(
        b'<bsdf type="diffuse"/>', b"<bsdf id='4' type='X'/>").replace(
        b'"a.xml"', b'"new-a.xml"').replace(b"'$f'", b"'new-b.xml'")
    assert {p.name: text for p, text in files.items()} == {
        "a.xml": (tmp_path / "a.xml").read_bytes().replace(b'<bsdf type="diffuse"/>',
                                                            b"<bsdf id='1' type='X'/>"),
        "b.xml": b"<scene>\n<bsdf id='3' type='X'/>\n<!-- b --></scene>"}
    untouched, none = unmerge(data, parts, {}, {})
    assert untouched == data and none == {}


def test10d_a_define_the_replacement_no_longer_references(tmp_path, monkeypatch):
    """-D e=30 for a phong's exponent: its replacement (the glossy lobe left out: a diffuse)
    references $e no more, which Mitsuba refuses as an unused parameter: the candidate was
    'not measured' (and an output with it failed to load, 'declares no <default> for e')."""
    scene = tmp_path / "phong.xml"
    scene.write_text(TINY.replace("CARD", "").replace(
        '<default name="res" value="24"/>', '<default name="res" value="24"/>'
        '<default name="e" value="20"/>').replace(
        '<bsdf type="lambert" id="ball">\n        <rgb name="reflectance" value="0.2, 0.5, 0.7"/>',
        '<bsdf type="phong" id="ball"><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.7"/>'
        '<float name="specular_reflectance" value="0.002"/><float name="exponent" value="$e"/>'))
    out = tmp_path / "out.xml"
    _fake_timings(monkeypatch, (1.0, 1.0, 1.0))  # the choice, not a noisy timing, is tested
    result = simplify(scene, TOLERANCE, output=out, cache=False, fits=False, repeats=3,
                      variant="llvm_ad_rgb", **dict(SMALL, defines={"res": "16", "e": "30"}))
    (ball,) = result.materials
    assert ball.candidates[ball.chosen].kind != "original", result.summary()
    assert "$e" not in out.read_text() and result.output == out


#: ashikhmin and lafortune in the forms whose candidates differ (test11).
LOBES = b"""<scene version="3.0.0">
    <bsdf type="ashikhmin" id="ash_glossy">
        <float name="specular_reflectance" value="0.9"/>
        <float name="diffuse_reflectance" value="0.05"/>
    </bsdf>
    <bsdf type="ashikhmin" id="ash_diffuse">
        <rgb name="diffuse_reflectance" value="0.6, 0.5, 0.4"/>
        <float name="nu" value="10"/><float name="nv" value="100"/>
    </bsdf>
    <bsdf type="lafortune" id="laf_mirror">
        <float name="cx_0" value="-2"/><float name="cy_0" value="-2"/><float name="cz_0" value="2"/>
        <float name="exponent_0" value="50"/><rgb name="specular_reflectance_0" value="0.7"/>
        <float name="diffuse_reflectance" value="0.1"/>
    </bsdf>
    <bsdf type="lafortune" id="laf_three">
        <float name="diffuse_reflectance" value="0.3"/>
        <float name="cx_0" value="-1"/><float name="cy_0" value="-1"/>
        <float name="cz_0" value="0.8"/>
        <float name="specular_reflectance_0" value="0.4"/>
        <float name="cx_1" value="1"/><float name="cy_1" value="1"/><float name="cz_1" value="1"/>
        <float name="exponent_1" value="5"/><float name="specular_reflectance_1" value="0.02"/>
        <float name="exponent_2" value="300"/><float name="specular_reflectance_2" value="0.2"/>
    </bsdf>
</scene>"""


def test11_ashikhmin_and_lafortune_candidates(variant_llvm_ad_rgb):
    """
    Candidates without rendering: ashikhmin's diffuse term left out where it is the weaker
    (its glossy lobe never: F reaches 1 at grazing angles whatever Rs), a fitted lambert where
    the glossy lobe is the weaker; a lafortune's weakest term left out (its diffuse term, or
    the weakest of its lobes by the mean albedo at 15°, 45° and 75°), and a one-lobe mirror
    lafortune as phong, which evaluates to the same values.
    """
    from mi_brdfs.bsdfspec import load_bsdf
    from mi_brdfs.checks import batch
    from mi_brdfs.simplify import candidates_for

    materials, _ = scene_bsdfs(LOBES)
    got, fits = {}, {}
    for m in materials:
        jobs = []
        cands = candidates_for(m, {}, lambda *job: jobs.append(job) or "fit skipped")
        got[m.label] = {label: (element, note) for label, _, element, note in cands}
        fits[m.label] = jobs
    assert set(got["ash_glossy"]) == {"ashikhmin, diffuse term left out"}, got["ash_glossy"]
    element, note = got["ash_glossy"]["ashikhmin, diffuse term left out"]
    assert ET.tostring(element).count(b'name="diffuse_reflectance" value="0.0"') == 1
    assert note.startswith("albedo at 45°: diffuse 0.00") and fits["ash_glossy"] == []
    assert set(got["ash_diffuse"]) == {"lambert (fit)"}, got["ash_diffuse"]
    assert fits["ash_diffuse"][0][1] == {"type": "lambert",
                                         "reflectance": {"type": "rgb", "value": [0.6, 0.5, 0.4]}}

    assert set(got["laf_mirror"]) == {"phong", "lafortune, diffuse term left out"}
    phong = ET.tostring(got["laf_mirror"]["phong"][0], encoding="unicode")
    assert phong.startswith('<bsdf type="phong" id="laf_mirror">') and "_0" not in phong
    wi, wo = (batch.random_directions(np.random.default_rng(1), 4096, sphere=False)
              for _ in range(2))
    original = batch.evaluate(load_bsdf(materials[2].text), wi, wo).value
    assert np.array_equal(batch.evaluate(load_bsdf(phong), wi, wo).value, original)

    assert set(got["laf_three"]) == {"lafortune, lobe 1 left out", "lambert (fit)"}
    element, note = got["laf_three"]["lafortune, lobe 1 left out"]
    assert note.startswith("mean albedo at 15°, 45°, 75°: diffuse 0.3"), note
    assert _params_of(element)["specular_reflectance_1"] == "0.0"
    load_bsdf(ET.tostring(element, encoding="unicode"))


def _params_of(element) -> dict:
    return {c.get("name"): c.get("value") for c in element}


MULTISCATTER = b"""<scene version="3.0.0">
    <bsdf type="cooktorrance" id="compensated">
        <boolean name="multiscatter" value="true"/>
        <string name="distribution" value="ggx"/>
        <string name="shadowing" value="smith"/>
        <float name="alpha" value="0.8"/>
        <string name="material" value="Au"/>
    </bsdf>
</scene>"""


def test12_multiscatter_can_be_dropped(variant_llvm_ad_rgb):
    """A compensated cooktorrance gets ``multiscatter=false`` (single scattering: it loads and
    evaluates below the compensated one) and roughconductor, said to lack the compensation."""
    from mi_brdfs.bsdfspec import load_bsdf
    from mi_brdfs.checks import batch
    from mi_brdfs.simplify import candidates_for

    (material,), _ = scene_bsdfs(MULTISCATTER)
    got = {label: (element, note) for label, _, element, note in
           candidates_for(material, {}, lambda *job: "fit skipped")}
    element, note = got["multiscatter=false"]
    assert _params_of(element)["multiscatter"] == "false" and "compensation" in note
    wi, wo = (batch.random_directions(np.random.default_rng(2), 4096, sphere=False)
              for _ in range(2))
    single = batch.evaluate(load_bsdf(ET.tostring(element, encoding="unicode")), wi, wo).value
    both = batch.evaluate(load_bsdf(material.text), wi, wo).value
    assert np.all(single <= both) and np.any(single < both)
    rough, note = got["roughconductor"]
    assert "multiscatter" not in _params_of(rough) and note.startswith("single scattering")


GLASS_MULTISCATTER = b"""<scene version="3.0.0">
    <bsdf type="cooktorrance" id="glass">
        <boolean name="transmission" value="true"/>
        <boolean name="multiscatter" value="true"/>
        <float name="eta" value="1.5"/>
        <float name="alpha" value="0.7"/>
    </bsdf>
</scene>"""


def test13_dielectric_multiscatter_can_be_dropped(variant_llvm_ad_rgb):
    """A compensated rough glass gets ``multiscatter=false`` and roughdielectric, said to be
    single scattering, which loads (the compensation's parameter left out)."""
    from mi_brdfs.bsdfspec import load_bsdf
    from mi_brdfs.simplify import candidates_for

    (material,), _ = scene_bsdfs(GLASS_MULTISCATTER)
    got = {label: (element, note) for label, _, element, note in
           candidates_for(material, {}, lambda *job: "fit skipped")}
    assert _params_of(got["multiscatter=false"][0])["multiscatter"] == "false"
    rough, note = got["roughdielectric"]
    assert "multiscatter" not in _params_of(rough) and note.startswith("single scattering")
    load_bsdf(ET.tostring(rough, encoding="unicode"))


def test20_quick_keeps_a_smaller_declared_resolution(tmp_path):
    """--quick renders at QUICK_RES at most: a scene that declares res = 32 keeps 32 (it was
    raised to 128), one that declares 512 renders at 128, an explicit define wins."""
    path = tmp_path / "s.xml"
    path.write_text("<scene/>")
    for declared, wanted in (("32", "32"), ("512", str(simplify_pipeline.QUICK_RES))):
        defines, _ = simplify_pipeline._defines(path, None, {"res": declared}, True)
        assert defines["res"] == wanted
    assert simplify_pipeline._defines(path, {"res": 700}, {"res": "32"}, True)[0]["res"] == "700"


@pytest.mark.parametrize("ratios,kept", [((0.99, 0.991, 1.10), True), ((2.0, 2.1, 1.95), False)],
                         ids=["noisy-around-1", "consistently-slower"])
def test21_simplicity_replaces_by_a_simpler_candidate_not_slower(tmp_path, monkeypatch, ratios,
                                                                 kept):
    """The default objective: lambert's built-in twin (diffuse: simpler, the same model) within
    the tolerance replaces it when it is not measurably slower, timings noisy around 1
    included (which the speed objective keeps: test07), and the reason says why; twice as
    slow, it does not replace."""
    _fake_timings(monkeypatch, ratios)
    result = simplify(write_scene(tmp_path), TOLERANCE, cache=False, fits=False, repeats=3,
                      **SMALL)
    (ball,) = result.materials
    assert ball.chosen != 0 if kept else ball.chosen == 0, result.summary()
    diffuse = next(c for c in ball.candidates if c.label == "diffuse")
    if kept:
        assert "simpler: Mitsuba's built-in of the same model" in ball.reason, ball.reason
    else:
        assert diffuse.verdict == "within, simpler, measurably slower", diffuse.verdict


def test22_choice_and_agreement_on_synthetic_candidates():
    """The rule on made-up numbers: of two simpler candidates not measurably slower, the
    faster; a swap of one feature for another (the distribution) is not simpler, however fast;
    predicted and measured speed-ups 3 standard errors apart are said not to agree."""
    from types import SimpleNamespace

    from mi_brdfs.simplify.choose import _choose
    from mi_brdfs.simplify.report import Candidate, MaterialResult, agreement

    def cand(label, kind, speedup, time):
        c = Candidate(label, kind, measured={"seeds": 2})
        c.within, c.bias, c.bias_lo, c.speedup, c.speedup_se = True, 0.001, 0.0, speedup, 0.02
        c.time_to_tolerance = time
        return c

    r = MaterialResult(SimpleNamespace(leaf=True, label="m"), [
        Candidate("original", "original", measured={"seeds": 2}),
        cand("distribution=ggx", "switch", 1.5, 0.5),
        cand("roughconductor", "built-in", 1.0, 1.0),
        cand("multiscatter=false", "switch", 1.2, 0.8)])
    _choose(r, 0.01, 2.0)
    assert r.candidates[r.chosen].label == "multiscatter=false", r.reason
    assert r.candidates[1].verdict == "within, not simpler"
    _choose(r, 0.01, 2.0, "speed")
    assert r.candidates[r.chosen].label == "distribution=ggx"
    measured = SimpleNamespace(speedup=1.005, speedup_se=0.029)
    assert "DO NOT agree" in agreement({"speedup": 1.093, "speedup_se": 0.030}, measured, 2.0)
    assert "agree within" in agreement({"speedup": 1.02, "speedup_se": 0.030}, measured, 2.0)


def test23_every_plugin_of_ours_gets_candidates_or_its_own_reason(variant_llvm_ad_rgb):
    """Every plugin of the registry is ours to simplify: merl and he once read "is not a plugin
    of mi_brdfs" (a list typed by hand); now each gets candidates, or, where none applies in
    any configuration (measured data, He et al.'s model), says so and how to find a cheaper
    model. A plugin of no package still gets that line, listing the registry's plugins."""
    scene = "".join(f'<bsdf type="{name}" id="{name}"/>' for name in mi_brdfs.PLUGINS)
    scene = f'<scene version="3.0.0">{scene}<bsdf type="nosuch" id="nosuch"/></scene>'
    materials, defaults = scene_bsdfs(scene.encode())
    plans = simplify_pipeline._plans(materials, defaults, None, [])
    reasons = {mat.label: reason for mat, cands, reason in plans if not cands}
    for name in mi_brdfs.PLUGINS:
        assert "not a plugin of mi_brdfs" not in reasons.get(name, ""), (name, reasons[name])
    for name in ("merl", "he"):
        assert reasons[name].startswith(f"simplify has no candidates for {name} ("), reasons
        assert "mi-brdfs fit TARGET --models all" in reasons[name], reasons
    assert reasons["nosuch"] == (f"nosuch is not a plugin of mi_brdfs "
                                 f"({', '.join(mi_brdfs.PLUGINS)}): simplify has no candidates "
                                 f"for it"), reasons
