"""
The page of ``mi-brdfs explore`` (mi_brdfs.explorer.app), driven from Python as the browser
drives it (a slider's throttled value, a typed field, a menu, the fit button): every view of
the BSDF changed follows, and only its; a value the plugin refuses shows its message on the
page and changes nothing; two pages (two browser sessions) keep their own state; the server (``mi-brdfs explore``) answers on 127.0.0.1,
refuses a port in use and an unknown BSDF in one line before it starts, and stops on SIGTERM.
"""

import os
import signal
import socket
import subprocess
import sys
import urllib.request

import numpy as np
import pytest


@pytest.fixture
def pn():
    """Panel, where the explore extra is installed (imported by the tests that use it: the
    import takes seconds, which a worker that runs none of them should not pay)."""
    return pytest.importorskip("panel")

GOLD = "cooktorrance alpha=0.3 material=Au"


def _move(widget, value):
    """What the browser does when a slider is released."""
    import param

    with param.edit_constant(widget):
        widget.value_throttled = value


def _views(x) -> dict:
    """What each view of BSDF 0 and 1 shows now, as arrays (copies)."""
    f = x.figures
    out = {}
    for i in range(len(x.session.entries)):
        out[("polar", i)] = np.array(f.polar_src[i].data["y"])
        out[("albedo", i)] = np.array(f.albedo_src[i].data["e"])
        out[("slice", i)] = np.array(f.slices[i][1].data["image"][0])
        out[("density", i)] = np.array(f.densities[i][1].data["image"][0])
        out[("lobe", i)] = np.array(x.data[i]["lobe"][2])
        out[("sphere", i)] = np.array(f.spheres[i][1].data["image"][0])
    return out


def _same(a, b) -> bool:
    return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))


def test01_a_slider_moves_every_view_of_its_bsdf(variant_llvm_ad_rgb, pn):
    """α of the first BSDF moved on its slider: its polar curve, albedo, 3-D lobe, slice,
    sampling density and sphere change, the second BSDF's views do not; the field, the XML and
    the Python follow; the timer then computes the verdicts, the cost per sample and further
    passes of the spheres."""
    from mi_brdfs.explorer.app import build

    page = build([GOLD, "lambert"])  # a second BSDF, cheap to trace
    x = page.explorer
    before, drawn = _views(x), np.concatenate(x.figures.lobe_src.data["ys"])
    (slider,), (field,) = x.sliders[(0, "alpha.value")]
    _move(slider, -1.0)
    after = _views(x)
    assert not _same(drawn, np.concatenate(x.figures.lobe_src.data["ys"]))  # the lobe drawn
    for (view, i), old in before.items():
        assert _same(old, after[(view, i)]) == (i == 1), (view, i)
    assert after[("polar", 0)].max() > 2 * before[("polar", 0)].max()  # narrower, taller
    assert field.value == "0.1" and not x.message.visible
    assert '<float name="alpha" value="0.1"/>' in x.code["xml"].object
    assert "'alpha': 0.1" in x.raw["python"].value
    for _ in range(3):  # verdicts of each BSDF, then the cost per sample
        x.tick()
    assert x.verdicts.object.count("✔") == 8 and "cost per sample" in x.verdicts.object
    passes = x.spheres.passes
    x.tick()
    assert x.spheres.passes == passes + 1


def test02_a_refused_value_is_shown_on_the_page(variant_llvm_ad_rgb, pn):
    """Text typed into α's field, and α = −1, are refused on the page in one line (the
    second in cooktorrance's own words); the views and the XML stay as they were."""
    from mi_brdfs.explorer.app import build

    x = build([GOLD]).explorer
    before, text = _views(x), x.code["xml"].object
    field = x.sliders[(0, "alpha.value")][1][0]
    for typed, words in (("rough", "expected a number"),
                         ("-1", 'cooktorrance: parameter "alpha" = -1')):
        field.value = typed
        assert x.message.visible and words in x.message.object
        assert len(x.message.object.splitlines()) == 1
    assert all(_same(v, _views(x)[k]) for k, v in before.items())
    assert x.code["xml"].object == text
    field.value = "0.2"
    assert not x.message.visible and 'value="0.2"' in x.code["xml"].object


