"""
A virtual gonioreflectometer: any BSDF (these plugins, Mitsuba's built-ins, a user's) tabulated
in MERL's format (:mod:`.merl`), so that every step from measured data to a fit can be tested
against a known answer, and MERL-format data of any BSDF handed to the tools that read it.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ..errors import MiBrdfsError, MiBrdfsWarning
from ..variants import keeps_variant
from . import merl


def _varying(obj, prefix: str = "", seen: set | None = None) -> list[str]:
    """
    The parameters of ``obj`` (and of the BSDFs nested in it) given as a texture that varies
    over the surface, named as ``mi.traverse`` names them, with the texture's class: those
    Mitsuba marks so (``bitmap``, ``checkerboard``, ``volume``), and ``mesh_attribute``, which
    it does not mark though its values live on the shape. A texture reached twice (both sides
    of a ``twosided``) is named once.
    """
    import mitsuba as mi

    found, seen = [], set() if seen is None else seen

    class Walk(mi.TraversalCallback):
        def put(self, key, value, *flags):
            if not isinstance(value, mi.Object) or id(value) in seen:
                return
            seen.add(id(value))
            if isinstance(value, mi.Texture) and (value.is_spatially_varying()
                                                  or value.class_name() == "MeshAttribute"):
                kind = re.sub(r"(Impl)?\[.*\]$", "", value.class_name())
                found.append(f"{prefix}{key} ({kind})")
            else:
                found.extend(_varying(value, f"{prefix}{key}.", seen))

    obj.traverse(Walk())
    return found


def _check_measurable(bsdf, name: str) -> list[str]:
    """
    Refuse, in one line, a BSDF that no MERL table describes: one with a parameter that varies
    over the surface (a table holds one BRDF; measured at one point it would say nothing of
    the others), and one with no diffuse or glossy reflection (delta components, a mirror or
    a smooth glass, have no finite value at any pair of directions; transmission is no BRDF).
    Returns → what the table leaves out beside it, in words (a delta reflection,
    transmission).
    """
    import mitsuba as mi

    varying = _varying(bsdf)
    if varying:
        which, it = ("a parameter that varies", "it") if len(varying) == 1 else \
            ("parameters that vary", "each")
        raise MiBrdfsError(f"measure: {name} has {which} over the surface, "
                           f"{', '.join(varying)}; MERL's format holds one BRDF for the whole "
                           f"surface: give {it} one value (a float or an RGB)")
    smooth = (mi.BSDFFlags.DiffuseReflection, mi.BSDFFlags.GlossyReflection)
    flags = [bsdf.flags(i) for i in range(bsdf.component_count())] or [bsdf.flags()]
    if not any(mi.has_flag(f, kind) for f in flags for kind in smooth):
        raise MiBrdfsError(f"measure: {name} has no diffuse or glossy reflection (its "
                           f"components are delta lobes or transmit), so there is no BRDF to "
                           f"tabulate: MERL's format holds finite values of f")
    return [what for what, flag in (("a delta reflection", mi.BSDFFlags.DeltaReflection),
                                    ("transmission", mi.BSDFFlags.Transmission))
            if any(mi.has_flag(f, flag) for f in flags)]


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


@keeps_variant
def measure(bsdf, path=None, variant: str | None = None, noise=(0.0, 0.0),
            seed: int = 0) -> np.ndarray:
    """
    The BRDF f of ``bsdf`` (any form of :mod:`mi_brdfs.bsdfspec`) at the centre of every MERL
    bin, ``(3, 90, 90, 180)``, NaN where either direction lies below the horizon (unmeasured, as
    in MERL's files); written to ``path`` (a ``.binary`` file) when given.

    Measured in ``variant`` (an RGB JIT variant; default: the current one if it is such a
    variant, else ``llvm_ad_rgb``), f = eval/cosθo; the caller's variant is set again on
    return, and when measure raises (:func:`mi_brdfs.variants.keeps_variant`). A BSDF with the
    Anisotropic flag is measured at φh = 0 only, and a warning says so.
    ``noise`` = (relative, absolute) adds measurement noise (:func:`add_noise`, ``seed``).

    Raises MiBrdfsError (one line), before anything is written, for a BSDF that no table
    describes: a parameter that varies over the surface (a texture such as ``bitmap``,
    ``checkerboard`` or ``mesh_attribute``), no diffuse or glossy reflection (``conductor``,
    ``dielectric``: delta lobes), or 0 at every bin above the horizon.
    """
    import mitsuba as mi

    from ..bsdfspec import describe, load_bsdf, parse
    from ..checks.batch import evaluate
    from ..registry import use_rgb_jit

    if path is not None and not str(path).endswith(".binary"):
        raise MiBrdfsError(f"measure: the output {path} must end in .binary (MERL's format)")
    use_rgb_jit("measure", variant)  # MERL's format holds red, green and blue
    loaded = load_bsdf(bsdf)
    name = describe(parse(bsdf))
    left_out = _check_measurable(loaded, name)
    if loaded.flags() & mi.BSDFFlags.Anisotropic:
        warnings.warn("measure: the BSDF is anisotropic and MERL's format isotropic: it is "
                      "measured at φh = 0 only", MiBrdfsWarning, stacklevel=3)
    wi, wo = merl.bin_directions()
    below = (wi[:, 2] <= 0.0) | (wo[:, 2] <= 0.0)
    value = evaluate(loaded, wi, wo).value
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(below[:, None], np.nan, value / wo[:, 2:3])
    if not np.any(f[~below] != 0.0):
        raise MiBrdfsError(f"measure: {name} is 0 at every bin above the horizon (it reflects "
                           f"nothing: a reflectance of 0, or transmission only); nothing to "
                           f"tabulate")
    if left_out:
        warnings.warn(f"measure: {name} also has {' and '.join(left_out)}, which the table of "
                      f"its BRDF leaves out", MiBrdfsWarning, stacklevel=3)
    values = add_noise(np.moveaxis(f.reshape(merl.RES + (3,)), -1, 0), *noise, seed=seed)
    if path is not None:
        merl.write(path, values)
    return values
