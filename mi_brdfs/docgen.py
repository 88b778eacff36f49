"""
The plugin reference, ``docs/plugins/*.md``, generated from the plugins' docstrings (``make docs``).

Each plugin class documents itself in Mitsuba 3's plugin markup: the reStructuredText that
Mitsuba's ``docs/generate_plugin_doc.py`` collects from its sources, with the
``pluginparameters`` table directive and the substitutions (``|float|``, ``|exposed|``, ...) of
Mitsuba's ``docs/conf.py``. This module converts that markup into GitHub-flavoured Markdown: one
page per plugin of :data:`mi_brdfs.registry.PLUGINS` (title, one-line summary, parameter table,
prose and math, the XML and Python examples) and an index, ``README.md``::

    python -m mi_brdfs.docgen            # (re)write docs/plugins/
    python -m mi_brdfs.docgen --check    # exit 1, naming the pages, when they are out of date

The one-line summary is the first sentence of the plugin module's docstring; everything else
comes from the class docstring. Markup the converter does not know is kept as text and named on
stderr; nothing is dropped silently. The output holds no date, so it is a pure function of the
docstrings (``tests/test_reference_docs.py`` compares the committed pages with it).
"""

from __future__ import annotations

import argparse
import ast
import difflib
import importlib
import inspect
import os
import re
import sys
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "docs" / "plugins"
INDEX = "README.md"
#: Every generated file carries this; a page with it that no plugin generates any more is stale.
MARKER = "by `make docs`; do not edit."

#: The substitutions of Mitsuba's docs/conf.py (rst_prolog), spelled out in words.
SUBSTITUTIONS = {
    "float": "float", "spectrum": "spectrum", "texture": "texture", "string": "string",
    "bool": "boolean", "int": "integer", "bsdf": "bsdf", "phase": "phase", "point": "point",
    "vector": "vector", "transform": "transform", "volume": "volume", "tensor": "tensor",
    "true": "`true`", "false": "`false`", "drjit": "`drjit`", "numpy": "`numpy`",
    "exposed": "exposed", "readonly": "read-only", "differentiable": "differentiable",
    "discontinuous": "discontinuous", "nbsp": "&nbsp;",
}
#: Roles that name Python objects (Sphinx's Python domain).
PY_ROLES = {"func", "meth", "class", "mod", "obj", "attr", "data", "exc"}
ADMONITIONS = {"note": "NOTE", "tip": "TIP", "hint": "TIP", "important": "IMPORTANT",
               "warning": "WARNING", "caution": "CAUTION", "danger": "CAUTION",
               "attention": "WARNING"}
CODE_LABELS = {"xml": "XML, in a scene file (`mi.load_file`, `mi.load_string`):",
               "python": "Python, a dictionary for `mi.load_dict`:"}

_DIRECTIVE = re.compile(r"^\.\.\s+([\w:-]+)::\s*(.*)$")
_LABEL = re.compile(r"^\.\.\s+_([^:]+):\s*$")
_UNDERLINE = re.compile(r"""^([=\-~^"'`#*+<>:._])\1+\s*$""")
_INLINE = re.compile(
    r"``(?P<literal>.+?)``"                              # ``literal``
    r"|:(?P<role>[\w:]+):`(?P<target>[^`]+?)`"           # :role:`target`
    r"|\|(?P<sub>\w+)\|",                                # |substitution|
    re.S)


@dataclass(frozen=True)
class Source:
    """What a plugin's page is generated from."""
    name: str          #: plugin id, as in ``<bsdf type="...">``
    module: str        #: ``mi_brdfs.plugins.<module>``
    class_name: str
    doc: str           #: the class docstring
    module_doc: str    #: the module docstring (its first sentence is the summary)

    @property
    def qualname(self) -> str:
        return f"{self.module}.{self.class_name}"


@dataclass
class Page:
    """A plugin's page: its Markdown text and what the index and the tests read from it."""
    name: str
    title: str
    summary: str
    text: str
    parameters: list = field(default_factory=list)   # the names in the parameter table
    warnings: list = field(default_factory=list)     # markup that did not convert cleanly


