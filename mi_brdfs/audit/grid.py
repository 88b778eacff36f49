"""
What the audit runs: every BSDF plugin of the installed Mitsuba that can be built standalone, and
the package's own, each over a small grid of configurations (defaults, rough and smooth, GGX and
Beckmann, both samplers, anisotropic, textured where it matters, nested in wrappers).

A configuration is a ``mi.load_dict`` dict, built in the variant that runs it (textures and
bitmaps are made there). Polarized BSDFs run in a polarized variant (:data:`POLARIZED_VARIANT`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: The variant of the polarized BSDFs in an ``llvm_*`` audit (the audit's own variant for the
#: others); a ``cuda_*`` audit runs them in ``cuda_ad_spectral_polarized``.
POLARIZED_VARIANT = "llvm_ad_spectral_polarized"


def polarized_variant(variant: str) -> str:
    """The polarized variant of the audit's backend (``llvm`` or ``cuda``)."""
    return variant.split("_", 1)[0] + POLARIZED_VARIANT[len("llvm"):]


@dataclass(frozen=True)
class Case:
    """One BSDF configuration of the audit."""

    bsdf: str                # the plugin name as in XML (of the outermost BSDF)
    config: str              # a short label, unique per bsdf ("default", "ggx α=0.05", ...)
    spec: tuple              # the load_dict dict, as sorted items (hashable); see :meth:`dict`
    polarized: bool = False  # run in POLARIZED_VARIANT
    quick: bool = False      # part of `mi-brdfs audit --quick`
    tags: tuple = field(default=())

    @property
    def key(self) -> str:
        return f"{self.bsdf} | {self.config}"

    def dict(self) -> dict:
        return _thaw(self.spec)


def _freeze(value):
    if isinstance(value, dict):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, list):
        return ("__list__", tuple(_freeze(v) for v in value))
    return value


def _thaw(value):
    if isinstance(value, tuple) and value and value[0] == "__list__":
        return [_thaw(v) for v in value[1]]
    if isinstance(value, tuple):
        return {k: _thaw(v) for k, v in value}
    return value


def case(bsdf: str, config: str, spec: dict, **kw) -> Case:
    return Case(bsdf, config, _freeze(spec), **kw)


def _checker(a=0.2, b=0.8) -> dict:
    """A checkerboard texture (spatially varying: the uv of the check's interactions matter)."""
    return {"type": "checkerboard", "color0": {"type": "rgb", "value": [a] * 3},
            "color1": {"type": "rgb", "value": [b] * 3}}


def _normal_map() -> dict:
    """A small bitmap of tilted normals, encoded as normalmap expects (n·0.5 + 0.5)."""
    return {"type": "bitmap", "raw": True, "filter_type": "bilinear",
            "bitmap": "__normal_map__"}


def _height_map() -> dict:
    return {"type": "bitmap", "raw": True, "filter_type": "bilinear", "bitmap": "__height_map__"}


RC = {"type": "roughconductor"}
RD = {"type": "roughdielectric"}
#: The optional factors of the dielectrics, read (and multiplied in) only when given.
_FACTORS = {"specular_reflectance": 0.8, "specular_transmittance": 0.6}
SPECULAR_FACTORS = "specular_reflectance=0.8 specular_transmittance=0.6"
#: The frame wrappers with both of their corrections switched off.
_NO_FIXES = {"flip_invalid_normals": False, "use_shadowing_function": False}
NO_FRAME_FIXES = "flip_invalid_normals=false use_shadowing_function=false"


def mitsuba_cases() -> list[Case]:
    """The grid of Mitsuba's built-in BSDFs (their switches: :mod:`.switches`)."""
    return _reflectors() + _layered() + _wrappers() + _polarized()


