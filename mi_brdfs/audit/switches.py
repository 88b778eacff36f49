"""
The switches of Mitsuba's built-in BSDFs: every parameter whose value selects a code path of the
plugin (a boolean such as ``sample_visible``, a distribution, a lobe that exists only when its
weight is not zero, a parameter read only when given), as Mitsuba 3.9.1's ``src/bsdfs/*.cpp``
branch on them, with the state each audit configuration puts it in.

:func:`coverage` reads the states off the grid's configurations (:mod:`.grid`), so the report's
coverage tables (:mod:`.report`) say what the audit really ran: for each switch, the
configurations in each of its states, or why the grid leaves it at its default. A switch without
such a reason must be exercised in every state (``tests/audit``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

#: Why the grid keeps a texture-valued parameter constant: the plugin reads it through
#: ``Texture::eval`` at the interaction, the same call for a bitmap as for a constant.
TEXTURE = ("read through Texture::eval like a constant (the same code for a texture; diffuse, "
           "blendbsdf and mask run a textured case)")


@dataclass(frozen=True)
class Switch:
    """One parameter that selects a code path, and how to read its state off a spec."""

    name: str                       # the parameter(s), as in XML
    selects: str                    # the code it selects, in a few words
    states: tuple                   # every state it has, the default first
    state: Callable[[dict], str]    # the state a configuration's spec puts it in
    default_only: str | None = None  # why the grid leaves it at its default (None: varied)
    menu: tuple = ()                # the values a scene gives it, where it is one option


def boolean(name: str, default: bool, selects: str, why: str | None = None) -> Switch:
    def state(spec):
        return str(bool(spec.get(name, default))).lower()
    return Switch(name, selects, (str(default).lower(), str(not default).lower()), state, why,
                  (default, not default))


def choice(name: str, options: tuple, selects: str, why: str | None = None) -> Switch:
    return Switch(name, selects, options, lambda spec: str(spec.get(name, options[0])), why,
                  options)


def nonzero(name: str, selects: str, why: str | None = None) -> Switch:
    """A weight that is 0 by default, whose lobe or term exists only when it is given ≠ 0."""
    def state(spec):
        return "> 0" if name in spec and spec[name] != 0 else "0"
    return Switch(name, selects, ("0", "> 0"), state, why)


def given(name: str, selects: str, why: str | None = None) -> Switch:
    """A parameter the plugin reads (and multiplies in) only when the spec gives it."""
    return Switch(name, selects, ("absent", "given"),
                  lambda spec: "given" if name in spec else "absent", why)


def textured(name: str, why: str | None = TEXTURE) -> Switch:
    def state(spec):
        value = spec.get(name)
        return "texture" if isinstance(value, dict) and value.get("type") not in (
            "rgb", "spectrum", "uniform") else "constant"
    return Switch(name, "a spatially varying value", ("constant", "texture"), state, why)


def _anisotropic(spec) -> str:
    return "αu, αv" if "alpha_u" in spec else "α"


ANISOTROPIC = Switch("alpha_u/alpha_v", "an anisotropic distribution (Anisotropic flag)",
                     ("α", "αu, αv"), _anisotropic)
DISTRIBUTION = choice("distribution", ("beckmann", "ggx"), "the microfacet distribution")
VISIBLE = boolean("sample_visible", True, "visible-normal sampling vs. D·cosθm (with the "
                  "widened α in roughdielectric)")


def _nested(spec) -> str:
    return "two BSDFs" if sum(isinstance(v, dict) for v in spec.values()) > 1 else "one BSDF"


def _frame_switches() -> tuple:
    return (boolean("flip_invalid_normals", True, "mirroring a perturbed normal that faces "
                    "away from wi"),
            boolean("use_shadowing_function", True, "the shadowing term of Conty Estevez et "
                    "al. 2019"))


_REFLECTANCE = given("specular_reflectance", "a factor on the specular reflection")
_TRANSMITTANCE = given("specular_transmittance", "a factor on the specular transmission")
_ETA_K = Switch("eta/k or material", "complex IOR from η, k (default η = 0, k = 1) vs. a named "
                "material's tables", ("η, k", "material"),
                lambda spec: "material" if "material" in spec else "η, k")


def principled_switches(thin: bool) -> tuple:
    """principled's and principledthin's lobe flags (``get_flag``: given and not 0)."""
    out = [nonzero(n, what) for n, what in (
        ("anisotropic", "anisotropic GGX lobes"), ("sheen", "the sheen lobe"),
        ("sheen_tint", "the tinted sheen"), ("spec_tint", "the tinted specular Fresnel"),
        ("flatness", "the fake-subsurface diffuse"),
        ("spec_trans", "the specular transmission lobe" + (" and the specular reflection "
                                                           "lobe" if thin else "")))]
    if thin:
        out.append(nonzero("diff_trans", "the diffuse transmission lobe"))
    else:
        out += [nonzero("metallic", "the metallic weighting of the lobes"),
                nonzero("clearcoat", "the clearcoat lobe")]
    out.append(textured("roughness"))
    if not thin:
        out.append(given("eta", "η given instead of derived from specular",
                         "a parameterisation: eval and sample use the resulting η either way"))
    return tuple(out)


#: plugin → its switches (Mitsuba 3.9.1). Plugins without switches map to ().
SWITCHES: dict[str, tuple] = {
    "diffuse": (textured("reflectance", None),),
    "conductor": (_ETA_K, textured("specular_reflectance")),
    "roughconductor": (DISTRIBUTION, VISIBLE, ANISOTROPIC, _ETA_K, _REFLECTANCE,
                       textured("alpha")),
    "dielectric": (_REFLECTANCE, _TRANSMITTANCE),
    "thindielectric": (_REFLECTANCE, _TRANSMITTANCE),
    "roughdielectric": (DISTRIBUTION, VISIBLE, ANISOTROPIC, _REFLECTANCE, _TRANSMITTANCE,
                        textured("alpha")),
    "plastic": (boolean("nonlinear", False, "the nonlinear internal-scattering term"),
                _REFLECTANCE, textured("diffuse_reflectance")),
    "roughplastic": (DISTRIBUTION, VISIBLE,
                     boolean("nonlinear", False, "the nonlinear internal-scattering term"),
                     _REFLECTANCE, textured("diffuse_reflectance")),
    "principled": principled_switches(thin=False),
    "principledthin": principled_switches(thin=True),
    "hair": (Switch("sigma_a or melanin", "absorption from σa instead of the pigments' "
                    "concentrations", ("melanin", "sigma_a"),
                    lambda spec: "sigma_a" if "sigma_a" in spec else "melanin"),),
    "blendbsdf": (textured("weight", None),),
    "twosided": (Switch("nested BSDFs", "the back side's own BSDF (a second branch of every "
                        "method)", ("one BSDF", "two BSDFs"), _nested),
                 boolean("allow_transmission", False, "accepting a transmissive nested BSDF",
                         "only lifts the constructor's refusal of transmissive nested BSDFs; "
                         "the methods run the same code")),
    "mask": (textured("opacity", None),),
    "bumpmap": _frame_switches(),
    "normalmap": _frame_switches(),
    "null": (),
    "pplastic": (DISTRIBUTION, VISIBLE, ANISOTROPIC, _REFLECTANCE,
                 textured("diffuse_reflectance")),
    "polarizer": (boolean("polarizing", True, "a linear polarizer vs. plain attenuation"),),
    "retarder": (),
    "circular": (boolean("left_handed", False, "the left- vs. right-handed circular "
                         "polarizer"),),
}


@dataclass
class Row:
    """One switch of one plugin in the grid: its configurations per state."""

    switch: Switch
    configs: dict                  # state -> [configuration labels]

    @property
    def missing(self) -> list:
        """The states no configuration exercises."""
        return [s for s in self.switch.states if not self.configs.get(s)]


def coverage(cases) -> dict[str, list[Row]]:
    """plugin → one :class:`Row` per switch, for the plugins of ``cases`` that have an entry in
    :data:`SWITCHES`, in the order the cases first name them."""
    out: dict[str, list[Row]] = {}
    for case in cases:
        if case.bsdf not in SWITCHES:
            continue
        rows = out.setdefault(case.bsdf, [Row(sw, {}) for sw in SWITCHES[case.bsdf]])
        spec = case.dict()
        for row in rows:
            row.configs.setdefault(row.switch.state(spec), []).append(case.config)
    return out


def unexercised(cases) -> list[str]:
    """'plugin: switch (state)' for each state of a switch with no reason to stay at its
    default that no configuration exercises."""
    return [f"{plugin}: {row.switch.name} ({state})"
            for plugin, rows in coverage(cases).items() for row in rows
            if row.switch.default_only is None for state in row.missing]