def test03_a_switch_menu_reloads_the_plugin(variant_llvm_ad_rgb, pn):
    """The distribution menu set to GGX: a new plugin object in the session and in its
    sphere, the views redrawn (GGX's longer tail), the XML naming it."""
    from mi_brdfs.explorer.app import build

    x = build([GOLD]).explorer
    menu = next(w for w in x.columns[0].objects if getattr(w, "label", "") == "distribution")
    old, before = x.session.entries[0].bsdf, _views(x)
    menu.value = "ggx"
    entry = x.session.entries[0]
    assert entry.bsdf is not old and x.spheres.bsdfs[0] is entry.bsdf
    assert not _same(before[("polar", 0)], _views(x)[("polar", 0)])
    assert '<string name="distribution" value="ggx"/>' in x.code["xml"].object


def test09_the_polar_plot_at_several_incident_angles(variant_llvm_ad_rgb, pn):
    """Two other θi typed: each BSDF gets their curves (the lobe at 60° is the polar view's
    at 60°), none gives none back; a text that is no list of angles is refused on the
    page."""
    from mi_brdfs.explorer.app import build

    x = build([GOLD]).explorer
    assert x.set_view(more="0, 60")
    main, (at0, at60, unused) = x.figures.polar_src[0], x.figures.polar_more[0]
    theta_o, (want,) = x.session.polar(60.0)
    t = np.radians(theta_o)
    np.testing.assert_allclose(at60.data["y"], want * np.cos(t), rtol=1e-6, atol=1e-9)
    assert len(at0.data["y"]) == len(main.data["y"]) and len(unused.data["y"]) == 0
    for bad in ("sixty", "95", "1, 2, 3, 4"):
        assert not x.set_view(more=bad) and "other θi" in x.message.object
    assert x.set_view(more="") and len(at60.data["y"]) == 0 and not x.message.visible


def test10_the_light_moves_and_changes_kind(variant_llvm_ad_rgb, pn):
    """The light moved, then made a point light: the sphere is rendered anew each time (its
    first pass), with the new light: the images differ."""
    from mi_brdfs.explorer.app import build

    x = build(["lambert"]).explorer
    image = lambda: np.array(x.figures.spheres[0][1].data["image"][0])  # noqa: E731
    before = image()
    x.set_view(light=(60.0, 180.0))
    moved = image()
    assert x.spheres.passes == 1 and not _same(before, moved)
    x.set_view(light_kind="point")
    assert x.spheres.light == "point" and x.spheres.passes == 1 and not _same(moved, image())


def test11_a_colour_picked_is_the_reflectance_in_linear_rgb(variant_llvm_ad_rgb, pn):
    """A reflectance has a colour picker: #808080 picked sets ρ = 0.2158 in each channel
    (sRGB 128/255 linearised, IEC 61966-2-1), once (the field and sliders that follow it set
    nothing again); the slider's move shows in the picker."""
    from mi_brdfs.explorer.app import build

    x = build(["lambert reflectance=0.5,0.5,0.5"]).explorer
    (r, g, b), (field, picker) = x.sliders[(0, "reflectance.value")]
    calls = []
    original = x.set_parameter
    x.set_parameter = lambda *a: calls.append(a) or original(*a)
    picker.value = "#808080"
    assert len(calls) == 1
    np.testing.assert_allclose(x.session.entries[0].controls["reflectance.value"].value,
                               [0.21586] * 3, rtol=1e-4)
    assert field.value == "0.2159, 0.2159, 0.2159" and r.value == pytest.approx(0.21586, 1e-4)
    _move(g, 1.0)
    assert len(calls) == 2 and picker.value == "#80ff80"


def test12_what_the_plugin_says_is_shown_beside_the_bsdf(variant_llvm_ad_rgb, pn):
    """Ward reflecting 1.1 > 1: its plugin's warning is on the page (not in the terminal),
    and goes when a typed ρs brings the sum below 1."""
    from mi_brdfs.explorer.app import build

    x = build(["ward diffuse_reflectance=0.6 specular_reflectance=0.5"]).explorer
    assert x.said.visible and "**1: ward(" in x.said.object and "1.1 > 1" in x.said.object
    x.sliders[(0, "specular_reflectance.value")][1][0].value = "0.2"
    assert not x.said.visible and not x.message.visible


