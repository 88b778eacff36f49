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
from .result import CheckResult

#: Wavelengths given to spectral variants, where a BSDF may depend on them.
WAVELENGTHS = (450.0, 500.0, 550.0, 600.0)


def _interaction(n: int, wi):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.uv = mi.Point2f(0.5, 0.5)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    if mi.is_spectral:
        si.wavelengths = dr.zeros(mi.Spectrum, n) + mi.Spectrum(WAVELENGTHS)
    return si


def bsdf_adapter(bsdf, wi, ctx=None):
    """
    ``(sample_func, pdf_func)`` for ``mi.chi2.ChiSquareTest`` on a loaded BSDF.

    Like ``mi.chi2.BSDFAdapter``, but takes the BSDF object (so a plugin is built once, not per
    call), sets the wavelengths in spectral variants, and marks samples with zero weight as
    failed (their direction is not counted).
    """
    ctx = ctx or mi.BSDFContext()

    def sample_func(sample):
        si = _interaction(dr.width(sample), wi)
        bs, weight = bsdf.sample(ctx, si, sample[0], mi.Point2f(sample[1], sample[2]))
        ok = dr.any(mi.unpolarized_spectrum(weight) != 0)
        return bs.wo, dr.select(ok, mi.Float(1.0), mi.Float(0.0))

    def pdf_func(wo):
        return bsdf.pdf(ctx, _interaction(dr.width(wo), wi), wo)

    return sample_func, pdf_func


def chi2_bsdf(bsdf, wi=(0.0, 0.0, 1.0), ctx=None, res: int = 101, ires: int = 4,
              sample_count: int = 1_000_000, seed: int = 0, significance: float = 0.01,
              test_count: int = 1) -> CheckResult:
    """
    Pearson's χ² test: does ``sample()`` draw directions with the density that ``pdf()`` reports?

    Parameter ``bsdf`` (dict | str | mi.BSDF): the BSDF (see :mod:`mi_brdfs.bsdfspec`).

    Parameter ``wi`` (3 floats): the incident direction in the local frame (normalised here).

    Parameter ``ctx`` (mi.BSDFContext | None): e.g. to test one lobe (``ctx.component = i``).

    Parameter ``res``, ``ires`` (int): histogram resolution in θ (odd, so no cell edge lies on the
    horizon: Mitsuba's default 101) and the per-cell integration resolution of the pdf. Raise
    ``ires`` to 16–32 for sharp lobes (α ≤ 0.05), as Mitsuba's own tests do.

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
    sample_func, pdf_func = bsdf_adapter(obj, wi, ctx)
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=sample_count, res=res, ires=ires, seed=seed)
    passed = bool(test.run(significance_level=significance, test_count=test_count, quiet=True))
    p = float(test.p_value) if test.p_value is not None else float("nan")
    where = f"{describe(bsdf)} at wi=({wi[0]:.3f}, {wi[1]:.3f}, {wi[2]:.3f})"
    if passed:
        message = f"χ²: {where}: p = {p:.3g} ≥ {significance:g} (sample() matches pdf())"
    else:
        reason = " ".join(str(test.messages).split())[-300:]
        message = f"χ²: {where}: rejected, p = {p:.3g} < {significance:g}: {reason}"
    return CheckResult("chi2", passed, p, significance, message,
                       details={"wi": wi.tolist(), "res": res, "ires": ires,
                                "sample_count": sample_count, "histogram": test.histogram,
                                "pdf": test.pdf})
