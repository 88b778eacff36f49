"""
docs/architecture.md's layer table is the package's real import graph: every module of
``mi_brdfs`` sits in exactly one layer, and no import (at module level or inside a function)
reaches a layer above its own.
"""

import re
from pathlib import Path

import pytest
from test_imports import PACKAGE, import_graph

PAGE = PACKAGE.parent / "docs" / "architecture.md"


def layers_of(page_text: str) -> list[tuple[str, list[str]]]:
    """
    (layer, entries) of the page's layer table, lowest layer first: the rows of the table under
    the heading "## Layers", whose second column lists the layer's modules as backticked paths
    relative to ``mi_brdfs/`` (``errors.py``, ``scattering/`` for a whole package).
    """
    section = page_text.split("## Layers", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("|")][2:]
    table = []
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        table.append((cells[0], re.findall(r"`([^`]+)`", cells[1])))
    return table


def _matches(module: str, entry: str) -> bool:
    """Whether the module (dotted, under ``mi_brdfs``) is the table's ``entry``."""
    path = module.split(".")[1:]
    if entry.endswith("__init__.py"):  # a package's own module ("__init__.py": the root)
        return path == entry.split("/")[:-1]
    if entry.endswith("/"):
        package = entry.rstrip("/").split("/")
        return path[:len(package)] == package
    return path == entry[:-len(".py")].split("/")


def layer_index(graph, table) -> dict[str, int]:
    """module -> index of its layer; raises AssertionError for a module in none or in two."""
    index = {}
    for module in graph:
        found = [i for i, (_, entries) in enumerate(table)
                 if any(_matches(module, e) for e in entries)]
        assert len(found) == 1, (f"{module} is in {len(found)} layers of docs/architecture.md "
                                 f"(must be in exactly one)")
        index[module] = found[0]
    return index


def upward_imports(graph, table) -> list[str]:
    """Every import that reaches a layer above the importing module's."""
    index = layer_index(graph, table)
    return [f"{a} ({table[index[a]][0]}) -> {b} ({table[index[b]][0]})"
            for a in sorted(graph) for b in sorted(graph[a]) if index[b] > index[a]]


def test01_every_module_in_one_layer_and_no_import_upward():
    table = layers_of(PAGE.read_text(encoding="utf-8"))
    assert len(table) >= 5
    graph = import_graph()
    assert upward_imports(graph, table) == []


def test02_every_entry_names_a_module():
    """A table entry that matches no module (a renamed or removed one) is stale."""
    graph = import_graph()
    for layer, entries in layers_of(PAGE.read_text(encoding="utf-8")):
        for entry in entries:
            assert any(_matches(m, entry) for m in graph), f"{layer}: `{entry}` is no module"


PAGE_FIXTURE = """
## Layers

| layer | modules | owns |
|---|---|---|
| low | `a.py`, `sub/` | |
| high | `__init__.py`, `b.py` | |

## Next
"""


def _package(tmp_path, files: dict) -> Path:
    pkg = tmp_path / "mi_brdfs"
    for name, text in files.items():
        (pkg / name).parent.mkdir(parents=True, exist_ok=True)
        (pkg / name).write_text(text)
    return pkg


def test03_an_upward_import_is_found(tmp_path):
    """A lazy import from a low layer into a high one is reported; the reverse is not."""
    pkg = _package(tmp_path, {"__init__.py": "", "a.py": "def f():\n    from . import b\n",
                              "b.py": "from .sub import c\n", "sub/__init__.py": "",
                              "sub/c.py": ""})
    found = upward_imports(import_graph(pkg), layers_of(PAGE_FIXTURE))
    assert found == ["mi_brdfs.a (low) -> mi_brdfs.b (high)"]


def test04_a_module_in_no_layer_is_found(tmp_path):
    pkg = _package(tmp_path, {"__init__.py": "", "a.py": "", "b.py": "", "sub/__init__.py": "",
                              "orphan.py": ""})
    with pytest.raises(AssertionError, match="orphan is in 0 layers"):
        layer_index(import_graph(pkg), layers_of(PAGE_FIXTURE))
