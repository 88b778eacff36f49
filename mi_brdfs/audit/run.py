"""
Running the audit: every :class:`~mi_brdfs.audit.grid.Case` through the battery of checks and
Mitsuba's own χ² harness, in worker processes (:func:`mi_brdfs.runner.run`: Ctrl-C or SIGTERM
stops them at once), each case's results cached on disk as it finishes so that an interrupted
audit resumes where it stopped.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
import time
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

from .. import runner
from ..errors import MiBrdfsError
from . import grid

#: Incident angles (degrees) of Mitsuba's own χ² harness: normal, 45°, grazing (cosθ = 0.1).
MITSUBA_CHI2_THETAS = (0.0, 45.0, 84.26)


def _jsonable(value):
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()
                if not hasattr(v, "shape") or getattr(v, "size", 0) <= 16}
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def _record(case: grid.Case, variant: str, result) -> dict:
    return {"bsdf": case.bsdf, "config": case.config, "variant": variant,
            "check": result.name, "passed": bool(result.passed), "skipped": bool(result.skipped),
            "value": _jsonable(result.value), "tolerance": _jsonable(result.tolerance),
            "message": result.message, "details": _jsonable(result.details)}


def mitsuba_chi2(bsdf_xml: str, theta: float, quick: bool):
    """Mitsuba's own harness, as its test suite runs it: ``mi.chi2.BSDFAdapter`` on the XML,
    default resolution, one test per angle."""
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    from ..checks.result import CheckResult
    wi = [math.sin(math.radians(theta)), 0.0, math.cos(math.radians(theta))]
    # BSDFAdapter takes the plugin type and its inner XML: unwrap the <bsdf type=...> element
    head, _, body = bsdf_xml.partition(">")
    kind = head.split('type="', 1)[1].split('"', 1)[0]
    inner = body.rsplit("</bsdf>", 1)[0] if not head.endswith("/") else ""
    sample_func, pdf_func = BSDFAdapter(kind, inner, wi=wi)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=100_000 if quick else 1_000_000)
    try:
        passed = bool(test.run(quiet=True))
    except Exception as e:  # noqa: BLE001 - the harness's own failure is a result here
        return CheckResult(f"mitsuba chi2 θ={theta:g}°", False, math.nan, "n/a",
                           f"Mitsuba's χ² harness raised: {str(e).splitlines()[0][:200]}")
    log = " ".join(str(test.messages).split())[-300:]
    p = float(test.p_value) if test.p_value is not None else math.nan
    return CheckResult(f"mitsuba chi2 θ={theta:g}°", passed, p, 0.01,
                       f"Mitsuba's χ² harness at θ = {theta:g}°: "
                       f"{'passed' if passed else 'failed'}: {log}")


def run_case(case: grid.Case, variant: str, quick: bool) -> list[dict]:
    """All checks of one case in ``variant`` (the polarized variant for polarized BSDFs)."""
    from .. import registry
    from ..bsdfspec import to_xml
    from ..checks import run_battery
    from . import build, sides

    variant = grid.polarized_variant(variant) if case.polarized else variant
    registry.use_variant(variant, fallback=False)
    t0 = time.perf_counter()
    records = []
    try:
        bsdf = build.load(case)
    except Exception as e:  # noqa: BLE001 - a case that does not load is a finding
        from ..checks.result import CheckResult
        return [_record(case, variant, CheckResult("load", False, math.nan, "n/a",
                                                   f"does not load: {str(e)[:300]}"))]
    for result in run_battery(bsdf, quick=quick, progress=False, gradients=True):
        records.append(_record(case, variant, result))
    for result in sides.check_sides(bsdf, n=2_000 if quick else 20_000):
        records.append(_record(case, variant, result))
    harness = _harness_applies(bsdf, case)
    for theta in MITSUBA_CHI2_THETAS:
        if harness is None:
            result = mitsuba_chi2(to_xml(case.dict()), theta, quick)
        else:
            from ..checks.result import CheckResult
            result = CheckResult(f"mitsuba chi2 θ={theta:g}°", True, math.nan, "n/a",
                                 f"Mitsuba's χ² harness: not applicable: {harness}",
                                 skipped=True)
        records.append(_record(case, variant, result))
    ours = {r["check"].split("θ=")[1]: r["passed"] for r in records
            if r["check"].startswith("chi2 θ=")}
    for r in records:
        r["case_seconds"] = round(time.perf_counter() - t0, 2)
        if r["check"].startswith("mitsuba chi2 θ="):  # our χ² at the same angle, for triage
            r["details"]["ours_passed"] = ours.get(r["check"].split("θ=")[1])
    return records


def _harness_applies(bsdf, case) -> str | None:
    """Why Mitsuba's χ² harness cannot judge this case (None: it can)."""
    import mitsuba as mi
    if int(bsdf.flags()) & int(mi.BSDFFlags.Delta):
        return ("the BSDF has a Dirac lobe: mi.chi2.BSDFAdapter samples every lobe with the "
                "default context, and a Dirac lobe's pdf() is 0 by convention (our χ² restricts "
                "the context to the other lobes)")
    if any(isinstance(v, str) and v.startswith("__") for v in _leaves(case.dict())):
        return "the configuration holds a bitmap, which BSDFAdapter's XML cannot carry"
    if case.polarized:
        return ("polarized variant: mi.chi2.BSDFAdapter raises there (its sample_func masks "
                "`w[dr.all(weight == 0)] = 0` with a Mueller-matrix weight: 'Incompatible mask "
                "assignment ... Array44f'); our adapter reduces the weight to its unpolarized "
                "part")
    return None


