"""
Float64 NumPy reference implementations of the package's models: the oracle for the tests and
the validation campaign, written independently of the plugins. The models (``lambert.py``,
``phong.py``, ``cooktorrance.py``, ``ward.py``, ``orennayar.py``, ``quadrature.py``, and
``ngan.py``: the models of Ngan et al.'s fits as bbm defines them,
``he.py``: He, Torrance, Sillion & Greenberg 1991 in three readings, ``rtls.py``: the
Ross-Thick Li-Sparse-Reciprocal kernels of MODIS, ``rpv.py``: Rahman-Pinty-Verstraete,
``ocean.py``: Cox & Munk's sea surface) use NumPy alone; only :func:`for_spec` and :func:`color` here ask Mitsuba which variant is set (RGB
colours mean something else in spectral variants) and parse specs through
:mod:`mi_brdfs.bsdfspec`.

Each model is a small class with ``brdf(wi, wo)`` → f (without the cosine), arrays of shape
(n, channels), directions as (n, 3) unit vectors in the local frame (normal = +z, ``wi`` towards
the light or viewer, as in Mitsuba), and ``albedo(theta)`` → E(θ) per channel, by a closed form
where one exists, else by quadrature. :func:`for_spec` maps a BSDF specification (a
``load_dict`` dict, for our plugins and their built-in counterparts) to its reference.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np

from .ashikhmin import Ashikhmin
from .cooktorrance import CookTorrance, RoughDielectric
from .lafortune import Lafortune
from .multiscatter import Compensated, CompensatedDielectric
from .lambert import Lambert
from .orennayar import OrenNayar
from .phong import Phong
from .quadrature import hemisphere_albedo
from .ward import Ward

__all__ = ["for_spec", "color", "Lambert", "Phong", "CookTorrance", "RoughDielectric", "Ward",
           "OrenNayar", "Ashikhmin", "hemisphere_albedo"]


def color(value, default=None) -> np.ndarray | None:
    """
    A parameter value of a BSDF dict as per-channel float64, or None when the reference cannot
    know it in this variant (an RGB colour is upsampled to a spectrum in spectral variants; a
    texture varies over the surface).
    """
    if value is None:
        value = default
    if isinstance(value, (int, float)):
        return np.array([float(value)])
    if isinstance(value, dict) and value.get("type") == "rgb" and not mi.is_spectral \
            and not mi.is_monochromatic:
        return np.asarray(value["value"], dtype=np.float64).reshape(-1)
    if isinstance(value, dict) and value.get("type") == "spectrum" and \
            isinstance(value.get("value"), (int, float)):
        return np.array([float(value["value"])])
    return None


def for_spec(spec):
    """
    The float64 reference of a BSDF spec in any form (:mod:`mi_brdfs.bsdfspec`), or None where
    the package has none (for a spec that is not a dict once parsed: XML, a loaded mi.BSDF).
    A ``preset`` stands for the parameters it gives the plugin (:func:`mi_brdfs.presets.spec`;
    the spec's own parameters win, as in a scene).
    """
    from ..bsdfspec import parse

    spec = parse(spec)
    if not isinstance(spec, dict):
        return None
    if "preset" in spec:  # the parameters the plugin takes from it (mi_brdfs.presets)
        from ..presets import spec as preset_spec
        given = {k: v for k, v in spec.items() if k not in ("type", "preset")}
        spec = preset_spec(spec["type"], spec["preset"], **given)
    kind = spec.get("type")
    if kind in ("lambert", "diffuse"):
        rho = color(spec.get("reflectance"), 0.5)
        return None if rho is None else Lambert(rho)
    if kind == "phong":
        rho_d = color(spec.get("diffuse_reflectance"), 0.5)
        k_s = color(spec.get("specular_reflectance"), 0.2)
        n = spec.get("exponent", 30.0)
        if rho_d is None or k_s is None or not isinstance(n, (int, float)):
            return None
        return Phong(rho_d, k_s, n, spec.get("form", "normalized"), spec.get("lobe", "mirror"))
    if kind == "ward":
        alpha = (spec.get("alpha_u"), spec.get("alpha_v")) if "alpha_u" in spec \
            else spec.get("alpha", 0.1)
        rho_d = color(spec.get("diffuse_reflectance"), 0.5)
        rho_s = color(spec.get("specular_reflectance"), 0.2)
        numbers = alpha if isinstance(alpha, tuple) else (alpha,)
        if rho_d is None or rho_s is None or \
                not all(isinstance(a, (int, float)) for a in numbers):
            return None
        return Ward(alpha, rho_d, rho_s, spec.get("form", "balanced"))
    if kind == "orennayar":
        rho, sigma = color(spec.get("reflectance"), 0.5), spec.get("sigma", 0.2)
        if rho is None or not isinstance(sigma, (int, float)):
            return None
        return OrenNayar(rho, sigma, spec.get("form", "qualitative"))
    if kind == "lafortune":
        return Lafortune.from_spec(spec, color)
    if kind == "ashikhmin":
        return Ashikhmin.from_spec(spec, color)
    if kind == "roughdielectric" or (kind == "cooktorrance" and spec.get("transmission")):
        return _rough_dielectric(spec)
    if kind in ("cooktorrance", "roughconductor"):
        return _cooktorrance(spec)
    if kind == "he":
        return _he(spec)
    if kind == "rtls":
        return _rtls(spec)
    if kind == "hapke":
        return _hapke(spec)
    if kind == "rpv":
        return _rpv(spec)
    if kind == "ocean":
        return _ocean(spec)
    return None


def _ocean(spec):
    """The reference of an ``ocean`` dict (the plugin's defaults); None for textures."""
    from .ocean import Ocean
    index = [color(spec.get(name), default) for name, default in
             (("eta", 1.33), ("k", 0.0), ("ext_ior", 1.000277))]
    whitecaps = spec.get("whitecaps", False)
    whitecaps = None if whitecaps is False else color(0.22 if whitecaps is True else whitecaps)
    scalars = [spec.get(name, d) for name, d in (("wind_speed", 0.1), ("wind_direction", None))]
    if any(x is None for x in index) or ("whitecaps" in spec and whitecaps is None) or \
            not all(isinstance(x, (int, float, type(None))) for x in scalars):
        return None
    return Ocean(scalars[0], *index, wind_direction=scalars[1], whitecaps=whitecaps,
                 shadowing=spec.get("shadowing", True))


def _rtls(spec):
    """The reference of an ``rtls`` dict (its defaults those of :mod:`.rtls`'s plugin);
    None for textures."""
    from .rtls import RTLS
    weights = [color(spec.get(name), default) for name, default in
               (("f_iso", 0.209741), ("f_vol", 0.081384), ("f_geo", 0.004140))]
    shape = [spec.get(name, default) for name, default in (("h", 2.0), ("r", 1.0), ("b", 1.0))]
    if any(w is None for w in weights) or not all(isinstance(x, (int, float)) for x in shape):
        return None
    return RTLS(*weights, *shape)


def _rpv(spec):
    """The reference of an ``rpv`` dict (Eradiate's defaults, ρc = ρ0 unless given); None for
    textures."""
    from .rpv import K, RHO_0, RPV, G
    rho_0 = color(spec.get("rho_0"), RHO_0)
    rest = [color(spec.get(name), default) for name, default in (("k", K), ("g", G))]
    rho_c = color(spec["rho_c"]) if "rho_c" in spec else rho_0
    if rho_0 is None or rho_c is None or any(x is None for x in rest):
        return None
    return RPV(rho_0, *rest, rho_c)


def _hapke(spec):
    """The reference of a ``hapke`` dict (Eradiate's defaults); None for textures."""
    from .hapke import DEFAULTS, Hapke
    values = [color(spec.get(name), default) for name, default in DEFAULTS.items()]
    return None if any(v is None for v in values) else Hapke(*values)


def _he(spec):
    """
    The reference of an ``he`` dict at the wavelengths of the current variant's plugin (RGB's
    three, monochrome's one); None in spectral variants (their wavelengths are sampled), for
    named materials, textures and a ``specular_reflectance`` other than 1.
    """
    import mitsuba as mi

    from ..scattering.he import DEFAULT_SIGMA0, DEFAULT_TAU, MONO_WAVELENGTH, RGB_WAVELENGTHS
    from .he import HTSG
    if mi.variant() is None or mi.is_spectral or "material" in spec or \
            spec.get("specular_reflectance", 1.0) != 1.0:
        return None
    sigma0, tau = spec.get("sigma0", DEFAULT_SIGMA0), spec.get("tau", DEFAULT_TAU)
    eta, k = color(spec.get("eta"), 1.5), color(spec.get("k"), 0.0)
    a = color(spec.get("diffuse_reflectance"), 0.0)
    if any(x is None for x in (eta, k, a)) or \
            not all(isinstance(x, (int, float)) for x in (sigma0, tau)):
        return None
    wavelength = [MONO_WAVELENGTH] if mi.is_monochromatic else list(RGB_WAVELENGTHS)
    return HTSG(sigma0, tau, wavelength, eta, k, a, spec.get("variant", "westin"),
                spec.get("terms", "variant"))


def _rough_dielectric(spec):
    """
    The reference of a ``roughdielectric`` dict or a ``cooktorrance`` one with
    ``transmission`` (named media take Mitsuba's values); None for textures.
    """
    from ..materials import dielectric_ior
    alpha = (spec.get("alpha_u"), spec.get("alpha_v")) if "alpha_u" in spec \
        else spec.get("alpha", 0.1)
    numbers = alpha if isinstance(alpha, tuple) else (alpha,)
    if "eta" in spec:
        eta = spec["eta"]
    else:
        eta = dielectric_ior(spec.get("int_ior", "bk7")) / \
            dielectric_ior(spec.get("ext_ior", "air"), name="ext_ior")
    specular = color(spec.get("specular_reflectance"), 1.0)
    transmittance = color(spec.get("specular_transmittance"), 1.0)
    if not all(isinstance(a, (int, float)) for a in (*numbers, eta)) or specular is None \
            or transmittance is None:
        return None
    model = RoughDielectric(alpha, spec.get("distribution", "beckmann"), eta, specular,
                            transmittance)
    return CompensatedDielectric(model) if spec.get("multiscatter") else model


def _cooktorrance(spec):
    """
    The reference of a ``cooktorrance`` dict, or of a ``roughconductor`` one, which is the same
    model with Smith's G as Mitsuba computes it and the exact Fresnel term (its defaults η = 0,
    k = 1: F ≡ 1). None for named materials (their spectra are Mitsuba's data) and textured
    roughness; ``alpha_u``/``alpha_v`` give the anisotropic model.
    """
    alpha = (spec.get("alpha_u"), spec.get("alpha_v")) if "alpha_u" in spec \
        else spec.get("alpha", 0.1)
    numbers = alpha if isinstance(alpha, tuple) else (alpha,)
    if not all(isinstance(a, (int, float)) for a in numbers) or "material" in spec:
        return None
    params = {"distribution": spec.get("distribution", "beckmann")}
    if spec["type"] == "roughconductor":
        eta, k, diffuse = color(spec.get("eta"), 0.0), color(spec.get("k"), 1.0), np.zeros(1)
        params.update(shadowing="smith", fresnel="exact")
    else:
        params.update(shadowing=spec.get("shadowing", "vcavity"),
                      fresnel=spec.get("fresnel", "exact"))
        if "eta" not in spec and params["fresnel"] != "none":
            return None  # the default material, copper
        eta, k = color(spec.get("eta"), 1.5), color(spec.get("k"), 0.0)
        diffuse = color(spec.get("diffuse_reflectance"), 0.0)
    specular = color(spec.get("specular_reflectance"), 1.0)
    if any(x is None for x in (eta, k, specular, diffuse)):
        return None
    model = CookTorrance(alpha, eta=eta, k=k, specular=specular, diffuse=diffuse, **params)
    return Compensated(model) if spec.get("multiscatter") else model
