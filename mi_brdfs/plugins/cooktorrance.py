"""
The textbook Cook-Torrance BRDF (Beckmann D, V-cavity G, exact Fresnel), with the switches that
make it comparable to Mitsuba's built-ins: GGX, Smith's masking as Mitsuba computes it, Schlick's
Fresnel, visible-normal sampling and the paper's diffuse base.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..scattering import microfacet, multiscatter
from ..scattering.fresnel import IOR_MAX
from . import cooktorrance_film, lobes, properties
from .cooktorrance_conductor import Compensation, MicrofacetReflection
from .cooktorrance_dielectric import InterfaceCompensation, MicrofacetInterface
from ..materials import conductor_ior, conductor_names, dielectric_ior, material_ior  # noqa: F401

PLUGIN = "cooktorrance"
SHADOWING = ("vcavity", "smith")
FRESNEL = ("exact", "schlick", "none")

#: The named conductor used when neither ``material`` nor ``eta`` is given: copper, the metal
#: of Cook & Torrance's own figures (and Mitsuba 0.6's conductor default).
DEFAULT_MATERIAL = "Cu"



_REFRACTION_ONLY = "is a parameter of the refraction lobe: give transmission = true as well"
_DIELECTRIC_ONLY = "with transmission = true: only a dielectric transmits"

#: What excludes what, one line each: (the setting, the parameter it refuses, why). A setting
#: is ``transmission`` or ``reflection`` (transmission = true or false), a parameter given
#: (``eta``, ``k``), or ``!eta``: no eta, without transmission (which reads int_ior and
#: ext_ior instead). Checked in order: the first that applies is the error.
EXCLUSIONS = (
    ("transmission", "material", "must not be given with transmission = true: names a "
                                 "conductor; transmission needs a dielectric (give eta, or "
                                 "int_ior and ext_ior)"),
    ("transmission", "diffuse_reflectance", "must not be given with transmission = true: a "
                                            "diffuse base under a transmitting interface is not "
                                            "part of the model (Walter et al. 2007)"),
    ("reflection", "specular_transmittance", _REFRACTION_ONLY),
    ("reflection", "int_ior", _REFRACTION_ONLY),
    ("reflection", "ext_ior", _REFRACTION_ONLY),
    ("eta", "int_ior", "must not be given together with eta (eta is int_ior/ext_ior)"),
    ("eta", "ext_ior", "must not be given together with eta (eta is int_ior/ext_ior)"),
    ("eta", "material", "must not be given together with eta or k (it sets both)"),
    ("k", "material", "must not be given together with eta or k (it sets both)"),
    ("!eta", "k", "needs eta as well (or a material instead of both)"),
)

#: The switches ``transmission`` needs: parameter -> (the value, why).
WITH_TRANSMISSION = {
    "shadowing": ("smith", "the V-cavity masking (Cook & Torrance 1982) is derived for light "
                           "above the surface, and gives no masking for a refracted pair"),
    "fresnel": ("exact", "the refracted fraction is 1 − F, with total internal reflection"),
}


def _check_exclusions(props, transmission: bool) -> None:
    """:data:`EXCLUSIONS` and, with ``transmission``, :data:`WITH_TRANSMISSION` and k = 0."""
    settings = {"transmission": transmission, "reflection": not transmission,
                "eta": "eta" in props, "k": "k" in props,
                "!eta": "eta" not in props and not transmission}
    for setting, name, why in EXCLUSIONS:
        if settings[setting]:
            properties.reject(props, PLUGIN, name, why)
    if not transmission:
        return
    for name, (value, why) in WITH_TRANSMISSION.items():
        if name in props and props[name] != value:
            raise ParameterError(PLUGIN, name, props[name],
                                 f"must be \"{value}\" with transmission = true: {why}")
    if "k" in props and not (props.type("k") in (mi.Properties.Type.Float,
                                                 mi.Properties.Type.Integer)
                             and float(props["k"]) == 0.0):
        raise ParameterError(PLUGIN, "k", props["k"], "must be 0 (or absent) " + _DIELECTRIC_ONLY)


def _read_dielectric(props) -> float:
    """
    The relative index η = η_int/η_ext of ``transmission``: ``eta`` (a number ≠ 1) or
    ``int_ior``/``ext_ior`` (numbers or names, as ``roughdielectric`` takes them; defaults
    ``bk7`` inside and ``air`` outside).
    """
    if "eta" in props:
        eta, where = _dielectric_eta(props), "eta"
    else:
        inside = dielectric_ior(props["int_ior"] if "int_ior" in props else "bk7", PLUGIN,
                                "int_ior")
        outside = dielectric_ior(props["ext_ior"] if "ext_ior" in props else "air", PLUGIN,
                                 "ext_ior")
        # divided in float32, as roughdielectric divides them
        eta, where = float(np.float32(inside) / np.float32(outside)), "int_ior"
    if eta == 1.0:
        raise ParameterError(PLUGIN, where, props[where] if where in props else eta,
                             "must make the relative index int_ior/ext_ior differ from 1 (an "
                             "index-matched interface does not scatter)")
    if not 1.0 / IOR_MAX <= eta <= IOR_MAX:
        raise ParameterError(PLUGIN, where, props[where] if where in props else eta,
                             f"must make the relative index int_ior/ext_ior lie within "
                             f"[{1.0 / IOR_MAX:g}, {IOR_MAX:g}]")
    return eta


def _dielectric_eta(props) -> float:
    """``eta`` with transmission: a number, or a uniform ``<spectrum>`` (one value: refraction
    bends every wavelength alike in this model, so a dispersive η is refused)."""
    if props.type("eta") != mi.Properties.Type.Spectrum:
        return properties.number(props, PLUGIN, "eta", 1.5, lo=0.0, hi=IOR_MAX, lo_open=True)
    tex = properties.texture(props, PLUGIN, "eta", 1.5, lo=0.0, hi=IOR_MAX, lo_open=True)
    rng = properties.texture_range(tex)
    if rng is None or rng[0] != rng[1]:
        raise ParameterError(PLUGIN, "eta", props["eta"],
                             "must be one number with transmission = true: refraction bends "
                             "every wavelength alike in this model (no dispersion)")
    return rng[0]


def _read_ior(props, needed: bool):
    """
    ``(eta, k, material)`` from ``material`` or ``eta``/``k`` (see the class docstring); all
    None when the Fresnel term is off (``needed`` false) and none of them is given.
    """
    if not needed and "material" not in props and "eta" not in props:
        return None, None, None
    return properties.ior(props, PLUGIN, DEFAULT_MATERIAL)


GLOSSY_FLAGS = lobes.flag("GlossyReflection", "FrontSide")
ANISOTROPIC = lobes.flag("Anisotropic")
REFLECTION_FLAGS = lobes.flag("GlossyReflection", "FrontSide", "BackSide")
TRANSMISSION_FLAGS = lobes.flag("GlossyTransmission", "FrontSide", "BackSide", "NonSymmetric")
DIFFERENTIABLE = mi.ParamFlags.Differentiable
DISCONTINUOUS = mi.ParamFlags.Differentiable | mi.ParamFlags.Discontinuous


class CookTorrance(mi.BSDF):
    r"""
    .. _bsdf-cooktorrance:

    Cook-Torrance microfacet reflectance (:monosp:`cooktorrance`)
    -------------------------------------------------------------

    .. pluginparameters::

     * - alpha, alpha_u, alpha_v
       - |float| or |texture|
       - Roughness α: for Beckmann the RMS slope of the microfacets, Cook & Torrance's *m*
         (the same quantity as ``roughconductor``'s ``alpha``), finite and ≥ 0; values below
         10⁻⁴ are clamped to 10⁻⁴, as Mitsuba does. ``alpha_u`` and ``alpha_v`` (both, and
         not with ``alpha``) make it anisotropic: α along the tangent and the bitangent of the
         surface (Default: ``alpha`` = 0.1)
       - |exposed|, |differentiable|, |discontinuous|

     * - distribution
       - |string|
       - Microfacet distribution D: ``beckmann`` (Cook & Torrance 1982) or ``ggx``
         (Default: ``beckmann``)

     * - shadowing
       - |string|
       - Masking-shadowing G: ``vcavity`` (Cook & Torrance 1982:
         min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·L)/(V·H))) or ``smith`` (separable Smith
         G1(ωi)·G1(ωo) exactly as Mitsuba's microfacet code computes it, so that the plugin
         reproduces ``roughconductor``) (Default: ``vcavity``)

     * - material
       - |string|
       - A measured conductor of Mitsuba's IOR data, the names and data of ``conductor`` and
         ``roughconductor`` (``Au``, ``Ag``, ``Al``, ``Cu``, ``Cr``, ...), or ``none``, their
         perfect conductor (η = 0, k = 1: F ≡ 1). Exclusive with ``eta``/``k``
         (Default: ``Cu`` when ``eta`` is not given either)

     * - eta, k
       - |spectrum| or |texture|
       - Relative index of refraction η + ik, each within [0, 10⁶] (float32 overflows in
         the Fresnel terms beyond about 10⁹); k = 0 is a dielectric (η > 0 then), η = 0
         with k = 1 a perfect mirror. ``k`` needs ``eta`` and defaults to
         0 with it (``roughconductor``: 1). With ``transmission``, η is one number (a float
         or a uniform spectrum) (Default: from ``material``)
       - |exposed|, |differentiable|, |discontinuous|

     * - fresnel
       - |string|
       - Fresnel term F of η, k: ``exact`` (the full conductor/dielectric formula),
         ``schlick`` (R0 + (1 − R0)(1 − cosθ)⁵ with R0 = ((η−1)² + k²)/((η+1)² + k²)) or
         ``none`` (F ≡ 1, for white furnace tests) (Default: ``exact``)

     * - specular_reflectance
       - |spectrum| or |texture|
       - Factor on the microfacet lobe, within [0, 1]; leave it at 1 for physical
         realism (Default: 1.0)
       - |exposed|, |differentiable|

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - Albedo ρ of the paper's optional Lambertian base ρ/π, within [0, 1]. When it is
         the constant 0 there is no diffuse lobe at all (flags, sampling and cost)
         (Default: 0.0)
       - |exposed|, |differentiable| (when not 0)

     * - sample_visible
       - |bool|
       - Sample the visible microfacet normals of the chosen ``shadowing`` (Heitz & d'Eon
         2014) instead of D(m)·cosθm (Walter et al. 2007) (Default: |true|)

     * - multiscatter
       - |bool|
       - Add the energy compensation of Kulla & Conty 2017: a second, reciprocal lobe that
         gives back the light the microfacet lobe loses to bounces between microfacets, so
         that a white furnace reads 1 at every roughness and angle (F ≡ 1); coloured by
         Kulla & Conty's F_ms with a Fresnel term. With ``transmission``, their dielectric
         extension: reflection plus refraction reads 1 from either side (importance
         transport). Anisotropic surfaces use the tables of sqrt(αu·αv), an approximation
         (warned: the furnace departs from 1 both ways) (Default: |false|: single
         scattering, and no cost)

     * - transmission
       - |bool|
       - Add the refraction lobe of Walter et al. 2007: a rough dielectric interface, lit
         from either side (Default: |false|: reflection only, and no cost for refraction)

     * - int_ior, ext_ior
       - |float| or |string|
       - With ``transmission``: the interior and exterior index of refraction, numbers or
         the names ``dielectric`` takes (``bk7``, ``water``, ``air``, ...); ``eta`` instead
         gives their ratio (Default: ``bk7``, ``air``)

     * - specular_transmittance
       - |spectrum| or |texture|
       - With ``transmission``: factor on the refraction lobe, within [0, 1] (Default: 1.0)
       - |exposed|, |differentiable|

     * - film_thickness
       - |float| or |texture|
       - Thickness (nm) of a thin film over the surface, one value per point within
         [0, 10⁵] (a texture gives an oil slick's colours); with a conductor or with
         ``transmission``. Absent or 0: no film, and no cost (Default: 0)
       - |exposed|, |differentiable|

     * - film_eta
       - |float| or |texture|
       - The film's real index of refraction relative to the exterior (as ``eta`` is), within
         (0, 100]; needs ``film_thickness`` (Default: 1.33, water)
       - |exposed|, |differentiable|

     * - preset
       - |string|
       - A published fit that fills every parameter the scene does not give (explicit ones
         win): ``ngan:<material>``, Ngan et al. 2005's Cook-Torrance fit to a MERL material
         (``beckmann``, ``vcavity``, ``schlick``, a diffuse base); docs/presets.md lists the
         materials and the conversion (Default: none)
       -

    The model of the lectures, in Walter et al.'s normalisation:

    .. math::

        f(\omega_i, \omega_o) = \frac{\rho_d}{\pi} +
            k_s\,\frac{F(\omega_i\cdot h)\,D(h)\,G(\omega_i, \omega_o, h)}
                      {4\,\cos\theta_i\,\cos\theta_o},
        \qquad h = \frac{\omega_i + \omega_o}{\lVert\omega_i + \omega_o\rVert},

    with the normalised Beckmann D = exp(−tan²θh/α²)/(π α² cos⁴θh). The 1982 paper prints
    the same model as (F/π)·D'·G/((N·L)(N·V)) with D' = exp(−tan²β/m²)/(4 m² cos⁴β): the
    π moved from D into the prefactor, the 4 from the prefactor into D'. ``eval`` returns
    f·cosθo; one-sided (0 below the surface on either side), like ``roughconductor``.

    **Sampling.** A microfacet normal h is drawn from the visible normals of ωi under the
    model's own masking, pdf D·G1(ωi, h)·(ωi·h)/cosθi, or from D(h)·cosθh, and reflected;
    the pdf of ωo carries the Jacobian 1/(4 ωo·h). With ``smith`` the visible normals are
    Smith's (Mitsuba's sampler) and G1 in the pdf is Mitsuba's (Walter's rational
    approximation for Beckmann, within 0.35 % of the exact one), so that eval, pdf and the
    sample weights equal ``roughconductor``'s; with ``vcavity`` they are the V-cavity's
    (Heitz & d'Eon 2014, §5: h from D·cosθh, then one of the two facets of its V-groove
    by their projected areas), so the sample weight is F·G/G1(ωi) ≤ F. With the diffuse
    base a lobe is chosen with probabilities proportional to mean(k_s·F(cosθi)) and
    mean(ρd), and ``pdf`` is the mixture.

    **Default Fresnel.** Copper (``material`` = ``Cu``) with the exact formula: Cook and
    Torrance built the model to render metals (their figures are copper vases), a named
    metal is the physically meaningful reading of "Fresnel on", and Mitsuba 0.6's
    ``conductor`` defaulted to copper. ``roughconductor``'s own default (η = 0, k = 1) is a
    100 % mirror, i.e. F ≡ 1: ask for that with ``fresnel`` = ``none``.

    **Anisotropy.** With ``alpha_u`` ≠ ``alpha_v`` the microfacet slopes are stretched by
    αu along the surface's tangent (the local x axis, ``dp_du``) and αv along its bitangent:
    D(h) = exp(−(hx²/αu² + hy²/αv²)/hz²)/(π αu αv hz⁴) for Beckmann, and Smith's Λ takes α
    projected on the azimuth of its direction (Heitz 2014, "Understanding the
    Masking-Shadowing Function"). A brushed metal is rough across the brushing direction:
    the highlight stretches along the axis with the larger α.

    **Transmission** (``transmission`` = |true|; Walter et al. 2007, the model of
    ``roughdielectric``). η = int_ior/ext_ior is a number (refraction bends every wavelength
    alike); from inside, the relative index is 1/η. For ωo on the other side of the surface,
    with η the relative index in the direction of travel, the generalised half vector
    h = ±(ωi + η ωo)/‖ωi + η ωo‖ (turned to the normal's side) gives the refraction lobe

    .. math::

        f_t = k_t\,\frac{|\omega_i\cdot h|\,|\omega_o\cdot h|}{|\cos\theta_i|\,
              |\cos\theta_o|}\,\frac{\eta^2\,(1 - F)\,D\,G}
              {(\omega_i\cdot h + \eta\,\omega_o\cdot h)^2}\cdot\frac{1}{\eta^2}

    where the last factor, 1/η², applies in radiance transport only (Veach 1997, §5.2: the
    radiance of refracted light scales with the squared index; importance does not), and
    the reflection lobe is the model above with the dielectric F, on both sides. F is the
    exact dielectric Fresnel term with total internal reflection. Sampling draws h (visible
    normals of ωi turned to the normal's side, or D·cosθh with Walter's widened α), then
    reflects with probability F and refracts otherwise; the pdf carries F or 1 − F and the
    Jacobian η² abs(ωo·h) / (ωi·h + η ωo·h)² (Walter eq. 17). ``shadowing`` must be ``smith``
    (its default then): Smith's Λ is defined on both sides of the surface, whereas the
    V-cavity masking of Cook & Torrance 1982 is derived for light above the surface, and
    the joint masking of a refracted pair of directions is not given there. ``fresnel``
    must be ``exact``; ``material``, a ``k`` ≠ 0 and the diffuse base are rejected.

    **Limits.** α is clamped to ≥ 10⁻⁴. The microfacet normals are sampled without the
    float32 collapse of the textbook formula (see
    :meth:`mi_brdfs.scattering.microfacet.Distribution.sample`), but below α ≈ 10⁻³ the lobe is
    narrower than a χ² histogram resolves: there the plugin behaves as a smooth mirror whose
    albedo tends to F (tested). Single scattering loses energy at high α and grazing angles
    (the light that bounces between microfacets is missing: ``validation/REPORT.md`` gives
    the white-furnace albedo), unless ``multiscatter`` gives it back; the diffuse base is
    added, not coupled, so ρd + E_spec ≤ 1 is up to the user (ρd + ks > 1 warns, values
    kept).

    **Energy compensation** (``multiscatter`` = |true|; Kulla & Conty 2017, after Kelemen &
    Szirmay-Kalos 2001). A second lobe ks·F_ms·(1 − E(μi))(1 − E(μo))/(π (1 − E_avg)) adds the
    light of the bounces between microfacets, with E(μ) the albedo of the lobe above with
    F ≡ 1 at incidence cosine μ, E_avg = 2∫E(μ)μ dμ, and the Fresnel colour
    F_ms = F_avg² E_avg/(1 − F_avg (1 − E_avg)), F_avg = 2∫F(μ)μ dμ (1 with ``fresnel`` =
    ``none``, R0 + (1 − R0)/21 with ``schlick``). With F ≡ 1 the albedo is then 1 at every
    angle, up to the interpolation of E. E comes from tables that ``mi-brdfs tables`` builds
    from this lobe, per distribution and masking (64 μ × 128 α nodes, α up to 2; beyond,
    the compensation falls short); the lobe is reciprocal. It is sampled from the
    cosine-weighted hemisphere, chosen against the microfacet normals in proportion to the
    two lobes' albedos at ωi. ``validation/REPORT.md`` compares it with the true multiple
    scattering of Heitz et al. 2016.

    With ``transmission`` (Kulla & Conty's dielectric extension) E is the albedo E_R+T of
    reflection plus refraction, tabulated over μ, α and η (32 × 64 × 32 nodes, η from 1/3 to
    3; beyond, the end of the table is read and the plugin warns), lit from above at η and
    from below at 1/η. The light single scattering loses, 1 − E(μi) on ωi's side, leaves
    through a lobe shaped (1 − E'(μo))/(π (1 − E'_avg)) on ωo's side (E' that side's table):
    the share x refracted, 1 − x reflected. The shares keep the pair reciprocal across the
    interface (detailed balance: x_above (1 − E_avg,above) = η² x_below (1 − E_avg,below)),
    from the interface's average transmittance T_avg = 1 − F_avg(η) above, T_avg/η² below:
    x = T_avg·K/(1 − E_avg), K the smaller 1 − E_avg of the two sides. ks and kt scale the
    two parts, and radiance through refraction is divided by η² as for the single scattering.

    **Polarized variants.** With ``fresnel`` = ``exact`` the microfacet lobe returns the
    Mueller matrix of specular reflection at the facet m (the conductor's or dielectric's
    Fresnel amplitudes for s and p light and their phase difference), its reference frames
    rotated from the plane of reflection into the Stokes bases of the incident and outgoing
    directions (:func:`mi_brdfs.scattering.fresnel.polarized_reflection`): with ``smith`` the
    values of ``roughconductor`` (tested element by element and through the ``stokes``
    integrator). ``schlick`` (an approximation of the unpolarized reflectance, without the
    phases) and ``none`` give depolarizers, and so do the diffuse base and the compensation,
    added to the lobe's matrix. With ``transmission`` both lobes are depolarizers, as
    ``roughdielectric``'s are in Mitsuba 3.9.1.

    **Thin film** (``film_thickness`` > 0; Born & Wolf, "Principles of Optics", §7.6.1;
    Belcour & Barla 2017, "A Practical Extension to Microfacet Theory for the Modeling of
    Varying Iridescence", §4). A layer of index ``film_eta`` and the given thickness covers
    the base; the light reflected back and forth in it interferes, and the film's
    reflectance R, the Airy sum of the Fresnel amplitudes (with their phase shifts) of its
    two interfaces for s and p light, replaces F at the microfacet's cosine ωi·m
    (:mod:`mi_brdfs.scattering.thinfilm`); refraction takes 1 − R (the film absorbs
    nothing: R + T = 1 at every wavelength and angle), and the choice between reflection and
    refraction is made by the mean of R over the channels. Spectral variants evaluate R
    exactly at each sampled wavelength. RGB and mono variants integrate R against each
    channel's sensitivity (Mitsuba's CIE 1931 colour-matching functions under D65, to linear
    sRGB), in Fourier space as Belcour & Barla do, with the sensitivities' transforms
    tabulated rather than fitted, and tabulated once per material over (cosθ, thickness)
    where the indices are constants and the thickness's range is known (colours outside
    sRGB's gamut clipped into it): an RGB render agrees with the spectral render of the same
    scene developed to sRGB (docs/thinfilm.md measures it). Polarized variants return the
    film's Mueller matrix (Mitsuba's Fresnel matrix without a film; in mono polarized
    variants at the channel's mean wavelength). With ``multiscatter`` on a conductor, F_avg
    is the film's (a 5-node rule at the hit point), so a non-absorbing film on a perfect
    mirror keeps the white furnace at 1. With ``transmission`` the dielectric's albedo tables
    are shifted per channel by what the film changes, Σ_j K_j(μ) (R − F)(c_j) over 12 facet
    cosines c_j, the kernels K_j of the masking's difference between reflection and
    refraction computed at load for the material's η
    (:mod:`mi_brdfs.scattering.multiscatter_film`), so the compensated rough glass under a
    film keeps the white furnace at 1 too. From inside, an RGB film's colour is its table
    from outside read at Snell's image of the cosine (a lossless stack reflects the same from
    both sides), which keeps the refraction reciprocal. A film with ``fresnel`` other than
    ``exact``, and ``film_eta`` without ``film_thickness``, are refused.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="cooktorrance">
                <string name="material" value="Au"/>
                <float name="alpha" value="0.2"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'cooktorrance', 'material': 'Au', 'alpha': 0.2}
    """

    def __init__(self, props):
        super().__init__(props)
        properties.preset(props, PLUGIN)  # a preset's parameters, where the scene gives none
        #: Roughness α (Beckmann: RMS slope) along the tangent and the bitangent: the same
        #: texture when isotropic.
        self.m_alpha_u, self.m_alpha_v = properties.roughness(props, PLUGIN)
        self.m_anisotropic = self.m_alpha_u is not self.m_alpha_v
        #: 'beckmann' or 'ggx'.
        self.m_distribution = properties.choice(props, PLUGIN, "distribution", "beckmann",
                                                microfacet.DISTRIBUTIONS)
        #: Whether the refraction lobe is there (a rough dielectric interface).
        self.m_transmission = properties.boolean(props, PLUGIN, "transmission", False)
        _check_exclusions(props, self.m_transmission)
        #: 'vcavity' or 'smith'.
        self.m_shadowing = properties.choice(props, PLUGIN, "shadowing",
                                             "smith" if self.m_transmission else "vcavity",
                                             SHADOWING)
        #: 'exact', 'schlick' or 'none'.
        self.m_fresnel = properties.choice(props, PLUGIN, "fresnel", "exact", FRESNEL)
        #: Sample visible normals (else D·cosθ).
        self.m_sample_visible = properties.boolean(props, PLUGIN, "sample_visible", True)
        #: Kulla & Conty's energy compensation.
        self.m_multiscatter = properties.boolean(props, PLUGIN, "multiscatter", False)
        if self.m_multiscatter:
            self._warn_beyond_tables()
        if self.m_multiscatter and self.m_anisotropic:
            properties.warn(PLUGIN, "multiscatter with alpha_u, alpha_v: the albedo tables are "
                                    "isotropic, read at sqrt(alpha_u*alpha_v), so the white "
                                    "furnace departs from 1 (below, and at grazing incidence "
                                    "above it; validation/REPORT.md measures by how much)")
        #: Factor on the microfacet (reflection) lobe.
        self.m_specular_reflectance = properties.reflectance(props, PLUGIN,
                                                             "specular_reflectance", 1.0)
        #: The thin film (cooktorrance_film.Film), None without one.
        self.m_film = cooktorrance_film.read(props, PLUGIN, self.m_fresnel)
        if self.m_transmission:
            self._read_transmission(props)
        else:
            self._read_reflection(props)
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

    def _warn_beyond_tables(self):
        """Where α can be known at load and exceeds the albedo tables' last node, say so: the
        table's end is read there, and the compensation falls short."""
        alpha_max = multiscatter.load_tables()["alpha_max"]
        for tex in {id(t): t for t in (self.m_alpha_u, self.m_alpha_v)}.values():
            rng = properties.texture_range(tex)
            if rng is not None and rng[1] > alpha_max:
                properties.warn(PLUGIN, f"multiscatter with alpha = {rng[1]:g}: the albedo "
                                        f"tables end at alpha = {alpha_max:g} and are read "
                                        f"there, so the white furnace falls below 1")

    def _read_transmission(self, props):
        """The dielectric's index and the factor on its refraction lobe."""
        #: The relative index int_ior/ext_ior (a Float: refraction bends all wavelengths
        #: alike); m_k and m_material are None.
        eta = _read_dielectric(props)
        self.m_eta, self.m_k, self.m_material = mi.Float(eta), None, None
        eta_max = multiscatter.load_tables()["eta_max"] if self.m_multiscatter else None
        if eta_max is not None and not 1.0 / eta_max <= eta <= eta_max:
            properties.warn(PLUGIN, f"multiscatter with eta = {eta:g}: the albedo tables end at "
                                    f"eta = {1.0 / eta_max:.4g} and {eta_max:g}, and are read "
                                    f"there, so the white furnace departs from 1")
        #: Factor on the refraction lobe.
        self.m_specular_transmittance = properties.reflectance(props, PLUGIN,
                                                               "specular_transmittance", 1.0)
        #: No diffuse base under a transmitting interface.
        self.m_diffuse_reflectance = None

    def _read_reflection(self, props):
        """The conductor's (or reflecting dielectric's) index and the optional diffuse base."""
        #: Relative IOR η + ik, and the material it came from (None: given as eta, k).
        self.m_eta, self.m_k, self.m_material = _read_ior(props, self.m_fresnel != "none")
        if self.m_fresnel == "none" and self.m_eta is not None:
            properties.warn(PLUGIN, "fresnel = none: eta and k (or the material) are not used")
        self.m_specular_transmittance = None
        #: Albedo of the Lambertian base; None when it is the constant 0 (no lobe).
        diffuse = properties.reflectance(props, PLUGIN, "diffuse_reflectance", 0.0)
        self.m_diffuse_reflectance = None if properties.is_zero(diffuse) else diffuse
        if self.m_diffuse_reflectance is not None:
            properties.warn_sum(props, PLUGIN, ("diffuse_reflectance", diffuse),
                                ("specular_reflectance", self.m_specular_reflectance),
                                "the diffuse base is added, not coupled, so the lobes' albedos "
                                "can add up to more than 1 (at every angle with fresnel = none, "
                                "towards grazing incidence with a Fresnel term)")

    # The lobes do the work (lobes.Mixture): without transmission the microfacet lobe
    # (component 0), its compensation and the diffuse base (component 1); with it the
    # interface (reflection 0, refraction 1) and its compensation, as pbrt-v4 separates
    # ConductorBxDF and DielectricBxDF.
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def traverse(self, cb):
        if self.m_anisotropic:
            cb.put("alpha_u", self.m_alpha_u, DISCONTINUOUS)
            cb.put("alpha_v", self.m_alpha_v, DISCONTINUOUS)
        else:
            cb.put("alpha", self.m_alpha_u, DISCONTINUOUS)
        if self.m_transmission:
            cb.put("eta", self.m_eta, DISCONTINUOUS)
        elif self.m_fresnel != "none":
            cb.put("eta", self.m_eta, DISCONTINUOUS)
            cb.put("k", self.m_k, DISCONTINUOUS)
        cb.put("specular_reflectance", self.m_specular_reflectance, DIFFERENTIABLE)
        if self.m_specular_transmittance is not None:
            cb.put("specular_transmittance", self.m_specular_transmittance, DIFFERENTIABLE)
        if self.m_diffuse_reflectance is not None:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance, DIFFERENTIABLE)
        if self.m_film is not None:
            cb.put("film_thickness", self.m_film.thickness, DIFFERENTIABLE)
            cb.put("film_eta", self.m_film.eta, DIFFERENTIABLE)

    def parameters_changed(self, keys=()):
        """The lobes, from the parameters as they are now."""
        aniso = ANISOTROPIC if self.m_anisotropic else 0
        # the albedo tables of the compensation, at the roughness where it is uniform
        alpha = multiscatter.uniform_alpha(self.m_alpha_u, self.m_alpha_v) \
            if self.m_multiscatter else None
        if self.m_transmission:
            # an index set through mi.traverse is not checked: clipped into the accepted range
            eta = properties.clip(self.m_eta, 1.0 / IOR_MAX, IOR_MAX)
            tables = multiscatter.dielectric_tables(self.m_distribution, eta, alpha) \
                if self.m_multiscatter else None
            single = MicrofacetInterface(
                self.m_distribution, self.m_alpha_u, self.m_alpha_v, self.m_sample_visible,
                eta, self.m_specular_reflectance, self.m_specular_transmittance,
                (REFLECTION_FLAGS | aniso, TRANSMISSION_FLAGS | aniso), tables, self.m_film)
            compensation = None if tables is None else InterfaceCompensation(single)
        else:
            table = multiscatter.conductor_table(self.m_distribution, self.m_shadowing,
                                                 alpha) if self.m_multiscatter else None
            single = MicrofacetReflection(
                self.m_distribution, self.m_alpha_u, self.m_alpha_v, self.m_shadowing,
                self.m_fresnel, self.m_sample_visible, self.m_eta, self.m_k,
                self.m_specular_reflectance, GLOSSY_FLAGS | aniso, table, self.m_film)
            compensation = None if table is None else Compensation(single)
        terms = [single, compensation]
        if self.m_diffuse_reflectance is not None:
            terms.append(lobes.Diffuse(self.m_diffuse_reflectance, component=1))
        self.lobes = lobes.Mixture([t for t in terms if t is not None],
                                   two_sided=self.m_transmission)

    def to_string(self):
        if self.m_transmission:
            ior = (f"  transmission = true,\n  eta = {float(dr.slice(self.m_eta)):g},\n"
                   f"  specular_transmittance = "
                   f"{properties.indent(self.m_specular_transmittance)},\n")
        elif self.m_material is not None:
            ior = f"  material = {self.m_material},\n"
        elif self.m_eta is not None:
            ior = (f"  eta = {properties.indent(self.m_eta)},\n"
                   f"  k = {properties.indent(self.m_k)},\n")
        else:
            ior = ""
        if self.m_anisotropic:
            alpha = (f"  alpha_u = {properties.indent(self.m_alpha_u)},\n"
                     f"  alpha_v = {properties.indent(self.m_alpha_v)},\n")
        else:
            alpha = f"  alpha = {properties.indent(self.m_alpha_u)},\n"
        diffuse = properties.indent(self.m_diffuse_reflectance) \
            if self.m_diffuse_reflectance is not None else "0 (no diffuse lobe)"
        film = "" if self.m_film is None else (
            f",\n  film_thickness = {properties.indent(self.m_film.thickness)},\n"
            f"  film_eta = {properties.indent(self.m_film.eta)}")
        return (f"CookTorrance[\n"
                f"  distribution = {self.m_distribution},\n"
                f"  shadowing = {self.m_shadowing},\n"
                f"  fresnel = {self.m_fresnel},\n"
                f"  sample_visible = {str(self.m_sample_visible).lower()},\n"
                f"  multiscatter = {str(self.m_multiscatter).lower()},\n"
                f"{alpha}"
                f"{ior}"
                f"  specular_reflectance = {properties.indent(self.m_specular_reflectance)},\n"
                f"  diffuse_reflectance = {diffuse}{film}\n"
                f"]")
