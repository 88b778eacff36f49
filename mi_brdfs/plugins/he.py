"""
He, Torrance, Sillion & Greenberg's (1991) physically based BRDF (HTSG): a specular delta, a
directional diffuse lobe from Kirchhoff's scattering by a Gaussian random surface, and a
uniform diffuse term; the terms in :mod:`mi_brdfs.scattering.he`, the directional diffuse lobe
sampled from a density tabulated from the float64 reference (:mod:`mi_brdfs.reference.he`) by
the sampler of measured data (:class:`mi_brdfs.measured.warp.Sampler`).
"""

from __future__ import annotations

import dataclasses
import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..measured import warp
from ..reference import he as reference
from ..scattering import he as terms
from . import empirical, lobes, properties

PLUGIN = "he"

#: The phase variance g above which the sampler's density takes Beckmann's asymptote e^(−c/g)/g
#: in place of a series summed to convergence (the ``paper`` reading's): that sum's cost grows
#: as √g (hours at σ0 = 1000 µm), and above g = 1000 the asymptote differs from it by about
#: 1/g, which a sampling density, whose pdf is exact whatever its shape, can spare.
SAMPLER_ROUGH = 1e3


#: Mitsuba's visible range (µm; MI_CIE_MIN, MI_CIE_MAX), into which a wavelength is clamped.
VISIBLE = (0.36, 0.83)

#: The ranges (µm) of σ0 and τ: refused outside them at load; a value set later through
#: ``mi.traverse`` (an optimiser's step can leave them) is clipped into them where the lobes
#: read it. τ ≥ 1 nm: a shorter autocorrelation length describes no surface of Gaussian
#: heights (and τ = 0 makes the shadowing 0/0).
SIGMA0_RANGE = (0.0, 1e3)
TAU_RANGE = (1e-3, 1e4)
#: The parameters the albedo depends on: a preset that gives them all is warned about as such.
ENERGY_NAMES = ("sigma0", "tau", "eta", "k", "material", "specular_reflectance",
                "diffuse_reflectance", "variant", "terms")


def wavelengths(si):
    """λ in µm per channel: the sampled wavelengths in spectral variants (clamped into
    :data:`VISIBLE`: a default interaction has λ = 0), else the RGB or monochrome ones of
    :mod:`mi_brdfs.scattering.he`."""
    if mi.is_spectral:
        return dr.clip(si.wavelengths * 1e-3, *VISIBLE)
    if mi.is_monochromatic:
        return mi.UnpolarizedSpectrum(terms.MONO_WAVELENGTH)
    return mi.UnpolarizedSpectrum(mi.Color3f(*terms.RGB_WAVELENGTHS))


def _representative(tex, default: float) -> float:
    """One value of a texture for the sampler's density: the middle of its range where that
    can be known at load, else ``default``."""
    r = properties.texture_range(tex)
    return default if r is None else 0.5 * (r[0] + r[1])


def _length(props, name: str, default: float, bounds: tuple[float, float]) -> float:
    """A length in µm within ``bounds``; ParameterError naming the range and the unit."""
    value = properties.number(props, PLUGIN, name, default)
    if not bounds[0] <= value <= bounds[1]:
        raise ParameterError(PLUGIN, name, value,
                             f"must be within [{bounds[0]:g}, {bounds[1]:g}] (µm)")
    return value


