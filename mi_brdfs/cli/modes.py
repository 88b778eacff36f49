"""
What each command's options mean in each of its modes, as data, checked before any work.

Some commands do different things with different arguments: ``fit`` fits one model
(``--model``), every lecture model to one TARGET (``--models``), or sweeps several TARGET
files; ``plot`` draws a lobe, an albedo curve or a slice; ``furnace`` renders only with
``--render``. :data:`MODES` declares, for each such command, its modes (the first one whose
arguments select it is the one chosen) and the options that only some of them take. An option
given in a mode that does not take it would do nothing there, so it is refused in one line that
names the option and the mode, e.g. ``fit: --compare-published goes with --models (one TARGET);
this is a fit of one model (--model)``, before the variant is set or a file is read. The parser
leaves those options None, so that an option given can be told from one left out; their
defaults, which may differ between modes, are here, but for a default output file, which the
command names itself (it may not replace an existing file:
:func:`mi_brdfs.imageio.planned_outputs`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import MiBrdfsError


@dataclass(frozen=True)
class Mode:
    """
    One way a command runs. ``name``: what it is, in "this is NAME"; ``short``: how "OPTION
    goes with SHORT" names it; ``chosen``: whether the parsed arguments select it;
    ``takes``: the options that only some modes of the command take, as spelled on the command
    line, each with its default in this mode (None: none; a function: of the arguments);
    ``needs``: (an option this mode cannot run without, the line that says so).
    """

    name: str
    short: str
    chosen: Callable
    takes: dict = field(default_factory=dict)
    needs: tuple | None = None


def bsdf_count(tokens) -> int:
    """How many BSDFs the command-line tokens name (each starts at a word without '=', or an
    XML fragment), without reading a file or loading a plugin."""
    from ..bsdfspec import _words

    return sum(1 for w in _words(tokens) if "=" not in w or w.lstrip().startswith("<"))


def models_folder(args) -> str:
    """The default folder of ``fit TARGET --models``: a new one named after the TARGET
    (``gold.binary``: ``gold-models``; ``roughconductor alpha=0.3``: ``roughconductor-models``)."""
    first = args.target[0].split()[0] if args.target[0].split() else "target"
    stem = "bsdf" if first.startswith("<") else Path(first).stem or "target"
    return f"{stem}-models"


_FIT_SWEEP = ("several TARGETs make a sweep, which takes --models (the lecture models fitted to "
              "each file, e.g. --models all); --model fits one model to one TARGET")

#: Each command's modes, in the order they are tried; options that no mode of a command lists
#: are taken by every mode.
MODES = {
    "fit": (
        Mode("a sweep (several TARGETs)", "a sweep (several TARGET files with --models)",
             lambda a: bsdf_count(a.target) > 1,
             {"--out": "sweep", "--workers": None, "--scheduler": None, "--force": None},
             needs=("--models", _FIT_SWEEP)),
        Mode("a fit of the models to one TARGET (--models)", "--models (one TARGET)",
             lambda a: a.models is not None,
             {"--out": models_folder, "--compare-published": None, "--force": None}),
        Mode("a fit of one model (--model)", "--model (one TARGET)", lambda a: True,
             {"--free": None, "-o/--output": None, "--plot": None}),
    ),
    "furnace": (
        Mode("the furnace render (--render)", "--render", lambda a: a.render,
             {"-o/--output": None, "--spp": 128, "--res": 64, "--force": None}),
        Mode("the albedo table alone (no --render)", "the table alone", lambda a: True),
    ),
    "plot": (
        Mode("plot lobe", "plot lobe", lambda a: a.kind == "lobe",
             {"--thetas": None, "--log": None, "--no-cos": None}),
        Mode("plot albedo", "plot albedo", lambda a: a.kind == "albedo",
             {"--thetas": None, "-n/--samples": None}),
        Mode("plot slice", "plot slice", lambda a: a.kind == "slice", {"--res": 128}),
        Mode("plot pp", "plot pp", lambda a: a.kind == "pp", {"--thetas": None}),
    ),
    "render": (
        Mode("a render without its PNG preview (--no-png)", "--no-png", lambda a: a.no_png),
        Mode("a render with its PNG preview", "the PNG preview (no --no-png)", lambda a: True,
             {"--exposure": 0.0}),
    ),
    "compare": (
        Mode("a comparison of two scenes (A.xml B.xml)", "A.xml B.xml",
             lambda a: len(a.scenes) == 2),
        Mode("a comparison of one scene with itself, a material swapped", "one SCENE",
             lambda a: len(a.scenes) == 1, {"--swap": None},
             needs=("--swap", "compare takes A.xml B.xml, or one scene with --swap ID=BSDF")),
    ),
    "measure": (
        Mode("a measurement with noise (--noise)", "--noise", lambda a: a.noise is not None,
             {"--seed": 0}),
        Mode("an exact measurement (no --noise)", "exact", lambda a: True),
    ),
}
for _command in ("validate", "bench"):
    MODES[_command] = (
        Mode("a partial run (--only), which cannot fill every figure the documents quote",
             "--only", lambda a: a.only is not None),
        Mode("the whole run", "the whole run (no --only)", lambda a: True,
             {"--readme": None}),
    )


def _dest(option: str) -> str:
    """The attribute of an option as spelled (``-o/--output``: ``output``)."""
    return max(option.split("/"), key=len).lstrip("-").replace("-", "_")


def _given(value) -> bool:
    return value is not None and value is not False and value != []


def check(args) -> None:
    """
    Refuse, in one line, an option that the mode ``args`` choose does not take, or a mode
    without what it needs; then give each option of the mode left out its default.
    """
    modes = MODES.get(args.command, ())
    mode = next((m for m in modes if m.chosen(args)), None)
    if mode is None:
        return  # no mode fits (too many scenes, ...): the command says what it takes
    if mode.needs and not _given(getattr(args, _dest(mode.needs[0]))):
        raise MiBrdfsError(f"{args.command}: {mode.needs[1]}")
    for option in dict.fromkeys(o for m in modes for o in m.takes):
        if option not in mode.takes and _given(getattr(args, _dest(option))):
            where = " or ".join(m.short for m in modes if option in m.takes)
            raise MiBrdfsError(f"{args.command}: {option} goes with {where}; this is "
                               f"{mode.name}")
    for option, default in mode.takes.items():
        if getattr(args, _dest(option)) is None and default is not None:
            setattr(args, _dest(option), default(args) if callable(default) else default)


def table() -> list[tuple[str, str, str]]:
    """(command, mode, the options only it takes) for every mode: the table of docs/usage.md."""
    return [(command, mode.name, ", ".join(f"`{o}`" for o in mode.takes) or "—")
            for command, modes in MODES.items() for mode in modes]
