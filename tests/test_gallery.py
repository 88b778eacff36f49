"""
``python -m mi_brdfs.gallery --quick`` renders every row and column of the gallery at a tiny
resolution into a PNG whose layout is the one :func:`mi_brdfs.gallery.layout` describes:
rows × columns tiles, each with something rendered in it, separated by blank gaps, with labels.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import LLVM_OK
from mi_brdfs import gallery

RES = 16
#: The variant of the quick gallery here (the gallery's default is gallery.VARIANT, llvm_ad_rgb)
VARIANT = "scalar_rgb"


def test01_every_plugin_and_form_has_a_row():
    from mi_brdfs import registry

    plugins = {row.base["type"] for row in gallery.ROWS}
    assert plugins == set(registry.PLUGINS)
    merl = [row.spec(c) for row in gallery.ROWS if row.base["type"] == "merl"
            for c in range(len(row.columns))]
    assert merl and all("source" in spec for spec in merl)  # each tile tabulates its source
    forms = {(row.base["type"], row.base.get("form")) for row in gallery.ROWS}
    for form in ("normalized", "lecture", "original"):
        assert ("phong", form) in forms
    for form in ("original", "duer", "balanced"):
        assert ("ward", form) in forms
    for form in ("qualitative", "full"):
        assert ("orennayar", form) in forms
    ct = [row.base for row in gallery.ROWS if row.base["type"] == "cooktorrance"]
    assert {b.get("shadowing") for b in ct} >= {"vcavity", "smith"}
    assert any(b.get("distribution") == "ggx" for b in ct)
    assert any(b.get("transmission") for b in ct)
    # the energy compensation of both lobes: the conductor and the dielectric
    assert {bool(b.get("transmission")) for b in ct if b.get("multiscatter")} == {False, True}
    assert any("alpha_u" in row.spec(0) for row in gallery.ROWS)
    ashikhmin = [row.spec(c) for row in gallery.ROWS if row.base["type"] == "ashikhmin"
                 for c in range(len(row.columns))]
    assert any(spec["nu"] < spec["nv"] for spec in ashikhmin)
    assert any(spec["nu"] > spec["nv"] for spec in ashikhmin)
    lobes = {(s["cx_0"] > 0, abs(s["cz_0"]) < -s["cx_0"]) for row in gallery.ROWS
             if row.base["type"] == "lafortune" for s in map(row.spec, range(len(row.columns)))}
    assert lobes >= {(True, False), (False, True), (False, False)}  # retro, off-specular, mirror
    assert all(len(row.columns) >= 3 for row in gallery.ROWS)


def test02_layout_is_fixed_in_pixels():
    box = gallery.layout(4, 3, 20)
    assert box.width == gallery.LABEL_W + 3 * 20 + 2 * gallery.GAP + gallery.MARGIN
    assert box.height == (gallery.HEADER_H + 4 * (gallery.TITLE_H + 20) + 3 * gallery.GAP
                          + gallery.MARGIN)
    x, y = box.tiles[3][2]
    assert x + 20 + gallery.MARGIN == box.width and y + 20 + gallery.MARGIN == box.height


def _read_png(path) -> np.ndarray:
    import mitsuba as mi

    image = np.array(mi.Bitmap(str(path)))
    return image[:, :, :3].astype(np.int16)


def test03_quick_gallery(tmp_path):
    """
    In scalar_rgb (``--variant``): a JIT variant compiles a kernel for nearly every tile, most
    of this test's time with an empty kernel cache; each plugin's JIT renders are tested with
    the plugin (tests/plugins). The merl tiles' sources are tabulated in llvm_ad_rgb.
    """
    if not LLVM_OK:
        pytest.skip("the gallery tabulates its merl tiles in llvm_ad_rgb, which needs a working "
                    "libLLVM")
    pytest.importorskip("matplotlib")
    out, exr = tmp_path / "gallery.png", tmp_path / "tiles"
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    proc = subprocess.run([sys.executable, "-m", "mi_brdfs.gallery", "--quick", "--res", str(RES),
                           "--spp", "2", "--out", str(out), "--exr", str(exr),
                           "--variant", VARIANT],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path, env=env)
    assert proc.returncode == 0, f"exit {proc.returncode}:\n{proc.stdout}\n{proc.stderr[-3000:]}"
    rows, columns = len(gallery.ROWS), max(len(r.columns) for r in gallery.ROWS)
    assert f"{rows} rows × {columns} columns" in proc.stdout

    box = gallery.layout(rows, columns, RES)
    image = _read_png(out)
    assert image.shape[:2] == (box.height, box.width)
    white = np.all(image >= 250, axis=2)
    for r in range(rows):
        for c in range(columns):
            x, y = box.tiles[r][c]
            tile = image[y + 1:y + RES - 1, x + 1:x + RES - 1]
            assert not np.all(white[y + 1:y + RES - 1, x + 1:x + RES - 1]), (r, c)
            assert tile.std() > 1, f"tile {r}, {c} is uniform: nothing rendered"
            if c + 1 < columns:  # the gap to the next tile, beside the tile, is blank
                gap = white[y + 1:y + RES - 1, x + RES + 2:x + RES + gallery.GAP - 2]
                assert gap.all(), f"no gap right of tile {r}, {c}"
        x0, y0, w, h = box.label_box(r)
        assert not white[y0:y0 + h, x0:x0 + w].all(), f"row {r} has no label"
    # nothing below the last row of tiles (a label may reach below its tiny tiles)
    assert white[box.height - gallery.MARGIN + 2:, gallery.LABEL_W:].all()

    tiles = sorted(exr.glob("*.exr"))
    assert len(tiles) == rows * columns
    from mi_brdfs.imageio import read_exr

    tile, header = read_exr(tiles[0])
    assert tile.shape == (RES, RES, 3) and np.all(np.isfinite(tile))
    assert header["render.variant"] == VARIANT
