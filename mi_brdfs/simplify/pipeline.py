"""
:func:`simplify`, step by step: the scene read and checked, the engine and its cache set up,
the candidates of every material measured, the choice made, the simplified scene verified at
other seeds, and the scene file and the report written (see :mod:`mi_brdfs.simplify`).
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import time
from pathlib import Path

from ..errors import MiBrdfsError, ParameterError, counts, mitsuba_error_line
from ..variants import keeps_variant
from .candidates import _cached_fit, candidates_for, kept_reason
from .choose import OBJECTIVES, _choose, _derive, _predict
from .measure import (
    CACHE_VERSION, MAX_SEEDS, MIN_REPEATS, _Cache, _Engine, _key, _original_numbers,
    default_cache_dir,
)
from .report import Candidate, MaterialResult, SimplifyResult, plot, write_report
from ..scenes import _check_film, used_defines
from .scene import NAMES_FILES, element_text, locate, merge_includes, scene_bsdfs, splice, unmerge

#: Settings (full, quick): spp per seed, timing repeats, seconds per timing render, resolution
#: of ``--quick`` (through ``-D res=`` where the scene declares that default).
SPP = (64, 16)
REPEATS = (7, 3)
TIMING_S = (0.15, 0.04)
QUICK_RES = 128

#: Fit sizes (full, quick).
FIT_SIZES = ({}, {"pairs": 4096, "steps": 200, "thetas_deg": (0.0, 45.0, 80.0)})


def _public(fn):
    """``fn`` under the name of :mod:`mi_brdfs.simplify`, which exports it (the one-line error
    of a bad count names ``simplify.simplify``, as it always has)."""
    fn.__module__ = "mi_brdfs.simplify"
    return fn


def _check_tolerance(tolerance) -> float:
    ok = isinstance(tolerance, (int, float)) and not isinstance(tolerance, bool) \
        and 0 < tolerance < 1
    if not ok:  # a relative RMSE of 1 is a black image's against any other
        raise MiBrdfsError(f"simplify: tolerance = {tolerance!r} is invalid: must lie in "
                           f"(0, 1) (a relative RMSE, e.g. 0.01; 1 is a black image's)")
    return float(tolerance)


def _report_dir(report) -> Path | None:
    if report is None:
        return None
    from ..imageio import output_folder

    return output_folder(report, f"report {report}", "SIMPLIFY.md")


@counts("spp", "repeats")
@_public
@keeps_variant
def simplify(scene, tolerance: float = 0.01, *, variant: str | None = None, output=None,
             report=None, quick: bool = False, spp: int | None = None,
             defines: dict | None = None, cache=True, confidence: float = 2.0,
             objective: str = "simplicity", fits: bool = True, repeats: int | None = None,
             progress: bool = False) -> SimplifyResult:
    """
    Measure cheaper candidates for every material of ``scene`` and write the simplified scene
    (see :mod:`mi_brdfs.simplify`).

    Parameter ``scene``: a scene file or bundled name. ``tolerance``: on the relative RMSE
    (RMSE over the reference image's mean) of the converged image against the original's.
    ``variant``: Mitsuba variant (default: the current one, else llvm_ad_rgb where it works);
    the caller's is set again on return, and when simplify raises.
    ``output``: where to write the simplified scene (None: not written). ``report``: a folder
    for SIMPLIFY.md, the plot and (by default) the cache. ``quick``: ``res`` of
    :data:`QUICK_RES` at most (where the scene declares that default) and fewer spp, repeats and fit
    steps. ``spp``: per seed, for the original and every candidate. ``defines``: ``<default>``
    overrides. ``cache``: True (``report/cache`` or :func:`default_cache_dir`), a folder, or
    False. ``objective``: ``simplicity`` (a simpler candidate within the tolerance and not
    measurably slower replaces a material: the fastest of them; the order of simplicity:
    :data:`~mi_brdfs.simplify.choose.SIMPLER_KINDS`, :data:`~mi_brdfs.simplify.choose.
    SIMPLER_SWITCHES`) or ``speed`` (only a measurably faster one). ``confidence``: standard
    errors by which a speed-up must differ from 1 to count as measurably faster or slower (0:
    any estimated difference). ``fits``: also fit cheaper models. ``repeats``: timing
    pairs per candidate (3 or more, else no speed-up has a standard error: none counts as
    measurably faster but with ``confidence`` 0).

    Returns → :class:`SimplifyResult`. Raises MiBrdfsError (one line) for bad input.
    """
    from ..progress import Progress

    clock = time.perf_counter()
    tolerance = _check_tolerance(tolerance)
    if not (isinstance(confidence, (int, float)) and not isinstance(confidence, bool)
            and math.isfinite(confidence) and confidence >= 0):
        raise MiBrdfsError(f"simplify: confidence = {confidence!r} is invalid: must be a finite "
                           f"number >= 0 (standard errors; 0: any estimated gain)")
    if objective not in OBJECTIVES:
        raise MiBrdfsError(f"simplify: objective = {objective!r} is invalid: must be one of "
                           f"{', '.join(OBJECTIVES)}")
    path, (data, source), out, report_dir, materials, scene_defaults, included = \
        _read(scene, output, report, defines)
    variant = _use_variant(variant)
    defines, notes = _defines(path, defines, scene_defaults, quick)
    _check_film(path.name, data.decode("utf-8", "replace"), defines)
    notes[:0] = included
    level = 1 if quick else 0
    spp = spp or SPP[level]
    repeats = repeats or REPEATS[level]
    if repeats < MIN_REPEATS and confidence > 0:
        notes.append(f"{repeats} timing repeats give no standard error (3 or more do): no "
                     f"candidate counts as measurably faster")
    values = dict(scene_defaults, **defines)
    store, engine = _engine(path, data, report_dir, cache, variant, defines, spp, repeats, level)
    fit_fn = _cached_fit(store, FIT_SIZES[level])

    # candidates of every material (fits included), then the measurements
    plans = _plans(materials, values, fit_fn if fits else None, notes)
    total = 2 + sum(len(c) for _, c, _ in plans)
    bar = Progress(total, label=f"simplify {path.name}", unit=" scenes") if progress else None
    try:
        results = _measure(plans, engine, data, tolerance, bar)
        ref_numbers, original_time = _decide(results, engine, tolerance, confidence, objective)
        predicted = _within_together(results, ref_numbers, tolerance, original_time, notes)
        verification, replacements, text, predicted = _verify(
            results, data, engine, ref_numbers, tolerance, original_time, predicted, notes)
        if bar:
            bar.update(total, note="verified")
    finally:
        if bar:
            bar.close()

    measured = {}
    if verification is not None and verification.ok:
        measured = {"speedup": verification.speedup, "bias": verification.bias}
    result = SimplifyResult(scene=path, tolerance=tolerance, variant=variant, spp=spp,
                            defines=defines, quick=quick, materials=results,
                            original=ref_numbers, replacements=replacements, text=text,
                            verification=verification, predicted=predicted, measured=measured,
                            notes=notes, renders=engine.renders, objective=objective)
    result.text, result.included = _split(result, source, out)
    if out is not None:
        _write_scene(result, out)
    result.seconds = time.perf_counter() - clock
    if report_dir is not None:
        result.figure = plot(result, report_dir / "simplify.png")
        result.report = write_report(result, report_dir / "SIMPLIFY.md")
    return result


def _read(scene, output, report, defines) -> tuple:
    """
    (path, (bytes, source), output path or None, report folder or None, materials,
    ``<default>`` values, notes on the materials of included files left alone) of the scene,
    each checked before any work. The bytes are the scene's with the files it includes merged
    in (:func:`~.scene.merge_includes`); source is (the scene file's own
    bytes, those files' :class:`~.scene.Part` records).
    """
    from ..imageio import check_writable
    from ..scenes import scene_path, scene_text

    if not isinstance(scene, (str, os.PathLike)):
        raise ParameterError("simplify", "scene", scene, "must be a scene file or the name of "
                             "a bundled scene (e.g. 'showcase')")
    if defines is not None and not isinstance(defines, dict):
        raise ParameterError("simplify", "defines", defines, "must be a dict {name: value} of "
                             "the scene's <default>s")
    path = scene_path(scene)
    scene_text(path)  # a file that is no UTF-8 <scene> is one line, before any work
    data = path.read_bytes()
    if output is not None and Path(output).suffix.lower() != ".xml":
        raise ParameterError("simplify", "output", str(output),
                             "must end in .xml (the simplified scene is an XML file)")
    out = check_writable(output) if output is not None else None
    if out is not None and out.resolve() == path.resolve():
        raise MiBrdfsError(f"simplify: the output {out} is the scene itself: write the "
                           f"simplified scene to another file")
    report_dir = _report_dir(report)
    values = dict(scene_bsdfs(data)[1], **{k: str(v) for k, v in (defines or {}).items()})
    merged, parts = merge_includes(path.parent, data, values)
    materials, scene_defaults = scene_bsdfs(merged)
    locate(materials, parts, data)
    if out is not None:
        _check_included_names(path, out, parts)
    included = _included(path, merged, values, {path.resolve(), *(p.file for p in parts)})
    if not materials:
        raise MiBrdfsError(f"{path.name} has no <bsdf>: nothing to simplify" if not included
                           else f"{path.name} has no <bsdf> of its own, nothing to simplify: "
                                f"{'; '.join(included)}")
    return path, (merged, (data, parts)), out, report_dir, materials, scene_defaults, included


def _included(path: Path, data: bytes, values: dict, seen: set | None = None) -> list[str]:
    """
    A note for each file the scene ``<include>``s (and they include) that holds a ``<bsdf>``,
    or that cannot be read, but those of ``seen`` (the scene and the files merged into it):
    simplify says what it leaves alone.
    """
    from .scene import includes

    seen = seen if seen is not None else {path.resolve()}
    notes = []
    for name in includes(data):
        name = re.sub(r"\$(\w+)", lambda m: str(values.get(m.group(1), m.group(0))), name)
        file = (path.parent / name).resolve()
        if file in seen:
            continue
        seen.add(file)
        try:
            text = file.read_bytes()
            found, _ = scene_bsdfs(text)
        except (OSError, MiBrdfsError) as e:
            why = "not found beside the scene" if isinstance(e, FileNotFoundError) else \
                f"unreadable ({getattr(e, 'strerror', None) or e})"
            notes.append(f"included file {name}: {why}; any materials in it are left alone")
            continue
        if found:
            listed = ", ".join(f"{m.label} ({m.type})" for m in found if m.parent is None)
            notes.append(f"materials in included file {name} ({listed}): left alone "
                         f"(a file included from another folder that names files relative "
                         f"to it, or by an included file, is not edited; copy them into "
                         f"{path.name} to simplify them)")
        notes += _included(file, text, values, seen)
    return notes


def _use_variant(variant: str | None) -> str:
    """The variant measured in: ``variant``, else the current one, else the default."""
    import mitsuba as mi

    from ..registry import use_variant

    if variant is not None or mi.variant() is None:
        use_variant(variant)
    return mi.variant()


def _defines(path: Path, defines: dict | None, scene_defaults: dict, quick: bool) -> tuple:
    """(defines as strings, notes): each must name a ``<default>`` of the scene; ``quick``
    adds ``res`` where the scene declares it."""
    defines = {k: str(v) for k, v in (defines or {}).items()}
    unknown = sorted(set(defines) - set(scene_defaults))
    if unknown:
        raise MiBrdfsError(f"{path.name} declares no <default> for {', '.join(unknown)} (a "
                           f"define must name a <default name=...> of the scene)")
    notes = []
    if quick and "res" not in defines:
        if "res" in scene_defaults:
            declared = scene_defaults["res"]
            # at most QUICK_RES: a scene that declares less keeps its own
            defines["res"] = str(min(QUICK_RES, int(declared))) if declared.isdigit() \
                else str(QUICK_RES)
        else:
            notes.append("--quick: the scene declares no <default name=\"res\">, so it renders "
                         "at its own resolution")
    return defines, notes


def _engine(path: Path, data: bytes, report_dir: Path | None, cache, variant: str,
            defines: dict, spp: int, repeats: int, level: int) -> tuple:
    """(cache, engine): the cache folder of ``cache`` for this scene's content, and the engine
    whose measurements are stored under a key of every setting."""
    import mitsuba as mi

    from .._version import __version__

    if cache is True:
        cache_dir = (report_dir / "cache") if report_dir else default_cache_dir()
    elif cache:
        cache_dir = Path(cache).expanduser()
    else:
        cache_dir = None
    scene_hash = hashlib.sha256(data).hexdigest()
    store = _Cache(cache_dir / scene_hash[:16] if cache_dir else None)
    settings = {"version": CACHE_VERSION, "mi_brdfs": __version__, "mitsuba": mi.__version__,
                "variant": variant, "defines": defines, "spp": spp, "repeats": repeats,
                "timing_s": TIMING_S[level], "scene": scene_hash}
    engine = _Engine(path, data, defines, spp, repeats, TIMING_S[level], MAX_SEEDS, store,
                     _key(settings))
    return store, engine


def _plans(materials: list, values: dict, fit_fn, notes: list) -> list:
    """(material, its candidates, why it has none or '') of every material; a material whose
    candidates fail gets none, and a note."""
    plans = []
    for mat in materials:
        try:
            cands = candidates_for(mat, values, fit_fn)
            reason = "" if cands else kept_reason(mat, fit_fn is not None)
        except MiBrdfsError as e:
            cands, reason = [], f"no candidates: {e}"
            notes.append(f"{mat.label}: no candidates ({e})")
        plans.append((mat, cands, reason))
    return plans


def _measure(plans: list, engine: _Engine, data: bytes, tolerance: float, bar) -> list:
    """The original, then every candidate in the scene with only its material replaced: a
    :class:`MaterialResult` per material (the original first), the progress ``bar`` updated."""
    done = 0
    engine.info()
    done += 1
    if bar:
        bar.update(done, note="the original")
    results = []
    for mat, cands, reason in plans:
        entries = [Candidate("original", "original", mat.text)]
        for label, kind, element, note in cands:
            c = Candidate(label, kind, note=note)
            if element is None:
                c.error = note or "no candidate"
            else:
                c.xml = element_text(element, mat.indent)
                try:
                    c.measured, c.cached = engine.measure(
                        splice(data, {(mat.start, mat.end): c.xml}), tolerance)
                except (MiBrdfsError, RuntimeError) as e:
                    c.error = mitsuba_error_line(e)
            entries.append(c)
            done += 1
            if bar:
                bar.update(done, note=f"{mat.label}: {label}"[:50])
        results.append(MaterialResult(mat, entries, reason=reason))
    return results


def _decide(results: list, engine: _Engine, tolerance: float, confidence: float,
            objective: str) -> tuple:
    """
    (the original's numbers, its time to the tolerance): every measured candidate derived
    against them (the original as one with ratios 1 and no bias), and each material's choice.
    """
    ref_numbers = _original_numbers(results, engine)
    original_time = ref_numbers["variance_1spp_ref"] * ref_numbers["ref_seconds_per_spp"] \
        / tolerance ** 2
    for r in results:
        r.candidates[0].measured = dict(ref_numbers, b2=0.0, b2_se=0.0, noise=0.0,
                                        bias=0.0, bias_hi=0.0, bias_lo=0.0,
                                        variance_ratio=1.0, variance_ratio_se=0.0,
                                        cost_ratio=1.0, cost_ratio_se=0.0, flip=None)
        for c in r.candidates:
            if c.ok:
                _derive(c, ref_numbers, tolerance, original_time)
        _choose(r, tolerance, confidence, objective)
    return ref_numbers, original_time


def _within_together(results: list, ref_numbers: dict, tolerance: float, original_time: float,
                     notes: list) -> dict:
    """The prediction of :func:`_predict`, once the chosen replacements whose bias² add up
    beyond τ² are dropped, the largest first."""
    predicted = _predict(results, ref_numbers, tolerance, original_time)
    while predicted["bias"] > tolerance:  # the parts' bias² add up beyond τ²
        worst = max((r for r in results if r.chosen),
                    key=lambda r: r.candidates[r.chosen].measured["b2"])
        notes.append(f"the chosen replacements' biases add up beyond the tolerance: "
                     f"{worst.label} kept as it was")
        worst.candidates[worst.chosen].verdict = "within alone, not with the others"
        worst.chosen, worst.reason = 0, "kept: the replacements together exceed the tolerance"
        worst.candidates[0].verdict = "kept"
        predicted = _predict(results, ref_numbers, tolerance, original_time)
    return predicted


def _verify(results: list, data: bytes, engine: _Engine, ref_numbers: dict, tolerance: float,
            original_time: float, predicted: dict, notes: list) -> tuple:
    """
    (verification or None, replacements, simplified text, prediction): the simplified scene
    measured at the seeds of 'verify'; while its bias bound exceeds the tolerance, the chosen
    replacement with the largest bias is dropped and the scene measured again.
    """
    verification = None
    while True:
        chosen = [r for r in results if r.chosen]
        replacements = {(r.material.start, r.material.end): r.candidates[r.chosen].xml
                        for r in chosen}
        text = splice(data, replacements)
        if not chosen:
            verification = None  # none left: the original, which needs no verification
            break
        # independent seeds and timing: the simplified scene is measured afresh, even where
        # it is one candidate's scene
        verification = Candidate("simplified scene", "simplified")
        verification.measured, verification.cached = engine.measure(text, tolerance, "verify")
        _derive(verification, ref_numbers, tolerance, original_time)
        if verification.bias_hi <= tolerance:
            break
        worst = max(chosen, key=lambda r: r.candidates[r.chosen].measured["b2"])
        notes.append(f"the simplified scene's bias {verification.bias:.4f} (bound "
                     f"{verification.bias_hi:.4f}, {verification.measured['seeds']} seeds) "
                     f"was not within the tolerance: {worst.label} kept as it was")
        worst.candidates[worst.chosen].verdict = "within alone, not with the others"
        worst.chosen, worst.reason = 0, "kept: the replacements together exceeded the " \
                                        "tolerance"
        worst.candidates[0].verdict = "kept"
        predicted = _predict(results, ref_numbers, tolerance, original_time)
    return verification, replacements, text, predicted


def _included_name(path: Path, out: Path | None, part) -> str:
    """The file name of a simplified included file: beside the output scene (or, with none,
    the name it would have beside the scene's ``-simplified`` file), prefixed by its stem."""
    stem = out.stem if out is not None else f"{path.stem}-simplified"
    return f"{stem}.{part.file.name}"


def _check_included_names(path: Path, out: Path, parts: list) -> None:
    """No simplified included file may overwrite the scene or a file it includes."""
    originals = {path.resolve(), *(p.file for p in parts)}
    for part in parts:
        target = (out.parent / _included_name(path, out, part)).resolve()
        if target in originals:
            raise MiBrdfsError(f"simplify: the simplified {part.name} would be written to "
                               f"{target.name}, which the scene reads: name the output "
                               f"scene otherwise")


def _split(result: SimplifyResult, source: tuple, out: Path | None) -> tuple:
    """(the simplified scene file's bytes, {file name: bytes} of each included file with a
    replacement, which it then includes instead)."""
    data, parts = source
    names = {p.file: _included_name(result.scene, out, p) for p in parts}
    text, included = unmerge(data, parts, result.replacements, names)
    return text, {names[part.file]: content for part, content in included.items()}


def _write_scene(result: SimplifyResult, out: Path) -> None:
    """Write the simplified included files, then the scene, each atomically, and check that
    the scene loads."""
    from ..imageio import atomic_path
    from ..scenes import load_scene

    for name, content in result.included.items():
        with atomic_path(out.parent / name, ".xml") as tmp:
            Path(tmp).write_bytes(content)
    with atomic_path(out, ".xml") as tmp:
        Path(tmp).write_bytes(result.text)
    result.output = out
    own = re.sub(rb"<include\b[^>]*>", lambda m: b"" if any(
        name.encode("utf-8") in m.group(0) for name in result.included) else m.group(0),
        result.text)  # the included files written beside it resolve there
    if out.parent.resolve() != result.scene.parent.resolve() and re.search(NAMES_FILES, own):
        result.notes.append(f"{out} lies in another folder than {result.scene.name}, whose "
                            f"relative file names (meshes, textures, included files) then "
                            f"resolve elsewhere")
        return
    scene_text = result.text + b"".join(result.included.values())
    load_scene(out, used_defines(result.defines, scene_text, tuple(result.included)))
