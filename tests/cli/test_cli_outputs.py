"""
Nothing written unasked into the user's folder (mi_brdfs.imageio.planned_outputs): each command,
run from a folder that holds files of the names it would write, leaves them untouched and says
so in one line before any work; --force replaces them; a file named with -o is replaced.
"""

import pytest

from conftest import LLVM_OK
from helpers import cli_one_line_error
from mi_brdfs.cli import main

RENDER = ["--spp", "1", "-D", "res=8"]
FORCE = "or pass --force to replace it"

#: (command, the file already there, the line that refuses it)
REFUSED = [
    (["render", "furnace", *RENDER], "furnace.exr",
     "render: ./furnace.exr exists; name another with -o, " + FORCE),
    (["render", "furnace", *RENDER, "-o", "mine.exr"], "mine.png",
     "render: ./mine.png (the PNG preview beside the EXR) exists; name another EXR with -o, "
     "pass --no-png, " + FORCE),
    (["furnace", "diffuse", "--render"], "furnace.exr", "furnace: ./furnace.exr exists"),
    (["furnace", "diffuse", "--render", "-o", "f.exr"], "f.png",
     "furnace: ./f.png (the PNG preview beside the EXR) exists"),
    (["plot", "lobe", "diffuse"], "lobe.png", "plot: ./lobe.png exists; name another with -o"),
    (["compare", "furnace", "--swap", "material=diffuse"], "compare.png",
     "compare: ./compare.png exists"),
    (["compare", "furnace", "--swap", "material=diffuse", "-o", "c.png"], "c-diff.exr",
     "compare: ./c-diff.exr (an EXR beside the figure) exists; name another figure with -o"),
    (["simplify", "furnace", "--quick"], "furnace-simplified.xml",
     "simplify: ./furnace-simplified.xml exists"),
    (["simplify", "furnace", "--quick", "-o", "s.xml", "--report", "r"], "r/simplify.png",
     "simplify: ./r/simplify.png exists; name another folder with --report, " + FORCE),
    (["fit", "gold.binary", "--models", "ward"], "gold-models/models.md",
     "fit: ./gold-models/models.md exists; name another folder with --out, " + FORCE),
    (["fit", "gold.binary", "--models", "ward", "--out", "mine"], "mine/spheres.png",
     "fit: ./mine/spheres.png exists"),
    (["fit", "a.binary", "b.binary", "--models", "ward"], "sweep/sweep.json",
     "fit: ./sweep/sweep.json exists; name another folder with --out"),
    (["validate", "--quick"], "validation/REPORT.md",
     "validate: ./validation/REPORT.md exists; name another folder with --out, " + FORCE),
    (["bench", "--quick", "--out", "b"], "b/SPEED_ACCURACY.md", "bench: ./b/SPEED_ACCURACY.md"),
    (["audit", "--quick"], "validation/audit/findings-quick.json",
     "audit: ./validation/audit/findings-quick.json exists"),
]


def _merl_files(folder, names):
    """Files of a MERL file's size and header, each with other content (a sweep reads them
    before it plans its report)."""
    import struct

    for i, name in enumerate(names):
        with open(folder / name, "wb") as f:
            f.write(struct.pack("<3i", 90, 90, 180) + bytes([i]))
            f.truncate(12 + 3 * 90 * 90 * 180 * 8)


def _tree(folder):
    return {str(p.relative_to(folder)): p.read_bytes() if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


@pytest.mark.parametrize("args,existing,message", REFUSED,
                         ids=[" ".join(a)[:50] + f" ({e})" for a, e, _ in REFUSED])
def test01_an_existing_file_is_refused_untouched(tmp_path, monkeypatch, args, existing,
                                                 message):
    if args[0] in ("fit", "validate", "bench", "audit") and not LLVM_OK:
        pytest.skip("needs llvm_ad_rgb")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    if "a.binary" in args:
        _merl_files(tmp_path, ["a.binary", "b.binary"])
    (tmp_path / existing).parent.mkdir(parents=True, exist_ok=True)
    (tmp_path / existing).write_text(f"the user's own {existing}\n")
    before = _tree(tmp_path)
    cli_one_line_error(args, message)
    assert _tree(tmp_path) == before  # untouched, and nothing else written


def test02_force_replaces_and_a_named_file_is_replaced(tmp_path, monkeypatch, capsys):
    """--force replaces a default output; -o names a file, which is replaced without it (but
    not the PNG beside it: test01)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    for name in ("slice.png", "mine.exr"):
        (tmp_path / name).write_text("the user's own\n")
    assert main(["plot", "slice", "diffuse", "--res", "4", "--force"]) == 0
    assert (tmp_path / "slice.png").read_bytes()[:4] == b"\x89PNG"
    assert main(["render", "furnace", *RENDER, "-o", "mine.exr", "-q"]) == 0
    assert (tmp_path / "mine.exr").read_bytes()[:4] == b"v/1\x01"  # OpenEXR's magic number
    assert (tmp_path / "mine.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.skipif(not LLVM_OK, reason="fit needs llvm_ad_rgb")
def test03_fit_models_writes_a_new_folder_named_after_the_target(tmp_path, monkeypatch,
                                                                 capsys):
    """fit TARGET --models without --out writes ./TARGET-models/, not the current folder,
    whose models.md (the user's) stays as it was (the fits stubbed: where they go is tested)."""
    from mi_brdfs.fit import models

    pytest.importorskip("matplotlib")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "models.md").write_text("the user's own notes\n")
    folders = []

    def fits(target, names, metric, out, **kwargs):
        folders.append(out)
        return {"scores": {}, "published": None, "written": []}

    monkeypatch.setattr(models, "fit_models", fits)
    assert main(["fit", "gold.binary", "--models", "ward", "-q"]) == 0
    assert folders == [tmp_path / "gold-models"] and folders[0].is_dir()
    assert (tmp_path / "models.md").read_text() == "the user's own notes\n"
