"""
The reflection lobe of :mod:`~mi_brdfs.plugins.cooktorrance` without transmission: the
Cook-Torrance microfacet lobe ks·F·D·G/(4 cosθi cosθo), one-sided, with the paper's optional
Lambertian base ρd/π, the two mixed for sampling (Veach 1997, §9.2.4). pbrt-v4's
``ConductorBxDF`` and Mitsuba's ``roughconductor`` are the same lobe without the base.

Every method works in the local frame (normal +z), takes ``si.wi`` and ``wo`` as Mitsuba hands
them, and looks ``mi.*`` up when it is called, so that one class serves every variant.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..scattering import fresnel, microfacet, mixture, multiscatter, vector
from . import lobes, properties

#: F of each ``fresnel`` setting, per spectrum (``none``: F ≡ 1, no term).
FRESNEL_TERMS = {"exact": fresnel.exact, "schlick": fresnel.schlick, "none": None}


class ConductorLobe:
    """
    The microfacet reflection lobe and its diffuse base, for
    :class:`~mi_brdfs.plugins.cooktorrance.CookTorrance` to delegate to. Component 0 is the
    microfacet lobe (as ``roughconductor``'s only one, with its energy compensation when there
    is one), component 1 the diffuse base.

    Parameter ``kind`` (str): 'beckmann' or 'ggx'. Parameter ``alpha_u``, ``alpha_v``
    (mi.Texture): the roughness, the same texture when isotropic. Parameter ``shadowing``
    (str): 'vcavity' or 'smith'. Parameter ``fresnel`` (str): 'exact', 'schlick' or 'none'.
    Parameter ``sample_visible`` (bool): visible normals, else D·cosθ. Parameter ``eta``,
    ``k`` (mi.Texture | None): the complex index (None with ``fresnel`` 'none').
    Parameter ``specular`` (mi.Texture): ks. Parameter ``diffuse`` (mi.Texture | None): ρd,
    None for no base. Parameter ``table`` (multiscatter.Table | None): the albedo table of
    the lobe's distribution and masking for Kulla & Conty's energy compensation, None for
    single scattering only.

    **Sampling.** Two samplers: microfacet normals for the single-scattering lobe, and the
    cosine-weighted hemisphere for the lobes that are smooth in ωo (the diffuse base and the
    compensation lobe, whose shape (1 − E(μo)) cosθo is close to a cosine). A sampler is
    picked in proportion to the albedos of its lobes at ωi; the pdf is their mixture.
    """

    def __init__(self, kind, alpha_u, alpha_v, shadowing, fresnel, sample_visible, eta, k,
                 specular, diffuse, table=None):
        self.kind, self.alpha_u, self.alpha_v = kind, alpha_u, alpha_v
        self.shadowing, self.sample_visible = shadowing, sample_visible
        self.fresnel, self.fresnel_term = fresnel, FRESNEL_TERMS[fresnel]
        self.eta, self.k = eta, k
        self.specular, self.diffuse, self.table = specular, diffuse, table
        #: E(μ) and E_avg at the surface's roughness (None without compensation)
        self.albedos = None if table is None else \
            multiscatter.Albedos(table, alpha_u, alpha_v)
        #: F_avg where the index is the same everywhere and for every wavelength (no texture,
        #: not a spectral variant): a constant of the material, computed once, not per lookup
        self.f_avg = None
        if table is not None and fresnel != "none" and not mi.is_spectral and \
                not (eta.is_spatially_varying() or k.is_spatially_varying()):
            self.f_avg = self._fresnel_average(dr.zeros(mi.SurfaceInteraction3f), True)
            dr.make_opaque(self.f_avg)
        #: F_ms/(π (1 − E_avg)) where the roughness and F_avg are constants as well
        self.ms_factor = None
        if self.albedos is not None and self.albedos.row is not None and \
                (fresnel == "none" or self.f_avg is not None):
            self.ms_factor = self._ms_factor(self.f_avg, self.albedos.row.average)
            dr.make_opaque(self.ms_factor)

    def distribution(self, si, active) -> microfacet.Distribution:
        """The microfacet distribution at ``si``."""
        return microfacet.Distribution(
            self.kind, *properties.roughness_at(self.alpha_u, self.alpha_v, si, active))

    def enabled(self, ctx):
        """Which lobes the context enables: (microfacet, diffuse), bools."""
        return (ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0),
                self.diffuse is not None and ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, 1))

    def eval_pdf(self, ctx, si, wo, active=True, at_wi=None):
        """(f·cosθo, pdf of :meth:`sample`) at ``wo``: the enabled lobes and their mixture.
        ``at_wi``: :meth:`_at_wi` where :meth:`sample` has it."""
        use_mf, use_diffuse = self.enabled(ctx)
        if not (use_mf or use_diffuse):
            return mi.Spectrum(0.0), mi.Float(0.0)
        wi = si.wi
        active = active & (wi.z > 0) & (wo.z > 0)  # one-sided
        if lobes.none(active):
            return mi.Spectrum(0.0), mi.Float(0.0)
        if use_mf and not use_diffuse and self.table is None:
            return lobes.finish(*self._microfacet(si, wi, wo, active), active)
        if at_wi is None:
            at_wi = self._at_wi(si, wi, active, use_mf, use_diffuse)
        p_normal, _, ms_scale = at_wi
        # the lobes sampled from the cosine-weighted hemisphere: ρd/π·cosθo and f_ms·cosθo
        value = mi.Spectrum(0.0)
        if use_diffuse:
            value = self.diffuse.eval(si, active) * dr.inv_pi * wo.z
        if use_mf and self.table is not None:
            e_o = self._albedos(si, wo.z, active)[0]
            value = value + ms_scale * (dr.maximum(1.0 - e_o, 0.0) * wo.z)
        pdf = wo.z * dr.inv_pi
        if use_mf:  # and the single-scattering lobe, sampled by its microfacet normals
            value_ss, pdf_ss = self._microfacet(si, wi, wo, active)
            value, pdf = value + value_ss, mixture.pdf(p_normal, pdf_ss, pdf)
        return lobes.finish(value, pdf, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        """(BSDFSample3f, weight f·cosθo/pdf): a microfacet normal reflected, or the
        cosine-weighted hemisphere, chosen by ``sample1``."""
        bs, sample2 = lobes.new_sample(), lobes.point2(sample2)
        use_mf, use_diffuse = self.enabled(ctx)
        if not (use_mf or use_diffuse):
            return bs, mi.Spectrum(0.0)
        wi = si.wi
        active = active & (wi.z > 0)  # one-sided: the local frame's z is cosθ
        if lobes.none(active):
            return bs, mi.Spectrum(0.0)
        if use_mf and not use_diffuse and self.table is None:
            return bs, self._sample_microfacet(si, wi, sample1, sample2, active, bs)
        # sample1 picks the microfacet normals with probability p (and, rescaled, a facet of
        # the V-groove, or which lobe the cosine sample stands for); the weight is f·cosθo
        # over the mixture density.
        at_wi = self._at_wi(si, wi, active, use_mf, use_diffuse)
        p = at_wi[0] if use_mf else 0.0
        pick = (sample1 < p) if use_mf else False

        def reflected():
            u_facet = mixture.rescale(sample1, p)
            return vector.reflect(wi, self._sample_normal(si, wi, active, sample2, u_facet))

        bs.wo = lobes.choose(pick, reflected,
                             lambda: mi.warp.square_to_cosine_hemisphere(sample2))
        glossy = pick | self._cosine_is_glossy(sample1, p, at_wi, use_mf, use_diffuse)
        bs.sampled_type = dr.select(glossy, mi.UInt32(lobes.flag("GlossyReflection")),
                                    mi.UInt32(lobes.flag("DiffuseReflection")))
        bs.sampled_component = dr.select(glossy, mi.UInt32(0), mi.UInt32(1))
        bs.eta = 1.0
        value, bs.pdf = self.eval_pdf(ctx, si, bs.wo, active, at_wi)
        return bs, lobes.weight(value, bs.pdf, active)

    def _at_wi(self, si, wi, active, use_mf, use_diffuse):
        """
        What the lobes need of ωi alone: (the probability of the microfacet-normal sampler;
        of a cosine sample, the probability that it stands for the compensation lobe rather
        than the diffuse base; the compensation's ks·F_ms·(1 − E(μi))/(π (1 − E_avg)), or
        None). The weights are the lobes' albedos: mean(ks·F(cosθi)) of the single scattering
        without compensation, with it mean(ks·F_avg)·E(μi) (F_avg is at hand; a weight
        needs no exact value), mean(ks·F_ms)·(1 − E(μi)) of the compensation, mean(ρd) of
        the diffuse base.
        """
        w_normal, w_ms, w_diffuse, ms_scale = 0.0, 0.0, 0.0, None
        if use_mf and self.table is None:
            w_normal = dr.mean(self._specular(si, wi.z, 1.0, active))
        elif use_mf:  # F_avg, which the compensation needs anyway, stands for F(cosθi)
            ms_scale, e_i, e_avg, ks_f_avg = self._compensation(si, wi, active)
            w_normal = dr.mean(ks_f_avg) * e_i
            w_ms = dr.mean(ms_scale) * (dr.pi * dr.maximum(1.0 - e_avg, 0.0))
        if use_diffuse:
            w_diffuse = dr.mean(self.diffuse.eval(si, active))
        p_normal = mixture.probability(w_normal, w_ms + w_diffuse, 1.0 if use_mf else 0.0)
        return p_normal, mixture.probability(w_ms, w_diffuse, 0.0), ms_scale

    def _cosine_is_glossy(self, sample1, p, at_wi, use_mf, use_diffuse):
        """Whether a cosine-hemisphere sample stands for the compensation lobe (glossy,
        component 0) rather than the diffuse base: ``sample1``, past ``p``, rescaled to
        [0, 1) and compared with the compensation's share of the two lobes' albedos."""
        if not (use_mf and self.table is not None):
            return False
        if not use_diffuse:
            return True
        u = (sample1 - p) / dr.maximum(1.0 - p, 1e-30)
        return u < at_wi[1]

    def _albedos(self, si, mu, active):
        """(E(μ), E_avg) at the roughness at ``si``."""
        return self.albedos(mu, lambda: self.distribution(si, active))

    def _compensation(self, si, wi, active):
        """(ks·F_ms·(1 − E(μi))/(π (1 − E_avg)), E(μi), E_avg, ks·F_avg) of Kulla & Conty's
        lobe."""
        e_i, e_avg = self._albedos(si, wi.z, active)
        ks = self.specular.eval(si, active)
        f_avg = None
        if self.fresnel != "none":
            f_avg = self.f_avg if self.f_avg is not None else \
                self._fresnel_average(si, active)
        factor = self.ms_factor if self.ms_factor is not None else \
            self._ms_factor(f_avg, e_avg)
        scale = ks * (factor * dr.maximum(1.0 - e_i, 0.0))
        return scale, e_i, e_avg, ks if f_avg is None else ks * f_avg

    @staticmethod
    def _ms_factor(f_avg, e_avg):
        """F_ms/(π (1 − E_avg)): the compensation lobe's factor besides ks and the (1 − E)."""
        factor = multiscatter.lobe(0.0, 0.0, e_avg)
        return factor if f_avg is None else factor * multiscatter.multiple_fresnel(f_avg, e_avg)

    def _fresnel_average(self, si, active):
        """F_avg of the Fresnel term at ``si``, per channel."""
        eta, k = self.eta.eval(si, active), self.k.eval(si, active)
        if self.fresnel == "exact":
            return multiscatter.fresnel_average(eta, k)
        return multiscatter.schlick_average(fresnel.r0(eta, k))

    def _sample_microfacet(self, si, wi, sample1, sample2, active, bs):
        """Fill ``bs`` from the microfacet lobe alone; returns the weight in closed form."""
        # a microfacet normal m, and ωo = ωi reflected about it
        m = self._sample_normal(si, wi, active, sample2, sample1)
        bs.wo = wo = vector.reflect(wi, m)
        bs.sampled_type = mi.UInt32(lobes.flag("GlossyReflection"))
        bs.sampled_component = mi.UInt32(0)
        bs.eta = 1.0
        # the terms at ωo as stored, so that bs.pdf = pdf(bs.wo)
        active = active & (wo.z > 0)
        if lobes.none(active):
            return mi.Spectrum(0.0)
        weight, bs.pdf = self._microfacet(si, wi, wo, active, weight=True)
        return dr.select(active, lobes.depolarize(weight), 0.0)

    def _sample_normal(self, si, wi, active, sample2, u_facet):
        """A microfacet normal: D·cosθ, Smith's visible normals of ωi, or the V-cavity's
        (whose facet of the V-groove ``u_facet`` picks)."""
        distr = self.distribution(si, active)
        if not self.sample_visible:
            return distr.sample(sample2)
        if self.shadowing == "smith":
            return distr.sample_visible(wi, sample2)
        return distr.sample_vcavity_visible(wi, sample2, u_facet)

    def _microfacet(self, si, wi, wo, active, weight=False):
        """
        (f·cosθo, pdf) of the microfacet lobe for ωi, ωo above the surface; with ``weight``
        (for :meth:`sample`) (f·cosθo/pdf, pdf), in closed form where D and 4 cosθi cancel:
        ks·F·G1(ωo) (Smith's visible normals), ks·F·G/G1(ωi) (the V-cavity's),
        ks·F·G·(ωo·m)/(cosθi cosθm) (D·cos).
        """
        m = vector.half_vector(wi, wo)
        cos_im, cos_om = vector.dot(wi, m), vector.dot(wo, m)
        # Both directions must see the front of the facet: false only when rounding makes
        # ωi + ωo vanish (grazing, nearly opposite directions).
        active = active & (cos_im > 0) & (cos_om > 0)
        if lobes.none(active):
            return mi.Spectrum(0.0), mi.Float(0.0)
        distr = self.distribution(si, active)
        # D, the masking-shadowing G, and G1(ωi) of the visible normals
        D = distr.ndf(m)
        if self.shadowing == "smith":
            g1_wi = distr.smith_g1_mitsuba(wi, m, cos_im)
            g1_wo = distr.smith_g1_mitsuba(wo, m, cos_om)
            G = g1_wi * g1_wo
        else:
            G = microfacet.vcavity_g(wi, wo, m)
            g1_wi = microfacet.vcavity_g1(wi, m) if self.sample_visible else None
        # the density of ωo: visible normals or D·cosθm, through the reflection's Jacobian
        if self.sample_visible:
            pdf = microfacet.pdf_visible_reflection(D, g1_wi, wi)
        else:
            pdf = microfacet.pdf_ndf(D, m) * microfacet.reflection_jacobian(wo, m)
        # f·cosθo = ks F D G / (4 cosθi cosθo) · cosθo, or the sample weight
        if not weight:
            factor = D * G / (4.0 * wi.z)
        elif not self.sample_visible:
            factor = G * cos_om / dr.maximum(wi.z * m.z, 1e-30)
        elif self.shadowing == "smith":
            factor = g1_wo
        else:
            factor = G / dr.maximum(g1_wi, 1e-30)
        if weight:
            active = active & (pdf > 0)
        value = self._specular(si, cos_im, factor, active)
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def _specular(self, si, cos_theta, factor, active):
        """ks·factor·F(cosθ), F at the cosine between ωi and the facet normal."""
        value = self.specular.eval(si, active) * factor
        if self.fresnel_term is not None:
            value = value * self.fresnel_term(cos_theta, self.eta.eval(si, active),
                                              self.k.eval(si, active))
        return value