def _reflectors() -> list[Case]:
    """diffuse, the conductors and the dielectrics."""
    c = []
    c += [case("diffuse", "default", {"type": "diffuse"}, quick=True),
          case("diffuse", "textured reflectance", {"type": "diffuse", "reflectance": _checker()})]
    c += [case("conductor", "default (η = 0, k = 1)", {"type": "conductor"}),
          case("conductor", "Au", {"type": "conductor", "material": "Au"})]
    for dist in ("beckmann", "ggx"):
        for a in (0.05, 0.3):
            c.append(case("roughconductor", f"{dist} α={a} Au",
                          dict(RC, distribution=dist, alpha=a, material="Au")))
        c.append(case("roughconductor", f"{dist} α=0.3 sample_visible=false",
                      dict(RC, distribution=dist, alpha=0.3, sample_visible=False)))
        c.append(case("roughconductor", f"{dist} αu=0.05 αv=0.3",
                      dict(RC, distribution=dist, alpha_u=0.05, alpha_v=0.3)))
    c.append(case("roughconductor", "ggx α=0.3 specular_reflectance=0.5",
                  dict(RC, distribution="ggx", alpha=0.3, specular_reflectance=0.5)))
    c += [case("dielectric", "default (bk7/air)", {"type": "dielectric"}),
          case("dielectric", "water", {"type": "dielectric", "int_ior": "water"}),
          case("dielectric", SPECULAR_FACTORS, dict({"type": "dielectric"}, **_FACTORS))]
    c += [case("thindielectric", "default", {"type": "thindielectric"}),
          case("thindielectric", SPECULAR_FACTORS, dict({"type": "thindielectric"}, **_FACTORS))]
    for dist in ("beckmann", "ggx"):
        for a in (0.05, 0.3):
            c.append(case("roughdielectric", f"{dist} α={a}",
                          dict(RD, distribution=dist, alpha=a)))
        c.append(case("roughdielectric", f"{dist} α=0.3 sample_visible=false",
                      dict(RD, distribution=dist, alpha=0.3, sample_visible=False)))
        c.append(case("roughdielectric", f"{dist} αu=0.05 αv=0.3",
                      dict(RD, distribution=dist, alpha_u=0.05, alpha_v=0.3)))
    c.append(case("roughdielectric", "ggx α=0.3 " + SPECULAR_FACTORS,
                  dict(RD, distribution="ggx", alpha=0.3, **_FACTORS)))
    return c


def _layered() -> list[Case]:
    """plastic, roughplastic, principled, principledthin and hair."""
    c = []
    c += [case("plastic", "default", {"type": "plastic"}),
          case("plastic", "nonlinear", {"type": "plastic", "nonlinear": True}),
          case("plastic", "specular_reflectance=0.5",
               {"type": "plastic", "specular_reflectance": 0.5})]
    c += [case("roughplastic", "default (beckmann α=0.1)", {"type": "roughplastic"}),
          case("roughplastic", "ggx α=0.5", {"type": "roughplastic", "distribution": "ggx",
                                            "alpha": 0.5}, quick=True),
          case("roughplastic", "beckmann α=0.3 nonlinear",
               {"type": "roughplastic", "alpha": 0.3, "nonlinear": True}),
          case("roughplastic", "ggx α=0.5 sample_visible=false specular_reflectance=0.5",
               {"type": "roughplastic", "distribution": "ggx", "alpha": 0.5,
                "sample_visible": False, "specular_reflectance": 0.5})]
    c += [case("principled", "default", {"type": "principled"}),
          case("principled", "roughness=0.1", {"type": "principled", "roughness": 0.1},
               quick=True),
          case("principled", "metallic=1 roughness=0.3",
               {"type": "principled", "metallic": 1.0, "roughness": 0.3}),
          case("principled", "anisotropic=0.8", {"type": "principled", "anisotropic": 0.8}),
          case("principled", "clearcoat=1 sheen=1",
               {"type": "principled", "clearcoat": 1.0, "sheen": 1.0}),
          case("principled", "spec_trans=0.7 roughness=0.3",
               {"type": "principled", "spec_trans": 0.7, "roughness": 0.3}),
          case("principled", "flatness=0.5 sheen=1 sheen_tint=0.5 spec_tint=0.5",
               {"type": "principled", "flatness": 0.5, "sheen": 1.0, "sheen_tint": 0.5,
                "spec_tint": 0.5})]
    c += [case("principledthin", "default", {"type": "principledthin"}),
          case("principledthin", "roughness=0.1 diff_trans=0.5",
               {"type": "principledthin", "roughness": 0.1, "diff_trans": 0.5}),
          case("principledthin", "spec_trans=0.6 roughness=0.3",
               {"type": "principledthin", "spec_trans": 0.6, "roughness": 0.3}),
          case("principledthin", "spec_trans=0.4 anisotropic=0.5 spec_tint=0.5 flatness=0.5 "
               "sheen=1 sheen_tint=0.5",
               {"type": "principledthin", "spec_trans": 0.4, "anisotropic": 0.5,
                "spec_tint": 0.5, "flatness": 0.5, "sheen": 1.0, "sheen_tint": 0.5})]
    c += [case("hair", "default", {"type": "hair"}),
          case("hair", "sigma_a (no pigmentation)",
               {"type": "hair", "sigma_a": {"type": "rgb", "value": [0.8, 1.0, 1.4]}})]
    return c


