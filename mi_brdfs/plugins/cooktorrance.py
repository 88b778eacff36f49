"""
The textbook Cook-Torrance BRDF (Beckmann D, V-cavity G, exact Fresnel), with the switches that
make it comparable to Mitsuba's built-ins: GGX, Smith's masking as Mitsuba computes it, Schlick's
Fresnel, visible-normal sampling and the paper's diffuse base.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..scattering import fresnel, microfacet, mixture, vector
from . import _common
from .materials import conductor_ior, conductor_names, dielectric_ior, material_ior  # noqa: F401

PLUGIN = "cooktorrance"
SHADOWING = ("vcavity", "smith")
FRESNEL = ("exact", "schlick", "none")

#: The named conductor used when neither ``material`` nor ``eta`` is given: copper, the metal
#: of Cook & Torrance's own figures (and Mitsuba 0.6's conductor default).
DEFAULT_MATERIAL = "Cu"


def _constant_channels(props, name) -> list[float] | None:
    """The per-channel values of a float or ``<rgb>`` property, else None (a texture)."""
    kind = props.type(name)
    T = mi.Properties.Type
    if kind in (T.Float, T.Integer):
        return [float(props[name])]
    if kind == T.Color:
        return [float(c) for c in props[name]]
    return None


#: What ``transmission`` excludes, and why (one line each).
NOT_WITH_TRANSMISSION = {
    "material": "names a conductor; transmission needs a dielectric (give eta, or int_ior and "
                "ext_ior)",
    "diffuse_reflectance": "a diffuse base under a transmitting interface is not part of the "
                           "model (Walter et al. 2007)",
}


def _read_dielectric(props) -> float:
    """
    The relative index η = η_int/η_ext of ``transmission``: ``eta`` (a number ≠ 1, with ``k``
    absent or 0) or ``int_ior``/``ext_ior`` (numbers or names, as ``roughdielectric`` takes
    them; defaults ``bk7`` inside and ``air`` outside).
    """
    for name, why in NOT_WITH_TRANSMISSION.items():
        _common.reject(props, PLUGIN, name, f"must not be given with transmission = true: {why}")
    if "k" in props and not (props.type("k") in (mi.Properties.Type.Float,
                                                 mi.Properties.Type.Integer)
                             and float(props["k"]) == 0.0):
        raise ParameterError(PLUGIN, "k", props["k"], "must be 0 (or absent) with transmission "
                                                      "= true: only a dielectric transmits")
    if "eta" in props:
        for name in ("int_ior", "ext_ior"):
            _common.reject(props, PLUGIN, name, "must not be given together with eta (eta is "
                                                "int_ior/ext_ior)")
        eta = _common.number(props, PLUGIN, "eta", 1.5, lo=0.0, lo_open=True)
        where = "eta"
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
    return eta


def _read_ior(props, needed: bool):
    """
    ``(eta, k, material)`` from ``material`` or ``eta``/``k`` (see the class docstring); all
    None when the Fresnel term is off (``needed`` false) and none of them is given.
    """
    has_eta, has_k = "eta" in props, "k" in props
    if "material" in props:
        name = props["material"]
        if has_eta or has_k:
            raise ParameterError(PLUGIN, "material", name,
                                 "must not be given together with eta or k (it sets both)")
        return (*material_ior(name, PLUGIN), name)
    if not has_eta:
        if has_k:
            raise ParameterError(PLUGIN, "k", props["k"],
                                 "needs eta as well (or a material instead of both)")
        if not needed:
            return None, None, None
        return (*material_ior(DEFAULT_MATERIAL, PLUGIN), DEFAULT_MATERIAL)
    eta = _common.texture(props, PLUGIN, "eta", 1.5, lo=0.0, hi=math.inf)
    k = _common.texture(props, PLUGIN, "k", 0.0, lo=0.0, hi=math.inf)
    eta_c = _constant_channels(props, "eta")
    k_c = _constant_channels(props, "k") if has_k else [0.0]
    if eta_c is not None and k_c is not None:
        n = max(len(eta_c), len(k_c))
        if any(eta_c[i % len(eta_c)] == 0 and k_c[i % len(k_c)] == 0 for i in range(n)):
            raise ParameterError(PLUGIN, "eta", props["eta"],
                                 "must be > 0 where k = 0 (a dielectric; η = 0 needs k > 0)")
    return eta, k, None


V = _common.variant_tools()
# Bound once per variant: in scalar variants these are looked up at every call otherwise.
Spectrum, Float, UInt32 = mi.Spectrum, mi.Float, mi.UInt32
cosine_hemisphere = mi.warp.square_to_cosine_hemisphere
# the terms, as this variant runs them (see _common.variant_tools)
mf, vec = V.terms(microfacet), V.terms(vector)
GLOSSY = _common.flag("GlossyReflection")
DIFFUSE = _common.flag("DiffuseReflection")
GLOSSY_FLAGS = _common.flag("GlossyReflection", "FrontSide")
ANISOTROPIC = _common.flag("Anisotropic")
GLOSSY_T = _common.flag("GlossyTransmission")
REFLECTION_FLAGS = _common.flag("GlossyReflection", "FrontSide", "BackSide")
TRANSMISSION_FLAGS = _common.flag("GlossyTransmission", "FrontSide", "BackSide", "NonSymmetric")
RADIANCE = mi.TransportMode.Radiance
AD = dr.is_diff_v(mi.Float)
DIFFUSE_FLAGS = _common.flag("DiffuseReflection", "FrontSide")
#: The sample record's lobe indices and types, made once (a UInt32 costs 80 ns per call in a
#: scalar variant).
LOBE_0, LOBE_1 = UInt32(0), UInt32(1)
TYPE_GLOSSY, TYPE_DIFFUSE, TYPE_GLOSSY_T = UInt32(GLOSSY), UInt32(DIFFUSE), UInt32(GLOSSY_T)
DIFFERENTIABLE = mi.ParamFlags.Differentiable
DISCONTINUOUS = mi.ParamFlags.Differentiable | mi.ParamFlags.Discontinuous
fres = V.terms(fresnel)
FRESNEL_TERMS = {"exact": fresnel.exact, "schlick": fresnel.schlick}  # per spectrum
#: What scalar variants compile an instance's eval_pdf and sample for (floats.configure): the
#: switches, and which optional parts are absent (None).
CONFIGURATION = ("m_distribution", "m_shadowing", "m_fresnel", "m_sample_visible",
                 "m_transmission", "m_anisotropic")
OPTIONAL = ("m_diffuse_reflectance", "m_specular_transmittance", "_channels", "_alpha_const",
            "_distr", "_fresnel_term", "_ks_channels", "_kt_channels")
#: The material's part of each per-channel term (fresnel.exact_at and schlick_at take it).
FRESNEL_CONSTANTS = {"exact": fres.exact_constants, "schlick": fres.r0}


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
         ``roughconductor`` (``Au``, ``Ag``, ``Al``, ``Cu``, ``Cr``, ...). Exclusive with
         ``eta``/``k`` (Default: ``Cu`` when ``eta`` is not given either)

     * - eta, k
       - |spectrum| or |texture|
       - Relative index of refraction η + ik, finite, η ≥ 0, k ≥ 0; k = 0 is a dielectric
         (η > 0 then), η = 0 with k = 1 a perfect mirror. ``k`` needs ``eta`` and defaults to
         0 with it (``roughconductor``: 1) (Default: from ``material``)
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
    Jacobian η² |ωo·h| / (ωi·h + η ωo·h)² (Walter eq. 17). ``shadowing`` must be ``smith``
    (its default then): Smith's Λ is defined on both sides of the surface, whereas the
    V-cavity masking of Cook & Torrance 1982 is derived for light above the surface, and
    the joint masking of a refracted pair of directions is not given there. ``fresnel``
    must be ``exact``; ``material``, a ``k`` ≠ 0 and the diffuse base are rejected.

    **Limits.** α is clamped to ≥ 10⁻⁴. The microfacet normals are sampled without the
    float32 collapse of the textbook formula (see
    :func:`mi_brdfs.scattering.microfacet.sample_ndf`), but below α ≈ 10⁻³ the lobe is
    narrower than a χ² histogram resolves: there the plugin behaves as a smooth mirror whose
    albedo tends to F (measured in the tests). Single scattering loses energy at high α and
    grazing angles (F = 1, V-cavity, α = 0.5: E = 0.89 at normal incidence); the diffuse base
    is added, not coupled, so ρd + E_spec ≤ 1 is up to the user.

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
        #: Roughness α (Beckmann: RMS slope) along the tangent and the bitangent: the same
        #: texture when isotropic.
        self.m_alpha_u, self.m_alpha_v = _common.roughness(props, PLUGIN)
        self.m_anisotropic = self.m_alpha_u is not self.m_alpha_v
        #: 'beckmann' or 'ggx'.
        self.m_distribution = _common.choice(props, PLUGIN, "distribution", "beckmann",
                                             mf.DISTRIBUTIONS)
        #: Whether the refraction lobe is there (a rough dielectric interface).
        self.m_transmission = _common.boolean(props, PLUGIN, "transmission", False)
        #: 'vcavity' or 'smith'.
        self.m_shadowing = _common.choice(props, PLUGIN, "shadowing",
                                          "smith" if self.m_transmission else "vcavity",
                                          SHADOWING)
        #: 'exact', 'schlick' or 'none'.
        self.m_fresnel = _common.choice(props, PLUGIN, "fresnel", "exact", FRESNEL)
        if self.m_transmission:
            self._check_transmission(props)
            #: The relative index int_ior/ext_ior (a Float: refraction bends all wavelengths
            #: alike); m_k and m_material are None.
            self.m_eta, self.m_k, self.m_material = mi.Float(_read_dielectric(props)), None, None
        else:
            for name in ("specular_transmittance", "int_ior", "ext_ior"):
                _common.reject(props, PLUGIN, name, "is a parameter of the refraction lobe: "
                                                    "give transmission = true as well")
            #: Relative IOR η + ik, and the material it came from (None: given as eta, k).
            self.m_eta, self.m_k, self.m_material = _read_ior(props, self.m_fresnel != "none")
        if self.m_fresnel == "none" and self.m_eta is not None:
            _common.warn(PLUGIN, "fresnel = none: eta and k (or the material) are not used")
        #: Factor on the microfacet (reflection) lobe.
        self.m_specular_reflectance = _common.reflectance(props, PLUGIN,
                                                          "specular_reflectance", 1.0)
        #: Factor on the refraction lobe; None without transmission.
        self.m_specular_transmittance = _common.reflectance(
            props, PLUGIN, "specular_transmittance", 1.0) if self.m_transmission else None
        #: Albedo of the Lambertian base; None when it is the constant 0 (no lobe).
        diffuse = _common.reflectance(props, PLUGIN, "diffuse_reflectance", 0.0) \
            if not self.m_transmission else None
        self.m_diffuse_reflectance = None if diffuse is None or _common.is_zero(diffuse) \
            else diffuse
        #: Sample visible normals (else D·cosθ).
        self.m_sample_visible = _common.boolean(props, PLUGIN, "sample_visible", True)
        #: F on spectra (None for 'none'; on the per-channel floats of _channels, see _specular)
        self._fresnel_term = FRESNEL_TERMS.get(self.m_fresnel)
        self.parameters_changed()
        aniso = ANISOTROPIC if self.m_anisotropic else 0
        if self.m_transmission:  # as roughdielectric: reflection 0, transmission 1, both sides
            self.m_components = [REFLECTION_FLAGS | aniso, TRANSMISSION_FLAGS | aniso]
            self.m_flags = REFLECTION_FLAGS | TRANSMISSION_FLAGS | aniso
            return
        # Lobe 0 is the microfacet lobe (as roughconductor's only one), lobe 1 the diffuse.
        components = [GLOSSY_FLAGS | aniso]
        if self.m_diffuse_reflectance is not None:
            components.append(DIFFUSE_FLAGS)
        self.m_components = components  # a copy crosses to C++: assign, don't append
        self.m_flags = components[0] | (DIFFUSE_FLAGS if len(components) > 1 else 0)

    def _check_transmission(self, props):
        """The switches that ``transmission`` does not combine with, each one line."""
        if self.m_shadowing != "smith":
            raise ParameterError(PLUGIN, "shadowing", self.m_shadowing,
                                 "must be \"smith\" with transmission = true: the V-cavity "
                                 "masking (Cook & Torrance 1982) is derived for light above the "
                                 "surface, and gives no masking for a refracted pair")
        if self.m_fresnel != "exact":
            raise ParameterError(PLUGIN, "fresnel", self.m_fresnel,
                                 "must be \"exact\" with transmission = true (the refracted "
                                 "fraction is 1 − F, with total internal reflection)")

    eval, pdf = _common.eval_half, _common.pdf_half

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs, sample2 = V.new_sample(), V.point2(sample2)
        lobes = self._lobes(ctx)
        use_mf, use_diffuse = lobes
        wi = V.direction(si.wi)
        if self.m_transmission:
            return self._sample_dielectric(ctx, si, wi, sample1, sample2, active, bs, lobes)
        active = active & (wi.z > 0)  # one-sided: the local frame's z is cosθ
        if V.none(active) or not (use_mf or use_diffuse):
            return bs, Spectrum(0.0)
        if not use_diffuse:
            return self._sample_microfacet(si, wi, sample1, sample2, active, bs)
        # Both lobes: sample1 picks the microfacet lobe with probability p (and, rescaled, a
        # facet of the V-groove); the weight is f·cosθo over the mixture density.
        p = self._p_microfacet(si, wi, active) if use_mf else 0.0
        pick = (sample1 < p) if use_mf else False

        def microfacet():
            return vec.reflect(wi, self._sample_normal(si, wi, active, sample2,
                                                      mixture.rescale(sample1, p)))

        def diffuse():
            return cosine_hemisphere(sample2)

        bs.wo = V.to_mitsuba(V.choose(pick, microfacet, diffuse))
        bs.sampled_type = V.select(pick, TYPE_GLOSSY, TYPE_DIFFUSE)
        bs.sampled_component = V.select(pick, LOBE_0, LOBE_1)
        bs.eta = 1.0
        value, bs.pdf = self._eval_pdf(si, wi, V.direction(bs.wo), active, lobes, p)
        ok = active & (bs.pdf > 0)
        return bs, V.select(ok, value / V.select(ok, bs.pdf, 1.0), 0.0)

    def _sample_microfacet(self, si, wi, sample1, sample2, active, bs):
        """:meth:`sample` of the microfacet lobe alone, with the weight in closed form."""
        # a microfacet normal m, and ωo = ωi reflected about it
        m = self._sample_normal(si, wi, active, sample2, sample1)
        wo = vec.reflect(wi, m)
        bs.wo = V.to_mitsuba(wo)
        bs.sampled_type, bs.sampled_component = TYPE_GLOSSY, LOBE_0
        bs.eta = 1.0
        # the terms at bs.wo as stored (float32 in scalar variants), so that bs.pdf = pdf(bs.wo)
        wo = V.direction(bs.wo)
        active = active & (wo.z > 0)
        weight, bs.pdf = self._microfacet(si, wi, wo, active, weight=True)
        return bs, V.select(active, V.depolarize(weight), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        lobes = self._lobes(ctx)
        if not (lobes[0] or lobes[1]):
            return Spectrum(0.0), Float(0.0)
        if self.m_transmission:
            value, pdf = self._dielectric(si, V.direction(si.wi), V.direction(wo), active, lobes,
                                          ctx.mode == RADIANCE)
            return V.depolarize(value), pdf
        return self._eval_pdf(si, V.direction(si.wi), V.direction(wo), active, lobes)

    def _eval_pdf(self, si, wi, wo, active, lobes, p_microfacet=None):
        """(f·cosθo, pdf of :meth:`sample`) at ``wo``: the enabled lobes and their mixture."""
        # (the methods on a call's path exit once, at their end: scalar variants compile them
        # into their callers, see floats.specialise_class)
        use_mf, use_diffuse = lobes
        active = active & (wi.z > 0) & (wo.z > 0)  # one-sided
        if V.none(active):
            value, pdf = Spectrum(0.0), Float(0.0)
        else:
            if use_mf:
                value, pdf = self._microfacet(si, wi, wo, active)
            if use_diffuse:
                # ρd/π·cosθo, sampled by the cosine-weighted hemisphere
                value_d = self.m_diffuse_reflectance.eval(si, active) * dr.inv_pi * wo.z
                pdf_d = wo.z * dr.inv_pi
                if use_mf:
                    if p_microfacet is None:
                        p_microfacet = self._p_microfacet(si, wi, active)
                    value, pdf = value + value_d, mixture.pdf(p_microfacet, pdf, pdf_d)
                else:
                    value, pdf = value_d, pdf_d
            value, pdf = V.select(active, V.depolarize(value), 0.0), V.select(active, pdf, 0.0)
        return value, pdf

    def _microfacet(self, si, wi, wo, active, weight=False):
        """
        (f·cosθo, pdf) of the microfacet lobe for ωi, ωo above the surface; with ``weight``
        (for :meth:`sample`) (f·cosθo/pdf, pdf), in closed form where D and 4 cosθi cancel:
        ks·F·G1(ωo) (Smith's visible normals), ks·F·G/G1(ωi) (the V-cavity's),
        ks·F·G·(ωo·m)/(cosθi cosθm) (D·cos).
        """
        m = vec.half_vector(wi, wo)
        cos_im, cos_om = vec.dot(wi, m), vec.dot(wo, m)
        # Both directions must see the front of the facet: false only when rounding makes
        # ωi + ωo vanish (grazing, nearly opposite directions).
        active = active & (cos_im > 0) & (cos_om > 0)
        if V.none(active):
            value, pdf = Spectrum(0.0), Float(0.0)
        else:
            value, pdf = self._microfacet_terms(si, wi, wo, m, cos_im, cos_om, active, weight)
        return value, pdf

    def _microfacet_terms(self, si, wi, wo, m, cos_im, cos_om, active, weight):
        """:meth:`_microfacet` where ωi and ωo see the facet m (cosines ``cos_im``, ``cos_om``)."""
        kind = self.m_distribution
        alpha = self._alpha(si, active)
        # D, the masking-shadowing G, and G1(ωi) of the visible normals
        D = mf.ndf(kind, alpha, m)
        if self.m_shadowing == "smith":
            g1_wi = mf.smith_g1_mitsuba(kind, alpha, wi, m, cos_im)
            g1_wo = mf.smith_g1_mitsuba(kind, alpha, wo, m, cos_om)
            G = g1_wi * g1_wo
        else:
            G = mf.vcavity_g(wi, wo, m)
            g1_wi = None
            if self.m_sample_visible:
                g1_wi = mf.vcavity_g1(wi, m)
        # the density of ωo: visible normals or D·cosθm, through the reflection's Jacobian
        if self.m_sample_visible:
            pdf = mf.pdf_visible_reflection(D, g1_wi, wi)
        else:
            pdf = mf.pdf_ndf(D, m) * mf.reflection_jacobian(wo, m)
        # f·cosθo = ks F D G / (4 cosθi cosθo) · cosθo, or the sample weight
        if not weight:
            factor = D * G / (4.0 * wi.z)
        elif not self.m_sample_visible:
            factor = G * cos_om / dr.maximum(wi.z * m.z, 1e-30)
        elif self.m_shadowing == "smith":
            factor = g1_wo
        else:
            factor = G / dr.maximum(g1_wi, 1e-30)
        if weight:
            active = active & (pdf > 0)
        value = self._specular(si, cos_im, factor, active)
        return V.select(active, value, 0.0), V.select(active, pdf, 0.0)

    def _sample_dielectric(self, ctx, si, wi, sample1, sample2, active, bs, lobes):
        """:meth:`sample` with transmission: a microfacet normal, then reflection with
        probability F, else refraction (Walter et al. 2007, §5.3)."""
        has_r, has_t = lobes
        active = active & (wi.z != 0.0)
        if V.none(active) or not (has_r or has_t):
            weight = Spectrum(0.0)
        else:
            weight = self._sample_dielectric_lobe(ctx, si, wi, sample1, sample2, active, bs,
                                                  has_r, has_t)
        return bs, weight

    def _sample_dielectric_lobe(self, ctx, si, wi, sample1, sample2, active, bs, has_r, has_t):
        """:meth:`_sample_dielectric` where ωi is off the surface and a lobe is enabled: fills
        ``bs``, returns the weight."""
        cos_i = wi.z
        # the microfacet normal, seen from ωi turned to the normal's side
        up = V.select(cos_i < 0.0, -1.0, 1.0)
        m = self._sample_normal(si, mi.Vector3f(wi.x * up, wi.y * up, wi.z * up), active,
                                sample2, sample1, widen=True)
        cos_im = vec.dot(wi, m)
        # a normal drawn from D·cos may face away from ωi: no sample (as G1(ωi) = 0 there)
        active = active & (cos_im * cos_i > 0.0)
        F, cos_t, eta_it, eta_ti = fres.dielectric(cos_im, self._eta)
        # the lobe: reflect with probability F when both are enabled
        pick_r = (sample1 <= F) if (has_r and has_t) else has_r
        bs.wo = V.to_mitsuba(V.choose(pick_r, lambda: vec.reflect(wi, m),
                                      lambda: vec.refract(wi, m, cos_t, eta_ti)))
        bs.eta = V.select(pick_r, 1.0, eta_it)
        bs.sampled_component = V.select(pick_r, LOBE_0, LOBE_1)
        bs.sampled_type = V.select(pick_r, TYPE_GLOSSY, TYPE_GLOSSY_T)
        # the terms at bs.wo as stored, so that bs.pdf = pdf(bs.wo); a reflection that left
        # below the surface (or a refraction above it) is no sample, nor is a refraction that
        # float32 cannot represent (for η ≳ 100 at grazing facets, Snell's vector form loses
        # the unit length to cancellation)
        wo = V.direction(bs.wo)
        same_side = cos_i * wo.z > 0.0
        unit = dr.abs(vec.dot(wo, wo) - 1.0) < 1e-3
        active = active & V.select(pick_r, same_side, (cos_i * wo.z < 0.0) & unit)
        weight, bs.pdf = self._dielectric(si, wi, wo, active, (has_r, has_t),
                                          ctx.mode == RADIANCE, weight=True)
        return V.select(active, V.depolarize(weight), 0.0)

    def _dielectric(self, si, wi, wo, active, lobes, radiance, weight=False):
        """
        (f·|cosθo|, pdf) of the rough dielectric (transmission), both sides, both lobes; with
        ``weight`` (for :meth:`sample`) (f·|cosθo|/pdf, pdf) in closed form: k·F̂·G1(ωo) with
        visible normals, k·F̂·(D/D_widened)·G·|ωo·h|/(|cosθi| cosθh) with D·cos (|ωi·h| for a
        refraction), where k is the lobe's factor (and 1/η² for radiance through refraction)
        and F̂ is 1 when both lobes are sampled, else F or 1 − F.
        """
        has_r, has_t = lobes
        cos_i, cos_o = wi.z, wo.z
        reflect = cos_i * cos_o > 0.0
        if not has_t:
            active = active & reflect
        elif not has_r:
            active = active & (cos_i * cos_o < 0.0)
        # the relative index in the direction of travel, and the generalised half vector
        eta = V.select(cos_i > 0.0, self._eta, self._inv_eta)
        m = vec.generalized_half_vector(wi, wo, V.select(reflect, 1.0, eta))
        cos_im, cos_om = vec.dot(wi, m), vec.dot(wo, m)
        # each direction sees the front of the facet from its own side of the surface
        active = active & (cos_i != 0.0) & (cos_im * cos_i > 0.0) & (cos_om * cos_o > 0.0)
        if V.none(active):
            value, pdf = Spectrum(0.0), Float(0.0)
        else:
            value, pdf = self._dielectric_terms(si, wi, wo, m, cos_im, cos_om, reflect, eta,
                                                active, lobes, radiance, weight)
        return value, pdf

    def _dielectric_terms(self, si, wi, wo, m, cos_im, cos_om, reflect, eta, active, lobes,
                          radiance, weight):
        """:meth:`_dielectric` where both directions see the facet m (cosines ``cos_im``,
        ``cos_om``); ``eta`` is the relative index in the direction of travel."""
        has_r, has_t = lobes
        cos_i = wi.z
        kind = self.m_distribution
        alpha = self._alpha(si, active)
        D = mf.ndf(kind, alpha, m)
        F, _, _, _ = fres.dielectric(cos_im, self._eta)
        g1_wi = mf.smith_g1_mitsuba(kind, alpha, wi, m, cos_im)
        g1_wo = mf.smith_g1_mitsuba(kind, alpha, wo, m, cos_om)
        lobe_f = V.select(reflect, F, 1.0 - F)
        # the density of the normal (visible normals of the turned ωi, or the widened D·cos),
        # the lobe's probability, and the Jacobian of ωo
        abs_cos_i = dr.abs(cos_i)
        if self.m_sample_visible:
            pdf = D * g1_wi * dr.abs(cos_im) / abs_cos_i
        else:
            d_sample = mf.ndf(kind, self._widened(alpha, cos_i), m)
            pdf = mf.pdf_ndf(d_sample, m)
        if has_r and has_t:
            pdf = pdf * lobe_f
        pdf = pdf * V.choose(reflect, lambda: mf.reflection_jacobian(wo, m),
                             lambda: mf.refraction_jacobian(wi, wo, m, eta))
        # the lobe's factor: ks, or kt (and 1/η² for radiance: Veach 1997, §5.2)
        factor = self._lobe_factor(si, reflect, eta, radiance, active)
        if weight:
            chosen = self._chosen(lobe_f) if (has_r and has_t) else lobe_f
            if self.m_sample_visible:
                shape = g1_wo
            else:
                # |ωo·h| = |ωi·h| for a reflection, up to rounding: the one eval/pdf has
                cos_h = dr.abs(V.select(reflect, cos_om, cos_im))
                shape = (D / dr.maximum(d_sample, 1e-30)) * g1_wi * g1_wo * cos_h / \
                    dr.maximum(abs_cos_i * m.z, 1e-30)
            value = V.scale(factor, chosen * shape)
            active = active & (pdf > 0.0)
        else:
            G = g1_wi * g1_wo
            value = V.scale(factor, V.choose(
                reflect, lambda: F * D * G / (4.0 * abs_cos_i),
                lambda: dr.abs((1.0 - F) * D * G * eta * eta * cos_im * cos_om /
                               dr.maximum(cos_i * dr.square(cos_im + eta * cos_om), -1e30))))
        return V.select(active, value, 0.0), V.select(active, pdf, 0.0)

    @staticmethod
    def _chosen(probability):
        """The weight factor of a lobe chosen with ``probability`` (F or 1 − F): 1, whose
        derivative in AD variants is that of log(probability), the lobe choice being made on
        detached values (as roughdielectric, so that gradients through sample() stay
        unbiased)."""
        if not AD:
            return 1.0
        return dr.replace_grad(Float(1.0), probability / dr.detach(probability))

    def _lobe_factor(self, si, reflect, eta, radiance, active):
        """ks for a reflection, kt (over η² in radiance transport) for a refraction: spectra,
        or lists of per-channel floats where they are constants (see :meth:`parameters_changed`)."""
        return V.choose(reflect, lambda: self._reflection_factor(si, active),
                        lambda: self._refraction_factor(si, eta, radiance, active))

    def _reflection_factor(self, si, active):
        """ks (:meth:`_lobe_factor`)."""
        ks = self._ks_channels
        return ks if ks is not None else self.m_specular_reflectance.eval(si, active)

    def _refraction_factor(self, si, eta, radiance, active):
        """kt, over η² in radiance transport (:meth:`_lobe_factor`)."""
        kt = self._kt_channels
        if kt is not None:
            return [c / (eta * eta) for c in kt] if radiance else kt
        kt = self.m_specular_transmittance.eval(si, active)
        return kt / dr.square(eta) if radiance else kt

    def _widened(self, alpha, cos_i):
        """α widened for D·cos sampling through a dielectric (mf.walter_widening)."""
        k = mf.walter_widening(cos_i)
        return (alpha[0] * k, alpha[1] * k) if type(alpha) is tuple else alpha * k

    def _specular(self, si, cos_theta, factor, active):
        """ks·F(cosθ)·factor per channel, F at the cosine between ωi and the facet normal."""
        term = self._fresnel_term
        if self._channels is not None:  # constants as floats: the same terms, per channel
            values = []
            if term is None:
                for ks, _ in self._channels:
                    values.append(ks * factor)
            elif self.m_fresnel == "exact":  # (each call written out: compiled, they inline)
                c, c2, s2 = fres.incidence(cos_theta)
                for ks, (e2k2, ek4) in self._channels:
                    f = fres.exact_at(c, c2, s2, e2k2, ek4)
                    values.append(ks * f * factor)
            else:
                inc = fres.schlick_incidence(cos_theta)
                for ks, const in self._channels:
                    f = fres.schlick_at(inc, const)
                    values.append(ks * f * factor)
            value = V.spectrum(values)
        else:
            value = self.m_specular_reflectance.eval(si, active) * factor
            if term is not None:
                value = value * term(cos_theta, self.m_eta.eval(si, active),
                                     self.m_k.eval(si, active))
        return value

    def _p_microfacet(self, si, wi, active):
        """Probability of sampling the microfacet lobe when both lobes are on: in proportion
        to mean(ks·F(cosθi)) and mean(ρd)."""
        w_mf = dr.mean(self._specular(si, wi.z, 1.0, active))
        w_d = dr.mean(self.m_diffuse_reflectance.eval(si, active))
        return mixture.probability(w_mf, w_d, 1.0)

    def _sample_normal(self, si, wi, active, sample2, u_facet, widen=False):
        """A microfacet normal: D·cosθ (with ``widen``, of the widened α of a dielectric),
        Smith's visible normals of ωi, or the V-cavity's (whose facet of the V-groove
        ``u_facet`` picks)."""
        kind = self.m_distribution
        alpha = self._alpha(si, active)
        if not self.m_sample_visible:
            m = mf.sample_ndf(kind, self._widened(alpha, wi.z) if widen else alpha, sample2)
        elif self.m_shadowing == "smith":
            m = mf.sample_visible(kind, alpha, wi, sample2, self._distr)
        else:
            m = mf.sample_vcavity_visible(kind, alpha, wi, sample2, u_facet)
        return m

    def _lobes(self, ctx):
        """Which lobes the context enables: (microfacet, diffuse), or with transmission
        (reflection, refraction)."""
        second = ctx.is_enabled(GLOSSY_T, 1) if self.m_transmission else \
            self.m_diffuse_reflectance is not None and ctx.is_enabled(DIFFUSE, 1)
        return ctx.is_enabled(GLOSSY, 0), second

    def _alpha(self, si, active):
        """α at ``si`` (the pair (αu, αv) when anisotropic), clamped to mf.ALPHA_MIN as
        Mitsuba clamps it."""
        alpha = self._alpha_const
        return alpha if alpha is not None else \
            _common.alpha_at(self.m_alpha_u, self.m_alpha_v, si, active)

    def eval_diffuse_reflectance(self, si, active=True):
        # The default, eval(wo = n)·π, would count the glossy lobe
        # (https://github.com/mitsuba-renderer/mitsuba3/pull/1896).
        if self.m_diffuse_reflectance is None:  # (also with transmission: no diffuse base)
            return Spectrum(0.0)
        return self.m_diffuse_reflectance.eval(si, active)

    def traverse(self, cb):
        if self.m_anisotropic:
            cb.put("alpha_u", self.m_alpha_u, DISCONTINUOUS)
            cb.put("alpha_v", self.m_alpha_v, DISCONTINUOUS)
        else:
            cb.put("alpha", self.m_alpha_u, DISCONTINUOUS)
        if self.m_transmission:
            cb.put("eta", self.m_eta, DISCONTINUOUS)
        elif self._fresnel_term is not None:
            cb.put("eta", self.m_eta, DISCONTINUOUS)
            cb.put("k", self.m_k, DISCONTINUOUS)
        cb.put("specular_reflectance", self.m_specular_reflectance, DIFFERENTIABLE)
        if self.m_specular_transmittance is not None:
            cb.put("specular_transmittance", self.m_specular_transmittance, DIFFERENTIABLE)
        if self.m_diffuse_reflectance is not None:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance, DIFFERENTIABLE)

    def parameters_changed(self, keys=()):
        """In scalar variants, read constant parameters once: α (and Mitsuba's sampler for it),
        and in RGB ks, η and k as per-channel floats (see _common.variant_tools)."""
        self._alpha_const = self._distr = self._channels = None
        self._ks_channels = self._kt_channels = None
        if self.m_transmission:  # the relative index both ways (opaque: updates reuse kernels)
            self._eta, self._inv_eta = self.m_eta, dr.rcp(self.m_eta)
            if V.jit:
                dr.make_opaque(self._eta, self._inv_eta)
            else:
                self._eta, self._inv_eta = float(self._eta), float(self._inv_eta)
                if V.per_channel:  # constant ks and kt as per-channel floats
                    self._ks_channels = _common.constant_channels(self.m_specular_reflectance)
                    self._kt_channels = _common.constant_channels(
                        self.m_specular_transmittance)
        if V.jit:
            return
        self._alpha_const = _common.constant_alpha(self.m_alpha_u, self.m_alpha_v)
        if self._alpha_const is not None:
            self._distr = mf.distribution(self.m_distribution, self._alpha_const)
        if V.per_channel and not self.m_transmission:
            fresnel_on = self._fresnel_term is not None
            channels = [_common.constant_channels(t) if t is not None else [0.0, 0.0, 0.0]
                        for t in (self.m_specular_reflectance,
                                  self.m_eta if fresnel_on else None,
                                  self.m_k if fresnel_on else None)]
            if all(c is not None for c in channels):  # (ks, F's constants) of each channel
                constants = FRESNEL_CONSTANTS[self.m_fresnel] if fresnel_on else \
                    (lambda e, k: None)
                self._channels = [(ks, constants(e, k)) for ks, e, k in zip(*channels)]
        V.configure(self, CONFIGURATION, OPTIONAL)

    def to_string(self):
        if self.m_transmission:
            ior = (f"  transmission = true,\n  eta = {float(dr.slice(self.m_eta)):g},\n"
                   f"  specular_transmittance = {_common.indent(self.m_specular_transmittance)},\n")
        elif self.m_material is not None:
            ior = f"  material = {self.m_material},\n"
        elif self.m_eta is not None:
            ior = f"  eta = {_common.indent(self.m_eta)},\n  k = {_common.indent(self.m_k)},\n"
        else:
            ior = ""
        if self.m_anisotropic:
            alpha = (f"  alpha_u = {_common.indent(self.m_alpha_u)},\n"
                     f"  alpha_v = {_common.indent(self.m_alpha_v)},\n")
        else:
            alpha = f"  alpha = {_common.indent(self.m_alpha_u)},\n"
        diffuse = _common.indent(self.m_diffuse_reflectance) \
            if self.m_diffuse_reflectance is not None else "0 (no diffuse lobe)"
        return (f"CookTorrance[\n"
                f"  distribution = {self.m_distribution},\n"
                f"  shadowing = {self.m_shadowing},\n"
                f"  fresnel = {self.m_fresnel},\n"
                f"  sample_visible = {str(self.m_sample_visible).lower()},\n"
                f"{alpha}"
                f"{ior}"
                f"  specular_reflectance = {_common.indent(self.m_specular_reflectance)},\n"
                f"  diffuse_reflectance = {diffuse}\n"
                f"]")


V.specialise_class(CookTorrance)