def sources() -> list[Source]:
    """
    The docstrings of every plugin in :data:`mi_brdfs.registry.PLUGINS`, read from the plugin
    classes themselves (those of the current variant; ``scalar_rgb`` is set when none is).
    """
    import mitsuba as mi

    from . import registry

    if mi.variant() is None:
        registry.use_variant("scalar_rgb")
    else:
        registry.register()
    out = []
    for name, (module, class_name) in registry.PLUGINS.items():
        cls = registry.plugin_class(name)
        mod = sys.modules.get(cls.__module__) or importlib.import_module(module)
        out.append(Source(name, module, class_name, cls.__doc__ or "", mod.__doc__ or ""))
    return out


# --- inline markup ------------------------------------------------------------------------------

class _Converter:
    """Converts one docstring; collects what did not convert cleanly in ``warnings``."""

    def __init__(self, source: Source, out: Path, labels: dict[str, str]):
        self.source = source
        self.out = Path(out)
        self.labels = labels           # "bsdf-ward" -> "ward.md"
        self.warnings: list[str] = []

    def warn(self, message: str) -> None:
        self.warnings.append(f"{self.source.qualname}: {message}")

    # Inline text: a paragraph, a table cell. ----------------------------------------------------
    def inline(self, text: str, cell: bool = False) -> str:
        if cell:  # one line: a table cell has no line structure to protect
            text = " ".join(text.split())
        parts, pos = [], 0
        for m in _INLINE.finditer(text):
            parts.append(self._plain(text[pos:m.start()]))
            pos = m.end()
            if m.group("literal") is not None:
                parts.append(_code(m.group("literal")))
            elif m.group("role") is not None:
                parts.append(self._role(m.group("role"), m.group("target"), m.group(0)))
            else:
                sub = m.group("sub")
                if sub in SUBSTITUTIONS:
                    parts.append(SUBSTITUTIONS[sub])
                else:
                    self.warn(f"unknown substitution |{sub}| (kept as text)")
                    parts.append(self._plain(m.group(0), lint=False))
        parts.append(self._plain(text[pos:]))
        result = "".join(parts)
        if cell:
            result = " ".join(result.split()).replace("|", "\\|")
        return result

    def _plain(self, text: str, lint: bool = True) -> str:
        """Text outside any markup: escape what Markdown would read as markup of its own."""
        for m in re.finditer(r"(?<![\w|])\|(?=\S)([^|\n]*?\S)\|(?![\w|])", text) if lint else ():
            self.warn(f"'{m.group(0)}' is a substitution reference in reStructuredText "
                      f"(Sphinx: undefined substitution); kept as text here")
        text = text.replace("\\ ", "")               # RST's escaped space joins inline markup
        text = text.replace("$", "\\$").replace("~", "\\~")
        text = re.sub(r"<(?=[A-Za-z/!?])", "&lt;", text)
        # A line that continues a paragraph must not start a list, heading, quote or rule.
        # (CommonMark: only "1." or "1)" starts an ordered list inside a paragraph.)
        pattern = (r"(\n[ \t]*)([-+*](?=\s)|1[.)](?=\s)|#{1,6}(?=\s|$)|>|=+(?=[ \t]*(\n|$))"
                   r"|-+(?=[ \t]*(\n|$))|_{3,}(?=[ \t]*(\n|$)))")
        return re.sub(pattern, lambda m: m.group(1) + "\\" + m.group(2), text)

    def _role(self, role: str, target: str, raw: str) -> str:
        if role == "math":
            return f"${' '.join(target.split())}$"
        if role in ("monosp", "code", "literal", "samp", "file"):
            return _code(target)
        if role == "paramtype":
            return target
        if role == "ref":
            return self._ref(target)
        if role.removeprefix("py:") in PY_ROLES:
            return self._python_ref(role.removeprefix("py:"), target)
        self.warn(f"unknown role {raw!r} (kept as code)")
        return _code(target)

    def _ref(self, target: str) -> str:
        m = re.match(r"^(.*?)\s*<([^>]+)>$", target, re.S)
        text, label = (m.group(1), m.group(2)) if m else (None, target.strip())
        page = self.labels.get(label)
        if page is None:
            self.warn(f":ref:`{target}` names no plugin page (kept as text)")
            return text or label
        return f"[{text or page[:-3]}]({page})"

    def _python_ref(self, role: str, target: str) -> str:
        m = re.match(r"^(.*?)\s*<([^>]+)>$", target, re.S)
        text, name = (m.group(1), m.group(2)) if m else (None, target)
        if re.search(r"\s", name):
            self.warn(f"whitespace inside the reference :{role}:`{target!r}` "
                      "(Sphinx cannot resolve it; joined here)")
            name = re.sub(r"\s+", "", name)
        short = name.startswith("~")
        name = name.lstrip("~.")
        shown = text or (name.rsplit(".", 1)[-1] if short else name)
        link = self._source_file(name)
        if link is None and name.split(".")[0] == "mi_brdfs":
            self.warn(f":{role}:`{name}` names nothing in the package (kept as code)")
        return f"[{_code(shown)}]({link})" if link else _code(shown)

    def _source_file(self, dotted: str) -> str | None:
        """The file that defines ``dotted`` (a module or a top-level name of one), relative to
        the output folder; None unless it is in this package."""
        parts = dotted.split(".")
        if parts[0] != "mi_brdfs":
            return None
        for i in range(len(parts), 0, -1):
            base = ROOT.joinpath(*parts[:i])
            for path in (base.with_suffix(".py"), base / "__init__.py"):
                if path.is_file():
                    rest = parts[i:]
                    if rest and rest[0] not in _top_level_names(path):
                        return None
                    return os.path.relpath(path, self.out).replace(os.sep, "/")
        return None

    # Blocks. -------------------------------------------------------------------------------------
    def blocks(self, lines: list[str]) -> list[tuple]:
        """Split reStructuredText lines into blocks: ("label", name), ("title", text),
        ("directive", name, argument, body lines), ("para", lines)."""
        blocks, i = [], 0
        while i < len(lines):
            line = lines[i]
            if not line.strip():
                i += 1
                continue
            indent = len(line) - len(line.lstrip())
            stripped = line.strip()
            if _LABEL.match(stripped):
                blocks.append(("label", _LABEL.match(stripped).group(1)))
                i += 1
                continue
            if stripped.startswith(".. "):               # a directive, or a comment
                body, i = _indented_body(lines, i + 1, indent)
                m = _DIRECTIVE.match(stripped)
                if m:
                    blocks.append(("directive", m.group(1), m.group(2).strip(), body))
                continue
            if (i + 1 < len(lines) and _UNDERLINE.match(lines[i + 1].strip())
                    and not _UNDERLINE.match(stripped)):
                title = stripped
                if len(lines[i + 1].strip()) < len(title):
                    self.warn(f"title underline shorter than the title ({len(lines[i + 1].strip())}"
                              f" < {len(title)} characters; docutils warns)")
                blocks.append(("title", title))
                i += 2
                continue
            para = []
            while i < len(lines) and lines[i].strip() and not (
                    lines[i].strip().startswith(".. ") and para):
                para.append(lines[i][indent:] if lines[i][:indent].isspace() else lines[i].strip())
                i += 1
            if para and para[-1].endswith("::"):      # a literal block follows
                para[-1] = para[-1][:-2].rstrip() + (":" if not para[-1].endswith(" ::") else "")
                body, i = _indented_body(lines, i, indent)
                blocks.append(("para", para))
                blocks.append(("directive", "code-block", "", body))
                continue
            blocks.append(("para", para))
        return blocks

    def render_blocks(self, blocks: list[tuple], page: Page) -> list[str]:
        """Markdown chunks (joined by blank lines) for ``blocks``."""
        chunks = []
        described = False
        for block in blocks:
            kind = block[0]
            if kind in ("label", "title"):
                continue
            if kind == "para":
                if chunks and not described and chunks[-1].startswith("|"):
                    chunks.append("## Description")
                described = True
                chunks.append(self.inline("\n".join(block[1])))
                continue
            name, arg, body = block[1], block[2], block[3]
            if name == "pluginparameters":
                chunks.append("## Parameters")
                chunks.append(self.parameter_table(body, page))
            elif name == "math":
                if chunks and not described and chunks[-1].startswith("|"):
                    chunks.append("## Description")
                described = True
                chunks.extend(self.math(arg, body))
            elif name == "tabs":
                chunks.append("## Example")
                chunks.extend(self.tabs(body))
            elif name in ("code-tab", "code-block", "code", "sourcecode"):
                chunks.extend(self.code(arg, body, labelled=name == "code-tab"))
            elif name in ADMONITIONS:
                inner = self.render_blocks(self.blocks(_strip_options(body)), page)
                text = "\n\n".join([arg] + inner if arg else inner)
                chunks.append("\n".join([f"> [!{ADMONITIONS[name]}]"]
                                        + [f"> {ln}".rstrip() for ln in text.splitlines()]))
            else:
                self.warn(f"unknown directive '.. {name}::' (kept as a code block)")
                chunks.append("```rst\n" + "\n".join([f".. {name}:: {arg}".rstrip()] + body)
                              + "\n```")
        return chunks

    def parameter_table(self, body: list[str], page: Page) -> str:
        rows = []
        for line in _strip_options(body):
            s = line.strip()
            if s.startswith("* - "):
                rows.append([s[4:]])
            elif s.startswith("- ") or s == "-":
                if not rows:
                    self.warn(f"pluginparameters: cell before the first row: {s!r}")
                    continue
                rows[-1].append(s[2:])
            elif s:
                if not rows:
                    self.warn(f"pluginparameters: text before the first row: {s!r}")
                    continue
                rows[-1][-1] += "\n" + s
        out = ["| Parameter | Type | Description | Flags |", "|---|---|---|---|"]
        for row in rows:
            if not 3 <= len(row) <= 4:
                self.warn(f"pluginparameters: row {row[0]!r} has {len(row)} cells (3 or 4)")
            row = (row + ["", "", "", ""])[:4]
            names = [n.strip() for n in row[0].split(",") if n.strip()]
            page.parameters.extend(names)
            cells = [", ".join(_code(n) for n in names)]
            cells += [self.inline(c, cell=True) for c in row[1:]]
            out.append("| " + " | ".join(cells) + " |")
        return "\n".join(out)

    def math(self, arg: str, body: list[str]) -> list[str]:
        text = "\n".join([arg] + _strip_options(body) if arg else _strip_options(body))
        equations = [e for e in re.split(r"\n\s*\n", textwrap.dedent(text)) if e.strip()]
        chunks = []
        for eq in equations:
            lines = []
            for ln in eq.strip().splitlines():
                # TeX reads a backslash at the end of a line as a space (\ ); Markdown would read
                # it as a hard line break: join the lines.
                if lines and re.search(r"(?<!\\)(\\\\)*\\$", lines[-1]):
                    lines[-1] += " " + ln.strip()
                else:
                    lines.append(ln.strip())
            # As Sphinx does for MathJax (which would use split): aligned rows need an environment.
            if ("\\\\" in eq or "&" in eq) and "\\begin" not in eq:
                lines = ["\\begin{aligned}"] + lines + ["\\end{aligned}"]
            chunks.append("\n".join(["$$"] + lines + ["$$"]))
        return chunks

    def tabs(self, body: list[str]) -> list[str]:
        chunks = []
        for block in self.blocks(textwrap.dedent("\n".join(body)).splitlines()):
            if block[0] == "directive" and block[1] == "code-tab":
                chunks.extend(self.code(block[2], block[3], labelled=True))
            else:
                self.warn(f"tabs: expected '.. code-tab::', found {block[:2]!r} (left out)")
        return chunks

    def code(self, language: str, body: list[str], labelled: bool) -> list[str]:
        language = language.split()[0] if language else ""
        code = textwrap.dedent("\n".join(_strip_options(body))).strip("\n")
        fence = "```" if "```" not in code else "````"
        chunks = []
        if labelled:
            chunks.append(CODE_LABELS.get(language, f"{language or 'Code'}:"))
        chunks.append(f"{fence}{language}\n{code}\n{fence}")
        return chunks


