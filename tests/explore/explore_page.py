"""
Driving ``mi-brdfs explore``'s page in Debian's headless Chromium with Selenium, for the browser
test (tests/explore/test_browser.py) and the screenshots of docs/explore.md
(tools/explore_screenshots.py): the server as a subprocess, the browser through the system's
ChromeDriver (Selenium downloads nothing), and the page's parts found by their CSS classes
through the shadow roots in which Bokeh renders each component.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"

#: Chromium's flags on a machine with no display, no GPU and no network but loopback (and as
#: root, hence no sandbox): without the background-networking ones it tries Google's hosts at
#: every start. WebGL (Plotly's 3-D lobe) is then SwiftShader's, on the CPU, which Chromium
#: asks to be chosen explicitly. A new empty profile (--user-data-dir) is added per browser.
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--enable-unsafe-swiftshader", "--disable-dev-shm-usage", "--hide-scrollbars",
         "--force-device-scale-factor=1")

#: The views of the page, by CSS class.
VIEWS = ("mb-polar", "mb-albedo", "mb-lobe3d", "mb-slice", "mb-density", "mb-sphere")

#: Every element with class ``arguments[0]``, in the document and in every shadow root in it,
#: in document order (Bokeh renders each component in a shadow root of its own).
FIND_JS = """
const cls = arguments[0], root = arguments[1] || document, found = [];
(function walk(node) {
  for (const el of node.querySelectorAll('*')) {
    if (el.classList.contains(cls)) found.push(el);
    if (el.shadowRoot) walk(el.shadowRoot);
  }
})(root.shadowRoot || root);
return found;
"""

#: The bounding rectangles (viewport pixels) of the elements of each class in ``arguments[0]``,
#: by class, in one walk of the document and its shadow roots.
RECTS_JS = """
const classes = arguments[0], found = {};
for (const cls of classes) found[cls] = [];
(function walk(node) {
  for (const el of node.querySelectorAll('*')) {
    for (const cls of classes) {
      if (el.classList.contains(cls)) {
        const r = el.getBoundingClientRect();
        found[cls].push({x: r.x, y: r.y, width: r.width, height: r.height});
      }
    }
    if (el.shadowRoot) walk(el.shadowRoot);
  }
})(document);
return found;
"""

#: The text of an element, shadow roots included (Panel's panes keep their text in them).
TEXT_JS = """
function text(node) {
  if (node.nodeType === Node.TEXT_NODE) return node.textContent;
  if (node.nodeName === 'STYLE' || node.nodeName === 'SCRIPT') return '';
  let s = '';
  if (node.shadowRoot) s += text(node.shadowRoot);
  for (const c of node.childNodes) s += text(c);
  return s;
}
return text(arguments[0]);
"""

#: Whether an element is shown (Panel hides an invisible pane with display: none).
SHOWN_JS = "return arguments[0].checkVisibility();"


def missing() -> str | None:
    """Why the browser cannot be driven here (one line), or None."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e '.[test]')"
    for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver")):
        if not os.access(path, os.X_OK):
            return (f"{path} is missing: install Debian's {package} "
                    f"(tools/setup-system.sh does as root)")
    return None


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """``mi-brdfs explore --no-browser BSDF...`` on a free port, its stderr in ``stderr``
    (a file: a pipe nobody reads would block it); :meth:`stop` sends SIGTERM."""

    def __init__(self, specs, stderr: Path):
        self.port, self.stderr = free_port(), Path(stderr)
        self.url = f"http://127.0.0.1:{self.port}/"
        with open(self.stderr, "w") as err:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "mi_brdfs", "explore", "--no-browser",
                 "--port", str(self.port), *specs],
                stdout=subprocess.PIPE, stderr=err, text=True,
                env=dict(os.environ, MI_BRDFS_NO_PROGRESS="1"))
        line = self.proc.stdout.readline()  # printed once it listens ("" if it ended)
        if f":{self.port}/" not in line:
            self.stop()
            raise RuntimeError(f"mi-brdfs explore did not start: {line!r} "
                               f"{self.stderr.read_text()[-2000:]}")

    def errors(self) -> str:
        return self.stderr.read_text()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc.stdout.close()


@contextmanager
def chromium(width: int = 1400, height: int = 900):
    """A headless Chromium (a new empty profile, removed after) through the system's
    ChromeDriver, quit at the end of the ``with``; its console is read with
    ``driver.get_log('browser')``."""
    # both paths given, Selenium Manager has nothing to find; offline, it downloads nothing
    os.environ.setdefault("SE_OFFLINE", "true")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument(f"--window-size={width},{height}")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    with tempfile.TemporaryDirectory(prefix="mi-brdfs-chromium-") as profile:
        options.add_argument(f"--user-data-dir={profile}")
        driver = webdriver.Chrome(options=options,
                                  service=Service(executable_path=CHROMEDRIVER))
        try:
            yield driver
        finally:
            driver.quit()


def find(driver, cls: str, root=None) -> list:
    """The elements of class ``cls`` (under ``root``), shadow roots included."""
    return driver.execute_script(FIND_JS, cls, root)


def one(driver, cls: str, root=None):
    """The one element of class ``cls`` (under ``root``); AssertionError otherwise."""
    found = find(driver, cls, root)
    assert len(found) == 1, f"{len(found)} elements of class {cls!r} on the page, not 1"
    return found[0]


def rects(driver, classes) -> dict:
    """{class: [its elements' rectangles (x, y, width, height; viewport pixels)]}."""
    return driver.execute_script(RECTS_JS, list(classes))


def text(driver, element) -> str:
    return driver.execute_script(TEXT_JS, element)


def shown(driver, element) -> bool:
    return driver.execute_script(SHOWN_JS, element)


def until(condition, timeout: float, what: str, poll: float = 0.25):
    """``condition()``'s first true value within ``timeout`` seconds; AssertionError that
    names ``what`` otherwise. Polled every ``poll`` seconds: each look at the page walks its
    thousands of elements in Chromium, which shares the machine's cores with the server."""
    end = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"not within {timeout:g} s: {what}")
        time.sleep(poll)


def drawn(driver, timeout: float = 60.0, views_after_text: float = 15.0) -> None:
    """Wait until the XML has its text (the page's session is made, sent and drawn) and then
    every view has its size; AssertionError naming the views missing ``views_after_text``
    seconds after the XML, and at once where the page shows a Python traceback (Panel shows
    there an exception of the page's code)."""
    since = []

    def ready():
        body = text(driver, driver.find_element("tag name", "body"))
        assert "Traceback (most recent call last)" not in body, body[-3000:]
        if "<bsdf" not in "".join(text(driver, e) for e in find(driver, "mb-xml")):
            return False
        since.append(time.monotonic())
        sized = rects(driver, VIEWS)
        missing = [cls for cls in VIEWS if not any(r["height"] for r in sized[cls])]
        assert not missing or time.monotonic() - since[0] < views_after_text, \
            f"no element of class {', '.join(missing)} with a size on the page"
        return not missing
    until(ready, timeout, "the page's XML drawn")
