"""
A virtual gonioreflectometer: any BSDF (these plugins, Mitsuba's built-ins, a user's) tabulated
in MERL's format (:mod:`.merl`), so that every step from measured data to a fit can be tested
against a known answer, and MERL-format data of any BSDF handed to the tools that read it.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import MiBrdfsError, MiBrdfsWarning
from ..variants import keeps_variant
from . import merl


def _jit_rgb() -> bool:
    """Whether the current variant is an RGB JIT one (MERL's format holds RGB)."""
    import mitsuba as mi

    return mi.variant() is not None and mi.is_rgb and not mi.is_polarized \
        and mi.variant().startswith(("llvm", "cuda"))


@keeps_variant
def add_noise(values: np.ndarray, relative: float = 0.0, absolute: float = 0.0,
              seed: int = 0) -> np.ndarray:
    """
    ``values`` as a gonioreflectometer with Gaussian noise would measure them: per bin and
    channel, f' = max(0, f·(1 + relative·ε₁) + absolute·ε₂), ε independent standard normal
    draws (seeded): a relative error (the detector's gain, the light's stability) and an
    additive floor (dark current, stray light), the two terms of the error models of measured
    BRDF data (e.g. Matusik et al. 2003, §3). Unmeasured bins stay NaN.
    """
    for name, value in (("relative", relative), ("absolute", absolute)):
        if not (np.isfinite(value) and value >= 0):
            raise MiBrdfsError(f"measure: the {name} noise must be finite and ≥ 0, not {value}")
    if relative == 0 and absolute == 0:
        return values
    rng = np.random.default_rng(seed)
    noisy = values * (1.0 + relative * rng.standard_normal(values.shape)) \
        + absolute * rng.standard_normal(values.shape)
    return np.maximum(noisy, 0.0)  # NaN stays NaN


def measure(bsdf, path=None, variant: str | None = None, noise=(0.0, 0.0),
            seed: int = 0) -> np.ndarray:
    """
    The BRDF f of ``bsdf`` (any form of :mod:`mi_brdfs.bsdfspec`) at the centre of every MERL
    bin, ``(3, 90, 90, 180)``, NaN where either direction lies below the horizon (unmeasured, as
    in MERL's files); written to ``path`` (a ``.binary`` file) when given.

    Measured in ``variant`` (an RGB JIT variant; default: the current one if it is such a
    variant, else ``llvm_ad_rgb``), f = eval/cosθo. A
    BSDF with the Anisotropic flag is measured at φh = 0 only, and a warning says so.
    ``noise`` = (relative, absolute) adds measurement noise (:func:`add_noise`, ``seed``).
    """
    import mitsuba as mi

    from ..bsdfspec import load_bsdf
    from ..checks.batch import evaluate
    from ..registry import use_variant

    if path is not None and not str(path).endswith(".binary"):
        raise MiBrdfsError(f"measure: the output {path} must end in .binary (MERL's format)")
    if variant is not None or not _jit_rgb():
        use_variant(variant or "llvm_ad_rgb", fallback=False)
    if not _jit_rgb():
        raise MiBrdfsError(f"measure needs an RGB JIT variant (llvm_ad_rgb, cuda_ad_rgb), not "
                           f"{mi.variant()}: MERL's format holds red, green and blue")
    loaded = load_bsdf(bsdf)
    if loaded.flags() & mi.BSDFFlags.Anisotropic:
        warnings.warn("measure: the BSDF is anisotropic and MERL's format isotropic: it is "
                      "measured at φh = 0 only", MiBrdfsWarning, stacklevel=3)
    wi, wo = merl.bin_directions()
    below = (wi[:, 2] <= 0.0) | (wo[:, 2] <= 0.0)
    value = evaluate(loaded, wi, wo).value
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(below[:, None], np.nan, value / wo[:, 2:3])
    values = add_noise(np.moveaxis(f.reshape(merl.RES + (3,)), -1, 0), *noise, seed=seed)
    if path is not None:
        merl.write(path, values)
    return values
