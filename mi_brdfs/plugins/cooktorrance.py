"""
The textbook Cook-Torrance BRDF (Beckmann D, V-cavity G, exact Fresnel), with the switches that
make it comparable to Mitsuba's built-ins: GGX, Smith's masking as Mitsuba computes it, Schlick's
Fresnel, visible-normal sampling and the paper's diffuse base.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Callable, NamedTuple

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..scattering import fresnel
from ..scattering import microfacet as mf
from ..scattering.vector import dot, half_vector, reflect_f32
from . import _common

PLUGIN = "cooktorrance"
SHADOWING = ("vcavity", "smith")
FRESNEL = ("exact", "schlick", "none")

#: The named conductor used when neither ``material`` nor ``eta`` is given: copper, the metal
#: of Cook & Torrance's own figures (and Mitsuba 0.6's conductor default).
DEFAULT_MATERIAL = "Cu"


def conductor_names() -> list[str]:
    """
    The names ``material`` accepts: the conductors of Mitsuba's IOR data, found through the file
    resolver as Mitsuba finds their ``data/ior/<name>.eta.spd`` files for roughconductor.
    """
    folder = Path(str(mi.file_resolver().resolve("data/ior")))
    names = {p.name[: -len(".eta.spd")] for p in folder.glob("*.eta.spd")}
    return sorted(n for n in names if (folder / f"{n}.k.spd").is_file())


def _material_ior(name):
    """
    The (η, k) textures of a named conductor, taken from a ``roughconductor`` with that
    ``material``: the same data, resolved as Mitsuba resolves it in the current variant (an RGB
    colour in RGB variants, the measured spectra in spectral ones, luminance in mono).
    """
    names = conductor_names()
    if not isinstance(name, str) or name not in names:
        common = ", ".join(n for n in ("Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ir", "Li", "Rh", "W")
                           if n in names)
        raise ParameterError(PLUGIN, "material", name,
                             f"must name one of Mitsuba's {len(names)} measured conductors, e.g. "
                             f"{common} (all: mi_brdfs.plugins.cooktorrance.conductor_names())")
    found = {}

    class Collect(mi.TraversalCallback):
        def put(self, key, obj, flags):
            found[key] = obj

    mi.load_dict({"type": "roughconductor", "material": name}).traverse(Collect())
    return found["eta"], found["k"]


def conductor_ior(name: str, si=None):
    """
    (η, k) of a named conductor as float64 arrays, one value per channel of the current
    variant, the values ``cooktorrance`` and ``roughconductor`` use: RGB variants 3, mono 1,
    spectral ones the measured data at the wavelengths of ``si`` (give one there: a default
    ``mi.SurfaceInteraction3f()`` has wavelengths 0, outside the data, where η = k = 0).
    """
    eta, k = _material_ior(name)
    si = si if si is not None else mi.SurfaceInteraction3f()
    return tuple(np.array(mi.unpolarized_spectrum(t.eval(si)), dtype=np.float64).ravel()
                 for t in (eta, k))


def _constant_channels(props, name) -> list[float] | None:
    """The per-channel values of a float or ``<rgb>`` property, else None (a texture)."""
    kind = props.type(name)
    T = mi.Properties.Type
    if kind in (T.Float, T.Integer):
        return [float(props[name])]
    if kind == T.Color:
        return [float(c) for c in props[name]]
    return None


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
        return (*_material_ior(name), name)
    if not has_eta:
        if has_k:
            raise ParameterError(PLUGIN, "k", props["k"],
                                 "needs eta as well (or a material instead of both)")
        if not needed:
            return None, None, None
        return (*_material_ior(DEFAULT_MATERIAL), DEFAULT_MATERIAL)
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


class _Flat(NamedTuple):
    """cooktorrance's constant parameters as Python floats, for scalar variants."""

    alpha: float                 # clamped to ALPHA_MIN
    specular: Callable           # (cosθ, s) → [ks·F(cosθ)·s per channel] (F ≡ 1 for 'none')
    sampler: object              # mi.MicrofacetDistribution(α) for Smith's visible normals


