"""
Float32 against float64: how far a plugin's ``eval`` (in a float32 variant) departs from the
model's float64 reference (:mod:`mi_brdfs.reference`) at the *same* directions.

The directions are where the BSDF matters: drawn by its own ``sample()`` (so a sharp lobe is
probed across its width, not missed) at several incident angles; the float32 directions the
plugin saw are converted exactly to float64 for the reference, so only the arithmetic differs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..bsdfspec import load_bsdf, loaded_once
from ..errors import arguments, counts, valid_angles, valid_seed
from . import batch

#: Incident angles (degrees) at which the lobe is sampled.
THETAS = (0.0, 45.0, 80.0)

#: Relative error at which float32 is said to stop following float64 (the 99th percentile).
BREAK = 1e-3


@dataclass
class Precision:
    """Relative errors of f·cosθo over the sampled directions where the reference is not ~0."""

    spec: object
    median: float
    p99: float
    max: float
    count: int


@loaded_once()
@counts("n")
@arguments(seed=valid_seed, thetas=valid_angles(180.0, "degrees"))
def eval_precision(spec, n: int | None = None, seed: int = 0, thetas=THETAS) -> Precision | None:
    """
    Relative error of ``eval`` against the float64 reference, over ``n`` directions per incident
    angle drawn by the BSDF's ``sample()``; None when the package has no reference for ``spec``.
    Values whose reference is below 1e-6 of the largest are left out (relative error of noise).
    """
    from .. import reference

    model = reference.for_spec(spec)
    if model is None:
        return None
    bsdf = load_bsdf(spec)
    n = n or (20_000 if batch.is_jit() else 300)
    rng = np.random.default_rng(seed)
    errors = []
    for theta in np.radians(thetas):
        wi = np.asarray(batch.direction(theta), dtype=np.float32).astype(np.float64)
        s = batch.sample(bsdf, wi, rng.random(n), rng.random((n, 2)))
        keep = np.any(s.weight != 0, axis=1)
        wo = s.wo[keep].astype(np.float32).astype(np.float64)
        if not len(wo):
            continue
        value = batch.evaluate(bsdf, wi, wo).value
        exact = model.brdf(np.broadcast_to(wi, wo.shape), wo) * wo[:, 2:3]
        exact = np.broadcast_to(exact, value.shape)
        big = np.abs(exact) > 1e-6 * np.max(np.abs(exact))
        errors.append((np.abs(value - exact) / np.where(big, np.abs(exact), 1.0))[big])
    e = np.concatenate(errors) if errors else np.zeros(0)
    if not e.size:
        return Precision(spec, 0.0, 0.0, 0.0, 0)
    e = np.where(np.isfinite(e), e, np.inf)
    return Precision(spec, float(np.median(e)), float(np.percentile(e, 99)), float(e.max()),
                     int(e.size))