def _wrappers() -> list[Case]:
    """BSDFs that wrap others: blendbsdf, twosided, mask, bumpmap, normalmap; and null."""
    c = []
    c += [case("blendbsdf", "diffuse + roughconductor, weight 0.3",
               {"type": "blendbsdf", "weight": 0.3, "a": {"type": "diffuse"},
                "b": dict(RC, alpha=0.2)}),
          case("blendbsdf", "textured weight", {"type": "blendbsdf", "weight": _checker(),
                                                "a": {"type": "diffuse"},
                                                "b": {"type": "conductor"}})]
    c += [case("twosided", "diffuse", {"type": "twosided", "bsdf": {"type": "diffuse"}}),
          case("twosided", "roughconductor α=0.3",
               {"type": "twosided", "bsdf": dict(RC, alpha=0.3)}),
          case("twosided", "diffuse + roughconductor α=0.3",
               {"type": "twosided", "a": {"type": "diffuse"}, "b": dict(RC, alpha=0.3)},
               quick=True)]
    c += [case("mask", "opacity 0.4 on diffuse",
               {"type": "mask", "opacity": 0.4, "bsdf": {"type": "diffuse"}}),
          case("mask", "textured opacity on diffuse",
               {"type": "mask", "opacity": _checker(), "bsdf": {"type": "diffuse"}})]
    c += [case("bumpmap", "on roughconductor α=0.3",
               {"type": "bumpmap", "texture": _height_map(), "scale": 0.5,
                "bsdf": dict(RC, alpha=0.3)}),
          case("bumpmap", "on roughconductor α=0.3, " + NO_FRAME_FIXES,
               {"type": "bumpmap", "texture": _height_map(), "scale": 0.5,
                "bsdf": dict(RC, alpha=0.3), **_NO_FIXES}),
          case("normalmap", "on diffuse", {"type": "normalmap", "normalmap": _normal_map(),
                                           "bsdf": {"type": "diffuse"}}),
          case("normalmap", "on diffuse, " + NO_FRAME_FIXES,
               {"type": "normalmap", "normalmap": _normal_map(), "bsdf": {"type": "diffuse"},
                **_NO_FIXES}),
          case("normalmap", "on roughconductor αu=0.05 αv=0.3 (upstream's)",
               {"type": "normalmap", "normalmap": _normal_map(),
                "bsdf": dict(RC, alpha_u=0.05, alpha_v=0.3)})]
    c += [case("null", "default", {"type": "null"})]
    return c


def _polarized() -> list[Case]:
    """The BSDFs that run in the polarized variant."""
    c = []
    c += [case("pplastic", "default", {"type": "pplastic"}, polarized=True),
          case("pplastic", "ggx αu=0.05 αv=0.3 sample_visible=false specular_reflectance=0.5",
               {"type": "pplastic", "distribution": "ggx", "alpha_u": 0.05, "alpha_v": 0.3,
                "sample_visible": False, "specular_reflectance": 0.5}, polarized=True),
          case("polarizer", "default", {"type": "polarizer"}, polarized=True),
          case("polarizer", "polarizing=false", {"type": "polarizer", "polarizing": False},
               polarized=True),
          case("retarder", "default", {"type": "retarder"}, polarized=True),
          case("circular", "default", {"type": "circular"}, polarized=True),
          case("circular", "left_handed", {"type": "circular", "left_handed": True},
               polarized=True),
          case("roughconductor", "ggx α=0.3 (polarized variant)",
               dict(RC, distribution="ggx", alpha=0.3), polarized=True),
          case("roughdielectric", "ggx α=0.3 (polarized variant)",
               dict(RD, distribution="ggx", alpha=0.3), polarized=True)]
    return c


