"""
The optimisation of a fit: the direction pairs, the cube-root objective and Adam over the
transformed variables (see :mod:`mi_brdfs.fit`).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import MiBrdfsError
from .parameters import Parameter
from .spec import spec_text

#: ε of the cube-root objective (f·cosθi·cosθo units): keeps its gradient finite where it is 0.
EPSILON = 1e-6

#: The objectives (``metric``): what each compares, and how the pairs are weighed. The pairs
#: are drawn uniformly in (√θh, θd, φd), MERL's own spacing (Matusik et al. 2003), so the plain
#: mean is the mean over MERL's bins; the others are integrals over the sphere of directions,
#: each pair weighed by the solid angle dωi dωo its bin covers, ∝ cosθd·sinθd·sinθh·√θh
#: (:func:`solid_angle_weights`), with Δ of f·cosθi:
METRICS = {
    "cuberoot": "(f·cosθi·cosθo + ε)^(1/3), mean over the pairs (Forés et al. 2012)",
    "ngan": "L2 of f·cosθi over dωi dωo (Ngan, Durand & Matusik 2005, §4)",
    "low": "L2 of log(1 + f·cosθi) over dωi dωo (Low, Kronander, Ynnerman & Unger 2012, "
           "\"BRDF Models for Accurate and Efficient Rendering of Glossy Surfaces\", §6)",
    "bieron": "L2 of log(1 + f·cosθi) over cosθo dωi dωo (Bieron & Peers 2020, \"An Adaptive "
              "BRDF Fitting Metric\", CGF 39(4), as bsdfbenchmark/bbm computes it)",
}


def solid_angle_weights(wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The solid angle dωi dωo about each pair relative to the density of the pairs (uniform in
    u = √(2θh/π), θd, φd and φh), mean 1: dωi dωo = 4 cosθd dωh dωd (Rusinkiewicz 1998, §4),
    dωh = sinθh dθh dφh with dθh = πu du, and dωd = sinθd dθd dφd, so the weight is
    ∝ cosθd·sinθd·sinθh·√θh."""
    from ..measured.merl import half_diff

    theta_h, _, theta_d, _ = half_diff(wi, wo)
    w = np.cos(theta_d) * np.sin(theta_d) * np.sin(theta_h) * np.sqrt(theta_h)
    return w / w.mean()


def check_metric(metric: str) -> str:
    """``metric`` if it is one of :data:`METRICS`, else MiBrdfsError (one line)."""
    if metric not in METRICS:
        raise MiBrdfsError(f"fit: metric = {metric!r} is invalid: must be one of "
                           + ", ".join(repr(m) for m in METRICS))
    return metric


