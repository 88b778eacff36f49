"""
Cox & Munk's wind-roughened sea surface with Eradiate's plugin parameters
(``ocean_mishchenko``): the sunglint, a Beckmann microfacet lobe of the slopes' variance with
the Fresnel reflectance of water and Mishchenko & Travis's shadowing (its terms in
:mod:`mi_brdfs.scattering.ocean`), sampled by visible normals; optionally along the wind
(Cox & Munk's up- and cross-wind slopes) and with whitecaps (a Lambertian lobe weighted by
their coverage).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import drjit as dr
import mitsuba as mi

from ..scattering import fresnel, microfacet, vector
from ..scattering import ocean as terms
from . import lobes, properties

PLUGIN = "ocean"
#: Eradiate's defaults (its src/bsdfs/ocean_mishchenko.cpp).
DEFAULTS = {"wind_speed": 0.1, "eta": 1.33, "k": 0.0, "ext_ior": 1.000277}
#: The wind speeds taken (m/s): Eradiate's range; Monahan's coverage reaches 1 at 37.25 m/s.
WIND_RANGE = (0.0, 37.54)
#: Koepke's (1984) effective reflectance of whitecaps: ``whitecaps = true``.
WHITECAP_REFLECTANCE = 0.22


class Sea:
    """The surface as the lobes use it: the wind speed (m/s, clipped into
    :data:`WIND_RANGE`), the wind's azimuth (cos, sin; None: isotropic), the indices' textures,
    the shadowing switch and the whitecaps' reflectance (None: none)."""

    def __init__(self, wind_speed, azimuth, eta, k, ext_ior, shadowing, whitecaps):
        self.wind_speed = properties.clip(wind_speed, *WIND_RANGE)
        self.azimuth, self.shadowing, self.whitecaps = azimuth, shadowing, whitecaps
        self.eta, self.k, self.ext_ior = eta, k, ext_ior

    def distribution(self) -> microfacet.Distribution:
        """Beckmann's distribution of the slopes (in the wind's frame when anisotropic)."""
        return microfacet.Distribution(
            microfacet.BECKMANN, *terms.roughness(self.wind_speed, self.azimuth is not None))

    def to_wind(self, v):
        return v if self.azimuth is None else terms.to_wind(v, *self.azimuth)

    def from_wind(self, v):
        return v if self.azimuth is None else terms.from_wind(v, *self.azimuth)

    def index(self, si, active):
        """(η, k) of the water relative to the exterior, per channel."""
        ext = properties.clip_at(self.ext_ior, si, active, 1e-6, fresnel.IOR_MAX)
        eta = properties.clip_at(self.eta, si, active, 0.0, fresnel.IOR_MAX)
        k = properties.clip_at(self.k, si, active, 0.0, fresnel.IOR_MAX)
        return dr.minimum(eta / ext, fresnel.IOR_MAX), dr.minimum(k / ext, fresnel.IOR_MAX)

    def coverage(self):
        """Monahan's whitecap coverage W at the wind speed."""
        return terms.coverage(self.wind_speed)

    def glint_share(self):
        """The share of the surface the glint reflects from: 1 − W with whitecaps, else 1."""
        return 1.0 if self.whitecaps is None else 1.0 - self.coverage()


