r"""
The models of Ngan, Durand & Matusik's fits (2005, "Experimental Analysis of BRDF Models",
EGSR) in float64, as bbm defines them (https://github.com/bsdfbenchmark/bbm,
``include/bsdfmodel/ngan.h`` and the models it names), written from the formulas and taking a
fit's parameters as the file gives them: the oracle of :mod:`mi_brdfs.presets`' conversions,
independent of them. With h = (ωi + ωo)/‖ωi + ωo‖, θh its polar angle, A the fit's RGB
``albedo`` and ρd its Lambertian albedo, every model is f = ρd/π + A·S:

* ``ward``: S = exp(−tan²θh/α²)/(4π α² √(cosθi cosθo)) (Ward 1992, eq. 5a, isotropic);
* ``wardduer``: S = exp(−tan²θh/α²)/(4π α² cosθi cosθo) (Dür 2006);
* ``blinnphong``: S = (n+2)/(2π)·cosⁿ, of θh (``lobe`` halfway: Blinn-Phong, as Ngan et al.
  fit it) or of the angle between ωo and the mirror direction of ωi (``lobe`` mirror: bbm's
  ``nganblinnphong``, an alias of its modified Phong);
* ``cooktorrance``: S = D·G·F/(π cosθi cosθo), D = exp(−tan²θh/m²)/(π m² cos⁴θh),
  G = min(1, 2 cosθh cosθi/(ωi·h), 2 cosθh cosθo/(ωo·h)) (Torrance & Sparrow 1967),
  F = F0 + (1 − F0)(1 − ωi·h)⁵ with F0 the fit's ``eta`` (Cook & Torrance 1982 with
  Schlick 1994);
* ``ashikhminshirley``: S = (n+1)/(8π)·cosⁿθh·F(ωi·h)/((ωi·h) max(cosθi, cosθo)), F
  Schlick's with F0 = ``fresnelReflectance`` (Ashikhmin & Shirley 2000, the specular term);
* ``lafortune``: S = (n+2)/(2π)·max(0, Cxy(ix ox + iy oy) + Cz iz oz)ⁿ/max(Cxy², Cz²)^(n/2)
  (Lafortune et al. 1997, eq. 4, with Ngan's normalisation), computed as (g/c)ⁿ with
  c = max(|Cxy|, |Cz|), since gⁿ and cⁿ alone underflow float64 for the fits' exponents;
* ``he``: S = ρ_dd per channel, He et al.'s directional diffuse term as Westin et al.'s code
  has it (:mod:`mi_brdfs.reference.he`, σ0 = ``roughness``, τ = ``autocorrelation``, real
  η = ``eta``) at bbm's RGB wavelengths 0.645, 0.526 and 0.444 µm, with bbm's blend of the
  series (1 − w) and Beckmann's asymptote (w), w = clamp(g − 18, 0, 1) (``he_base``'s
  RoughApproxThreshold 18 of ``nganhe``); no delta.

Directions are (n, 3) unit vectors in the local frame (normal +z); f is 0 unless both are above
the surface.
"""

from __future__ import annotations

import math

import numpy as np

#: The models written here.
MODELS = ("ward", "wardduer", "blinnphong", "cooktorrance", "ashikhminshirley", "lafortune",
          "he")
#: bbm's RGB wavelengths (µm) and the g over which its NganHe blends into the asymptote.
HE_WAVELENGTHS, HE_BLEND = (0.645, 0.526, 0.444), (18.0, 19.0)


