"""
Bad input on the command line, as a new user types it: every case ends in one line
``mi-brdfs: error: ...`` naming the argument, the value and what is allowed, exit status 2, no
traceback and nothing written (run in-process, in an empty folder).
"""

import pytest

from helpers import cli_one_line_error
from mi_brdfs.cli import main

SCENES = {
    "bsdf.xml": '<bsdf version="3.0.0" type="diffuse"/>',
    "noversion.xml": '<?xml version="1.0"?>\n<!-- a material -->\n<bsdf type="diffuse"/>',
    "shape.xml": '<shape version="3.0.0" type="sphere"/>',
    "noint.xml": """<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
        <integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <emitter type="constant"/><shape type="sphere"/></scene>""",
    "nosensor.xml": """<scene version="3.0.0"><integrator type="path"/>
        <emitter type="constant"/><shape type="sphere"/></scene>""",
    "width.xml": """<scene version="3.0.0"><default name="res" value="8"/>
        <integrator type="path"/><sensor type="perspective"><film type="hdrfilm">
        <integer name="width" value="$res"/><integer name="height" value="8"/></film></sensor>
        <emitter type="constant"/><shape type="sphere"/></scene>""",
}

BAD = [
    (["render", "furnace", "--spp", "0"], "argument --spp: must be at least 1, got 0"),
    (["render", "furnace", "--spp", "-3"], "argument --spp: must be at least 1, got -3"),
    (["render", "furnace", "--spp", "abc"], "'abc' is not a whole number"),
    (["render", "furnace", "--pass-spp", "0"], "argument --pass-spp: must be at least 1"),
    (["render", "furnace", "--pass-spp", "-1"], "argument --pass-spp: must be at least 1"),
    (["render", "furnace", "--processes", "0"], "argument --processes: must be at least 1"),
    (["render", "furnace", "--processes", "-2"], "argument --processes: must be at least 1"),
    (["render", "furnace", "--exposure", "nan"], "argument --exposure: must be finite, got nan"),
    (["render", "furnace", "--exposure", "inf"], "argument --exposure: must be finite"),
    (["render", "furnace", "--time-budget", "0"], "--time-budget: must be finite and > 0"),
    (["render", "furnace", "--time-budget", "nan"], "--time-budget: must be finite and > 0"),
    (["render", "furnace", "--seed", "-1"], "argument --seed: must lie in [0, 2^32)"),
    (["render", "furnace", "-o", ""], "the output path is empty"),
    (["render", "furnace", "-o", "x.png"], "'x.png' must end in .exr"),
    (["render", "noint.xml", "--spp", "1"], "noint.xml has no <integrator>"),
    (["render", "nosensor.xml", "--spp", "1"], "nosensor.xml has no <sensor>"),
    (["render", "width.xml", "--spp", "1", "-D", "res=0"], "the film's width is 0"),
    (["furnace", "lambert", "-n", "0"], "argument -n/--samples: must be at least 1"),
    (["furnace", "lambert", "-n", "-5"], "argument -n/--samples: must be at least 1"),
    (["furnace", "lambert", "--render", "--res", "0"], "argument --res: must be at least 1"),
    (["furnace", "lambert", "--render", "-o", "x.png"], "'x.png' must end in .exr"),
    (["plot", "slice", "lambert", "--res", "0"], "argument --res: must be at least 1"),
    (["plot", "albedo", "lambert", "-n", "0"], "argument -n/--samples: must be at least 1"),
    (["plot", "lobe", "lambert", "-o", "x.exr"], "'x.exr' must end in .png or .pdf or .svg"),
    (["compare", "furnace", "--swap", "material=diffuse", "-o", "x.exr"],
     "'x.exr' must end in .png"),
    (["compare", "furnace", "--swap", "material=diffuse", "--spp", "0"],
     "argument --spp: must be at least 1"),
    (["validate", "--out", "/proc/foo"], "--out /proc/foo: cannot create the folder"),
    (["bench", "--out", "/etc/passwd"], "--out /etc/passwd: not a folder"),
    (["check", "lambert", "--json", "/nonexistent/x.json"], "folder /nonexistent does not exist"),
    (["check", "lambert", "--json", "x.txt"], "'x.txt' must end in .json"),
    (["check", "noint.xml"], "noint.xml holds a <scene>, not a <bsdf>"),
    # Mitsuba's own words, as for its built-ins: '... plugin of type "lambert": - string "form"'
    (["check", "lambert", "form=x"], "unreferenced property in"),
    (["check", "phong", "lobe=sideways"], 'phong: parameter "lobe" = "sideways" is invalid'),
    (["nosuchcommand"], "invalid choice: 'nosuchcommand'"),
    # a file whose root is not <scene>, wherever a scene is taken
    (["render", "bsdf.xml", "--spp", "1"], "bsdf.xml holds a <bsdf>, not a <scene>"),
    (["render", "noversion.xml", "--spp", "1"], "noversion.xml holds a <bsdf>, not a <scene>"),
    (["compare", "shape.xml", "--swap", "a=diffuse"], "shape.xml holds a <shape>, not a <scene>"),
    (["simplify", "bsdf.xml", "--quick"], "bsdf.xml holds a <bsdf>, not a <scene>"),
    (["tables", "-o", "/nonexistent/t.npz"], "folder /nonexistent does not exist"),
    (["simplify", "furnace", "--tolerance", "2"], "argument --tolerance: must lie in (0, 1)"),
    # a second value would silently replace the first
    (["check", "roughconductor", "alpha=0.3", "alpha=0.5"],
     "parameter 'alpha' is given twice for 'roughconductor'"),
    (["fit", "roughconductor", "--model", "cooktorrance", "--model", "ward"],
     "argument --model: given twice"),
    # --only that names nothing, or nothing the run has: no run of everything or of nothing
    (["audit", "--out", ".", "--quick", "--only", "ashikhmin,lafortune"],
     "--only ashikhmin,lafortune --quick: none of these is in the quick audit"),
    (["audit", "--out", ".", "--only", ","], "--only ',' names nothing"),
    (["audit", "--out", ".", "--only", ""], "--only '' names nothing"),
    (["validate", "--out", ".", "--only", ""], "--only '' names nothing"),
    (["bench", "--out", ".", "--only", ""], "--only '' names nothing"),
    (["render", "width.xml", "--spp", "1", "-D", "res="], "-D res= has no value"),
]