class Glint(lobes.Lobe):
    """
    (1 − W)·F(ωi·m)·D(m)·S(ωi, ωo)/(4 cosθi cosθo), m the half vector, sampled by the visible
    normals of ωi: density D(m) G1(ωi, m)/(4 cosθi) with G1 = 1/(1 + Λ(ωi)), sample weight
    (1 − W)·F·S/G1. Component 0, glossy reflection, front side.
    """

    kind, flags = "GlossyReflection", lobes.flag("GlossyReflection", "FrontSide")

    def __init__(self, sea: Sea):
        self.sea = sea

    def _terms(self, si, wo, active):
        """D, S, G1(ωi), the density and ωi·m at the half vector m (None where a scalar
        variant's lane is inactive)."""
        wi = si.wi
        m = vector.half_vector(wi, wo)
        cos_im, cos_om = vector.dot(wi, m), vector.dot(wo, m)
        active = active & (wi.z > 0) & (wo.z > 0) & (cos_im > 0) & (cos_om > 0)
        if lobes.none(active):
            return None
        distr, sea = self.sea.distribution(), self.sea
        lambda_i = distr.smith_lambda(sea.to_wind(wi))
        lambda_o = distr.smith_lambda(sea.to_wind(wo))
        D = distr.ndf(sea.to_wind(m))
        S = 1.0 / (1.0 + lambda_i + lambda_o) if sea.shadowing else 1.0
        g1 = 1.0 / (1.0 + lambda_i)
        pdf = microfacet.pdf_visible_reflection(D, g1, wi)
        return SimpleNamespace(m=m, cos_im=cos_im, D=D, S=S, g1=g1, pdf=pdf, active=active)

    def eval_pdf(self, ctx, si, wo, active):
        t = self._terms(si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        shape = t.D * t.S / dr.maximum(4.0 * si.wi.z, 1e-30)
        value = self._reflect(ctx, si, wo, t, shape, t.active)
        return dr.select(t.active, value, 0.0), dr.select(t.active, t.pdf, 0.0)

    def sample_weight(self, ctx, si, wo, active):
        """(1 − W)·F·S/G1(ωi): D and 4 cosθi cancel against the density."""
        t = self._terms(si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        ok = t.active & (t.pdf > 0)
        value = self._reflect(ctx, si, wo, t, t.S * (1.0 + self.sea.distribution()
                                                     .smith_lambda(self.sea.to_wind(si.wi))), ok)
        return dr.select(ok, value, 0.0), dr.select(t.active, t.pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        """ωi reflected about a visible normal of the slopes (Mitsuba's exact Beckmann
        sampler)."""
        m = self.sea.distribution().sample_visible(self.sea.to_wind(si.wi), sample2)
        wo = vector.reflect(si.wi, self.sea.from_wind(m))
        return wo, wo.z > 0

    def weight(self, ctx, si, active):
        """(1 − W)·mean F(cosθi): an estimate of the glint's albedo."""
        eta, k = self.sea.index(si, active)
        return dr.mean(self.sea.glint_share() * fresnel.exact(si.wi.z, eta, k))

    def _reflect(self, ctx, si, wo, t, factor, active):
        """(1 − W)·factor·F at the facet: per channel, and in polarized variants Fresnel's
        Mueller matrix of the reflection (as ``roughconductor``)."""
        eta, k = self.sea.index(si, active)
        scale = self.sea.glint_share() * factor
        if not mi.is_polarized:
            return fresnel.exact(t.cos_im, eta, k) * scale
        F = fresnel.polarized_reflection(si.wi, wo, t.m, eta, k,
                                         ctx.mode == mi.TransportMode.Radiance)
        return F @ mi.Spectrum(mi.UnpolarizedSpectrum(scale))


class Whitecaps(lobes.CosineLobe):
    """W·ρ/π: the whitecaps' Lambertian lobe (``reflectance`` ρ), component 1."""

    component = 1

    def __init__(self, sea: Sea):
        self.sea = sea

    def albedo(self, si, active):
        return self.sea.coverage() * properties.clip_at(self.sea.whitecaps, si, active)

    def value(self, si, wo, active):
        return self.albedo(si, active) * (dr.inv_pi * wo.z)

    def weight(self, ctx, si, active):
        return dr.mean(self.albedo(si, active))

    def diffuse_reflectance(self, si, active):
        return self.albedo(si, active)


def _whitecaps(props):
    """The whitecaps' reflectance texture from ``whitecaps`` (false: None; true: Koepke's
    0.22; a reflectance: itself)."""
    if "whitecaps" not in props:
        return None
    if isinstance(props["whitecaps"], bool):
        value = properties.boolean(props, PLUGIN, "whitecaps", False)
        return mi.load_dict({"type": "uniform", "value": WHITECAP_REFLECTANCE}) if value \
            else None
    return properties.reflectance(props, PLUGIN, "whitecaps", WHITECAP_REFLECTANCE)


def _wind_direction(props):
    """(cos, sin) of ``wind_direction`` (degrees), None where not given."""
    if "wind_direction" not in props:
        return None
    phi = math.radians(properties.number(props, PLUGIN, "wind_direction", 0.0))
    return math.cos(phi), math.sin(phi)


class Ocean(mi.BSDF):
    r"""
    .. _bsdf-ocean:

    Cox & Munk's wind-roughened sea surface (:monosp:`ocean`)
    ---------------------------------------------------------

    .. pluginparameters::

     * - wind_speed
       - |float|
       - The wind speed U at 12.5 m above the sea, in m/s, within [0, 37.54] (Default: 0.1)
       - |exposed|, |differentiable|

     * - eta, k
       - |spectrum| or |texture|
       - The real and imaginary parts of the water's index of refraction, η > 0, k ≥ 0
         (Default: 1.33, 0)
       - |exposed|, |differentiable|

     * - ext_ior
       - |spectrum| or |texture|
       - The real index of refraction of the medium above the sea, > 0 (Default: 1.000277, air)
       - |exposed|, |differentiable|

     * - shadowing
       - |bool|
       - Mishchenko & Travis's shadowing of the glint (Default: true)

     * - wind_direction
       - |float|
       - The azimuth the wind blows towards, in degrees in the local frame (from the tangent
         towards the bitangent). Given: Cox & Munk's anisotropic slopes along and across it.
         (Default: none, isotropic slopes)

     * - whitecaps
       - |bool|, |spectrum| or |texture|
       - Whitecaps: true for Koepke's effective reflectance 0.22, or their reflectance within
         [0, 1] (Default: false, none)
       - |exposed|, |differentiable| (a reflectance)

    The sunglint of a sea whose surface slopes are Gaussian, with the variances Cox & Munk
    measured from photographs of the sun's glitter (1954, "Measurement of the roughness of the
    sea surface from photographs of the sun's glitter", JOSA 44(11), eqs. 1-3, the clean
    surface), in the BRDF form of Mishchenko & Travis (1997, "Satellite retrieval of aerosol
    properties over the ocean using polarization as well as intensity of reflected sunlight",
    JGR 102(D14), eqs. 8-13):

    .. math::

        f = \frac{F(\omega_i\cdot m)\,P(z_x, z_y)\,S(\omega_i, \omega_o)}
                 {4\cos\theta_i\cos\theta_o\cos^4\theta_m}, \qquad
        P = \frac{1}{\pi\sigma^2} e^{-(z_x^2 + z_y^2)/\sigma^2}, \qquad
        \sigma^2 = 0.003 + 0.00512\,U,

    m the half vector of ωi and ωo and (zx, zy) = −(mx, my)/mz its slopes. P/cos⁴θm is
    Beckmann's distribution D of roughness α = σ: each slope axis has variance σ²/2, and
    Beckmann's exp(−tan²θm/α²) is P's exp(−(zx² + zy²)/σ²) (``mi_brdfs.scattering.ocean``). F is
    the Fresnel reflectance of unpolarized light at the facet for the complex index (η +
    ik)/ext_ior. S = 1/(1 + Λ(ωi) + Λ(ωo)) is the shadowing of Gaussian slopes (Tsang, Kong &
    Shin 1985, as Mishchenko & Travis use it), Λ(μ) = ½[√((1 − μ²)/π) σ/μ e^{−μ²/(σ²(1 −
    μ²))} − erfc(μ/(σ√(1 − μ²)))], which is Smith's Λ of the Beckmann distribution (its
    height-correlated masking-shadowing), computed exactly. ``shadowing = false`` drops S
    (with a warning at load: the albedo then exceeds 1 towards grazing incidence, F·(1 +
    Λ(ωi)) with F = 1).

    **Wind direction** (off by default). With ``wind_direction`` the slopes along and across
    the wind have Cox & Munk's variances σu² = 0.00316 U and σc² = 0.003 + 0.00192 U (their
    Gram-Charlier series without the skewness and peakedness terms): Beckmann's anisotropic D
    with αu² = 2σu² along the wind's azimuth and αv² = 2σc² across it, and Λ with the α of
    each direction's azimuth. Below U = 0.47 m/s σu² would fall under 0.0015, the isotropic
    fit's per-axis variance at U = 0: it is held there (σu² → 0 is a mirror along the wind).

    **Whitecaps** (off by default). With ``whitecaps`` a Lambertian lobe of Koepke's
    effective reflectance 0.22 (1984, "Effective reflectance of oceanic whitecaps", Applied
    Optics 23(11)), or the reflectance given, covers the share W = 2.95·10⁻⁶ U^3.52 of the
    surface (Monahan & O'Muircheartaigh 1980, "Optimal power-law description of oceanic
    whitecap coverage dependence on wind speed", J. Phys. Oceanogr. 10(12)), clipped to 1
    (from U = 37.25 m/s), and the glint the rest: f = W ρ/π + (1 − W) f_glint. W = 0.0098 at
    U = 10 m/s. Neither option costs anything when it is off; each does something in every
    mode, so none is refused.

    **Calm sea, grazing, energy.** Wind speed 0 is taken: Cox & Munk's fit keeps σ² ≥ 0.003
    (α = 0.055, a glint of a few degrees, not a mirror). Values are finite and non-negative at
    every pair: at grazing Λ grows without bound and S → 0; θi = θo = 0 is D's peak, 1/(πσ²);
    exact backscatter and the mirror direction are ordinary pairs. The glint reflects at most
    the light it receives: its sample weight is (1 − W)·F·S/G1(ωi) ≤ F ≤ 1
    (``tests/plugins/test_ocean.py``: for η = 10⁵, F ≈ 1, at wind speeds 0 to 37.54 m/s and θi
    up to 89.9°). Reciprocal: F(ωi·m) = F(ωo·m), D and S are symmetric, the whitecaps
    Lambertian. The glint's peak lies at the mirror direction for a calm sea; towards grazing
    and with wind it moves forward, where F and 1/(cosθi cos⁴θm) grow (2.25° at U = 5 m/s,
    θi = 40°).

    **Sampling.** ωi is reflected about a visible normal of the slope distribution (Heitz &
    d'Eon 2014; Mitsuba's exact Beckmann sampler, in the wind's frame when anisotropic): pdf
    D(m) G1(ωi, m)/(4 cosθi) with G1 = 1/(1 + Λ(ωi)), the same Λ as the value's. With
    whitecaps the glint and the cosine-weighted hemisphere are mixed in proportion to
    (1 − W)·F(cosθi) and W·ρ, with the mixture's pdf. Component 0 is the glint (glossy
    reflection), component 1 the whitecaps (diffuse reflection), front side only.

    **Eradiate.** The parameters are those of Eradiate's ``ocean_mishchenko``
    (src/bsdfs/ocean_mishchenko.cpp in its Mitsuba fork) with its defaults; its
    ``mi.traverse`` exposes wind_speed, eta, k and ext_ior, as here. It reads ``shadowing``
    and ignores it (always shadowed); ``wind_direction`` and ``whitecaps`` are this plugin's
    own (Eradiate's ``ocean_legacy`` has whitecaps of another reflectance). It computes Λ by
    Walter's rational approximation (Mitsuba's ``microfacet.h``) and F by Mishchenko &
    Travis's amplitude matrix. Compared with its values (``tests/plugins/test_ocean_eradiate.py``,
    against validation/eradiate/ocean.json, which ``make eradiate-values`` writes with
    ``eradiate-mitsuba`` 0.5.0 in a virtual environment of its own): 840 direction pairs (the
    grid and random pairs of ``rtls``'s table, exact backscatter at θ = 1°, 3°, …, 89° and
    the mirror direction at the same angles, three azimuths each) for four parameter sets (the
    defaults; U = 10 m/s under ext_ior = 1; a calm sea, U = 0, η = 1.34; a storm, U = 30 m/s,
    η = 1.5 + 0.3i under ext_ior = 1.2). Eradiate's values are finite and non-negative at all.
    They differ from the plugin's by up to 0.62 % (at the mirror direction, θ = 73°, U = 10
    m/s), all of it the rational Λ: the plugin's value times S_approx/S_exact equals
    Eradiate's within float32 rounding at 832, 807, 833 and 789 pairs of the four sets
    (scalar_rgb; 831, 807, 832, 790 in scalar_mono_double), within 10⁻³ where a direction is
    at the normal, which Eradiate moves by 4.9·10⁻⁴ rad (it holds μ ≤ 0.9999999). The rest,
    8, 33, 7 and 51 pairs
    (9, 33, 8, 50), are exact backscatter ωo = ωi, where Eradiate's Fresnel matrix divides by
    |ωi × ωo|⁴ and is 0/0: it returns 0, 10⁻⁶⁵ or values off by factors (0.398 against the
    paper's 0.052 at θ = 5°, defaults, float64); the plugin equals the float64 model there.

    **Polarized variants.** The glint is Fresnel's Mueller matrix of the reflection at the
    facet (``mi.mueller.specular_reflection`` rotated into Mitsuba's Stokes bases, as
    ``roughconductor`` does), scaled by D·S/(4 cosθi); the whitecaps are a depolarizer.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="ocean">
                <float name="wind_speed" value="10"/>
                <float name="eta" value="1.33"/>
                <float name="k" value="0"/>
                <float name="ext_ior" value="1.0"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'ocean', 'wind_speed': 10.0, 'eta': 1.33, 'k': 0.0, 'ext_ior': 1.0}
    """

    def __init__(self, props):
        super().__init__(props)
        self.m_wind_speed = mi.Float(properties.number(props, PLUGIN, "wind_speed",
                                                       DEFAULTS["wind_speed"], *WIND_RANGE))
        self.m_eta = properties.texture(props, PLUGIN, "eta", DEFAULTS["eta"], 0.0,
                                        fresnel.IOR_MAX, lo_open=True)
        self.m_k = properties.texture(props, PLUGIN, "k", DEFAULTS["k"], 0.0, fresnel.IOR_MAX)
        self.m_ext_ior = properties.texture(props, PLUGIN, "ext_ior", DEFAULTS["ext_ior"], 0.0,
                                            fresnel.IOR_MAX, lo_open=True)
        self.m_shadowing = properties.boolean(props, PLUGIN, "shadowing", True)
        self.m_azimuth = _wind_direction(props)
        self.m_wind_direction = None if self.m_azimuth is None else \
            float(props["wind_direction"])
        self.m_whitecaps = _whitecaps(props)
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        if not self.m_shadowing:
            properties.warn(PLUGIN, "shadowing = false: without Mishchenko & Travis's "
                                    "shadowing the glint's albedo exceeds 1 towards grazing "
                                    "incidence (F·(1 + Λ(ωi)), unbounded); values kept")

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobes from the parameters as they are now (the wind speed opaque: a new value
        updates the kernel's inputs, not its code)."""
        dr.make_opaque(self.m_wind_speed)
        sea = Sea(self.m_wind_speed, self.m_azimuth, self.m_eta, self.m_k, self.m_ext_ior,
                  self.m_shadowing, self.m_whitecaps)
        whitecaps = [] if self.m_whitecaps is None else [Whitecaps(sea)]
        self.lobes = lobes.Mixture([Glint(sea)] + whitecaps)

    def traverse(self, cb):
        if dr.is_jit_v(mi.Float):  # a Python float cannot be updated in scalar variants
            cb.put("wind_speed", self.m_wind_speed, mi.ParamFlags.Differentiable)
        for name in ("eta", "k", "ext_ior"):
            cb.put(name, getattr(self, f"m_{name}"), mi.ParamFlags.Differentiable)
        if self.m_whitecaps is not None:
            cb.put("whitecaps", self.m_whitecaps, mi.ParamFlags.Differentiable)

    def to_string(self):
        index = ",\n".join(f"  {name} = {properties.indent(getattr(self, f'm_{name}'))}"
                           for name in ("eta", "k", "ext_ior"))
        return (f"Ocean[\n  wind_speed = {self.m_wind_speed},\n"
                f"  wind_direction = {self.m_wind_direction},\n{index},\n"
                f"  shadowing = {self.m_shadowing},\n"
                f"  whitecaps = {properties.indent(self.m_whitecaps)}\n]")
