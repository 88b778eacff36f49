"""
The white furnace render: the BSDF on the unit sphere of ``scenes/furnace.xml``, inside a
constant environment of radiance 1, one bounce. A pixel that sees the sphere at angle θ to its
normal has the value E(θ); the background is 1. So the image is predictable from the albedo
curve, which is what this check does: it renders, predicts the image from E(θ) (analytic ray
casting of the same camera, 4×4 sub-pixel positions per pixel), and compares the means.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mitsuba as mi
import numpy as np

from ..bsdfspec import describe
from ..errors import counts
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


#: Incident angles (degrees) of the albedo curve behind the prediction: uniform in cosθ down
#: to cosθ = 0.001, where the sphere's rim samples E(θ).
THETAS = tuple(np.degrees(np.arccos(np.linspace(1.0, 0.001, 25))).round(3))


@counts("spp", "res", "n")
def furnace_render(spec, spp: int = 64, res: int = 64, seed: int = 0, max_depth: int = 2,
                   predict: bool = True, n: int | None = None) -> FurnaceRender:
    """
    Render the furnace with ``spec`` as the sphere's material in the current variant, and (with
    ``predict``) the image mean expected from the BSDF's albedo curve (the float64 reference
    where there is one, else ``sample()`` weights).
    """
    from .albedo import albedo_curve

    scene = load_scene("furnace", bsdfs={"material": spec}, spp=spp, res=res,
                       max_depth=max_depth)
    image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)
    finite = np.isfinite(image)
    expected = None
    if predict:
        from .. import reference

        model = reference.for_spec(spec)
        if model is not None:  # the float64 model's E(θ): no sampling needed
            best = np.array([model.albedo(t) for t in np.radians(THETAS)])
        else:
            best = albedo_curve(spec, THETAS, n=n, estimators=()).sampled
        expected = float(np.mean([expected_image(THETAS, best[:, c], res).mean()
                                  for c in range(best.shape[1])]))
    values = image[finite]
    return FurnaceRender(image=image, mean=float(values.mean()), std=float(values.std()),
                         min=float(values.min()), max=float(values.max()),
                         nonfinite=int((~finite).sum()), expected=expected, spp=spp, res=res)


@counts("spp", "res")
def check_furnace(spec, spp: int = 64, res: int = 64, tol: float = 0.005, **kwargs) -> CheckResult:
    """
    The furnace image must be finite everywhere and its mean within ``tol`` of the mean that
    the albedo curve predicts (for Lambert with ρ = 1: 1, the sphere vanishes).
    """
    from ..bsdfspec import load_bsdf

    if int(load_bsdf(spec).flags()) & int(mi.BSDFFlags.Transmission):
        # Light enters the sphere and leaves it after further bounces: one-bounce E(θ) does not
        # predict the image. Only the finiteness of the render is judged.
        r = furnace_render(spec, spp=spp, res=res, predict=False, **kwargs)
        msg = (f"furnace: {describe(spec)}: image mean {r.mean:.5f} (not predicted: the BSDF "
               f"transmits); {r.nonfinite} non-finite pixels")
        return CheckResult("furnace", r.nonfinite == 0, float(r.nonfinite), 0, msg,
                           details={"render": r})
    r = furnace_render(spec, spp=spp, res=res, **kwargs)
    dev = abs(r.mean - r.expected)
    passed = r.nonfinite == 0 and dev <= tol
    msg = (f"furnace: {describe(spec)}: image mean {r.mean:.5f} vs {r.expected:.5f} predicted "
           f"from E(θ) (|Δ| = {dev:.5f}, {'≤' if dev <= tol else '>'} {tol:g}); "
           f"{r.nonfinite} non-finite pixels; spread {r.std:.4f} "
           f"(min {r.min:.4f}, max {r.max:.4f})")
    return CheckResult("furnace", passed, dev, tol, msg, details={"render": r})