@pytest.mark.parametrize("args,message", BAD, ids=[" ".join(a)[:60] for a, _ in BAD])
def test01_one_line_exit_2_nothing_written(tmp_path, monkeypatch, args, message):
    for name, text in SCENES.items():
        (tmp_path / name).write_text(text)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    cli_one_line_error(args, message)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(SCENES)  # nothing written


def test02_no_emitter_is_a_warning(tmp_path, capsys):
    """A scene without an emitter renders (black), with a one-line warning."""
    scene = tmp_path / "dark.xml"
    scene.write_text(SCENES["width.xml"].replace('<emitter type="constant"/>', ""))
    assert main(["render", str(scene), "--spp", "1", "-q", "-o", str(tmp_path / "d.exr")]) == 0
    err = capsys.readouterr().err
    assert "mi-brdfs: warning: dark.xml has no emitter: its image is black" in err


@pytest.mark.skipif(bool(__import__("drjit").has_backend(__import__("drjit").JitBackend.CUDA)),
                    reason="a CUDA device is there: cuda_ad_rgb is usable")
@pytest.mark.parametrize("command", [["check", "lambert"], ["furnace", "lambert"],
                                     ["fit", "lambert", "--model", "lambert"]])
def test03_cuda_variant_without_a_device(tmp_path, monkeypatch, command):
    """--variant cuda_ad_rgb on a machine without CUDA: one line that says so and names the
    variants that work here (not drjit's advice to call jit_init)."""
    monkeypatch.chdir(tmp_path)
    line = cli_one_line_error(command + ["--variant", "cuda_ad_rgb"],
                              "variant 'cuda_ad_rgb' needs a CUDA device, and this machine has "
                              "none")
    assert "usable here: scalar_rgb" in line and "jit_init" not in line and "cuda_" not in \
        line.split("usable here:")[1], line


def test04_a_file_that_is_not_utf8_is_one_line(tmp_path, monkeypatch):
    """A scene file in another encoding (here UTF-16 with its byte-order mark) is one line,
    read as UTF-8 whatever the locale, in the CLI and from Python."""
    from mi_brdfs.errors import MiBrdfsError
    from mi_brdfs.scenes import load_scene

    path = tmp_path / "latin.xml"
    path.write_bytes('<scene version="3.0.0"/>'.encode("utf-16"))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    cli_one_line_error(["render", "latin.xml", "--spp", "1"], "latin.xml is not UTF-8 text")
    with pytest.raises(MiBrdfsError, match="latin.xml is not UTF-8 text"):
        load_scene(path)
    (tmp_path / "bsdf.xml").write_text(SCENES["bsdf.xml"])
    with pytest.raises(MiBrdfsError, match="bsdf.xml holds a <bsdf>, not a <scene>"):
        load_scene(tmp_path / "bsdf.xml")
