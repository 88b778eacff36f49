"""
The page of ``mi-brdfs explore`` (mi_brdfs.explorer.app), driven from Python as the browser
drives it (a slider's throttled value): the polar view and the XML follow a slider, a value the
plugin refuses shows its message on the page and changes nothing, two pages (two browser
sessions) keep their own state, and the server (``mi-brdfs explore``) answers on 127.0.0.1,
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


def _parts(page):
    import panel as pn

    """(the sliders by name, the polar plot's first data source, the XML pane, the message)."""
    sliders = {w.label: w for column in page[2] for w in getattr(column, "objects", [])
               if isinstance(w, pn.widgets.FloatSlider)}
    polar = page[3][0].object.renderers[0].data_source
    return sliders, polar, page[4], page[1]


def _move(slider, value):
    """What the browser does when a slider is released."""
    import param

    with param.edit_constant(slider):
        slider.value_throttled = value


def test01_a_slider_moves_the_views_and_the_xml(variant_llvm_ad_rgb, pn):
    from mi_brdfs.explorer.app import build

    page = build([GOLD])
    sliders, polar, xml, message = _parts(page)
    before = np.array(polar.data["y"])
    _move(sliders["alpha (log₁₀)"], -1.0)
    after = np.array(polar.data["y"])
    assert after.max() > 2 * before.max()  # a narrower lobe, a taller peak
    assert '<float name="alpha" value="0.1"/>' in xml.object
    assert not message.visible


def test02_a_refused_value_is_shown_on_the_page(variant_llvm_ad_rgb, pn):
    """η's red channel moved to 0 is refused by cooktorrance (η must be > 0): its message on
    the page, the views and the XML as they were."""
    from mi_brdfs.explorer.app import build

    page = build(["cooktorrance alpha=0.3 eta=1.5 k=0"])
    sliders, polar, xml, message = _parts(page)
    before, text = np.array(polar.data["y"]), xml.object
    eta = sliders["eta"]
    _move(eta, eta.start - 1.0)
    assert message.visible and "cooktorrance" in message.object
    np.testing.assert_array_equal(polar.data["y"], before)
    assert xml.object == text


def test03_two_pages_keep_their_own_state(variant_llvm_ad_rgb, pn):
    from mi_brdfs.explorer.app import build

    a, b = build([GOLD]), build([GOLD])
    _move(_parts(a)[0]["alpha (log₁₀)"], -1.0)
    assert 'value="0.1"' in _parts(a)[2].object and 'value="0.1"' not in _parts(b)[2].object
    assert a.session.entries[0].bsdf is not b.session.entries[0].bsdf


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _explore(*args):
    return subprocess.Popen([sys.executable, "-m", "mi_brdfs", "explore", "--no-browser", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, MI_BRDFS_NO_PROGRESS="1"))


def test04_the_server_serves_and_stops_on_sigterm(variant_llvm_ad_rgb, pn):
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


def test05_bad_input_ends_in_one_line_before_any_server(variant_llvm_ad_rgb, pn, capsys):
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