def _he(p: dict, wi, wo) -> np.ndarray:
    """ρ_dd of bbm's NganHe, (n, 3) (the module docstring)."""
    from .he import HTSG, Variant, effective_roughness, phase_variance
    surface = (p["roughness"], p["autocorrelation"], list(HE_WAVELENGTHS), p["eta"], 0.0)
    series = HTSG(*surface, variant=Variant(True, True, None, None))
    asymptote = HTSG(*surface, variant=Variant(True, True, None, 0.0))
    sigma = effective_roughness(wi[:, 2], wo[:, 2], p["roughness"], p["autocorrelation"])
    g = phase_variance(sigma, wi[:, 2], wo[:, 2], HE_WAVELENGTHS)
    w = np.clip((g - HE_BLEND[0]) / (HE_BLEND[1] - HE_BLEND[0]), 0.0, 1.0)
    return (1.0 - w) * series.directional_diffuse(wi, wo) + \
        w * asymptote.directional_diffuse(wi, wo)


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _schlick(f0, cos):
    return f0 + (1.0 - f0) * (1.0 - cos) ** 5


class NganFit:
    """f(ωi, ωo) of one fit: ``model`` (:data:`MODELS`), ``diffuse`` ρd (RGB) and ``params``
    as the fit file names them (``albedo``, ``roughness``, ``sharpness``, ...)."""

    def __init__(self, model: str, diffuse, params: dict, lobe: str = "halfway"):
        if model not in MODELS:
            raise ValueError(f"model must be one of {MODELS}")
        self.model, self.params, self.lobe = model, dict(params), lobe
        self.rho_d = np.asarray(diffuse, dtype=np.float64)
        self.albedo = np.asarray(params["albedo"], dtype=np.float64)

    def specular(self, wi, wo) -> np.ndarray:
        """S(ωi, ωo), (n,) ((n, 3) for ``he``), for both directions above the surface."""
        p, ci, co = self.params, wi[:, 2], wo[:, 2]
        if self.model == "he":
            return _he(p, wi, wo)
        h = _unit(wi + wo)
        ch, ih = h[:, 2], np.sum(wi * h, axis=1)
        tan2 = (1.0 - ch * ch) / (ch * ch)
        if self.model in ("ward", "wardduer"):
            a = p["roughness"]
            cosines = np.sqrt(ci * co) if self.model == "ward" else ci * co
            return np.exp(-tan2 / a ** 2) / (4.0 * math.pi * a * a * cosines)
        if self.model == "blinnphong":
            n = p["sharpness"]
            mirror = np.stack([-wi[:, 0], -wi[:, 1], wi[:, 2]], axis=1)
            cos = ch if self.lobe == "halfway" else np.maximum(np.sum(mirror * wo, axis=1), 0)
            return (n + 2.0) / (2.0 * math.pi) * cos ** n
        if self.model == "cooktorrance":
            m = p["roughness"]
            d = np.exp(-tan2 / m ** 2) / (math.pi * m * m * ch ** 4)
            g = np.minimum(1.0, np.minimum(2 * ch * ci / ih, 2 * ch * co / ih))
            return d * g * _schlick(p["eta"], ih) / (math.pi * ci * co)
        if self.model == "ashikhminshirley":
            n = p["sharpness"]
            return (n + 1.0) / (8.0 * math.pi) * ch ** n * _schlick(
                p["fresnelReflectance"], ih) / (ih * np.maximum(ci, co))
        n, cxy, cz = p["sharpness"], p["Cxy"], p["Cz"]
        g = cxy * (wi[:, 0] * wo[:, 0] + wi[:, 1] * wo[:, 1]) + cz * ci * co
        return (n + 2.0) / (2.0 * math.pi) * np.maximum(g / max(abs(cxy), abs(cz)), 0.0) ** n

    def brdf(self, wi, wo) -> np.ndarray:
        """f(ωi, ωo), (n, 3)."""
        wi, wo = np.atleast_2d(wi).astype(np.float64), np.atleast_2d(wo).astype(np.float64)
        above = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
            s = self.specular(wi, wo)
        s = np.where(above[:, None], s if s.ndim == 2 else s[:, None], 0.0)
        return np.where(above[:, None], self.rho_d / math.pi, 0.0) + s * self.albedo

    def eval_cos(self, wi, wo) -> np.ndarray:
        """f·cosθo, (n, 3): what a plugin's ``eval`` returns."""
        return self.brdf(wi, wo) * np.atleast_2d(wo)[:, 2:3]
