"""
The whole battery of checks on one BSDF, as ``mi-brdfs check`` runs it, and its table.
"""

from __future__ import annotations

import math
import time

import drjit as dr
import mitsuba as mi

from ..bsdfspec import load_bsdf, loaded_once
from ..errors import MiBrdfsError
from ..progress import Progress
from . import batch
from .albedo import albedo_curve, check_albedo_agreement, check_energy
from .consistency import check_consistency
from .furnace import check_furnace
from .gradients import check_gradients
from .lobes import check_lobes, check_pdf_integral
from .reciprocity import check_positivity, check_reciprocity
from .result import CheckResult
from .sampling import chi2_bsdf
from .stability import check_stability

#: Incident angles (degrees) of the χ² tests: normal, oblique, and cosθ = 0.1.
CHI2_THETAS = (0.0, 45.0, 84.26)


@loaded_once()
def run_battery(spec, quick: bool = False, render: bool = False, chi2_res: int | None = None,
                chi2_ires: int | None = None, progress: bool = True,
                gradients: bool = False) -> list[CheckResult]:
    """
    Every check on one BSDF (given as a dict, XML fragment or ``'type key=value'`` string), in
    the current variant: consistency, χ² sampling at normal, 45° and grazing incidence (JIT
    variants), energy conservation and the sample()/eval() albedo agreement, the lobes (context
    selection, additivity, ∫ pdf = the fraction of samples that succeed), reciprocity,
    positivity, the stability sweep at these parameters, with ``render`` the furnace render,
    and with ``gradients`` the derivatives of every differentiable parameter (AD variants).
    ``quick`` uses 10× fewer samples. χ² chooses its resolution from the lobe's sharpness
    (:func:`~mi_brdfs.checks.sampling.chi2_settings`, at least 8×8 points per cell: with
    Mitsuba's default of 4, roughconductor at α = 0.3 is rejected at cosθ = 0.1 only because the
    pdf integral is too coarse there; at 16 it passes).
    """
    load_bsdf(spec)  # fail early, with the plugin's one-line error
    jit = batch.is_jit()
    n = (100_000 if quick else 1_000_000) if jit else (500 if quick else 4_000)
    steps = [("consistency", lambda: [check_consistency(spec, n=n // 10 if jit else n // 4)])]
    if jit:
        tests = len(CHI2_THETAS)
        steps.append(("χ²", lambda: [
            _named(chi2_bsdf(spec, wi=batch.direction(math.radians(t)), res=chi2_res,
                             ires=chi2_ires, test_count=tests,
                             sample_count=n if quick else 1_000_000), f"chi2 θ={t:g}°")
            for t in CHI2_THETAS]))
    else:
        steps.append(("χ²", lambda: [CheckResult(
            "chi2", True, math.nan, "n/a", "χ²: skipped (mitsuba.chi2 needs a JIT variant)",
            skipped=True)]))

    def albedo_checks():
        curve = albedo_curve(spec, n=n, estimators=("eval", "quadrature", "reference"))
        flags = int(load_bsdf(spec).flags())
        mixed = flags & int(mi.BSDFFlags.Delta) and flags & int(mi.BSDFFlags.Smooth)
        agreement = (check_albedo_agreement(spec, n=n) if mixed  # non-delta lobes, own curve
                     else check_albedo_agreement(spec, curve=curve))
        return [check_energy(spec, curve=curve), agreement]

    def lobe_checks():
        lobes = check_lobes(spec, n=n // 5 if jit else n // 4)
        if not jit:
            return [lobes, CheckResult("pdf integral", True, math.nan, "n/a",
                                       "pdf integral: skipped (a sphere quadrature of pdf() "
                                       "takes minutes in a scalar variant)", skipped=True)]
        return [lobes, check_pdf_integral(spec, n=n // 2)]

    steps += [("albedo", albedo_checks), ("lobes", lobe_checks),
              ("reciprocity", lambda: [check_reciprocity(spec, n=n // 5 if jit else n // 10)]),
              ("positivity", lambda: [check_positivity(spec, n=n // 5 if jit else n // 10)]),
              ("stability", lambda: [check_stability(spec)])]
    if gradients:
        if not (jit and dr.is_diff_v(mi.Float)):
            raise MiBrdfsError(f"--gradients needs an AD variant (e.g. llvm_ad_rgb), not "
                               f"{mi.variant()}")
        steps.append(("gradients", lambda: [check_gradients(spec, n=128 if quick else 512)]))
    if render:
        steps.append(("furnace", lambda: [check_furnace(spec, spp=32 if quick else 128,
                                                        res=32 if quick else 64)]))
    results: list[CheckResult] = []
    bar = Progress(len(steps), label="checks", unit=" steps") if progress else None
    for i, (name, step) in enumerate(steps):
        t0 = time.perf_counter()
        for result in step():
            result.details.setdefault("seconds", time.perf_counter() - t0)
            results.append(result)
        if bar:
            bar.update(i + 1, note=name)
    if bar:
        bar.close()
    return results


def _named(result: CheckResult, name: str) -> CheckResult:
    result.name = name
    return result


def _fmt(value) -> str:
    if isinstance(value, float):
        if math.isnan(value):
            return "—"
        return f"{value:.4g}"
    return str(value)


def format_table(results: list[CheckResult], messages: bool = True) -> str:
    """A plain-text table: check | value | tolerance | result, then each message."""
    rows = [("check", "value", "tolerance", "result")]
    rows += [(r.name, _fmt(r.value), _fmt(r.tolerance),
              "skip" if r.skipped else "pass" if r.passed else "FAIL") for r in results]
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip() for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    if messages:
        lines.append("")
        lines += [("  " if r.passed else "✗ ") + r.message for r in results]
    return "\n".join(lines)
