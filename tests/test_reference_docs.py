"""
The plugin reference, docs/plugins/*.md: generated from the plugins' docstrings by
``make docs`` (:mod:`mi_brdfs.docgen`), committed, and kept true here: the committed pages are
what the docstrings generate, every parameter of a docstring's table is on its page, and the
examples on the pages load in Mitsuba.
"""

import re

import numpy as np
import pytest
from helpers import spec as spec_of

import mi_brdfs  # noqa: F401  (import first: it chooses the libLLVM before drjit loads)
import drjit as dr
import mitsuba as mi
from mi_brdfs import docgen

PAGES = docgen.DEFAULT_OUT
FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.M | re.S)


def _page(name):
    return (PAGES / f"{name}.md").read_text(encoding="utf-8")


def _examples(name):
    """language -> code of the fenced blocks on a plugin's page."""
    blocks = {}
    for lang, code in FENCE.findall(_page(name)):
        assert lang not in blocks, f"{name}.md: two {lang} examples"
        blocks[lang] = code
    return blocks


def _load_xml(xml):
    """The BSDF of a one-sphere scene that wraps the page's <bsdf> element."""
    scene = mi.load_string(
        f'<scene version="3.0.0">\n<shape type="sphere">\n{xml}</shape>\n</scene>')
    return scene.shapes()[0].bsdf()


def _values(bsdf):
    """eval() at a few pairs of directions, anisotropic ones included."""
    si = mi.SurfaceInteraction3f()
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0), mi.Vector3f(0, 0, 1))
    si.uv = mi.Point2f(0.3, 0.6)
    out = []
    for wi, wo in [((0.3, 0.2, 0.9), (-0.25, -0.1, 0.95)), ((0.6, 0.0, 0.5), (-0.1, 0.6, 0.4)),
                   ((0.0, 0.1, 1.0), (0.0, -0.2, 1.0))]:
        si.wi = dr.normalize(mi.Vector3f(wi))
        out.append(np.array(bsdf.eval(mi.BSDFContext(), si, dr.normalize(mi.Vector3f(wo)))))
    return np.array(out)


def test01_committed_pages_are_what_the_docstrings_generate(variant_scalar_rgb, capsys):
    """Fails when a docstring changed without `make docs` (or a page was edited by hand)."""
    problems = docgen.check(PAGES)
    assert not problems, "\n".join(problems) + "\nrun `make docs`"
    assert docgen.main(["--check"]) == 0
    assert "up to date" in capsys.readouterr().out


def test02_a_changed_docstring_fails_the_check(variant_scalar_rgb, monkeypatch, capsys):
    cls = mi_brdfs.plugin_class("lambert")
    assert "Diffuse albedo ρ" in cls.__doc__
    monkeypatch.setattr(cls, "__doc__", cls.__doc__.replace("Diffuse albedo ρ",
                                                            "Diffuse albedo ρ (changed)"))
    files, _ = docgen.generate(PAGES)
    assert "Diffuse albedo ρ (changed)" in files["lambert.md"]   # the page is the docstring's
    assert docgen.main(["--check"]) == 1
    out = capsys.readouterr().out
    assert "lambert.md: differs from its docstring" in out and "(changed)" in out
    assert "phong.md" not in out and "README.md" not in out
    assert "run `make docs`" in out


def test03_every_plugin_has_a_page_with_every_parameter_of_its_table(variant_scalar_rgb):
    index = _page("README")
    for name in mi_brdfs.PLUGINS:
        assert (PAGES / f"{name}.md").is_file(), f"no page for plugin {name}"
        assert f"]({name}.md)" in index, f"the index does not link {name}.md"
        doc = mi_brdfs.plugin_class(name).__doc__
        # Read the table from the docstring independently of the generator: " * - a, b" rows.
        names = [n.strip() for row in re.findall(r"^\s*\* - (.+)$", doc, re.M)
                 for n in row.split(",")]
        assert names, f"{name}: no pluginparameters table in the docstring"
        rows = [ln for ln in _page(name).splitlines() if ln.startswith("| `")]
        for n in names:
            assert any(f"`{n}`" in r.split(" | ")[0] for r in rows), \
                f"{name}.md: parameter {n} is not in the table"
        assert len(rows) == len(re.findall(r"^\s*\* - ", doc, re.M))
        # and every parameter the plugin exposes to mi.traverse is documented
        bsdf = mi.load_dict(spec_of(name))
        for key in mi.traverse(bsdf).keys():  # noqa: SIM118 (SceneParameters iterates items)
            assert key.split(".")[0] in names, f"{name}: {key} is exposed but not documented"


