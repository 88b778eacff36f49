"""
The screenshots of ``mi-brdfs explore`` in docs/explore.md: starts the server, opens its page in
Debian's headless Chromium at a fixed window size, waits until the views are drawn and the
spheres have settled, and saves one PNG per view (its element, found by its CSS class) and one
of the whole page into docs/explore/ (``page.png``, ``polar.png``, ...). ``make screenshots``
runs it.

    python tools/explore_screenshots.py [--out DIR] [BSDF ...]

Needs Chromium and ChromeDriver (Debian's ``chromium`` and ``chromium-driver``; the Makefile's
system step installs them as root), Selenium (the ``test`` extra) and Panel (``explore``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "explore"))

import explore_page as page  # noqa: E402  (the browser test's driving of the page)

#: What the screenshots show: a plugin beside its Mitsuba twin (curves overlaid, spheres side
#: by side with their difference).
DEFAULT = ["cooktorrance alpha=0.3 material=Au", "roughconductor alpha=0.3 material=Au"]

#: The window's size (pixels): the page's width; the height grows to the whole page for
#: page.png.
WIDTH, HEIGHT = 1400, 1200

#: The parts saved, by CSS class, and their files (the views, then the controls and the text).
PARTS = {cls: cls[len("mb-"):] for cls in page.VIEWS + ("mb-controls", "mb-verdicts",
                                                        "mb-xml")}

#: The bottom of the lowest element, shadow roots included (the document's own height does
#: not count what Bokeh lays out inside them).
BOTTOM_JS = """
let bottom = 0;
(function walk(node) {
  for (const el of node.querySelectorAll('*')) {
    bottom = Math.max(bottom, el.getBoundingClientRect().bottom + window.scrollY);
    if (el.shadowRoot) walk(el.shadowRoot);
  }
})(document);
return Math.ceil(bottom);
"""

#: Seconds to wait for the page and for the spheres to settle.
LOAD_S, SETTLE_S = 120.0, 60.0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("bsdf", nargs="*", default=DEFAULT, help="the BSDFs shown")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "explore",
                        help="folder of the PNGs (default: docs/explore)")
    args = parser.parse_args(argv)
    why = page.missing()
    if why:
        print(f"explore_screenshots: {why}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        server = page.Server(args.bsdf, Path(tmp) / "stderr.txt")
        try:
            with page.chromium(WIDTH, HEIGHT) as driver:
                written = _shoot(driver, server.url, args.out)
        finally:
            server.stop()
    for path in written:
        print(f"explore_screenshots: wrote {path}")
    return 0


def _shoot(driver, url: str, out: Path) -> list[Path]:
    """Load the page, wait for it to settle, save its parts and the whole page."""
    driver.get(url)
    page.drawn(driver, LOAD_S)
    _settle(driver)
    for _ in range(2):  # the page's height, again at the new window size
        frame = driver.get_window_size()["height"] - driver.execute_script(
            "return window.innerHeight")  # the window's own bars, in headless mode too
        driver.set_window_size(WIDTH, driver.execute_script(BOTTOM_JS) + 20 + frame)
        time.sleep(1.0)  # the layout at the new size
    driver.execute_script("window.scrollTo(0, 0)")
    written = []
    for cls, name in PARTS.items():
        found = page.find(driver, cls)
        if found and found[0].rect["height"]:
            path = out / f"{name}.png"
            path.write_bytes(found[0].screenshot_as_png)
            written.append(path)
    path = out / "page.png"
    driver.save_screenshot(str(path))
    return written + [path]


def _settle(driver) -> None:
    """Until the spheres stop changing (their passes done) and the verdicts are in."""
    def settled():
        before = page.one(driver, "mb-sphere").screenshot_as_png
        time.sleep(1.0)
        verdicts = page.text(driver, page.one(driver, "mb-verdicts"))
        return (page.one(driver, "mb-sphere").screenshot_as_png == before
                and "checking" not in verdicts)
    page.until(settled, SETTLE_S, "the spheres settled and the verdicts in")


if __name__ == "__main__":
    sys.exit(main())