def package_cases() -> list[Case]:
    """The package's own plugins."""
    ct = {"type": "cooktorrance"}
    return [
        case("lambert", "default", {"type": "lambert"}, quick=True),
        case("phong", "lecture", {"type": "phong", "form": "lecture"}),
        case("phong", "normalized, halfway", {"type": "phong", "form": "normalized",
                                              "lobe": "halfway"}),
        case("phong", "original (not reciprocal)", {"type": "phong", "form": "original"}),
        case("cooktorrance", "default (V-cavity, Cu)", ct),
        case("cooktorrance", "smith ggx α=0.3", dict(ct, shadowing="smith",
                                                     distribution="ggx", alpha=0.3)),
        case("cooktorrance", "αu=0.05 αv=0.3 smith", dict(ct, shadowing="smith", alpha_u=0.05,
                                                          alpha_v=0.3)),
        case("cooktorrance", "diffuse base", dict(ct, diffuse_reflectance=0.5)),
        case("cooktorrance", "transmission α=0.3", dict(ct, transmission=True, alpha=0.3)),
        case("cooktorrance", "smith ggx α=0.3 (polarized variant)",
             dict(ct, shadowing="smith", distribution="ggx", alpha=0.3, material="Au"),
             polarized=True),
        case("ward", "default (balanced)", {"type": "ward"}),
        case("ward", "original αu=0.1 αv=0.4", {"type": "ward", "form": "original",
                                                "alpha_u": 0.1, "alpha_v": 0.4}),
        case("orennayar", "full σ=0.5", {"type": "orennayar", "form": "full", "sigma": 0.5}),
        case("ashikhmin", "default (n = 100)", {"type": "ashikhmin"}),
        case("ashikhmin", "nu=10 nv=1000", {"type": "ashikhmin", "nu": 10.0, "nv": 1000.0}),
        case("lafortune", "default (one mirror lobe)", {"type": "lafortune"}),
        case("lafortune", "three lobes: mirror, off-specular, retro",
             {"type": "lafortune", "diffuse_reflectance": 0.2,
              "cx_0": -1.0, "cy_0": -1.0, "cz_0": 1.0, "exponent_0": 30.0,
              "specular_reflectance_0": 0.3, "cx_1": -1.0, "cy_1": -1.0, "cz_1": 0.8,
              "exponent_1": 10.0, "specular_reflectance_1": 0.2, "cx_2": 1.0, "cy_2": 1.0,
              "cz_2": 1.0, "exponent_2": 5.0, "specular_reflectance_2": 0.2}),
    ]


def all_cases() -> list[Case]:
    return mitsuba_cases() + package_cases()


#: The sea surface's parameters for the three ocean plugins of Eradiate's fork: a moderate wind
#: (5 m/s) and the wavelength (nm) that ocean_legacy and ocean_grasp need.
_OCEAN = {"wind_speed": 5.0}