def test04_two_pages_keep_their_own_state(variant_llvm_ad_rgb, pn):
    from mi_brdfs.explorer.app import build

    a, b = build([GOLD]).explorer, build([GOLD]).explorer
    _move(a.sliders[(0, "alpha.value")][0][0], -1.0)
    assert 'value="0.1"' in a.code["xml"].object and 'value="0.1"' not in b.code["xml"].object
    assert a.session.entries[0].bsdf is not b.session.entries[0].bsdf


def test08_the_notebook_entry_gives_the_same_page(variant_llvm_ad_rgb, pn):
    """``mi_brdfs.explore`` (a notebook's entry) returns the page as a Panel layout for the
    BSDFs given, a bundled scene in place of the sphere included; a scene without the id of
    its BSDF, or a scalar variant, is refused in one line."""
    import mi_brdfs
    from mi_brdfs.errors import MiBrdfsError

    page = mi_brdfs.explore(GOLD, scene="material", scene_bsdf="material")
    assert isinstance(page, pn.layout.Column) and page.explorer.spheres.light is None
    assert page.session.entries[0].name == "cooktorrance(alpha=0.3, material=Au)"
    assert page.explorer.figures.spheres[0][1].data["image"][0].shape[0] > 2  # a first pass
    with pytest.raises(MiBrdfsError, match="needs the id of the BSDF"):
        mi_brdfs.explore(GOLD, scene="material")
    with pytest.raises(MiBrdfsError, match="needs a JIT variant"):
        mi_brdfs.explore(GOLD, variant="scalar_rgb")


def test07_the_fit_button_fits_the_second_bsdf(variant_llvm_ad_rgb, pn):
    """Fit: the second BSDF (Mitsuba's roughconductor, α = 0.6) fitted to the first (our
    cooktorrance, α = 0.2, the same GGX and gold) comes out at α = 0.2, and is shown."""
    from mi_brdfs.explorer.app import build

    x = build(["cooktorrance alpha=0.2 material=Au distribution=ggx shadowing=smith",
               "roughconductor alpha=0.6 material=Au distribution=ggx"]).explorer
    assert x.fit()
    model = x.session.entries[1]
    assert float(model.params["alpha.value"][0]) == pytest.approx(0.2, rel=0.05)
    assert x.spheres.bsdfs[1] is model.bsdf and "fit" in x.fit_result.object


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _explore(*args):
    return subprocess.Popen([sys.executable, "-m", "mi_brdfs", "explore", "--no-browser", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, MI_BRDFS_NO_PROGRESS="1"))


def test05_the_server_serves_and_stops_on_sigterm(variant_llvm_ad_rgb, pn):
    """The page answers 200 on 127.0.0.1 at the port printed; SIGTERM stops the server within
    5 s with exit status 0."""
    port = _free_port()
    proc = _explore("--port", str(port), GOLD)
    try:
        line = proc.stdout.readline()
        assert f"http://localhost:{port}/" in line, line + proc.stderr.read()
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=60) as r:
            assert r.status == 200 and b"bokeh" in r.read().lower()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=5) == 0
    finally:
        proc.kill()


def test06_bad_input_ends_in_one_line_before_any_server(variant_llvm_ad_rgb, pn, capsys):
    """A port in use, an unknown plugin, five BSDFs, a scalar variant: one line each on
    stderr, exit status 2, nothing on stdout (no server started)."""
    from mi_brdfs.cli import main

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        cases = [(["--port", str(port), "lambert"], "cannot listen on 127.0.0.1"),
                 (["nosuchplugin"], "unknown plugin 'nosuchplugin'"),
                 (["lambert"] * 5, "at most 4 BSDFs"),
                 (["--variant", "scalar_rgb", "lambert"], "needs a JIT variant")]
        for args, hint in cases:
            assert main(["explore", "--no-browser", *args]) == 2, args
            out, err = capsys.readouterr()
            lines = err.strip().splitlines()
            assert out == "" and len(lines) == 1 and hint in lines[0], (args, out, err)
