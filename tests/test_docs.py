"""
The repository's text points at things that exist: every test the README, docs/ or a docstring
cites (``tests/….py::test…``) can be selected by that name, and every cited file is there.
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CITED = re.compile(r"(tests/[\w/]+\.py)(?:::(\w+))?")


def _texts():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
             *sorted((ROOT / "mi_brdfs").rglob("*.py")), *sorted((ROOT / "tests").rglob("*.py"))]
    return [f for f in files if f.name != "test_docs.py"]


def test01_cited_tests_are_selectable():
    cited = 0
    for path in _texts():
        for file, name in CITED.findall(path.read_text(encoding="utf-8")):
            target = ROOT / file
            assert target.is_file(), f"{path.relative_to(ROOT)} cites {file}, which is not there"
            if name:
                assert re.search(rf"^def {name}\(", target.read_text(encoding="utf-8"), re.M), \
                    f"{path.relative_to(ROOT)} cites {file}::{name}, which pytest cannot select"
            cited += 1
    assert cited > 10


def test02_a_stale_citation_is_caught(tmp_path):
    """The pattern finds a citation by number only, which pytest cannot select."""
    file, name = CITED.findall("see `tests/plugins/test_cooktorrance.py::test03`")[0]
    text = (ROOT / file).read_text(encoding="utf-8")
    assert not re.search(rf"^def {name}\(", text, re.M)