def metric_weights(metric: str, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """The weight of each pair in ``metric`` (mean 1)."""
    if check_metric(metric) == "cuberoot":
        return np.ones(len(wi))
    w = solid_angle_weights(wi, wo)
    if metric == "bieron":
        w = w * wo[:, 2]
    return w / w.mean()


def compared(metric: str, e, cos_i, cos_o):
    """What ``metric`` compares, from ``e`` = eval = f·cosθo (drjit or NumPy, per channel)."""
    import drjit as dr

    xp = np if isinstance(e, np.ndarray) else dr
    if metric == "cuberoot":
        return xp.power(e * cos_i + EPSILON, 1.0 / 3.0)
    f_cos = e * (cos_i / cos_o)
    return f_cos if metric == "ngan" else xp.log(1.0 + f_cos)


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


def objective_np(metric: str, values, wi, wo, target_values) -> float:
    """The objective of :func:`_run` in float64 for model values ``values`` (eval, (m, 3)),
    e.g. 0 for the zero model."""
    diff = compared(metric, np.asarray(values, np.float64), wi[:, 2:3], wo[:, 2:3]) \
        - compared(metric, np.asarray(target_values, np.float64), wi[:, 2:3], wo[:, 2:3])
    return float(np.mean(metric_weights(metric, wi, wo) * np.sum(diff ** 2, axis=1)) / 3.0)


@functools.lru_cache(maxsize=1)
def _above_horizon() -> np.ndarray:
    """The MERL bins whose centre (φh = 0) has both directions more than 10⁻³ above the
    horizon, in the bins' order: flags built once (the directions of every bin take tenths of
    a second, and every fit to a MERL file, and every score of one, asks)."""
    from ..measured import merl

    wi, wo = merl.bin_directions()
    above = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    above.flags.writeable = False
    return above


def measured_pairs(path, pairs: int, seed: int = 0):
    """
    (wi, wo, f·cosθo (m, 3)): ``pairs`` bins of a MERL file drawn at random (seeded, without
    replacement) among its measured bins above the horizon, at their centres, with a random φh
    (the data are isotropic), and the data's own values there: MERL's sample positions.
    """
    from ..measured import merl

    values = merl.read(path)
    theta_h, theta_d, phi_d = (a.ravel() for a in merl.bin_centres())
    flat = np.moveaxis(values, 0, -1).reshape(-1, 3)
    ok = np.flatnonzero(_above_horizon() & ~np.isnan(flat).any(axis=1))
    rng = np.random.default_rng(seed)
    pick = np.sort(rng.choice(ok, size=min(pairs, len(ok)), replace=False))
    wi, wo = merl.directions(theta_h[pick], rng.uniform(-np.pi, np.pi, len(pick)),
                             theta_d[pick], phi_d[pick])
    return wi, wo, flat[pick] * wo[:, 2:3]


def _target_values(target, target_bsdf, pairs: int, seed: int, notes: list):
    """
    (wi, wo, the target's eval, (m, 3)) at the direction pairs; pairs where the target's eval is
    not finite are left out (with a note in ``notes``). A measured target (``merl``) is
    compared at its own bins, with its own values (:func:`measured_pairs`).
    """
    from ..checks import batch

    if type(target_bsdf).__name__ == "Merl":
        wi, wo, target_values = measured_pairs(target_bsdf.filename, pairs, seed)
        if len(wi) == 0:  # the pairs are drawn among the measured bins: there is none
            raise MiBrdfsError(f"fit: {target_bsdf.filename} has no measured bin above the "
                               f"horizon: nothing to fit, with any number of pairs")
        notes.append(f"measured target: {len(wi)} of its bins, at their centres")
    else:
        wi, wo = direction_pairs(pairs, seed)
        target_values = None
    if len(wi) == 0:
        raise MiBrdfsError(f"fit: pairs = {pairs} leaves no direction pair above the horizon "
                           f"(about 3/4 of them are kept): give more pairs (default 16384)")
    if target_values is None:
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


def _run(bsdf, params: list[Parameter], start: dict, si, wo, target_c, weight, metric: str,
         steps: int, lr: float, bar, done: int):
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
        diff = compared(metric, bsdf.eval(ctx, si, wo), si.wi.z, wo.z) - target_c
        return dr.mean(weight * dr.squared_norm(diff)) / 3.0

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
                steps: int, lr: float, model, progress: bool, metric: str = "cuberoot") -> dict:
    """{label: (values, objective)}: :func:`_run` from each start of ``candidates``."""
    import mitsuba as mi

    from ..checks import batch
    from ..progress import Progress

    si, w = batch.interaction(wi, len(wi)), batch.vectors(wo)
    target = compared(metric, target_values, wi[:, 2:3], wo[:, 2:3])
    target_c = mi.Color3f(*[batch.floats(target[:, c]) for c in range(3)])
    weight = batch.floats(metric_weights(metric, wi, wo))
    bar = Progress(steps * len(candidates), label=f"fit {spec_text(model)}", unit=" steps") \
        if progress else None
    runs = {}
    try:
        for i, (label, start) in enumerate(candidates.items()):
            runs[label] = _run(bsdf, params, start, si, w, target_c, weight, metric, steps, lr,
                               bar, i * steps)
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