class Surface:
    """The surface's parameters as the lobes use them: σ0 and τ (µm), the index η + ik
    (textures), the reading of the paper and the series' length."""

    def __init__(self, sigma0, tau, eta, k, reading: str, count):
        self.sigma0, self.tau, self.eta, self.k = sigma0, tau, eta, k
        self.reading_name, self.reading = reading, terms.READINGS[reading]
        self.count = count

    def channels(self, si, active):
        """(λ, η, k) per channel at ``si``."""
        return wavelengths(si), self.eta.eval(si, active), self.k.eval(si, active)

    def key(self) -> tuple:
        """σ0, τ, a representative η and k, the reading and the series' length."""
        return (properties.as_float(self.sigma0), properties.as_float(self.tau),
                _representative(self.eta, 1.5), _representative(self.k, 0.0),
                self.reading_name, self.count)

    def model(self, reading=None) -> reference.HTSG:
        """The float64 reference of this surface at the RGB wavelengths and a representative
        index, in ``reading`` (a :class:`mi_brdfs.reference.he.Variant`; default: its own)."""
        sigma0, tau, eta, k = self.key()[:4]
        return reference.HTSG(sigma0, tau, wavelength=list(terms.RGB_WAVELENGTHS), eta=eta,
                              k=k, variant=reading or self.reading_name,
                              terms="variant" if self.count is None else self.count)

    def sampler(self) -> warp.Sampler:
        """The directional diffuse lobe's sampler, built from the float64 reference (shared
        by every instance of this surface)."""
        def directional_diffuse():
            reading = reference.VARIANTS[self.reading_name]
            if reading.terms is None and reading.rough_threshold is None and self.count is None:
                reading = dataclasses.replace(reading, rough_threshold=SAMPLER_ROUGH)
            model = self.model(reading)
            return lambda wi, wo: model.directional_diffuse(wi, wo).mean(axis=-1)

        return empirical.sampler((PLUGIN, *self.key()), directional_diffuse)


class Specular(lobes.DeltaLobe):
    """The coherent reflection, a delta at the mirror direction of weight ρ_s times the
    specular reflectance (component 0)."""

    kind, flags = "DeltaReflection", lobes.flag("DeltaReflection", "FrontSide")

    def __init__(self, surface: Surface, factor):
        self.surface, self.factor, self.component = surface, factor, 0

    def rho(self, si, active):
        """ρ_s = F(θi) e^(−g) S per channel."""
        s = self.surface
        lam, eta, k = s.channels(si, active)
        return terms.specular_weight(si.wi.z, s.sigma0, s.tau, lam, eta, k, s.reading)

    def delta_value(self, si, active):
        return self.rho(si, active) * properties.clip_at(self.factor, si, active, 0.0, math.inf)

    def weight(self, ctx, si, active):
        """ρ_s detached from σ0, τ, η and k (times the factor): the directional diffuse
        lobe's weight and density, tabulated when the parameters are set, do not follow
        them either, so the sampling probabilities are detached from them alike."""
        factor = properties.clip_at(self.factor, si, active, 0.0, math.inf)
        return dr.mean(dr.detach(self.rho(si, active)) * factor)


class DirectionalDiffuse(lobes.TabulatedLobe):
    """ρ_dd times the specular reflectance (component 1), sampled from its tabulated
    density."""

    def __init__(self, surface: Surface, factor):
        self.surface, self.factor, self.component = surface, factor, 1

    @property
    def sampler(self) -> warp.Sampler:
        """The tabulated sampler, built when first needed (``eval`` alone needs none: a fit
        that moves σ0 and τ at every step builds none)."""
        return self.surface.sampler()

    def value(self, si, wo, active):
        s = self.surface
        lam, eta, k = s.channels(si, active)
        rho = terms.directional_diffuse(si.wi, wo, s.sigma0, s.tau, lam, eta, k, s.reading,
                                        s.count)
        return rho * wo.z * properties.clip_at(self.factor, si, active, 0.0, math.inf)

    def weight(self, ctx, si, active):
        factor = properties.clip_at(self.factor, si, active, 0.0, math.inf)
        return self.sampler.albedo(si.wi) * dr.mean(factor)


