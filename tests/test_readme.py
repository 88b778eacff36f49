"""
Every code block of the README and docs/ that is meant to run is run, as a user would run it: each
Python block as a script in a fresh process and folder (a block whose first line names a pytest
file is written to that file and run by pytest), each XML ``<bsdf>`` block loaded by Mitsuba.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import LLVM_OK
from helpers import merl_file

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w+)[^\n]*\n(.*?)^```", re.M | re.S)


def blocks(language: str):
    out = []
    for doc in DOCUMENTS:
        for i, (lang, code) in enumerate(FENCE.findall(doc.read_text(encoding="utf-8"))):
            if lang == language:
                out.append(pytest.param(code, id=f"{doc.relative_to(ROOT)}#{i}"))
    return out


@pytest.mark.skipif(not LLVM_OK, reason="the examples use llvm_ad_rgb")
@pytest.mark.parametrize("code", blocks("python"))
def test01_python_blocks_run(code, tmp_path):
    env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1")
    first = code.lstrip().splitlines()[0]
    name = re.match(r"#\s*(test_\w+\.py)", first)
    if name:  # a pytest example: written to its file and run by pytest
        (tmp_path / name.group(1)).write_text(code)
        cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", name.group(1)]
    else:
        (tmp_path / "example.py").write_text(code)
        cmd = [sys.executable, "example.py"]
    p = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]


@pytest.mark.parametrize("xml", blocks("xml"))
def test02_xml_blocks_load(xml, variant_scalar_rgb, tmp_path):
    """Each <bsdf> block loads; a MERL file it names is found by Mitsuba's file resolver."""
    import mitsuba as mi
    if "<bsdf" not in xml or "bitmap" in xml:
        pytest.skip("not a self-contained <bsdf> (a scene fragment or a texture file)")
    for name in re.findall(r'name="filename" value="([^"]+\.binary)"', xml):
        (tmp_path / name).symlink_to(merl_file())
    kept = mi.FileResolver(mi.file_resolver())
    mi.file_resolver().prepend(str(tmp_path))
    try:
        _load_bsdf_block(xml)
    finally:
        mi.set_file_resolver(kept)


def _load_bsdf_block(xml):
    import mitsuba as mi
    bsdf = mi.load_string(f'<scene version="3.0.0">{xml}</scene>'.replace(
        '<scene version="3.0.0"><bsdf', '<scene version="3.0.0"><shape type="sphere"><bsdf', 1)
        .replace("</scene>", "</shape></scene>"))
    assert bsdf.shapes()[0].bsdf() is not None


def test03_the_readme_examples_are_found():
    assert len(blocks("python")) >= 2 and len(blocks("xml")) >= 1