def eradiate_cases() -> list[Case]:
    """The BSDF plugins Eradiate adds to its Mitsuba fork (``eradiate-mitsuba``,
    https://github.com/eradiate/mitsuba3, src/eradiate_plugins/bsdfs): the defaults, and
    the configurations where a model is known to leave its range (RTLS below zero, RPV with
    k < 1 at grazing incidence, Hapke's opposition peak)."""
    hapke = {"type": "hapke", "w": 0.5, "b": 0.3, "c": 0.5, "theta": 20.0, "B_0": 0.5,
             "h": 0.2}
    return [
        case("rtls", "default (f_iso 0.21, f_vol 0.081, f_geo 0.0041)", {"type": "rtls"}),
        case("rtls", "f_iso=0.1 f_vol=0.05 f_geo=0.05",
             {"type": "rtls", "f_iso": 0.1, "f_vol": 0.05, "f_geo": 0.05}),
        case("rpv", "default (rho_0=0.1 k=0.1 g=0)", {"type": "rpv"}),
        case("rpv", "rho_0=0.2 k=0.8 g=-0.2 rho_c=0.3",
             {"type": "rpv", "rho_0": 0.2, "k": 0.8, "g": -0.2, "rho_c": 0.3}),
        case("rpv", "rho_0=0.2 k=1.2 g=0.1", {"type": "rpv", "rho_0": 0.2, "k": 1.2,
                                             "g": 0.1}),
        case("hapke", "default (w=0.5 b=0.2 c=0.5 θ=30° B_0=0 h=0)", {"type": "hapke"}),
        case("hapke", "w=0.5 b=0.3 c=0.5 θ=20° B_0=0.5 h=0.2", hapke),
        case("hapke", "w=0.99 B_0=1 h=0.05", dict(hapke, w=0.99, B_0=1.0, h=0.05)),
        case("ocean_mishchenko", "default (wind 0.1 m/s)", {"type": "ocean_mishchenko"}),
        case("ocean_mishchenko", "wind 5 m/s", dict({"type": "ocean_mishchenko"}, **_OCEAN)),
        case("ocean_legacy", "λ=550 nm (default wind 0.1 m/s)",
             {"type": "ocean_legacy", "wavelength": 550.0}),
        case("ocean_legacy", "λ=550 nm wind 5 m/s",
             dict({"type": "ocean_legacy", "wavelength": 550.0}, **_OCEAN)),
        case("ocean_grasp", "λ=550 nm (default wind 0.1 m/s)",
             {"type": "ocean_grasp", "wavelength": 550.0}),
        case("ocean_grasp", "λ=550 nm wind 5 m/s",
             dict({"type": "ocean_grasp", "wavelength": 550.0}, **_OCEAN)),
        case("bilambertian", "default (0.5 / 0.5)", {"type": "bilambertian"}),
        case("bilambertian", "reflectance=0.7 transmittance=0.2",
             {"type": "bilambertian", "reflectance": 0.7, "transmittance": 0.2}),
        case("maignan", "default (C=0.1 ndvi=0)", {"type": "maignan"}),
        case("maignan", "C=5 ndvi=0.6", {"type": "maignan", "C": 5.0, "ndvi": 0.6}),
        case("selectbsdf", "indices=1 of diffuse, roughconductor α=0.3",
             {"type": "selectbsdf", "indices": 1.0, "a": {"type": "diffuse"},
              "b": dict(RC, alpha=0.3)}),
    ]


#: Eradiate's BSDF plugins that the audit lists but cannot build standalone, and why.
SKIPPED_ERADIATE = {
    "mqdiffuse": "needs a gridded measured BRDF (its `filename`); none ships with the fork",
    "measured_mono": "needs an RGL material file, like `measured`; none ships with the fork",
}

#: Per Mitsuba build (the distribution that installed ``mitsuba``,
#: :func:`mi_brdfs.registry.mitsuba_build`): what the audit runs there. Under a fork the
#: package's own plugins are left out (their audit is Mitsuba's; under the fork a plugin of
#: the fork's may stand in the place of one of ours, :func:`mi_brdfs.registry.own_plugins`).
BUILDS = {"eradiate-mitsuba": eradiate_cases}


def cases_for(build: str) -> list[Case]:
    """The configurations the audit runs under ``build``."""
    if build in BUILDS:
        return mitsuba_cases() + BUILDS[build]()
    return all_cases()


def skipped_for(build: str) -> dict:
    """The plugins of ``build`` the audit cannot build standalone, and why."""
    return dict(SKIPPED, **(SKIPPED_ERADIATE if build in BUILDS else {}))


#: BSDF plugins of Mitsuba 3 that the audit lists but cannot build standalone, and why.
SKIPPED = {
    "measured": "needs an RGL material file (https://rgl.epfl.ch/materials); none ships with "
                "Mitsuba or this package",
    "measured_polarized": "needs a measured pBRDF file (Baek et al. 2020); none ships",
}
