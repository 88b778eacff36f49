"""
``mi-brdfs explore`` in a real browser: the server started as a user starts it, its page driven
in Debian's headless Chromium by Selenium as a user drives it (a slider's handle dragged with the
mouse, a value typed into a field and Enter), what the page shows read back from the browser
(screenshots of the views, the text of the XML fragment and of the message). One server and one
browser, in one test (pytest-xdist would start them once per worker for several tests).

Skipped, with the reason, where Chromium, ChromeDriver (Debian's ``chromium`` and
``chromium-driver``, which ``tools/setup-system.sh`` installs as root), Selenium (the ``test``
extra) or a working libLLVM (the explorer needs a JIT variant) is missing.
"""

import io
import math
import re

import numpy as np
import pytest

import explore_page as page
from explore_page import VIEWS, find, one, shown, text, until

GOLD = "cooktorrance alpha=0.3 material=Au"

#: Seconds to wait for a page's first drawing (a new session traces its views' kernels) and
#: for a change to show.
LOAD_S, CHANGE_S = 60.0, 15.0

#: Mean absolute difference (8-bit levels) above which a view's screenshot has changed: the
#: plots are drawn the same until their data change; the sphere refines pass after pass, by
#: well under a level once it has settled (measured: 0.02), while a change of the BSDF moves
#: it by several.
CHANGED = {"mb-sphere": 1.0}
CHANGED_PLOT = 0.05


@pytest.fixture
def server(tmp_path):
    """``mi-brdfs explore`` of the gold Cook-Torrance, stopped with SIGTERM however the test
    ends."""
    import importlib.util

    import mi_brdfs

    if importlib.util.find_spec("panel") is None:  # (the server imports it, not this test)
        pytest.skip("panel is not installed (pip install -e '.[explore]')")
    if not mi_brdfs.llvm_usable():
        pytest.skip("no working libLLVM: mi-brdfs explore needs a JIT variant")
    why = page.missing()
    if why:
        pytest.skip(why)
    server = page.Server([GOLD], tmp_path / "server-stderr.txt")
    yield server
    server.stop()


#: The window: tall enough for the whole page of one BSDF, which one screenshot then shows.
WINDOW = (1400, 2800)


@pytest.fixture
def browser(server):
    """Headless Chromium, quit however the test ends."""
    with page.chromium(*WINDOW) as driver:
        yield driver


def test01_the_page_in_chromium(server, browser):
    """The page loads with no console error and no traceback; a dragged slider redraws every
    view and the XML follows it; a bad value typed into a field is refused on the page (the
    server prints no traceback); two windows (two sessions) keep their own BSDF."""
    first = _loads(browser, server.url)
    _a_dragged_slider_redraws_the_views_and_the_xml(browser)
    _a_bad_value_is_refused_on_the_page(browser, server)
    _two_windows_keep_their_own_state(browser, server.url, first)
    assert _console_errors(browser) == []
    assert "Traceback" not in server.errors(), server.errors()


def _loads(driver, url):
    """Open ``url``, wait for every view and the XML; no error in the console or on the
    page. The window's handle."""
    driver.get(url)
    page.drawn(driver, LOAD_S)  # fails at once where the page shows a traceback
    assert _console_errors(driver) == []
    assert not shown(driver, one(driver, "mb-alert"))
    assert _xml_number(driver, "alpha") == 0.3
    return driver.current_window_handle


def _a_dragged_slider_redraws_the_views_and_the_xml(driver):
    """Drag alpha's handle 60 px to the left: every view's picture changes, the XML gives
    alpha = 10^(the slider's value), the field shows it."""
    _settled(driver)
    before, same = _pictures(driver), []
    handle = one(driver, "noUi-handle", _slider(driver, "alpha (log₁₀)"))
    from selenium.webdriver.common.action_chains import ActionChains

    ActionChains(driver).click_and_hold(handle).move_by_offset(-60, 0).release().perform()

    def redrawn():
        now = _pictures(driver)
        same[:] = [cls for cls in VIEWS
                   if _difference(before[cls], now[cls]) <= CHANGED.get(cls, CHANGED_PLOT)]
        return not same
    try:
        until(redrawn, CHANGE_S, "every view redrawn after the slider")
    except AssertionError:
        raise AssertionError(f"not redrawn within {CHANGE_S:g} s after the slider: "
                             f"{', '.join(same)}") from None
    shown_value = float(text(driver, one(driver, "bk-slider-value",
                                         _slider(driver, "alpha (log₁₀)"))))
    assert shown_value < math.log10(0.3) - 0.5  # dragged to the left, far
    alpha = until(lambda: _xml_number(driver, "alpha") != 0.3 and _xml_number(driver, "alpha"),
                  CHANGE_S, "the XML's alpha after the slider")
    assert math.log10(alpha) == pytest.approx(shown_value, abs=1e-3)
    assert float(_field(driver, "alpha").get_attribute("value")) == pytest.approx(alpha,
                                                                                  rel=1e-3)