def _leaves(d):
    if isinstance(d, dict):
        for v in d.values():
            yield from _leaves(v)
    elif isinstance(d, list):
        for v in d:
            yield from _leaves(v)
    else:
        yield d


def _code_hash() -> str:
    """A hash of the checks' and the audit runner's source: a cached result is reused only
    while the code that produced it is unchanged."""
    root = Path(__file__).resolve().parents[1]
    files = sorted((root / "checks").glob("*.py")) + [root / "audit" / name for name in
                                                     ("run.py", "build.py", "sides.py")]
    h = hashlib.sha1()
    for f in files:
        h.update(f.read_bytes())
    return h.hexdigest()[:12]


def cache_key(case: grid.Case, variant: str, quick: bool) -> str:
    import mitsuba as mi

    from .._version import __version__
    text = repr((case.bsdf, case.config, case.spec, case.polarized, variant, quick,
                 mi.__version__, __version__, _code_hash()))
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def _init_worker(workdir: str):
    """No progress bars; the working directory a scratch folder (Mitsuba's χ² harness writes
    ``chi2_data.py`` into it on a rejection)."""
    os.environ.setdefault("MI_BRDFS_NO_PROGRESS", "1")
    os.makedirs(workdir, exist_ok=True)
    os.chdir(workdir)


def run(cases: list[grid.Case], variant: str, quick: bool, cache: Path, processes: int = 2,
        progress: bool = True, check=run_case) -> list[dict]:
    """
    The records of every case, from ``cache`` where a previous run left them, else computed in
    ``processes`` worker processes (``check(case, variant, quick)``: :func:`run_case`). A worker
    that dies (a crash inside Mitsuba) is a ``crash`` record for its case; the pool is
    restarted for the others. A case whose run raises is one line, and one MiBrdfsError once
    the others are done (and cached).
    """
    cache.mkdir(parents=True, exist_ok=True)
    records: dict[str, list] = {}
    todo = []
    for c in cases:
        path = cache / f"{cache_key(c, variant, quick)}.json"
        if path.exists():
            records[c.key] = json.loads(path.read_text())
        else:
            todo.append(c)

    def keep(case, out):
        path = cache / f"{cache_key(case, variant, quick)}.json"
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(out, indent=1))
        tmp.replace(path)
        records[case.key] = out

    pool = functools.partial(_pool, check=functools.partial(check, variant=variant, quick=quick),
                             cache=cache, keep=keep)
    failed = []
    while todo:
        broken = pool(todo, processes, progress, failed)
        if broken and len(broken) == len(todo):
            # every remaining case died with the pool: run them one at a time to find which
            for c in broken:
                if pool([c], 1, False, failed):
                    from ..checks.result import CheckResult
                    keep(c, [_record(c, variant, CheckResult(
                        "crash", False, math.nan, "n/a",
                        "the worker process died while checking this BSDF"))])
            todo = []
        else:
            todo = broken
    if failed:
        raise MiBrdfsError(f"audit: {len(failed)} of {len(cases)} cases failed (each above); the "
                           f"others are kept in {cache}, and the same command runs only those")
    return [r for c in cases for r in records[c.key]]


def _pool(todo: list, processes: int, progress: bool, failed: list, *, check, cache,
          keep) -> list:
    """``todo`` on ``processes`` worker processes (each result to ``keep``); the cases lost
    with a worker that died, in order; a case that raised is a line and goes to ``failed``."""
    broken = []

    def failure(case, error):
        if isinstance(error, BrokenProcessPool):
            broken.append(case)
        else:
            runner.report_failure("audit", case.key, error)
            failed.append(case)

    runner.run(todo, check, workers=max(1, processes), processes=True, initializer=_init_worker,
               initargs=(str(cache / "scratch"),), on_done=keep, on_failure=failure,
               label="audit", unit=" cases", keep=f"{cache} (the same command resumes there)",
               progress=progress)
    return [c for c in todo if c in broken]