def _code(text: str) -> str:
    """A Markdown code span of ``text`` (newlines become spaces, as in reStructuredText)."""
    text = " ".join(text.split())
    ticks = "`" * (max((len(t) for t in re.findall(r"`+", text)), default=0) + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{ticks}{pad}{text}{pad}{ticks}"


def _indented_body(lines: list[str], i: int, indent: int) -> tuple[list[str], int]:
    """The lines from ``i`` on indented deeper than ``indent`` (blank lines included), and the
    index after them; trailing blank lines are not part of the body."""
    body = []
    while i < len(lines) and (not lines[i].strip()
                              or len(lines[i]) - len(lines[i].lstrip()) > indent):
        body.append(lines[i])
        i += 1
    while body and not body[-1].strip():
        body.pop()
    return body, i


def _strip_options(body: list[str]) -> list[str]:
    """A directive's body without its leading ``:option: value`` lines."""
    k = 0
    while k < len(body) and re.match(r"^\s*:[\w-]+:", body[k]):
        k += 1
    return body[k:]


_names_cache: dict[Path, set] = {}


def _top_level_names(path: Path) -> set:
    if path not in _names_cache:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        names = set()
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                names.add(node.name)
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names.update(t.id for t in targets if isinstance(t, ast.Name))
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                names.update((a.asname or a.name).split(".")[0] for a in node.names)
        _names_cache[path] = names
    return _names_cache[path]


def _first_sentence(text: str) -> str:
    text = " ".join(text.split())
    for m in re.finditer(r"[.!?](?=\s+[A-Z(`])", text):
        if not re.search(r"(\bal|\be\.g|\bi\.e|\bcf|\bvs|\bFig|\bEq|\bSec)\.$", text[:m.end()]):
            return text[:m.end()]
    return text


# --- pages --------------------------------------------------------------------------------------

def render_page(source: Source, out: Path = DEFAULT_OUT, labels: dict | None = None) -> Page:
    """The Markdown page of one plugin (``out``: the folder it goes to, for relative links)."""
    labels = labels if labels is not None else {}
    conv = _Converter(source, out, labels)
    lines = inspect.cleandoc(source.doc).splitlines()
    blocks = conv.blocks(lines)
    titles = [b[1] for b in blocks if b[0] == "title"]
    if not titles:
        conv.warn("no title (a line underlined with -----); the class name is used")
    title = conv.inline(titles[0]) if titles else source.class_name
    summary = conv.inline(_first_sentence(source.module_doc)) if source.module_doc.strip() else ""
    if not summary:
        conv.warn("the module has no docstring, so the page has no summary")
    page = Page(source.name, title, " ".join(summary.split()), "")
    body = conv.render_blocks(blocks, page)
    if not page.parameters:
        conv.warn("no '.. pluginparameters::' table")
    footer = (f"Generated from the docstring of `{source.qualname}` {MARKER}")
    chunks = [f"# {title}"] + ([page.summary] if page.summary else []) + body + ["---", footer]
    page.text = "\n\n".join(chunks) + "\n"
    page.warnings = conv.warnings
    return page


def render_index(pages: list[Page]) -> str:
    rows = ["| Plugin | Summary | Page |", "|---|---|---|"]
    for p in pages:
        title = p.title.replace("|", "\\|")
        rows.append(f"| `{p.name}` | {p.summary.replace('|', chr(92) + '|')} | "
                    f"[{title}]({p.name}.md) |")
    chunks = [
        "# Plugin reference",
        ("The BSDF plugins that `import mi_brdfs` registers with Mitsuba 3 (in every variant), "
         "one page each: parameters, model, sampling and an example in XML and in Python."),
        "\n".join(rows),
        "---",
        "Generated from the docstrings of the plugin classes (`mi_brdfs.plugins`) " + MARKER,
    ]
    return "\n\n".join(chunks) + "\n"


def generate(out: Path = DEFAULT_OUT, srcs: list[Source] | None = None) -> tuple[dict, list]:
    """
    Every file of the reference for the folder ``out``.

    Returns → (dict[str, str], list[str]): file name -> Markdown text, and the warnings about
    markup that did not convert cleanly.
    """
    srcs = sources() if srcs is None else srcs
    labels = {}
    for s in srcs:
        for m in re.finditer(r"^\s*\.\.\s+_([^:]+):\s*$", s.doc, re.M):
            labels[m.group(1)] = f"{s.name}.md"
    pages = [render_page(s, out, labels) for s in srcs]
    files = {f"{p.name}.md": p.text for p in pages}
    files[INDEX] = render_index(pages)
    return files, [w for p in pages for w in p.warnings]


def check(out: Path = DEFAULT_OUT, files: dict | None = None) -> list[str]:
    """The problems of the committed reference in ``out``: files that differ from what the
    docstrings generate, are missing, or are generated pages no plugin has any more."""
    out = Path(out)
    files = generate(out)[0] if files is None else files
    problems = []
    for name, text in files.items():
        path = out / name
        if not path.is_file():
            problems.append(f"{_shown(path)}: missing")
            continue
        old = path.read_text(encoding="utf-8")
        if old != text:
            diff = list(difflib.unified_diff(old.splitlines(), text.splitlines(), "committed",
                                             "generated", n=0, lineterm=""))
            shown = "\n".join("    " + d for d in diff[2:14])
            more = "\n    ..." if len(diff) > 14 else ""
            problems.append(f"{_shown(path)}: differs from its docstring\n{shown}{more}")
    for path in sorted(out.glob("*.md")):
        if path.name not in files and MARKER in path.read_text(encoding="utf-8"):
            problems.append(f"{_shown(path)}: generated for a plugin that is gone")
    return problems


def write(out: Path = DEFAULT_OUT, files: dict | None = None) -> list[Path]:
    """Write the reference into ``out`` (only files whose text changes; stale generated pages
    are removed). Returns → list[Path]: the files written or removed."""
    out = Path(out)
    files = generate(out)[0] if files is None else files
    out.mkdir(parents=True, exist_ok=True)
    changed = []
    for name, text in files.items():
        path = out / name
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8", newline="\n")
            changed.append(path)
    for path in sorted(out.glob("*.md")):
        if path.name not in files and MARKER in path.read_text(encoding="utf-8"):
            path.unlink()
            changed.append(path)
    return changed


def _shown(path: Path) -> str:
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m mi_brdfs.docgen",
        description="Generate the plugin reference (Markdown) from the plugins' docstrings.")
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1, naming the files, when the pages in --out "
                             "differ from what the docstrings generate")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help="the folder of the pages (default: docs/plugins of the repository)")
    args = parser.parse_args(argv)
    files, warnings = generate(args.out)
    for w in warnings:
        print(f"docgen: warning: {w}", file=sys.stderr)
    if args.check:
        problems = check(args.out, files)
        for p in problems:
            print(p)
        if problems:
            print(f"{len(problems)} file(s) out of date: run `make docs` "
                  "(python -m mi_brdfs.docgen)")
            return 1
        print(f"{_shown(args.out)}: {len(files)} files up to date")
        return 0
    changed = write(args.out, files)
    for path in changed:
        print(f"{'wrote' if path.exists() else 'removed'} {_shown(path)}")
    print(f"{_shown(args.out)}: {len(files)} files, {len(changed)} changed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
