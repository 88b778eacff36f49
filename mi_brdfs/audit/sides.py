"""
The audit's own check of a BSDF whose lobes differ by side: ``twosided``, which lists the lobes
of its front BSDF with ``FrontSide`` and those of its back BSDF (the same one when it nests only
one) with ``BackSide``. The battery's checks draw ``wi`` above the surface only, so they never
see which lobe a back-facing sample reports, nor what selecting a lobe does there.

Two records per applicable case:

* ``sides``: in the default context, at front- and back-facing ``wi``, every sample that succeeds
  reports a component ``c < component_count()`` whose flags hold the side of ``wi``
  (``FrontSide`` for cosθi > 0, ``BackSide`` for cosθi < 0) and the sampled type
  (``sampled_type & ~flags(c) == 0``): the API's ``sampled_component`` is the index of the lobe
  that was sampled;
* ``sides selection``: with ``ctx.component = c`` (``BSDFContext::is_enabled``), a lobe of the
  other side yields no successful sample, and where the default context samples successfully,
  some lobe of that side does too.
"""

from __future__ import annotations

import math

import mitsuba as mi
import numpy as np

from ..checks import batch
from ..checks.result import CheckResult

#: Polar angles (degrees) of the incident directions on each side; the azimuth is random.
THETAS = (20.0, 60.0)


def side_split(bsdf) -> bool:
    """Whether the BSDF has a non-Null lobe of the front side only and one of the back only."""
    front, back, null = (int(mi.BSDFFlags.FrontSide), int(mi.BSDFFlags.BackSide),
                         int(mi.BSDFFlags.Null))
    flags = [int(bsdf.flags(c)) for c in range(bsdf.component_count())]
    lobes = [f for f in flags if not f & null]
    return (any(f & front and not f & back for f in lobes)
            and any(f & back and not f & front for f in lobes))


def _incident(rng, n: int, back: bool) -> np.ndarray:
    """``n`` directions at :data:`THETAS` (alternating), random azimuth, on one side."""
    theta = np.radians(np.resize(THETAS, n))
    phi = rng.random(n) * 2 * math.pi
    z = np.cos(theta) * (-1 if back else 1)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), z], axis=1)


def _samples(bsdf, wi, rng, ctx=None):
    n = len(wi)
    s = batch.sample(bsdf, wi, rng.random(n), rng.random((n, 2)), ctx)
    return s, np.any(s.weight != 0, axis=1)


def _side_flag(back: bool) -> int:
    return int(mi.BSDFFlags.BackSide if back else mi.BSDFFlags.FrontSide)


def _reported(bsdf, n: int, seed: int) -> tuple[list[str], int]:
    """Problems of the default context's samples (the ``sides`` record) and how many samples
    were judged."""
    rng, count, problems, judged = np.random.default_rng(seed), bsdf.component_count(), [], 0
    flags = np.array([int(bsdf.flags(c)) for c in range(count)] + [0], dtype=np.int64)
    for back in (False, True):
        s, ok = _samples(bsdf, _incident(rng, n, back), rng)
        judged += int(ok.sum())
        comp = np.where(s.sampled_component < count, s.sampled_component, count)
        out = ok & (s.sampled_component >= count)
        side = ok & ~out & ((flags[comp] & _side_flag(back)) == 0)
        kind = ok & ~out & ((s.sampled_type & ~flags[comp]) != 0)
        if out.any() or side.any() or kind.any():
            i = int(np.flatnonzero(out | side | kind)[0])
            c = int(s.sampled_component[i])
            problems.append(
                f"{'back' if back else 'front'}-facing wi: of {int(ok.sum())} samples, "
                f"{int(out.sum())} report a component ≥ {count}, {int(side.sum())} one without "
                f"{'BackSide' if back else 'FrontSide'}, {int(kind.sum())} one whose flags lack "
                f"the sampled type (e.g. component {c}, flags(c) = "
                f"{hex(int(flags[min(c, count)]))}, type {hex(int(s.sampled_type[i]))})")
    return problems, judged


def _selected(bsdf, n: int, seed: int) -> list[str]:
    """Problems of ``ctx.component = c`` on each side (the ``sides selection`` record)."""
    rng, count, problems = np.random.default_rng(seed + 1), bsdf.component_count(), []
    for back in (False, True):
        wi = _incident(rng, n, back)
        _, ok_all = _samples(bsdf, wi, rng)
        own = 0
        for c in range(count):
            ctx = mi.BSDFContext()
            ctx.component = c
            _, ok = _samples(bsdf, wi, rng, ctx)
            if int(bsdf.flags(c)) & _side_flag(back):
                own += int(ok.sum())
            elif ok.any():
                problems.append(f"ctx.component = {c} (flags {hex(int(bsdf.flags(c)))}, a lobe "
                                f"of the other side) at {'back' if back else 'front'}-facing "
                                f"wi: {int(ok.sum())} of {n} samples succeed")
        if ok_all.any() and own == 0:
            problems.append(f"{'back' if back else 'front'}-facing wi: no lobe of that side "
                            f"selected alone samples anything, the default context "
                            f"{int(ok_all.sum())} of {n}")
    return problems


def check_sides(bsdf, n: int = 20_000, seed: int = 0) -> list[CheckResult]:
    """The ``sides`` and ``sides selection`` records (module docstring); skipped records where
    the BSDF's lobes do not differ by side or the variant is not a JIT one."""
    if not batch.is_jit() or not side_split(bsdf):
        why = "lobes do not differ by side" if batch.is_jit() else "needs a JIT variant"
        return [CheckResult(name, True, math.nan, "n/a", f"{name}: not applicable ({why})",
                            skipped=True) for name in ("sides", "sides selection")]
    problems, judged = _reported(bsdf, n, seed)
    reported = CheckResult(
        "sides", not problems, float(len(problems)), 0,
        "sides: " + ("; ".join(problems) if problems else
                     f"every one of {judged} samples reports a lobe of the side of wi whose "
                     f"flags hold its type"))
    problems = _selected(bsdf, n, seed)
    selected = CheckResult(
        "sides selection", not problems, float(len(problems)), 0,
        "sides selection: " + ("; ".join(problems) if problems else
                               "selecting a lobe samples it on its own side only"))
    return [reported, selected]