def _a_bad_value_is_refused_on_the_page(driver, server):
    """-1 and 'abc' typed as alpha: the message on the page names the parameter and the
    value, the XML keeps the last good alpha; then 0.1 is taken and the message goes."""
    alert, kept = one(driver, "mb-alert"), _xml_number(driver, "alpha")
    for bad in ("-1", "abc"):
        _type(driver, "alpha", bad)
        until(lambda: shown(driver, alert) and bad in text(driver, alert), CHANGE_S,
              f"the message for alpha = {bad} on the page")
        assert "alpha" in text(driver, alert)
        assert _xml_number(driver, "alpha") == kept
    _type(driver, "alpha", "0.1")
    until(lambda: _xml_number(driver, "alpha") == 0.1, CHANGE_S, "alpha = 0.1 typed, taken")
    until(lambda: not shown(driver, alert), CHANGE_S, "the message gone after a good value")
    assert "Traceback" not in server.errors(), server.errors()


def _two_windows_keep_their_own_state(driver, url, first):
    """A second window starts from the BSDF given, not the first window's; a value typed in
    each shows in its own XML only."""
    driver.switch_to.new_window("window")
    second = driver.current_window_handle
    driver.get(url)
    until(lambda: find(driver, "mb-xml") and _xml_number(driver, "alpha"), LOAD_S,
          "the second window's XML")  # its views drawing meanwhile
    assert _xml_number(driver, "alpha") == 0.3  # though the first window has 0.1
    _type(driver, "alpha", "0.5")
    until(lambda: _xml_number(driver, "alpha") == 0.5, CHANGE_S, "alpha = 0.5 in window 2")
    driver.switch_to.window(first)
    _type(driver, "specular_reflectance", "0.25")
    until(lambda: _xml_number(driver, "specular_reflectance") == 0.25, CHANGE_S,
          "specular_reflectance = 0.25 in window 1")
    assert _xml_number(driver, "alpha") == 0.1
    driver.switch_to.window(second)
    assert _xml_number(driver, "alpha") == 0.5
    assert _xml_number(driver, "specular_reflectance") != 0.25


# -- reading and driving the page ---------------------------------------------------------------
def _console_errors(driver) -> list:
    return [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def _xml_number(driver, name):
    """The value of ``<float name="name" value="..."/>`` in the XML fragment, or None."""
    found = re.search(rf'<float name="{name}" value="([^"]+)"', text(driver, one(driver,
                                                                                "mb-xml")))
    return float(found.group(1)) if found else None


def _slider(driver, label):
    """The slider of the controls labelled ``label``."""
    sliders = [s for s in find(driver, "bk-Slider", one(driver, "mb-controls"))
               if text(driver, one(driver, "bk-slider-title", s)).startswith(label + ":")]
    assert len(sliders) == 1, f"{len(sliders)} sliders labelled {label!r}"
    return sliders[0]


def _field(driver, name):
    """The ``<input>`` of the field of parameter ``name``."""
    fields = [f for f in find(driver, "mb-field") if text(driver, f).strip() == name]
    assert len(fields) == 1, f"{len(fields)} fields for {name!r}"
    return driver.execute_script("return arguments[0].shadowRoot.querySelector('input')",
                                 fields[0])


def _type(driver, name, value):
    """Type ``value`` into the field of ``name`` and press Enter."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    field = _field(driver, name)
    # the keyboard's keys, as a user presses them (an element's send_keys puts the caret at
    # the end of an <input> in a shadow root, which it takes for unfocused)
    ActionChains(driver).click(field).key_down(Keys.CONTROL).send_keys("a") \
        .key_up(Keys.CONTROL).send_keys(value).perform()
    assert field.get_attribute("value") == value
    ActionChains(driver).send_keys(Keys.ENTER).perform()


def _pictures(driver) -> dict:
    """{view's class: its pixels, an (h, w, 3) float array}, cut from one screenshot of the
    window (one for the six views: Chromium encodes each screenshot as a PNG)."""
    from PIL import Image

    fits = driver.execute_script(
        "return document.documentElement.scrollHeight <= window.innerHeight")
    assert fits, f"the page is taller than the window {WINDOW}: make WINDOW taller"
    image = np.asarray(Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert("RGB"),
                       np.float64)
    out = {}
    for cls, found in page.rects(driver, VIEWS).items():
        assert len(found) == 1, f"{len(found)} elements of class {cls!r} on the page, not 1"
        r = found[0]
        x, y = round(r["x"]), round(r["y"])
        out[cls] = image[y:y + round(r["height"]), x:x + round(r["width"])]
    return out


def _difference(a, b) -> float:
    return float(np.abs(a - b).mean()) if a.shape == b.shape else math.inf


def _settled(driver, timeout=LOAD_S):
    """Wait until no view changes by half its threshold between two looks at the page (the
    spheres refine pass after pass)."""
    last = [_pictures(driver)]

    def still():
        now = _pictures(driver)
        moved = [cls for cls in VIEWS if _difference(last[0][cls], now[cls])
                 >= CHANGED.get(cls, CHANGED_PLOT) / 2]
        last[0] = now
        return not moved
    until(still, timeout, "the views settled")