@pytest.mark.parametrize("name", list(mi_brdfs.PLUGINS))
def test04_the_examples_on_each_page_load_and_agree(variant_scalar_rgb, name, tmp_path):
    """The XML example loads in a scene (mi.load_string), the Python one with mi.load_dict;
    both give the plugin, and the same BSDF (merl's file found by Mitsuba's file resolver)."""
    if name == "merl":
        (tmp_path / "gold-metallic-paint.binary").symlink_to(spec_of("merl")["filename"])
        kept = mi.FileResolver(mi.file_resolver())
        mi.file_resolver().prepend(str(tmp_path))
        try:
            return _examples_agree(name)
        finally:
            mi.set_file_resolver(kept)
    _examples_agree(name)


def _examples_agree(name):
    examples = _examples(name)
    assert set(examples) == {"xml", "python"}, f"{name}.md: examples {sorted(examples)}"
    cls = mi_brdfs.plugin_class(name)
    from_xml = _load_xml(examples["xml"])
    assert isinstance(from_xml, cls)
    spec = eval(compile(examples["python"], f"{name}.md", "eval"), {"mi": mi})
    assert isinstance(spec, dict) and spec["type"] == name
    from_dict = mi.load_dict(spec)
    assert isinstance(from_dict, cls)
    a, b = _values(from_xml), _values(from_dict)
    assert np.all(np.isfinite(a)) and np.any(a > 0)
    np.testing.assert_allclose(a, b, rtol=1e-6, err_msg=f"{name}.md: the XML and Python "
                               "examples describe different BSDFs")


def test05_the_pages_hold_markdown_only():
    """No reStructuredText is left outside code and math, and every table row has its cells."""
    known = "|".join(docgen.SUBSTITUTIONS)
    for path in sorted(PAGES.glob("*.md")):
        text = FENCE.sub("", path.read_text(encoding="utf-8"))
        text = re.sub(r"^\$\$\n.*?^\$\$$", "", text, flags=re.M | re.S)
        for pattern in (r":[\w:]+:`", r"^\s*\.\. ", rf"\|({known})\|", r"^\s*\* - "):
            found = re.search(pattern, text, re.M)
            assert not found, f"{path.name}: reStructuredText left: {found.group(0)!r}"
        for table in re.findall(r"(?:^\|.*\|\n)+", text, re.M):
            widths = {len(re.split(r"(?<!\\)\|", row)) for row in table.splitlines()}
            assert len(widths) == 1, f"{path.name}: a table with rows of {widths} cells"


def test06_write_then_check(tmp_path):
    """--check names a missing, an edited and a stale page; writing repairs all three."""
    files = {"a.md": "# a\n", "README.md": f"# index\n\n{docgen.MARKER}\n"}
    assert docgen.write(tmp_path, files) and not docgen.check(tmp_path, files)
    assert docgen.write(tmp_path, files) == []                     # unchanged: not rewritten
    (tmp_path / "a.md").write_text("# a, edited\n")
    (tmp_path / "gone.md").write_text(f"# gone\n\n{docgen.MARKER}\n")
    (tmp_path / "notes.md").write_text("# hand-written\n")
    problems = "\n".join(docgen.check(tmp_path, files))
    assert "a.md: differs" in problems
    assert "gone.md: generated for a plugin that is gone" in problems
    assert "notes.md" not in problems
    (tmp_path / "README.md").unlink()
    assert "README.md: missing" in "\n".join(docgen.check(tmp_path, files))
    docgen.write(tmp_path, files)
    assert not docgen.check(tmp_path, files)
    assert not (tmp_path / "gone.md").exists() and (tmp_path / "notes.md").exists()
