"""
Sampling checks: Pearson's χ² test of ``sample()`` against ``pdf()``, through ``mitsuba.chi2``.

``mitsuba.chi2`` needs a JIT variant (it uses wide arrays and scatter-adds), so these checks
raise :class:`mi_brdfs.MiBrdfsError` in scalar variants.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, load_bsdf
from ..errors import MiBrdfsError
from . import _batch
from .result import CheckResult

def bsdf_adapter(bsdf, wi, ctx=None):
    """
    ``(sample_func, pdf_func)`` for ``mi.chi2.ChiSquareTest`` on a loaded BSDF.

    Like ``mi.chi2.BSDFAdapter``, but takes the BSDF object (so a plugin is built once, not per
    call), sets the wavelengths in spectral variants, and marks samples with zero weight as
    failed (their direction is not counted).
    """
    ctx = ctx or mi.BSDFContext()

    def sample_func(sample):
        si = _batch.interaction(wi, dr.width(sample))
        bs, weight = bsdf.sample(ctx, si, sample[0], mi.Point2f(sample[1], sample[2]))
        ok = dr.any(mi.unpolarized_spectrum(weight) != 0)
        return bs.wo, dr.select(ok, mi.Float(1.0), mi.Float(0.0))

    def pdf_func(wo):
        return bsdf.pdf(ctx, _batch.interaction(wi, dr.width(wo)), wo)

    return sample_func, pdf_func


#: (largest pdf below which, θ resolution ``res``, per-cell integration ``ires``) for the
#: automatic choice of :func:`chi2_settings`.
RESOLUTIONS = ((5.0, 101, 8), (50.0, 201, 16), (500.0, 301, 32), (float("inf"), 401, 32))


def chi2_settings(bsdf, wi, ctx=None, n: int = 20_000) -> tuple[int, int, float]:
    """
    ``(res, ires, pdf_max)`` for a χ² test of ``bsdf`` at ``wi``, from how peaked its sampling
    density is (the largest ``bs.pdf`` of ``n`` samples). The histogram cells of
    ``mitsuba.chi2`` are uniform in (φ, cosθ), so a lobe around the normal of angular width w
    spans only about w²/2 in cosθ: sharp lobes need many more cells there (a GGX lobe with
    α = 0.05 at normal incidence is rejected at res 101, p = 0.003, and accepted at 201,
    p = 0.43, while its pdf is right).
    """
    rng = np.random.default_rng(12345)
    s = _batch.sample(bsdf, wi, rng.random(n), rng.random((n, 2)), ctx)
    ok = np.any(s.weight != 0, axis=1) & np.isfinite(s.pdf)
    pdf_max = float(np.max(s.pdf[ok])) if ok.any() else 0.0
    for limit, res, ires in RESOLUTIONS:
        if pdf_max < limit:
            return res, ires, pdf_max
    raise AssertionError("unreachable")


def chi2_bsdf(bsdf, wi=(0.0, 0.0, 1.0), ctx=None, res: int | None = 101, ires: int | None = 4,
              sample_count: int = 1_000_000, seed: int = 0, significance: float = 0.01,
              test_count: int = 1) -> CheckResult:
    """
    Pearson's χ² test: does ``sample()`` draw directions with the density that ``pdf()`` reports?

    Parameter ``bsdf`` (dict | str | mi.BSDF): the BSDF (see :mod:`mi_brdfs.bsdfspec`).

    Parameter ``wi`` (3 floats): the incident direction in the local frame (normalised here).

    Parameter ``ctx`` (mi.BSDFContext | None): e.g. to test one lobe (``ctx.component = i``).

    Parameter ``res``, ``ires`` (int | None): histogram resolution in θ (odd, so no cell edge lies
    on the horizon: Mitsuba's default 101) and the per-cell integration resolution of the pdf.
    Raise them for sharp lobes (α ≤ 0.05), as Mitsuba's own tests do; ``None`` chooses both
    from the lobe's sharpness (:func:`chi2_settings`).

    Parameter ``significance`` (float), ``test_count`` (int): the test rejects at
    ``significance`` after Šidák correction for ``test_count`` tests run together.

    Returns → CheckResult: value = p-value; passes when the hypothesis is not rejected.
    """
    if not dr.is_jit_v(mi.Float):
        raise MiBrdfsError(f"the χ² test needs a JIT variant (llvm_* or cuda_*), "
                           f"not {mi.variant()}")
    from mitsuba.chi2 import ChiSquareTest, SphericalDomain

    obj = load_bsdf(bsdf)
    wi = np.asarray(wi, dtype=np.float64)
    wi = wi / np.linalg.norm(wi)
    where = f"{describe(bsdf)} at wi=({wi[0]:.3f}, {wi[1]:.3f}, {wi[2]:.3f})"
    flags, delta = int(obj.flags()), int(mi.BSDFFlags.Delta)
    note = ""
    if ctx is None and flags & delta:
        # Dirac lobes have pdf() = 0 by convention: χ² can only judge the other lobes.
        smooth = flags & int(mi.BSDFFlags.All) & ~delta
        if not smooth & int(mi.BSDFFlags.Smooth):
            return CheckResult("chi2", True, float("nan"), "n/a",
                               f"χ²: {where}: not applicable (only Dirac delta lobes)",
                               skipped=True)
        ctx = mi.BSDFContext(mi.TransportMode.Radiance, smooth)
        note = " (non-delta lobes only)"
    if res is None or ires is None:
        auto_res, auto_ires, _ = chi2_settings(obj, wi, ctx)
        res, ires = res or auto_res, ires or auto_ires
    sample_func, pdf_func = bsdf_adapter(obj, wi, ctx)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=sample_count, res=res, ires=ires, seed=seed)
    passed = bool(test.run(significance_level=significance, test_count=test_count, quiet=True))
    p = float(test.p_value) if test.p_value is not None else float("nan")
    level = 1.0 - (1.0 - significance) ** (1.0 / test_count)  # Šidák, as mitsuba.chi2 does
    log = " ".join(str(test.messages).split())
    log = log.replace(' Target density and histogram were written to "chi2_data.py".', "")
    log = log.replace(' Target density and histogram were written to "chi2_data.py', "")
    if passed:
        message = (f"χ²: {where}{note}: p = {p:.3g} ≥ {level:.3g} (sample() matches pdf(); "
                   f"res {res}, ires {ires})")
    elif test.fail:
        message = f"χ²: {where}{note}: the test could not run: {log[-300:]}"
    else:
        message = f"χ²: {where}{note}: rejected, p = {p:.3g} < {level:.3g}: {log[-300:]}"
    return CheckResult("chi2", passed, p, level, message,
                       details={"wi": wi.tolist(), "res": res, "ires": ires,
                                "sample_count": sample_count, "histogram": test.histogram,
                                "pdf": test.pdf})