def build() -> type:
    """Define the ``cooktorrance`` plugin class on the current variant's ``mi.BSDF``."""
    tools = _common.variant_tools()
    select, new_sample, none = tools.select, tools.new_sample, tools.none
    depolarize = tools.depolarize
    GLOSSY = _common.flag("GlossyReflection")
    DIFFUSE = _common.flag("DiffuseReflection")
    GLOSSY_FLAGS = _common.flag("GlossyReflection", "FrontSide")
    DIFFUSE_FLAGS = _common.flag("DiffuseReflection", "FrontSide")
    # Bound once: scalar variants call these per ray, and each `mi.` lookup costs ~0.1 µs there.
    Spectrum, Float, UInt32, Vector3f = mi.Spectrum, mi.Float, mi.UInt32, mi.Vector3f
    reflect = mi.reflect
    cosine_hemisphere = mi.warp.square_to_cosine_hemisphere
    INV_PI = dr.inv_pi
    ALPHA_MIN = mf.ALPHA_MIN
    ALPHA_MIN_32 = float(np.float32(ALPHA_MIN))  # a texture holding 1e-4 holds it in float32
    ndf, vcavity_g, vcavity_g1 = mf.ndf, mf.vcavity_g, mf.vcavity_g1
    smith_g1_mitsuba = mf.smith_g1_mitsuba
    pdf_visible_reflection, pdf_ndf = mf.pdf_visible_reflection, mf.pdf_ndf
    jacobian = mf.reflection_jacobian
    sample_visible, sample_ndf = mf.sample_visible, mf.sample_ndf
    sample_vcavity_visible = mf.sample_vcavity_visible
    FRESNEL_TERMS = {"exact": fresnel.exact, "schlick": fresnel.schlick}
    exact_channels = fresnel.exact_channels
    reflection_floats = mf.reflection_floats
    jit = tools.jit
    # Scalar variants: one operation on a colour costs ~0.4 µs, on a Python float ~0.05 µs, so
    # the lobe is computed channel by channel on floats there, from α, ks, η and k read once
    # when they are constant (spectral variants evaluate them per call: they depend on the
    # wavelengths).
    flat_ok = not tools.jit and not mi.is_spectral
    DIFFERENTIABLE = mi.ParamFlags.Differentiable
    DISCONTINUOUS = mi.ParamFlags.Differentiable | mi.ParamFlags.Discontinuous

    class CookTorrance(mi.BSDF):
        r"""
        .. _bsdf-cooktorrance:

        Cook-Torrance microfacet reflectance (:monosp:`cooktorrance`)
        ------------------------------------------------------------

        .. pluginparameters::

         * - alpha
           - |float| or |texture|
           - Roughness α: for Beckmann the RMS slope of the microfacets, Cook & Torrance's *m*
             (the same quantity as ``roughconductor``'s ``alpha``), finite and ≥ 0; values below
             10⁻⁴ are clamped to 10⁻⁴, as Mitsuba does (Default: 0.1)
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

        **Limits.** α is clamped to ≥ 10⁻⁴. The microfacet normals are sampled without the
        float32 collapse of the textbook formula (see :func:`mi_brdfs.scattering.microfacet.
        sample_ndf`), but below α ≈ 10⁻³ the lobe is narrower than a χ² histogram resolves:
        there the plugin behaves as a smooth mirror whose albedo tends to F (measured in the
        tests). Single scattering loses energy at high α and grazing angles (F = 1, V-cavity,
        α = 0.5: E = 0.89 at normal incidence); the diffuse base is added, not coupled, so
        ρd + E_spec ≤ 1 is up to the user.

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
            for name in ("alpha_u", "alpha_v"):
                _common.reject(props, PLUGIN, name, "cooktorrance is isotropic: give alpha")
            #: Roughness α (Beckmann: RMS slope).
            self.m_alpha = _common.texture(props, PLUGIN, "alpha", 0.1, lo=0.0, hi=math.inf)
            low = _common.texture_range(self.m_alpha)
            if low is not None and low[0] < ALPHA_MIN_32:
                _common.warn(PLUGIN, f"alpha = {low[0]:g} is clamped to {ALPHA_MIN:g}, as in "
                                     f"Mitsuba's microfacet models")
            #: 'beckmann' or 'ggx'.
            self.m_distribution = _common.choice(props, PLUGIN, "distribution", "beckmann",
                                                 mf.DISTRIBUTIONS)
            #: 'vcavity' or 'smith'.
            self.m_shadowing = _common.choice(props, PLUGIN, "shadowing", "vcavity", SHADOWING)
            #: 'exact', 'schlick' or 'none'.
            self.m_fresnel = _common.choice(props, PLUGIN, "fresnel", "exact", FRESNEL)
            #: Relative IOR η + ik, and the material it came from (None: given as eta, k).
            self.m_eta, self.m_k, self.m_material = _read_ior(props, self.m_fresnel != "none")
            if self.m_fresnel == "none" and self.m_eta is not None:
                _common.warn(PLUGIN, "fresnel = none: eta and k (or the material) are not used")
            #: Factor on the microfacet lobe.
            self.m_specular_reflectance = _common.reflectance(props, PLUGIN,
                                                              "specular_reflectance", 1.0)
            #: Albedo of the Lambertian base; None when it is the constant 0 (no lobe).
            diffuse = _common.reflectance(props, PLUGIN, "diffuse_reflectance", 0.0)
            self.m_diffuse_reflectance = None if _common.is_zero(diffuse) else diffuse
            #: Sample visible normals (else D·cosθ).
            self.m_sample_visible = _common.boolean(props, PLUGIN, "sample_visible", True)
            self._fresnel_term = FRESNEL_TERMS.get(self.m_fresnel)
            #: Scalar variants: :func:`mf.reflection_floats` of this configuration.
            self._reflection_floats = functools.partial(
                reflection_floats, self.m_distribution, self.m_shadowing == "smith",
                self.m_sample_visible)
            #: The constant parameters as floats in a scalar variant (:class:`_Flat`, see
            #: flat_ok), else None.
            self._flat = None
            self.parameters_changed()
            # Lobe 0 is the microfacet lobe (as roughconductor's only one), lobe 1 the diffuse.
            components = [GLOSSY_FLAGS]
            if self.m_diffuse_reflectance is not None:
                components.append(DIFFUSE_FLAGS)
            self.m_components = components  # a copy crosses to C++: assign, don't append
            self.m_flags = GLOSSY_FLAGS | (DIFFUSE_FLAGS if len(components) > 1 else 0)

        # -- the maths: the same terms for eval, pdf, eval_pdf and sample ------------------

        def _lobes(self, ctx):
            """Which lobes the context enables: (microfacet, diffuse)."""
            return (ctx.is_enabled(GLOSSY, 0),
                    self.m_diffuse_reflectance is not None and ctx.is_enabled(DIFFUSE, 1))

        def _alpha(self, si, active):
            return dr.maximum(self.m_alpha.eval_1(si, active), ALPHA_MIN)

        def _fresnel(self, si, cos_theta, active):
            """F per channel at the cosine between ωi and the facet normal (1 for 'none')."""
            term = self._fresnel_term
            if term is None:
                return 1.0
            return term(cos_theta, self.m_eta.eval(si, active), self.m_k.eval(si, active))

        def _p_microfacet(self, si, active):
            """Probability of sampling the microfacet lobe when both lobes are on."""
            flat = self._flat
            if flat is not None:  # scalar: on the floats (5× faster than on a colour)
                weights = flat.specular(si.wi.z, 1.0)
                ws = sum(weights) / len(weights)
                rho = self.m_diffuse_reflectance.eval(si, active)
                wd = sum(rho) / len(rho)
            else:
                ws = dr.mean(self.m_specular_reflectance.eval(si, active) *
                             self._fresnel(si, si.wi.z, active))
                wd = dr.mean(self.m_diffuse_reflectance.eval(si, active))
            total = ws + wd
            return select(total > 0, ws / select(total > 0, total, 1.0), 1.0)

        def _microfacet(self, si, wi, wo, active, weight=False):
            """
            (f·cosθo, pdf) of the microfacet lobe, for ωi and ωo above the surface (given as
            ``mi.Vector3f``, or in scalar variants as (x, y, z) tuples of Python floats).

            With ``weight`` (for :meth:`sample`): (f·cosθo/pdf, pdf) from the same terms; in JIT
            variants the weight in closed form, where D and 4 cosθi cancel: ks·F·G1(ωo) (Smith's
            visible normals), ks·F·G/G1(ωi) (the V-cavity's), ks·F·G·(ωo·m)/(cosθi cosθm)
            (D·cos).
            """
            if not jit:  # one call per ray: the same terms, flat, on Python floats
                if not active:
                    return Spectrum(0.0), 0.0
                flat = self._flat
                alpha = flat.alpha if flat is not None else self._alpha(si, True)
                terms = self._reflection_floats(alpha, wi, wo)
                if terms is None:
                    return Spectrum(0.0), 0.0
                dg, pdf, cos_im = terms
                if weight:
                    dg = dg / pdf if pdf > 0.0 else 0.0
                if flat is not None:  # ks·F·factor per channel, one colour built
                    return Spectrum(*flat.specular(cos_im, dg)), pdf
                value = self.m_specular_reflectance.eval(si, True) * dg
                if self._fresnel_term is not None:
                    value = value * self._fresnel(si, cos_im, True)
                return value, pdf
            m = half_vector(wi, wo, Vector3f)
            cos_im, cos_om = dot(wi, m), dot(wo, m)
            # Both directions must see the front of the facet: false only when rounding makes
            # ωi + ωo vanish (grazing, nearly opposite directions).
            active = active & (cos_im > 0) & (cos_om > 0)
            if none(active):
                return Spectrum(0.0), Float(0.0)
            kind = self.m_distribution
            alpha = self._alpha(si, active)
            D = ndf(kind, alpha, m)
            if self.m_shadowing == "smith":
                g1_wi = smith_g1_mitsuba(kind, alpha, wi, m)
                g1_wo = smith_g1_mitsuba(kind, alpha, wo, m)
                G = g1_wi * g1_wo
            else:
                G = vcavity_g(wi, wo, m)
                g1_wi = vcavity_g1(wi, m) if self.m_sample_visible else None
            if self.m_sample_visible:
                pdf = pdf_visible_reflection(D, g1_wi, wi)
            else:
                pdf = pdf_ndf(D, m) * jacobian(wo, m)
            if not weight:  # f·cosθo = ks F D G / (4 cosθi cosθo) · cosθo
                factor = D * G / (4.0 * wi.z)
            elif not self.m_sample_visible:
                factor = G * cos_om / dr.maximum(wi.z * m.z, 1e-30)
            elif self.m_shadowing == "smith":
                factor = g1_wo
            else:
                factor = G / dr.maximum(g1_wi, 1e-30)
            if weight:
                active = active & (pdf > 0)
            value = self.m_specular_reflectance.eval(si, active) * factor
            if self._fresnel_term is not None:
                value = value * self._fresnel(si, cos_im, active)
            return select(active, value, 0.0), select(active, pdf, 0.0)

        def _eval_pdf(self, si, wo, active, lobes, p_microfacet=None):
            """f·cosθo and the pdf of ``sample()`` at ``wo``: the lobes and their mixture (the
            microfacet terms are in :meth:`_microfacet`, which sample() also calls)."""
            use_mf, use_diffuse = lobes
            if jit:
                wi = si.wi
                cos_theta_i, cos_theta_o = wi.z, wo.z
            else:  # tuples of Python floats: 0.1 µs, where a named tuple from attributes costs 0.5
                x, y, cos_theta_i = si.wi
                wi = (x, y, cos_theta_i)
                x, y, cos_theta_o = wo
                wo = (x, y, cos_theta_o)
            active = active & (cos_theta_i > 0) & (cos_theta_o > 0)  # one-sided
            if none(active):
                return Spectrum(0.0), Float(0.0)
            if use_mf:
                value, pdf = self._microfacet(si, wi, wo, active)
            if use_diffuse:
                value_d = self.m_diffuse_reflectance.eval(si, active) * INV_PI * cos_theta_o
                pdf_d = cos_theta_o * INV_PI
                if use_mf:
                    if p_microfacet is None:
                        p_microfacet = self._p_microfacet(si, active)
                    value = value + value_d
                    pdf = p_microfacet * pdf + (1.0 - p_microfacet) * pdf_d
                else:
                    value, pdf = value_d, pdf_d
            if not jit:  # active, or it returned above
                return depolarize(value), pdf
            return select(active, depolarize(value), 0.0), select(active, pdf, 0.0)

        # -- the BSDF interface ---------------------------------------------------------------

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = new_sample()
            lobes = use_mf, use_diffuse = self._lobes(ctx)
            if use_mf and not use_diffuse:
                if not jit:
                    return self._sample_scalar(si, sample1, sample2, active, bs)
                return self._sample_microfacet(si, sample1, sample2, active, bs)
            active = active & (si.wi.z > 0)
            if none(active) or not (use_mf or use_diffuse):
                return bs, Spectrum(0.0)
            p_microfacet = None
            if use_mf:
                alpha = self._alpha(si, active)
                if use_diffuse:
                    p_microfacet = self._p_microfacet(si, active)
                # With the diffuse base, sample1 chose the lobe: rescaled to [0, 1) within the
                # microfacet lobe's share, it still picks the V-cavity's facet.
                u_facet = sample1 if p_microfacet is None else \
                    sample1 / dr.maximum(p_microfacet, 1e-30)
                m = self._sample_normal(si.wi, alpha, sample2, u_facet)
                bs.wo = reflect(si.wi, m)
                bs.sampled_type, bs.sampled_component = UInt32(GLOSSY), UInt32(0)
            if use_diffuse:
                wo = cosine_hemisphere(sample2)
                kind, index = UInt32(DIFFUSE), UInt32(1)
                if use_mf:  # choose a lobe with sample1
                    pick = sample1 < p_microfacet
                    wo = select(pick, bs.wo, wo)
                    kind = select(pick, bs.sampled_type, kind)
                    index = select(pick, bs.sampled_component, index)
                bs.wo, bs.sampled_type, bs.sampled_component = wo, kind, index
            bs.eta = 1.0
            value, pdf = self._eval_pdf(si, bs.wo, active, lobes, p_microfacet)
            bs.pdf = pdf
            ok = active & (pdf > 0)
            return bs, select(ok, value / select(ok, pdf, 1.0), 0.0)

        def _sample_microfacet(self, si, sample1, sample2, active, bs):
            """
            :meth:`sample` of the microfacet lobe alone in JIT variants: its terms at the half
            vector of ``bs.wo`` as stored (so that bs.pdf = pdf(bs.wo) and weight =
            eval/pdf to float32 rounding), with the weight in closed form
            (:meth:`_microfacet`).
            """
            wi = si.wi
            active = active & (wi.z > 0)
            m = self._sample_normal(wi, self._alpha(si, active), sample2, sample1)
            bs.wo = reflect(wi, m)
            bs.sampled_type, bs.sampled_component = UInt32(GLOSSY), UInt32(0)
            bs.eta = 1.0
            active = active & (bs.wo.z > 0)
            weight, pdf = self._microfacet(si, wi, bs.wo, active, weight=True)
            bs.pdf = pdf
            return bs, select(active, depolarize(weight), 0.0)

        def _sample_normal(self, wi, alpha, sample2, u_facet):
            """A microfacet normal: D·cosθ, Smith's visible normals of ``wi``, or the
            V-cavity's (whose facet of the V-groove ``u_facet`` picks)."""
            if not self.m_sample_visible:
                return sample_ndf(self.m_distribution, alpha, sample2)
            if self.m_shadowing == "smith":
                if self._flat is not None:  # scalar: Mitsuba's sampler, built once
                    return self._flat.sampler.sample(wi, sample2)[0]
                return sample_visible(self.m_distribution, alpha, wi, sample2)
            return sample_vcavity_visible(self.m_distribution, alpha, wi, sample2, u_facet)

        def _sample_scalar(self, si, sample1, sample2, active, bs):
            """
            :meth:`sample` of the microfacet lobe alone in scalar variants: the same steps on
            Python floats where they are cheaper than Mitsuba's scalar types (a call per ray;
            every attribute of a Mitsuba object read or written costs 0.1–0.4 µs there).
            """
            w = si.wi
            x, y, z = w
            if not (active and z > 0):
                return bs, Spectrum(0.0)
            flat = self._flat
            alpha = flat.alpha if flat is not None else self._alpha(si, True)
            # the direction as bs.wo stores it (float32), so that weight = eval/pdf at bs.wo
            wo = reflect_f32((x, y, z), self._sample_normal(w, alpha, sample2, sample1))
            bs.wo, bs.eta, bs.sampled_type = Vector3f(*wo), 1.0, GLOSSY  # component: 0
            if not wo[2] > 0:
                return bs, Spectrum(0.0)
            weight, pdf = self._microfacet(si, (x, y, z), wo, True, weight=True)
            bs.pdf = pdf
            return bs, depolarize(weight)

        def eval(self, ctx, si, wo, active=True):
            lobes = self._lobes(ctx)
            if not (lobes[0] or lobes[1]):
                return Spectrum(0.0)
            return self._eval_pdf(si, wo, active, lobes)[0]

        def pdf(self, ctx, si, wo, active=True):
            lobes = self._lobes(ctx)
            if not (lobes[0] or lobes[1]):
                return Float(0.0)
            return self._eval_pdf(si, wo, active, lobes)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            lobes = self._lobes(ctx)
            if not (lobes[0] or lobes[1]):
                return Spectrum(0.0), Float(0.0)
            return self._eval_pdf(si, wo, active, lobes)

        def eval_diffuse_reflectance(self, si, active=True):
            # The default, eval(wo = n)·π, would count the glossy lobe (mitsuba3 PR #1896).
            if self.m_diffuse_reflectance is None:
                return Spectrum(0.0)
            return self.m_diffuse_reflectance.eval(si, active)

        def traverse(self, cb):
            cb.put("alpha", self.m_alpha, DISCONTINUOUS)
            if self._fresnel_term is not None:
                cb.put("eta", self.m_eta, DISCONTINUOUS)
                cb.put("k", self.m_k, DISCONTINUOUS)
            cb.put("specular_reflectance", self.m_specular_reflectance, DIFFERENTIABLE)
            if self.m_diffuse_reflectance is not None:
                cb.put("diffuse_reflectance", self.m_diffuse_reflectance, DIFFERENTIABLE)

        def parameters_changed(self, keys=()):
            """Read α, ks, η and k once as per-channel floats where that is valid (flat_ok)."""
            self._flat = None
            textures = [self.m_alpha, self.m_specular_reflectance]
            if self._fresnel_term is not None:
                textures += [self.m_eta, self.m_k]
            if not flat_ok or any(t.is_spatially_varying() for t in textures):
                return
            si = mi.SurfaceInteraction3f()
            alpha = max(float(self.m_alpha.eval_1(si)), ALPHA_MIN)
            ks = [float(c) for c in self.m_specular_reflectance.eval(si)]
            if self._fresnel_term is None:
                def specular(cos_theta, s):
                    return [k * s for k in ks]
            else:
                eta, k = self.m_eta.eval(si), self.m_k.eval(si)
                channels = [(float(eta[c]), float(k[c])) for c in range(len(eta))]
                if self.m_fresnel == "exact":
                    consts = [fresnel.channel_constants(e, k) for e, k in channels]

                    def specular(cos_theta, s):
                        return [k * f * s for k, f in zip(ks, exact_channels(cos_theta, consts))]
                else:
                    term = self._fresnel_term

                    def specular(cos_theta, s):
                        return [k * term(cos_theta, e, kk) * s for k, (e, kk) in zip(ks, channels)]
            distr = mi.MicrofacetDistribution(mf.mitsuba_type(self.m_distribution), alpha, True)
            self._flat = _Flat(alpha, specular, distr)

        def to_string(self):
            if self.m_material is not None:
                ior = f"  material = {self.m_material},\n"
            elif self.m_eta is not None:
                ior = f"  eta = {_common.indent(self.m_eta)},\n  k = {_common.indent(self.m_k)},\n"
            else:
                ior = ""
            diffuse = _common.indent(self.m_diffuse_reflectance) \
                if self.m_diffuse_reflectance is not None else "0 (no diffuse lobe)"
            return (f"CookTorrance[\n"
                    f"  distribution = {self.m_distribution},\n"
                    f"  shadowing = {self.m_shadowing},\n"
                    f"  fresnel = {self.m_fresnel},\n"
                    f"  sample_visible = {str(self.m_sample_visible).lower()},\n"
                    f"  alpha = {_common.indent(self.m_alpha)},\n"
                    f"{ior}"
                    f"  specular_reflectance = {_common.indent(self.m_specular_reflectance)},\n"
                    f"  diffuse_reflectance = {diffuse}\n"
                    f"]")

    return CookTorrance
