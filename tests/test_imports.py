"""
The package's modules import each other without a cycle: every ``import`` statement counts,
at module level or inside a function (a lazy import still ties the two modules together).
"""

import ast
import functools
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "mi_brdfs"


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@functools.cache
def _parsed(path: Path, mtime_ns: int) -> ast.Module:
    """The module's syntax tree, parsed once per version of the file (several tests walk the
    package's modules)."""
    return ast.parse(path.read_text(encoding="utf-8"))


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """
    module -> the package's modules it imports. ``import x.y`` depends on ``x.y``;
    ``from x import a`` on the submodule ``x.a`` where ``a`` is one, else on ``x`` itself
    (``a`` is then an attribute of its ``__init__``, such as ``from .. import __version__``),
    relative imports resolved; an import of the root package (``import mi_brdfs``) counts.
    """
    modules = {_module_name(p, root): p for p in root.rglob("*.py")}
    graph = {name: set() for name in modules}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(_parsed(path, path.stat().st_mtime_ns)):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join(anchor + ([base] if base else []))
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                           for a in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:  # x.y.function -> x.y
                    target = target.rpartition(".")[0]
                if target and target != name:
                    graph[name].add(target)
    return graph


def root_imports(graph: dict[str, set[str]]) -> list[str]:
    """The modules that import the root package (its ``__init__``: the public entry, which
    imports nearly everything), other than the command line's own."""
    root = min(graph, key=len)
    command_line = (f"{root}.cli", f"{root}.__main__")
    return sorted(m for m, targets in graph.items()
                  if root in targets and not m.startswith(command_line))


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as a list of modules, or None."""
    state: dict[str, int] = {}  # 1: on the stack, 2: done
    stack: list[str] = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test01_no_import_cycle():
    graph = import_graph()
    assert len(graph) > 40 and graph["mi_brdfs.scenes"] >= {"mi_brdfs.errors"}
    cycle = find_cycle(graph)
    assert cycle is None, " -> ".join(cycle)


def test02_a_cycle_is_found(tmp_path):
    """The graph and the search see a cycle through a lazy, relative import."""
    pkg = tmp_path / "mi_brdfs"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("def f():\n    from ..a import g\n")
    cycle = find_cycle(import_graph(pkg))
    assert cycle is not None and set(cycle) == {"mi_brdfs.a", "mi_brdfs.sub.b"}


def test03_no_module_imports_the_root_package():
    """
    The root package (``mi_brdfs/__init__.py``) is the public entry: it registers the plugins
    and imports the layers below. A module under it that imports it back (``import mi_brdfs``,
    ``from .. import __version__``) hides an upward dependency; each takes what it needs from
    the module that defines it (``registry``, ``_version``).
    """
    graph = import_graph()
    assert "mi_brdfs.cli.commands" in graph
    assert root_imports(graph) == []


def test04_a_root_import_is_found(tmp_path):
    """The graph sees ``import mi_brdfs`` and ``from .. import attribute`` as imports of the
    root, and ``from .. import submodule`` as an import of the submodule only."""
    pkg = tmp_path / "mi_brdfs"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("__version__ = '0'\n")
    (pkg / "a.py").write_text("def f():\n    import mi_brdfs\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("from .. import __version__\n")
    (pkg / "sub" / "c.py").write_text("from .. import a\nfrom . import b\n")
    graph = import_graph(pkg)
    assert root_imports(graph) == ["mi_brdfs.a", "mi_brdfs.sub.b"]
    assert graph["mi_brdfs.sub.c"] == {"mi_brdfs.a", "mi_brdfs.sub.b"}
