"""
Messages that point the right way: the presets listed by a command, a MERL file where a scene
is taken named as the BSDF it is, a warning printed once per command.
"""

import struct

import pytest

from helpers import cli_one_line_error
from mi_brdfs.cli import main


def test01_presets_lists_the_materials_and_the_plugins_that_take_them(capsys):
    """The 86 materials of Ngan et al.'s fit files (docs/presets.md), each a row marking the
    plugins that take its fit; with a plugin, its presets one per line."""
    assert main(["presets"]) == 0
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if line.startswith("material "))
    assert header.split() == ["material", "cooktorrance", "he", "lafortune", "phong", "ward",
                              "ward", "(ngan-wardduer:)"]
    rows = out.split(header)[1].strip().splitlines()
    assert len(rows) == 86
    assert rows[0].split() == ["alum-bronze", "x", "x", "x", "x", "x", "x"]
    assert "ashikhmin" in out and "not exact" in out  # no exact conversion: said, not listed
    assert main(["presets", "ward"]) == 0
    names = capsys.readouterr().out.split()
    assert len(names) == 2 * 86 and "ngan:gold-metallic-paint" in names
    assert "ngan-wardduer:gold-metallic-paint" in names
    cli_one_line_error(["presets", "diffuse"], "presets diffuse: no presets; the plugins that "
                                               "take preset=... are ashikhmin, cooktorrance")
    cli_one_line_error(["presets", "ashikhmin"], "presets ashikhmin: no published fit converts "
                                                 "exactly")


def _merl_header(path):
    path.write_bytes(struct.pack("<3i", 90, 90, 180) + bytes(64))


@pytest.mark.parametrize("args", [["render", "{f}", "--spp", "1"],
                                  ["compare", "{f}", "--swap", "a=diffuse"],
                                  ["compare", "furnace", "{f}"],
                                  ["simplify", "{f}", "--quick"]])
@pytest.mark.parametrize("name", ["gold.binary", "gold.dat"])
def test02_a_merl_file_where_a_scene_goes_is_named_as_a_bsdf(tmp_path, monkeypatch, args,
                                                             name):
    """By its suffix or by MERL's header (90, 90, 180): one line saying how to use it as a BSDF,
    where "not UTF-8" said nothing of it."""
    monkeypatch.chdir(tmp_path)
    _merl_header(tmp_path / name)
    line = cli_one_line_error([a.format(f=name) for a in args],
                              f"{name} is a MERL measured BRDF, not a scene: use it as a BSDF, "
                              f"merl filename={name} (e.g. mi-brdfs check merl filename={name};")
    assert "UTF-8" not in line
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]


def test03_a_warning_is_printed_once_per_command(tmp_path, monkeypatch, capsys):
    """A plot loads its BSDF once per curve (and matplotlib's style contexts reset Python's
    record of the warnings shown): the same warning, once."""
    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    assert main(["plot", "lobe", "ward diffuse_reflectance=0.6 specular_reflectance=0.5",
                 "--variant", "llvm_ad_rgb"]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warned) == 1 and "reaches 1.1 > 1" in warned[0] and \
        "values kept" in warned[0], warned