class He(mi.BSDF):
    r"""
    .. _bsdf-he:

    He-Torrance-Sillion-Greenberg reflectance (:monosp:`he`)
    --------------------------------------------------------

    .. pluginparameters::

     * - sigma0
       - |float|
       - rms roughness σ0 of the surface's heights in µm, within [0, 1000] (Default: 0.18;
         a value set through ``mi.traverse`` outside the range acts as its nearest end)
       - |exposed|, |differentiable|

     * - tau
       - |float|
       - autocorrelation length τ of the heights in µm, within [0.001, 10000] (Default: 3;
         a value set through ``mi.traverse`` outside the range acts as its nearest end)
       - |exposed|, |differentiable|

     * - material
       - |string|
       - A conductor of Mitsuba's measured spectra (``Au``, ``Al``, ...: as ``roughconductor``
         names them) for η and k (Default: none: ``eta`` and ``k``)

     * - eta, k
       - |spectrum| or |texture|
       - The complex index of refraction η + ik of the surface, each finite and ≥ 0, not both
         0 (Default: η = 1.5, k = 0, a dielectric)
       - |exposed|, |differentiable|

     * - specular_reflectance
       - |spectrum| or |texture|
       - A factor on the specular and directional diffuse terms, ≥ 0 (Default: 1; Ngan et
         al.'s fits use it, with values above 1)
       - |exposed|, |differentiable|

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - The albedo a of the uniform diffuse term a/π, within [0, 1] (Default: 0: no term)
       - |exposed|, |differentiable|

     * - variant
       - |string|
       - The reading of the paper: ``westin`` (Westin et al.'s reference code), ``paper`` (as
         printed) or ``holzschuch`` (Holzschuch & Pacanowski's) (Default: ``westin``)

     * - terms
       - |int|
       - The length of the series of the directional diffuse term (Default: the reading's:
         48 for ``westin``, 128 for ``paper``, 10 for ``holzschuch``)

     * - preset
       - |string|
       - A published fit that fills every parameter the scene does not give (explicit ones
         win): ``ngan:<material>``, Ngan et al. 2005's He fit to a MERL material (westin
         reading; ``specular_reflectance`` its albedo); docs/presets.md lists the materials,
         the conversion and what differs from bbm's model. The fit's own terms keep the
         albedo under 1, but its albedo A, up to 7470, scales the coherent delta too: a
         preset warns, naming itself, where that delta reflects more than 1 (Default: none)

    He, Torrance, Sillion & Greenberg (1991, "A Comprehensive Physical Model for Light
    Reflection", SIGGRAPH) derive reflection from Kirchhoff's scattering by a surface of
    Gaussian heights (rms σ0, autocorrelation length τ) at wavelength λ:

    .. math::

        f = \rho_s\,\frac{\delta(\omega_o - M(\omega_i))}{\cos\theta_o} + \rho_{dd} +
        \frac{a}{\pi},

    three components: 0, the **specular** (coherent) reflection, a delta at the mirror
    direction M(ωi) of weight ρ_s = F(θi) e^(−g) S (Eqs. 73-74), as Mitsuba's
    ``conductor`` has one; 1, the **directional diffuse** lobe ρ_dd = F G S D/(π cosθi
    cosθo), F the unpolarized Fresnel reflectance at the local angle, D a series in the
    phase variance g = (2πσ(cosθi + cosθo)/λ)² (Eqs. 71, 76-79);
    2, the **uniform diffuse** term, where ``diffuse_reflectance`` is not 0. S is Smith's
    shadowing of the Gaussian surface and σ the roughness it leaves visible (Eqs. 24-25,
    80-83); ``specular_reflectance`` multiplies the first two. The terms and their
    derivations: ``mi_brdfs.scattering.he`` and the float64 reference
    ``mi_brdfs.reference.he``.

    **Readings.** The paper has been read three ways (bsdfbenchmark/bbm documents them):
    ``westin`` (the default) has the errata's e^(−a²) in the shadowing and v_xy in wave
    numbers in the series, and takes Beckmann's rough-surface asymptote for g > 18.5; it is the
    only reading that tends to a Beckmann microfacet lobe of α = 2σ/τ as the surface roughens
    and keeps the albedo at most 1, and the one Ngan et al.'s (2005) fits used. ``paper`` is
    the equations as printed, ``holzschuch`` Holzschuch & Pacanowski's reading, the series
    cut at 10 terms. Both read v_xy in unit vectors, which makes the lobe (2π/λ)² times too
    strong at any roughness: their albedo exceeds 1 from nearly smooth surfaces on, e.g. 6.3
    for glass (the default index) at σ0 = 0.05 µm, τ = 3 µm and normal incidence, 1.4 for a
    metal at σ0 = 0.002 µm (docs/models.md; the plugin warns at load).

    **The series.** Summed in logarithms over a window of ``terms`` consecutive orders (from
    m = 1; centred on m ≈ g for ``paper``): against the converged float64 series the window
    leaves less than 10⁻⁶ up to g = 22 with 48 terms (``westin`` needs g ≤ 18.5) and up to
    g = 163 with 128 centred ones; beyond, raise ``terms``.

    **Wavelengths.** Spectral variants evaluate every term at each sampled wavelength; RGB
    variants at λ = 0.645, 0.526 and 0.444 µm for red, green and blue (the wavelengths of
    bsdfbenchmark/bbm's RGB configuration, with which Ngan et al.'s fits are evaluated);
    monochrome ones at 0.55 µm. η and k are read per channel as ``roughconductor`` reads them.

    **Sampling.** The delta is picked with probability in proportion to ρ_s, the uniform
    diffuse term by the cosine-weighted hemisphere in proportion to a, and the directional
    diffuse lobe in proportion to its albedo, from a density tabulated per incident angle
    through the half vector (the sampler of ``merl``: ``mi_brdfs.measured.warp``), built from
    the float64 reference at the RGB wavelengths when the surface's parameters are set, with
    an exact pdf and a tenth of it the cosine's. A sample of the delta has ``bs.pdf`` = the
    probability of picking it, as Mitsuba's ``plastic``.

    **Polarized variants.** The model averages the two polarizations: values are
    depolarizers. The BSDF is one-sided (0 for either direction below the surface).

    .. tabs::
        .. code-tab:: xml

            <bsdf type="he">
                <float name="sigma0" value="0.18"/>
                <float name="tau" value="3"/>
                <string name="material" value="Al"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'he', 'sigma0': 0.18, 'tau': 3.0, 'material': 'Al'}
    """

    def __init__(self, props):
        super().__init__(props)
        given = set(props.keys())  # what the scene gives, before the preset fills the rest
        properties.preset(props, PLUGIN)  # a preset's parameters, where the scene gives none
        self.m_sigma0 = mi.Float(_length(props, "sigma0", terms.DEFAULT_SIGMA0, SIGMA0_RANGE))
        self.m_tau = mi.Float(_length(props, "tau", terms.DEFAULT_TAU, TAU_RANGE))
        self.m_eta, self.m_k, self.m_material = properties.ior(props, PLUGIN, None)
        self.m_specular_reflectance = properties.texture(props, PLUGIN, "specular_reflectance",
                                                         1.0, 0.0, math.inf)
        diffuse = properties.reflectance(props, PLUGIN, "diffuse_reflectance", 0.0)
        self.m_diffuse_reflectance = None if properties.is_zero(diffuse) else diffuse
        self.m_variant = properties.choice(props, PLUGIN, "variant", "westin",
                                           tuple(terms.READINGS))
        self.m_terms = None if "terms" not in props else \
            int(properties.number(props, PLUGIN, "terms", 1, 1, 4096))
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        self._warn_energy(props, diffuse, given)

    def _warn_energy(self, props, diffuse, given):
        """
        Warn (values kept) where the albedo can exceed 1: the uniform diffuse term is added,
        not coupled, and the ``paper`` and ``holzschuch`` readings' directional diffuse term
        alone exceeds 1 from nearly smooth surfaces on (its albedo tabulated at the RGB
        wavelengths). Where a preset gives every value the albedo depends on (``given``: the
        names the scene gives), :meth:`_warn_preset` says what the preset does instead.
        """
        if "preset" in given and not given & set(ENERGY_NAMES):
            self._warn_preset(props)
            return
        properties.warn_sum(props, PLUGIN, ("diffuse_reflectance", diffuse),
                            ("specular_reflectance", self.m_specular_reflectance),
                            "the uniform diffuse term is added, not coupled, so the albedo "
                            "can exceed 1 towards grazing incidence, where Fresnel's "
                            "reflectance tends to 1")
        peak = self.lobes.lobes[1].sampler.albedo_max
        factor = properties.upper_bound(props, "specular_reflectance",
                                        self.m_specular_reflectance)
        peak *= 1.0 if factor is None else float(max(factor))
        if peak > 1.0 + 1e-3:
            why = ("specular_reflectance included" if self.m_variant == "westin" else
                   "only westin's reading keeps it under 1: with v_xy read in unit vectors "
                   "the lobe is (2π/λ)² times too strong, smooth or rough")
            properties.warn(PLUGIN, f"the directional diffuse term's albedo reaches {peak:.3g}"
                                    f" > 1 in the {self.m_variant} reading ({why}); values "
                                    f"kept")

    def _warn_preset(self, props):
        """
        A preset's values are the published fit's, whose own terms, A·ρ_dd + ρd/π, reflect
        at most 0.48 of the light in every fit (docs/presets.md): no warning about them. What
        the plugin adds, He et al.'s coherent delta, is scaled by the fit's A as well, up to
        7470 where A makes up for the Fresnel reflectance of an index near 1: warn, naming the
        preset, where its weight A·ρ_s exceeds 1 at some θi ≤ 89° (the reference's ρ_s at the
        RGB wavelengths).
        """
        factor = np.asarray(properties.upper_bound(props, "specular_reflectance",
                                                   self.m_specular_reflectance))
        theta = np.radians(np.arange(90.0))
        wi = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
        weight = self.lobes.lobes[0].surface.model().specular(wi) * factor
        if weight.max() > 1.0 + 1e-3:
            angle = int(np.unravel_index(np.argmax(weight), weight.shape)[0])
            properties.warn(PLUGIN, f"preset {props['preset']}: the fit's specular_reflectance "
                                    f"A (up to {factor.max():.4g}) also scales the coherent "
                                    f"delta, which the fitted model has not: the delta "
                                    f"reflects up to {weight.max():.4g} of the light at θi = "
                                    f"{angle}°; values kept as published (docs/presets.md)")

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobes from the parameters as they are now (σ0 and τ opaque: a new value updates
        the kernel's inputs, not its code), and the directional diffuse lobe's sampler for
        them."""
        dr.make_opaque(self.m_sigma0, self.m_tau)
        # values set through mi.traverse are not checked: clipped into the accepted ranges
        surface = Surface(properties.clip(self.m_sigma0, *SIGMA0_RANGE),
                          properties.clip(self.m_tau, *TAU_RANGE), self.m_eta, self.m_k,
                          self.m_variant, self.m_terms)
        factor = self.m_specular_reflectance
        diffuse = [lobes.Diffuse(self.m_diffuse_reflectance, component=2)] \
            if self.m_diffuse_reflectance is not None else []
        self.lobes = lobes.Mixture([Specular(surface, factor),
                                    DirectionalDiffuse(surface, factor)] + diffuse)

    def traverse(self, cb):
        if dr.is_jit_v(mi.Float):  # a Python float cannot be updated in scalar variants
            cb.put("sigma0", self.m_sigma0, mi.ParamFlags.Differentiable)
            cb.put("tau", self.m_tau, mi.ParamFlags.Differentiable)
        cb.put("eta", self.m_eta, mi.ParamFlags.Differentiable)
        cb.put("k", self.m_k, mi.ParamFlags.Differentiable)
        cb.put("specular_reflectance", self.m_specular_reflectance,
               mi.ParamFlags.Differentiable)
        if self.m_diffuse_reflectance is not None:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance,
                   mi.ParamFlags.Differentiable)

    def to_string(self):
        ior = f"material = \"{self.m_material}\"" if self.m_material else \
            f"eta = {properties.indent(self.m_eta)},\n  k = {properties.indent(self.m_k)}"
        return (f"He[\n  sigma0 = {self.m_sigma0},\n  tau = {self.m_tau},\n  {ior},\n"
                f"  variant = \"{self.m_variant}\",\n  terms = {self.m_terms},\n"
                f"  specular_reflectance = {properties.indent(self.m_specular_reflectance)},"
                f"\n  diffuse_reflectance = {properties.indent(self.m_diffuse_reflectance)}\n]")
