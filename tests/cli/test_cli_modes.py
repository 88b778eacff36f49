"""
Options that mean something in the mode chosen (mi_brdfs.cli.modes): an option a command's mode
does not take is one line naming the option and the mode, before any work (the files named do
not exist and the variant asked for is unknown: neither is looked at), and nothing is written.
"""

from pathlib import Path

import pytest

from helpers import cli_one_line_error
from mi_brdfs.cli import modes
from mi_brdfs.cli.parser import _parser

WARD = "ward diffuse_reflectance=0.6 specular_reflectance=0.5"

REFUSED = [
    # fit: one model (--model), the models on one TARGET (--models), a sweep (several TARGETs)
    (["fit", "a.binary", "--model", "ward", "--compare-published"],
     "fit: --compare-published goes with --models (one TARGET); this is a fit of one model "
     "(--model)"),
    (["fit", "a.binary", "--model", "ward", "--out", "d"],
     "fit: --out goes with a sweep (several TARGET files with --models) or --models (one "
     "TARGET); this is a fit of one model (--model)"),
    (["fit", "a.binary", "--model", "ward", "--scheduler", "tcp://127.0.0.1:1"],
     "fit: --scheduler goes with a sweep (several TARGET files with --models); this is a fit of "
     "one model (--model)"),
    (["fit", "a.binary", "--model", "ward", "--force"], "fit: --force goes with a sweep"),
    (["fit", "a.binary", "b.binary", "--models", "all", "--compare-published"],
     "fit: --compare-published goes with --models (one TARGET); this is a sweep (several "
     "TARGETs)"),
    # --workers with one file fits in this process: refused, not a sweep of one file
    (["fit", "a.binary", "--models", "all", "--workers", "2"],
     "fit: --workers goes with a sweep (several TARGET files with --models); this is a fit of "
     "the models to one TARGET (--models)"),
    (["fit", "a.binary", "--models", "ward", "--free", "alpha"],
     "fit: --free goes with --model (one TARGET); this is a fit of the models to one TARGET"),
    (["fit", "a.binary", "--models", "ward", "-o", "f.json"], "fit: -o/--output goes with --model"),
    (["fit", "a.binary", "--models", "ward", "--plot", "f.png"], "fit: --plot goes with --model"),
    (["fit", "a.binary", "b.binary", "--model", "ward"],
     "fit: several TARGETs make a sweep, which takes --models"),
    (["fit", "a.binary", "--models", ""],
     "--models '' names no model: give 'all' or names among phong, ward, cooktorrance, "
     "ashikhmin, lafortune, he"),
    (["fit", "a.binary", "--models", " , "], "--models ' , ' names no model"),
    # the mode is checked before the variant is set
    (["fit", "a.binary", "--model", "ward", "--out", "d", "--variant", "nosuch_rgb"],
     "fit: --out goes with"),
    # furnace renders only with --render
    (["furnace", "diffuse", "-o", "f.exr"],
     "furnace: -o/--output goes with --render; this is the albedo table alone (no --render)"),
    (["furnace", "diffuse", "--spp", "4"], "furnace: --spp goes with --render"),
    (["furnace", "diffuse", "--res", "4"], "furnace: --res goes with --render"),
    (["furnace", "diffuse", "--force"], "furnace: --force goes with --render"),
    # plot: each kind its options
    (["plot", "slice", "diffuse", "--thetas", "30"],
     "plot: --thetas goes with plot lobe or plot albedo or plot pp; this is plot slice"),
    (["plot", "lobe", "diffuse", "-n", "64"],
     "plot: -n/--samples goes with plot albedo; this is plot lobe"),
    (["plot", "slice", "diffuse", "-n", "64"], "plot: -n/--samples goes with plot albedo"),
    (["plot", "albedo", "diffuse", "--log"], "plot: --log goes with plot lobe; this is plot "
                                             "albedo"),
    (["plot", "slice", "diffuse", "--no-cos"], "plot: --no-cos goes with plot lobe"),
    (["plot", "lobe", "diffuse", "--res", "64"], "plot: --res goes with plot slice; this is "
                                                 "plot lobe"),
    (["render", "furnace", "--no-png", "--exposure", "1"],
     "render: --exposure goes with the PNG preview (no --no-png); this is a render without its "
     "PNG preview (--no-png)"),
    (["compare", "a.xml", "b.xml", "--swap", "material=diffuse"],
     "compare: --swap goes with one SCENE; this is a comparison of two scenes (A.xml B.xml)"),
    (["compare", "a.xml"], "compare takes A.xml B.xml, or one scene with --swap ID=BSDF"),
    (["measure", "diffuse", "-o", "d.binary", "--seed", "3"],
     "measure: --seed goes with --noise; this is an exact measurement (no --noise)"),
    (["validate", "--only", "lambert", "--readme", "README.md"],
     "validate: --readme goes with the whole run (no --only); this is a partial run (--only)"),
    (["bench", "--only", "lambert", "--readme", "README.md"], "bench: --readme goes with the "
                                                             "whole run"),
]


@pytest.mark.parametrize("args,message", REFUSED, ids=[" ".join(a)[:60] for a, _ in REFUSED])
def test01_an_option_the_mode_does_not_take_is_refused(tmp_path, monkeypatch, args, message):
    monkeypatch.chdir(tmp_path)
    cli_one_line_error(args, message)
    assert list(tmp_path.iterdir()) == []


def _checked(*argv):
    args = _parser().parse_args(list(argv))
    modes.check(args)
    return args


def test02_defaults_come_from_the_mode():
    """The options of a mode left out get that mode's defaults; other modes leave them None
    (the parser gives none, so that an option given can be told from one left out)."""
    args = _checked("furnace", "diffuse", "--render")
    assert (args.spp, args.res, args.output) == (128, 64, None)  # (-o: the command's default)
    args = _checked("furnace", "diffuse")
    assert (args.spp, args.res) == (None, None)
    assert _checked("plot", "slice", "diffuse").res == 128
    assert _checked("plot", "lobe", "diffuse").res is None
    assert _checked("render", "furnace").exposure == 0.0
    assert _checked("measure", "diffuse", "-o", "d.binary", "--noise", "0.1").seed == 0
    assert _checked("fit", "gold.binary", "--models", "all").out == "gold-models"
    assert _checked("fit", "roughconductor alpha=0.3", "--models", "all").out == \
        "roughconductor-models"
    assert _checked("fit", "a.binary", "b.binary", "--models", "all").out == "sweep"
    assert _checked("fit", "a.binary", "--models", "all", "--out", "x").out == "x"
    assert _checked("fit", "a.binary", "--model", "ward").out is None


def test03_targets_are_counted_as_the_parser_reads_them():
    """One BSDF with its parameters, quoted or not, is one TARGET; two names are two."""
    assert modes.bsdf_count(["roughconductor", "alpha=0.3", "material=Au"]) == 1
    assert modes.bsdf_count(["roughconductor alpha=0.3 material=Au"]) == 1
    assert modes.bsdf_count(['<bsdf type="diffuse"/>']) == 1
    assert modes.bsdf_count(["a.binary", "b.binary", "diffuse"]) == 3


def test04_the_docs_show_the_table():
    """docs/usage.md shows every mode and the options only it takes, as cli.modes declares."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "usage.md").read_text()
    for command, mode, options in modes.table():
        assert f"| `{command}` | {mode} | {options} |" in text, (command, mode)
