"""
The lobes of :mod:`~mi_brdfs.plugins.cooktorrance` with ``transmission``: a rough dielectric
interface lit from either side, reflecting with the dielectric Fresnel term F and refracting
with 1 − F (Walter, Marschner, Li & Torrance 2007, "Microfacet Models for Refraction through
Rough Surfaces"), the model of Mitsuba's ``roughdielectric`` and of pbrt-v4's ``DielectricBxDF``.

Every method works in the local frame (normal +z), takes ``si.wi`` and ``wo`` as Mitsuba hands
them, and looks ``mi.*`` up when it is called, so that one class serves every variant.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..scattering import fresnel, microfacet, mixture, multiscatter, vector
from . import lobes, properties


class DielectricLobe:
    """
    Reflection (component 0) and refraction (component 1) of a rough dielectric, for
    :class:`~mi_brdfs.plugins.cooktorrance.CookTorrance` to delegate to; Smith's masking as
    Mitsuba computes it, the exact dielectric Fresnel term.

    Parameter ``kind`` (str): 'beckmann' or 'ggx'. Parameter ``alpha_u``, ``alpha_v``
    (mi.Texture): the roughness, the same texture when isotropic. Parameter
    ``sample_visible`` (bool): visible normals, else D·cosθ of Walter's widened α.
    Parameter ``eta`` (mi.Float): the relative index int_ior/ext_ior. Parameter
    ``specular``, ``transmittance`` (mi.Texture): the factors ks and kt on the two lobes.
    Parameter ``tables`` ((multiscatter.Table, multiscatter.Table) | None): the albedo tables
    lit from above and from below (:func:`~mi_brdfs.scattering.multiscatter.dielectric_tables`)
    for the energy compensation, None for single scattering only.

    **Energy compensation** (Kulla & Conty 2017, their dielectric extension): the light that
    single scattering loses, 1 − E(μi) of the albedo E_R+T on ωi's side, comes back through a
    lobe (1 − E(μi))(1 − E'(μo))/(π (1 − E'_avg)) on ωo's side, E' that side's albedo: the
    share 1 − x reflected, x refracted (:func:`~mi_brdfs.scattering.multiscatter.
    transmitted_shares`, reciprocal across the interface), times ks or kt (and 1/η² for
    radiance through refraction, as the single scattering). It is sampled from the cosine
    hemisphere of the side it leaves on, mixed with the microfacet sampler by the albedos:
    the microfacet sampler with probability E(μi).
    """

    def __init__(self, kind, alpha_u, alpha_v, sample_visible, eta, specular, transmittance,
                 tables=None):
        self.kind, self.alpha_u, self.alpha_v = kind, alpha_u, alpha_v
        self.sample_visible = sample_visible
        # the relative index both ways (opaque: a changed η updates the kernel's inputs)
        self.eta, self.inv_eta = eta, dr.rcp(eta)
        dr.make_opaque(self.eta, self.inv_eta)
        self.specular, self.transmittance = specular, transmittance
        #: E(μ) and E_avg lit from above and from below, and the interface's average
        #: transmittance from above, 1 − F_avg(η) (None without compensation)
        self.albedos = None
        if tables is not None:
            t_above = 1.0 - multiscatter.fresnel_average(self.eta, 0.0, nodes=32)
            dr.make_opaque(t_above)
            self.albedos = multiscatter.TwoSided(tables, alpha_u, alpha_v, t_above, self.eta)

    def distribution(self, si, active) -> microfacet.Distribution:
        """The microfacet distribution at ``si``."""
        return microfacet.Distribution(
            self.kind, *properties.roughness_at(self.alpha_u, self.alpha_v, si, active))

    @staticmethod
    def enabled(ctx):
        """Which lobes the context enables: (reflection, refraction), bools."""
        return (ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0),
                ctx.is_enabled(mi.BSDFFlags.GlossyTransmission, 1))

    def eval_pdf(self, ctx, si, wo, active=True):
        """(f·|cosθo|, pdf of :meth:`sample`) at ``wo``, both sides, both lobes."""
        enabled = self.enabled(ctx)
        if not (enabled[0] or enabled[1]):
            return mi.Spectrum(0.0), mi.Float(0.0)
        radiance = ctx.mode == mi.TransportMode.Radiance
        value, pdf = self._terms(si, si.wi, wo, active, enabled, radiance)
        if self.albedos is not None:
            value, pdf = self._compensated(si, si.wi, wo, active, enabled, radiance,
                                           value, pdf)
        return lobes.depolarize(value), pdf

    def sample(self, ctx, si, sample1, sample2, active=True):
        """(BSDFSample3f, weight): a microfacet normal, then reflection with probability F,
        else refraction (Walter et al. 2007, §5.3); with the compensation, that or (picked by
        ``sample1``) the cosine hemisphere on the side the compensation's share chooses."""
        bs, sample2 = lobes.new_sample(), lobes.point2(sample2)
        enabled = self.enabled(ctx)
        if not (enabled[0] or enabled[1]):
            return bs, mi.Spectrum(0.0)
        wi = si.wi
        active = active & (wi.z != 0.0)
        if lobes.none(active):
            return bs, mi.Spectrum(0.0)
        radiance = ctx.mode == mi.TransportMode.Radiance
        if self.albedos is not None:
            return self._sample_compensated(si, sample1, sample2, active, enabled, radiance,
                                            bs)
        wo, active = self._sample_microfacet(si, wi, sample1, sample2, active, enabled)
        if lobes.none(active):
            return bs, mi.Spectrum(0.0)
        self._fill(bs, wi, wo)
        weight, bs.pdf = self._terms(si, wi, wo, active, enabled, radiance, weight=True)
        return bs, dr.select(active, lobes.depolarize(weight), 0.0)

    def _sample_microfacet(self, si, wi, sample1, sample2, active, enabled):
        """(ωo, active): a microfacet normal, reflected about with probability F (``sample1``)
        when both lobes are enabled, else refracted through; not active where that fails."""
        has_r, has_t = enabled
        cos_i = wi.z
        # the microfacet normal, seen from ωi turned to the normal's side
        up = dr.select(cos_i < 0.0, -1.0, 1.0)
        m = self._sample_normal(si, mi.Vector3f(wi.x * up, wi.y * up, wi.z * up), active,
                                sample2)
        cos_im = vector.dot(wi, m)
        # a normal drawn from D·cos may face away from ωi: no sample (as G1(ωi) = 0 there)
        active = active & (cos_im * cos_i > 0.0)
        F, cos_t, _, eta_ti = fresnel.dielectric(cos_im, self.eta)
        pick_r = (sample1 <= F) if (has_r and has_t) else has_r
        wo = lobes.choose(pick_r, lambda: vector.reflect(wi, m),
                          lambda: vector.refract(wi, m, cos_t, eta_ti))
        # a reflection that left below the surface (or a refraction above it) is no sample,
        # nor is a refraction that float32 cannot represent (for η ≳ 100 at grazing facets,
        # Snell's vector form loses the unit length to cancellation)
        same_side = cos_i * wo.z > 0.0
        unit = dr.abs(vector.dot(wo, wo) - 1.0) < 1e-3
        return wo, active & dr.select(pick_r, same_side, (cos_i * wo.z < 0.0) & unit)

    def _fill(self, bs, wi, wo):
        """``bs``'s direction, relative index, component and type for ωo."""
        reflect = wi.z * wo.z > 0.0
        bs.wo = wo
        bs.eta = dr.select(reflect, 1.0, dr.select(wi.z > 0.0, self.eta, self.inv_eta))
        bs.sampled_component = dr.select(reflect, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(reflect, mi.UInt32(lobes.flag("GlossyReflection")),
                                    mi.UInt32(lobes.flag("GlossyTransmission")))

    def _sample_normal(self, si, wi_up, active, sample2):
        """A microfacet normal for ωi turned up (``wi_up``): visible normals, or D·cosθ of the
        widened α (Walter et al. 2007, §5.3)."""
        distr = self.distribution(si, active)
        if self.sample_visible:
            return distr.sample_visible(wi_up, sample2)
        return distr.scaled(microfacet.walter_widening(wi_up.z)).sample(sample2)

    def _terms(self, si, wi, wo, active, lobes_on, radiance, weight=False):
        """
        (f·|cosθo|, pdf) of both lobes; with ``weight`` (for :meth:`sample`)
        (f·|cosθo|/pdf, pdf) in closed form: k·F̂·G1(ωo) with visible normals,
        k·F̂·(D/D_widened)·G·|ωo·h|/(|cosθi| cosθh) with D·cos (|ωi·h| for a refraction),
        where k is the lobe's factor (and 1/η² for radiance through refraction) and F̂ is 1
        when both lobes are sampled, else F or 1 − F.
        """
        has_r, has_t = lobes_on
        cos_i, cos_o = wi.z, wo.z
        reflect = cos_i * cos_o > 0.0
        if not has_t:
            active = active & reflect
        elif not has_r:
            active = active & (cos_i * cos_o < 0.0)
        # the relative index in the direction of travel, and the generalised half vector
        eta = dr.select(cos_i > 0.0, self.eta, self.inv_eta)
        m = vector.generalized_half_vector(wi, wo, dr.select(reflect, 1.0, eta))
        cos_im, cos_om = vector.dot(wi, m), vector.dot(wo, m)
        # each direction sees the front of the facet from its own side of the surface
        active = active & (cos_i != 0.0) & (cos_im * cos_i > 0.0) & (cos_om * cos_o > 0.0)
        if lobes.none(active):
            return mi.Spectrum(0.0), mi.Float(0.0)
        # D, Smith's G1 of both directions and the lobe's Fresnel factor
        distr = self.distribution(si, active)
        D = distr.ndf(m)
        F, _, _, _ = fresnel.dielectric(cos_im, self.eta)
        g1_wi = distr.smith_g1_mitsuba(wi, m, cos_im)
        g1_wo = distr.smith_g1_mitsuba(wo, m, cos_om)
        lobe_f = dr.select(reflect, F, 1.0 - F)
        # the density of the normal (visible normals of the turned ωi, or the widened D·cos),
        # the lobe's probability, and the Jacobian of ωo
        abs_cos_i = dr.abs(cos_i)
        if self.sample_visible:
            pdf = D * g1_wi * dr.abs(cos_im) / abs_cos_i
        else:
            d_sample = distr.scaled(microfacet.walter_widening(cos_i)).ndf(m)
            pdf = microfacet.pdf_ndf(d_sample, m)
        if has_r and has_t:
            pdf = pdf * lobe_f
        pdf = pdf * lobes.choose(reflect, lambda: microfacet.reflection_jacobian(wo, m),
                                 lambda: microfacet.refraction_jacobian(wi, wo, m, eta))
        # the lobe's factor: ks, or kt (and 1/η² for radiance: Veach 1997, §5.2)
        factor = lobes.choose(reflect, lambda: self.specular.eval(si, active),
                              lambda: self._refraction_factor(si, eta, radiance, active))
        if weight:
            chosen = _chosen(lobe_f) if (has_r and has_t) else lobe_f
            if self.sample_visible:
                shape = g1_wo
            else:
                # |ωo·h| = |ωi·h| for a reflection, up to rounding: the one eval/pdf has
                cos_h = dr.abs(dr.select(reflect, cos_om, cos_im))
                shape = (D / dr.maximum(d_sample, 1e-30)) * g1_wi * g1_wo * cos_h / \
                    dr.maximum(abs_cos_i * m.z, 1e-30)
            value = factor * (chosen * shape)
            active = active & (pdf > 0.0)
        else:
            G = g1_wi * g1_wo
            value = factor * lobes.choose(
                reflect, lambda: F * D * G / (4.0 * abs_cos_i),
                lambda: dr.abs((1.0 - F) * D * G * eta * eta * cos_im * cos_om /
                               dr.maximum(cos_i * dr.square(cos_im + eta * cos_om), -1e30)))
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def _side_albedos(self, si, mu, above, active):
        """(E(μ), E_avg) of the side ``above`` (a mask) at the roughness at ``si``."""
        return self.albedos(mu, above, lambda: self.distribution(si, active))

    def _at_wi(self, si, wi, active, enabled):
        """What the compensation needs of ωi alone: (the probability of the microfacet
        sampler, E(μi); of a cosine sample, the probability that it reflects; the lobe's
        (1 − E(μi))/π times its reflected share, and times its refracted share)."""
        has_r, has_t = enabled
        above = wi.z > 0.0
        x_above, x_below = self.albedos.transmitted(lambda: self.distribution(si, active))
        x = dr.select(above, x_above, x_below)
        e_i = self._side_albedos(si, dr.abs(wi.z), above, active)[0]
        missing = dr.maximum(1.0 - e_i, 0.0) * dr.inv_pi
        q_reflect = (1.0 - x) if (has_r and has_t) else (1.0 if has_r else 0.0)
        return dr.clip(e_i, 0.0, 1.0), q_reflect, missing * (1.0 - x), missing * x

    def _compensated(self, si, wi, wo, active, enabled, radiance, value_ss, pdf_ss, at_wi=None):
        """(f·|cosθo|, pdf) of the single scattering (``value_ss``, ``pdf_ss``) plus the
        compensation lobe, and the mixture density of :meth:`sample`."""
        has_r, has_t = enabled
        p_ss, q_reflect, reflected, refracted = \
            self._at_wi(si, wi, active, enabled) if at_wi is None else at_wi
        reflect = wi.z * wo.z > 0.0
        active = active & (wi.z != 0.0) & (wo.z != 0.0)
        if not (has_r and has_t):
            active = active & (reflect if has_r else ~reflect)
        abs_cos_o = dr.abs(wo.z)
        e_o, avg_o = self._side_albedos(si, abs_cos_o, wo.z > 0.0, active)
        shape = dr.maximum(1.0 - e_o, 0.0) * abs_cos_o / dr.maximum(1.0 - avg_o, 1e-7)
        eta = dr.select(wi.z > 0.0, self.eta, self.inv_eta)
        value = lobes.choose(
            reflect, lambda: self.specular.eval(si, active) * (reflected * shape),
            lambda: self._refraction_factor(si, eta, radiance, active) * (refracted * shape))
        pdf = dr.select(reflect, q_reflect, 1.0 - q_reflect) * abs_cos_o * dr.inv_pi
        return (value_ss + dr.select(active, value, 0.0),
                mixture.pdf(p_ss, pdf_ss, dr.select(active, pdf, 0.0)))

    def _sample_compensated(self, si, sample1, sample2, active, enabled, radiance, bs):
        """:meth:`sample` with the compensation: the microfacet sampler with probability E(μi),
        else the cosine hemisphere, reflected with the compensation's reflected share."""
        wi = si.wi
        at_wi = self._at_wi(si, wi, active, enabled)
        p_ss, q_reflect = at_wi[0], at_wi[1]
        pick = sample1 < p_ss
        wo_ss, valid = self._sample_microfacet(si, wi, mixture.rescale(sample1, p_ss),
                                               sample2, active, enabled)
        u = (sample1 - p_ss) / dr.maximum(1.0 - p_ss, 1e-30)
        wo_c = mi.warp.square_to_cosine_hemisphere(sample2)
        side = dr.select((u < q_reflect) == (wi.z > 0.0), 1.0, -1.0)
        wo = dr.select(pick, wo_ss, mi.Vector3f(wo_c.x, wo_c.y, wo_c.z * side))
        active = active & dr.select(pick, valid, True)
        self._fill(bs, wi, wo)
        value, pdf_ss = self._terms(si, wi, wo, active, enabled, radiance)
        value, bs.pdf = self._compensated(si, wi, wo, active, enabled, radiance, value,
                                          pdf_ss, at_wi)
        return bs, lobes.weight(lobes.depolarize(value), bs.pdf, active)

    def _refraction_factor(self, si, eta, radiance, active):
        """kt, over η² in radiance transport (Veach 1997, §5.2: the radiance of refracted light
        scales with the squared index; importance does not)."""
        kt = self.transmittance.eval(si, active)
        return kt / dr.square(eta) if radiance else kt


def _chosen(probability):
    """The weight factor of a lobe chosen with ``probability`` (F or 1 − F): 1, whose
    derivative in AD variants is that of log(probability), the lobe choice being made on
    detached values (as roughdielectric, so that gradients through sample() stay unbiased)."""
    if not dr.is_diff_v(mi.Float):
        return 1.0
    return dr.replace_grad(mi.Float(1.0), probability / dr.detach(probability))
