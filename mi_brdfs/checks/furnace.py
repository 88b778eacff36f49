"""
The white furnace render: the BSDF on the unit sphere of ``scenes/furnace.xml``, inside a
constant environment of radiance 1, one bounce. A pixel that sees the sphere at angle θ to its
normal has the value E(θ); the background is 1. So the image is predictable from the albedo
curve, which is what this check does: it renders, predicts the image from E(θ) (analytic ray
casting of the same camera, 4×4 sub-pixel positions per pixel), and compares the means.

A BSDF that transmits sends part of the light into the sphere; with one bounce that part ends
inside (the next vertex is the sphere's inner side, beyond the path's depth), so the pixel is
the reflected fraction E_r(θ) alone, predicted from the reflection lobes: the float64 reference
where there is one, else ``eval()`` at directions the checker draws (independent of the BSDF's
sampler), else (Dirac lobes) the ``sample()`` weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe, loaded_once
from ..errors import arguments, counts, nonnegative, valid_seed
from ..scenes import load_scene
from .result import CheckResult

#: The furnace camera (scenes/furnace.xml): at (0, 0, 5) looking at the unit sphere, fov 30°.
CAMERA_DISTANCE, FOV_DEG = 5.0, 30.0


def view_cosines(res: int, sub: int = 4) -> np.ndarray:
    """
    cosθ between the view ray and the sphere normal at each sub-pixel sample, (res, res, sub²);
    NaN where the ray misses the sphere (background).
    """
    t = math.tan(math.radians(FOV_DEG) / 2)
    offsets = (np.arange(sub) + 0.5) / sub
    coords = (np.arange(res)[:, None] + offsets[None, :]).reshape(-1) / res  # (res·sub,)
    x = (2 * coords - 1) * t
    X, Y = np.meshgrid(x, x, indexing="xy")
    d = np.stack([X, -Y, -np.ones_like(X)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = np.array([0.0, 0.0, CAMERA_DISTANCE])
    b = d @ o
    disc = b * b - (o @ o - 1.0)
    hit = disc >= 0
    dist = -b - np.sqrt(np.where(hit, disc, 0))
    p = o + dist[..., None] * d
    cos = np.where(hit, -np.sum(d * p, axis=-1), np.nan)
    cos = cos.reshape(res, sub, res, sub).transpose(0, 2, 1, 3).reshape(res, res, sub * sub)
    return cos


def expected_image(albedo_theta_deg, albedo_values, res: int) -> np.ndarray:
    """The furnace image predicted from an albedo curve E(θ) (one channel), (res, res)."""
    cos = view_cosines(res)
    theta = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    value = np.interp(theta, albedo_theta_deg, albedo_values)
    return np.where(np.isnan(cos), 1.0, value).mean(axis=2)


@dataclass
class FurnaceRender:
    """A furnace render and what the albedo curve predicts for it."""

    image: np.ndarray
    mean: float
    std: float
    min: float
    max: float
    nonfinite: int
    expected: float | None
    spp: int
    res: int
    #: the standard error of the image mean, from the pixels' spread about the prediction
    error: float | None = None


#: Incident angles (degrees) of the albedo curve behind the prediction: uniform in cosθ down
#: to cosθ = 0.001, where the sphere's rim samples E(θ).
THETAS = tuple(np.degrees(np.arccos(np.linspace(1.0, 0.001, 25))).round(3))


def _reflected_albedo(spec, n: int | None) -> np.ndarray:
    """E_r(θ) at :data:`THETAS` of the reflection lobes, radiance transport, (angles, channels)."""
    from .. import reference
    from ..bsdfspec import load_bsdf
    from .albedo import albedo_eval, albedo_sampled

    model = reference.for_spec(spec)
    if isinstance(model, reference.RoughDielectric):
        return np.array([model.albedo(t, radiance=True, lobes="reflection")
                         for t in np.radians(THETAS)])
    bsdf = load_bsdf(spec)
    ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.Reflection)
    smooth = int(bsdf.flags()) & int(mi.BSDFFlags.Smooth) & int(mi.BSDFFlags.Reflection)
    delta = int(bsdf.flags()) & int(mi.BSDFFlags.DeltaReflection)
    rows = []
    for i, t in enumerate(np.radians(THETAS)):
        value = albedo_eval(bsdf, t, n, seed=1000 + i, ctx=ctx)[0] if smooth else 0.0
        if delta:  # Dirac reflection: eval() is 0 there, the weights see it
            delta_ctx = mi.BSDFContext(mi.TransportMode.Radiance, +mi.BSDFFlags.DeltaReflection)
            value = value + albedo_sampled(bsdf, t, n, seed=i, ctx=delta_ctx)[0]
        rows.append(np.broadcast_to(value, (len(np.atleast_1d(value)),)))
    return np.array(rows)


@loaded_once()
@counts("spp", "res", "n")
@arguments(seed=valid_seed)
def furnace_render(spec, spp: int = 64, res: int = 64, seed: int = 0, max_depth: int = 2,
                   predict: bool = True, n: int | None = None,
                   reflection_only: bool = False) -> FurnaceRender:
    """
    Render the furnace with ``spec`` as the sphere's material in the current variant, and (with
    ``predict``) the image mean expected from the BSDF's albedo curve (the float64 reference
    where there is one, else ``sample()`` weights); with ``reflection_only`` from the albedo
    of its reflection lobes (a BSDF that transmits, rendered with one bounce).
    """
    from .albedo import albedo_curve

    scene = load_scene("furnace", bsdfs={"material": spec}, spp=spp, res=res,
                       max_depth=max_depth)
    image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
    finite = np.isfinite(image)
    expected = None
    if predict and reflection_only:
        best = _reflected_albedo(spec, n)
    elif predict:
        from .. import reference

        model = reference.for_spec(spec)
        if model is not None:  # the float64 model's E(θ): no sampling needed
            best = np.array([model.albedo(t) for t in np.radians(THETAS)])
        else:
            best = albedo_curve(spec, THETAS, n=n, estimators=()).sampled
    error = None
    if predict:
        predicted = np.mean([expected_image(THETAS, best[:, c], res)
                             for c in range(best.shape[1])], axis=0)
        expected = float(predicted.mean())
        pixels = np.all(finite, axis=-1) if image.ndim == 3 else finite
        residual = (image.mean(axis=-1) if image.ndim == 3 else image) - predicted
        error = float(residual[pixels].std() / np.sqrt(max(pixels.sum(), 1)))
    values = image[finite]
    return FurnaceRender(image=image, mean=float(values.mean()), std=float(values.std()),
                         min=float(values.min()), max=float(values.max()),
                         nonfinite=int((~finite).sum()), expected=expected, spp=spp, res=res,
                         error=error)


@loaded_once()
@counts("spp", "res")
@arguments(tol=nonnegative)
def check_furnace(spec, spp: int = 64, res: int = 64, tol: float | None = None,
                  **kwargs) -> CheckResult:
    """
    The furnace image must be finite everywhere and its mean within ``tol`` of the mean that
    the albedo curve predicts (for Lambert with ρ = 1: 1, the sphere vanishes); by default
    0.005 plus 4 standard errors of the image mean (from the pixels' spread about the
    prediction), so that few samples per pixel are judged by their noise. A BSDF that
    transmits is rendered with one bounce and predicted from its reflected fraction (see the
    module docstring).
    """
    from ..bsdfspec import load_bsdf

    transmits = bool(int(load_bsdf(spec).flags()) & int(mi.BSDFFlags.Transmission))
    if transmits:
        kwargs = dict(kwargs, max_depth=2, reflection_only=True)
    r = furnace_render(spec, spp=spp, res=res, **kwargs)
    if tol is None:
        tol = 0.005 + 4.0 * r.error
    dev = abs(r.mean - r.expected)
    passed = r.nonfinite == 0 and dev <= tol
    what = "the reflected E_r(θ), one bounce" if transmits else "E(θ)"
    msg = (f"furnace: {describe(spec)}: image mean {r.mean:.5f} vs {r.expected:.5f} predicted "
           f"from {what} (|Δ| = {dev:.5f}, {'≤' if dev <= tol else '>'} {tol:g}); "
           f"{r.nonfinite} non-finite pixels; spread {r.std:.4f} "
           f"(min {r.min:.4f}, max {r.max:.4f})")
    return CheckResult("furnace", passed, dev, tol, msg, details={"render": r})
