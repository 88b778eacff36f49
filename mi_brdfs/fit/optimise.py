"""
The optimisation of a fit: the direction pairs, the cube-root objective and Adam over the
transformed variables (see :mod:`mi_brdfs.fit`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import MiBrdfsError
from .parameters import Parameter
from .spec import spec_text

#: ε of the cube-root objective (f·cosθi·cosθo units): keeps its gradient finite where it is 0.
EPSILON = 1e-6


# -------------------------------------------------------------------------------------------------
# Direction pairs
# -------------------------------------------------------------------------------------------------


def direction_pairs(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    (wi, wo), each (m, 3) with m ≤ n: ``n`` pairs drawn in half/difference angles (θh = (π/2)u²,
    θd uniform, φd and φh uniform; see :mod:`mi_brdfs.fit`), those with both directions above
    the horizon (cosθ > 10⁻³).
    """
    rng = np.random.default_rng(seed)
    u = rng.random((n, 4))
    th, td = (math.pi / 2) * u[:, 0] ** 2, (math.pi / 2) * u[:, 1]
    pd, ph = 2 * math.pi * u[:, 2], 2 * math.pi * u[:, 3]
    h = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=1)
    t = np.stack([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), -np.sin(th)], axis=1)
    b = np.cross(h, t)
    d = np.stack([np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)], axis=1)
    wi = d[:, :1] * t + d[:, 1:2] * b + d[:, 2:3] * h  # the difference vector in h's frame
    wo = 2 * np.sum(wi * h, axis=1, keepdims=True) * h - wi
    ok = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    return wi[ok], wo[ok]


def _target_values(target, target_bsdf, pairs: int, seed: int, notes: list):
    """
    (wi, wo, the target's eval, (m, 3)) at the direction pairs; pairs where the target's eval is
    not finite are left out (with a note in ``notes``).
    """
    from ..checks import batch

    wi, wo = direction_pairs(pairs, seed)
    if len(wi) == 0:
        raise MiBrdfsError(f"fit: pairs = {pairs} leaves no direction pair above the horizon "
                           f"(about 3/4 of them are kept): give more pairs, e.g. 4096")
    target_values = batch.evaluate(target_bsdf, wi, wo).value
    target_values = np.broadcast_to(target_values, (len(wi), 3)) if target_values.shape[1] == 1 \
        else target_values
    finite = np.all(np.isfinite(target_values), axis=1)
    if not finite.all():
        notes.append(f"{int((~finite).sum())} pairs where the target's eval is not finite were "
                     f"left out")
        wi, wo, target_values = wi[finite], wo[finite], target_values[finite]
    if not np.any(target_values > 0):
        raise MiBrdfsError(f"the target {spec_text(target)} has eval = 0 at every direction pair "
                           f"(only delta lobes, or no reflection?): nothing to fit")
    return wi, wo, target_values


# -------------------------------------------------------------------------------------------------
# Adam from each start
# -------------------------------------------------------------------------------------------------


def _require_ad_rgb(variant: str | None) -> str:
    import drjit as dr
    import mitsuba as mi

    from ..registry import use_variant

    if variant is not None:
        use_variant(variant, fallback=False)
    elif mi.variant() is None:
        use_variant("llvm_ad_rgb", fallback=False)
    current = mi.variant()
    if not dr.is_diff_v(mi.Float) or not mi.is_rgb or mi.is_polarized:
        raise MiBrdfsError(f"fit needs an RGB variant with automatic differentiation "
                           f"(llvm_ad_rgb or cuda_ad_rgb); {current} has "
                           f"{'no AD' if not dr.is_diff_v(mi.Float) else 'no plain RGB'}")
    return current


def _cbrt(x):
    import drjit as dr

    return dr.power(x + EPSILON, 1.0 / 3.0)


def _run(bsdf, params: list[Parameter], start: dict, si, wo, target_c, steps: int, lr: float,
         bar, done: int):
    """Adam from ``start`` ({name: value}); returns (values {name: array}, final objective)."""
    import drjit as dr
    import mitsuba as mi

    traversed = mi.traverse(bsdf)
    ctx = mi.BSDFContext()
    opt = mi.ad.Adam(lr=lr)
    ranges = {p.name: p.x_range() for p in params}
    for p in params:
        opt[p.name] = p.drjit(p.encode(start[p.name]))

    def objective():
        for p in params:
            traversed[p.key] = p.decode(opt[p.name])
        traversed.update()
        diff = _cbrt(bsdf.eval(ctx, si, wo) * si.wi.z) - target_c
        return dr.mean(dr.squared_norm(diff)) / 3.0

    for step in range(steps):
        # cosine decay from lr to lr/100: large steps first, then settle
        opt.set_learning_rate(lr * (0.01 + 0.99 * 0.5 * (1 + math.cos(math.pi * step / steps))))
        loss = objective()
        dr.backward(loss)
        opt.step()
        for p in params:
            lo, hi = ranges[p.name]
            opt[p.name] = dr.clip(opt[p.name], lo, hi)
        if bar is not None:
            bar.update(done + step + 1)
    with dr.suspend_grad():
        loss = float(np.asarray(objective()).ravel()[0])
    values = {p.name: p.decode(np.array(opt[p.name], dtype=np.float64).ravel()) for p in params}
    return values, loss


def _run_starts(bsdf, params: list[Parameter], candidates: dict, wi, wo, target_values,
                steps: int, lr: float, model, progress: bool) -> dict:
    """{label: (values, objective)}: :func:`_run` from each start of ``candidates``."""
    import mitsuba as mi

    from ..checks import batch
    from ..progress import Progress

    si, w = batch.interaction(wi, len(wi)), batch.vectors(wo)
    projected = target_values * wi[:, 2:3]  # f·cosθi·cosθo
    target_c = mi.Color3f(*[batch.floats(np.cbrt(projected[:, c] + EPSILON))
                            for c in range(3)])
    bar = Progress(steps * len(candidates), label=f"fit {spec_text(model)}", unit=" steps") \
        if progress else None
    runs = {}
    try:
        for i, (label, start) in enumerate(candidates.items()):
            runs[label] = _run(bsdf, params, start, si, w, target_c, steps, lr, bar, i * steps)
    finally:
        if bar is not None:
            bar.close()
    return runs


def _best(runs: dict, model) -> str:
    """The label of the run with the lowest objective; MiBrdfsError when every run diverged."""
    best = min(runs, key=lambda label: (not math.isfinite(runs[label][1]), runs[label][1]))
    loss = runs[best][1]
    if not math.isfinite(loss):
        raise MiBrdfsError(f"the fit of {spec_text(model)} diverged (objective {loss}) from every "
                           f"start")
    return best
