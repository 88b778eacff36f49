"""
The quantities of Earth observation for any BSDF, as the papers on the models of the field
report them (Schaepman-Strub et al. 2006, "Reflectance quantities in optical remote sensing —
definitions and case studies", Remote Sensing of Environment 103; Lucht, Schaaf & Strahler
2000, "An Algorithm for the Retrieval of Albedo from Space Using Semiempirical BRDF Models",
IEEE TGRS 38(2)):

- the bidirectional reflectance factor, BRF = π·f = π·eval/cosθo, the BRDF relative to that
  of a white Lambertian surface (1 for it, at every direction pair; dimensionless);
- the principal plane (:func:`principal_plane`): the BRF against the view zenith in the plane
  that holds the sun, backward (the viewer on the sun's side, where the hot spot is, at
  θo = θi) and forward (the specular side);
- the black-sky albedo, the directional-hemispherical reflectance E(θ) = ∫ f cosθo dωo at the
  sun's zenith θ (``mi-brdfs furnace`` measures it), and the white-sky albedo, the
  bihemispherical reflectance under isotropic illumination, 2 ∫ E(θ) cosθ sinθ dθ
  (:func:`white_sky_albedo`).

The sun is ωi (towards the light), the viewer ωo, as Mitsuba's ``si.wi`` and ``wo``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bsdfspec import load_bsdf, loaded_once
from .checks import batch
from .errors import MiBrdfsError, arguments, counts, valid_seed

#: The sun zeniths of the principal-plane plot by default (degrees).
SUN_ZENITHS = (0.0, 30.0, 60.0)
#: The view zeniths of the principal plane: every half degree within 89° of the zenith,
#: backward positive (the sun's side), forward negative.
VIEW_ZENITHS = np.arange(-178, 179) * 0.5
#: Samples of the white-sky albedo: JIT variants vectorise, scalar ones call Python per sample.
WHITE_SKY_SAMPLES = {True: 1_000_000, False: 4_000}


@dataclass
class PrincipalPlane:
    """The BRF in the principal plane of one BSDF: ``brf`` (sun zeniths, view zeniths,
    channels) at ``view_zenith_deg``, signed (backward > 0, the sun's side), per sun zenith
    ``sun_zenith_deg``."""

    spec: object
    sun_zenith_deg: np.ndarray
    view_zenith_deg: np.ndarray
    brf: np.ndarray

    def hot_spot(self) -> np.ndarray:
        """The BRF at the hot spot (view zenith = sun zenith, backward), (sun zeniths,
        channels)."""
        k = [int(np.argmin(np.abs(self.view_zenith_deg - t))) for t in self.sun_zenith_deg]
        return self.brf[np.arange(len(k)), k]


def _sun_zeniths(thetas) -> np.ndarray:
    thetas = np.atleast_1d(np.asarray(thetas, dtype=np.float64))
    if thetas.size == 0 or not np.all((thetas >= 0) & (thetas < 90)):
        raise MiBrdfsError(f"principal plane: sun zeniths must lie in [0, 90) degrees, got "
                           f"{thetas.tolist()}")
    return thetas


@loaded_once()
def principal_plane(spec, sun_zeniths_deg=SUN_ZENITHS) -> PrincipalPlane:
    """
    The BRF = π·eval/cosθo of ``spec`` in the principal plane at each sun zenith (degrees, in
    [0, 90)): the sun at azimuth 0, ωi = (sinθi, 0, cosθi), the viewer at ωo = (sin v, 0,
    cos v) for the signed view zenith v of :data:`VIEW_ZENITHS` (and each sun zenith, so that
    the hot spot is a node): v > 0 backward, v < 0 forward. One call for every pair.
    """
    suns = _sun_zeniths(sun_zeniths_deg)
    views = np.union1d(VIEW_ZENITHS, suns)
    t_i, t_o = (np.radians(a) for a in np.meshgrid(suns, views, indexing="ij"))
    wi = np.stack([np.sin(t_i), np.zeros_like(t_i), np.cos(t_i)], axis=-1).reshape(-1, 3)
    wo = np.stack([np.sin(t_o), np.zeros_like(t_o), np.cos(t_o)], axis=-1).reshape(-1, 3)
    value = batch.evaluate(load_bsdf(spec), wi, wo).value
    brf = math.pi * value / wo[:, 2:3]
    return PrincipalPlane(spec, suns, views, brf.reshape(len(suns), len(views), -1))


@dataclass
class WhiteSky:
    """The white-sky albedo per channel, ``value`` ± ``err`` (the standard error), from the
    mean sample() weight over ``n`` cosine-weighted incident directions."""

    value: np.ndarray
    err: np.ndarray
    n: int

    def line(self) -> str:
        """One line, the brightest channel, as ``mi-brdfs furnace`` prints it."""
        c = int(np.argmax(self.value))
        return (f"white-sky albedo (bihemispherical, isotropic illumination): "
                f"{self.value[c]:.5f} ± {self.err[c]:.5f} (mean sample() weight over {self.n} "
                f"cosine-weighted incident directions)")


@counts("n")
@arguments(seed=valid_seed)
def white_sky_albedo(spec, n: int | None = None, seed: int = 0) -> WhiteSky:
    """
    The white-sky albedo 2 ∫ E(θ) cosθ sinθ dθ = ∫∫ f cosθi cosθo dωi dωo/π of ``spec``, by
    Monte Carlo: ωi drawn from the cosine-weighted hemisphere (density cosθi/π, the weight of
    the integral), ωo by the BSDF's sample(), whose weight is f·cosθo/pdf: the mean weight is
    an unbiased estimate, with its standard error. ``n`` samples (default 10⁶ in JIT variants,
    4000 in scalar ones). For a BSDF that transmits, the weight holds the transmitted part
    too, as E(θ) of ``mi-brdfs furnace`` does.
    """
    n = n if n is not None else WHITE_SKY_SAMPLES[batch.is_jit()]
    rng = np.random.default_rng(seed)
    u = rng.random((n, 5))
    r, phi = np.sqrt(u[:, 0]), 2 * math.pi * u[:, 1]
    wi = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u[:, 0])], axis=1)
    s = batch.sample(load_bsdf(spec), wi, u[:, 2], u[:, 3:])
    weight = np.where(np.isfinite(s.weight), s.weight, np.nan)
    return WhiteSky(weight.mean(axis=0), weight.std(axis=0, ddof=1) / math.sqrt(max(n, 2)), n)
