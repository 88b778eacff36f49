"""
The lobes of :mod:`~mi_brdfs.plugins.cooktorrance` with ``transmission``: a rough dielectric
interface lit from either side, reflecting with the dielectric Fresnel term F and refracting
with 1 − F (:class:`MicrofacetInterface`; Walter, Marschner, Li & Torrance 2007, "Microfacet
Models for Refraction through Rough Surfaces", the model of Mitsuba's ``roughdielectric`` and
of pbrt-v4's ``DielectricBxDF``), and Kulla & Conty's energy compensation of it
(:class:`InterfaceCompensation`), mixed by :class:`~mi_brdfs.plugins.lobes.Mixture`.

Every method works in the local frame (normal +z), takes ``si.wi`` and ``wo`` as Mitsuba hands
them, and looks ``mi.*`` up when it is called, so that one class serves every variant.
"""

from __future__ import annotations

from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np

from ..scattering import fresnel, microfacet, multiscatter, multiscatter_film, vector
from . import lobes, properties


class MicrofacetInterface(lobes.Lobe):
    """
    Reflection (component 0, ``flags[0]``) and refraction (component 1, ``flags[1]``) of a rough
    dielectric, sampled together: a microfacet normal, then reflection with probability F, else
    refraction (Walter et al. 2007, §5.3); Smith's masking as Mitsuba computes it.

    Parameter ``kind`` (str): 'beckmann' or 'ggx'. Parameter ``alpha_u``, ``alpha_v``
    (mi.Texture): the roughness, the same texture when isotropic. Parameter
    ``sample_visible`` (bool): visible normals, else D·cosθ of Walter's widened α.
    Parameter ``eta`` (mi.Float): the relative index int_ior/ext_ior. Parameter
    ``specular``, ``transmittance`` (mi.Texture): the factors ks and kt on the two lobes.
    Parameter ``tables`` ((multiscatter.AlbedoTable, multiscatter.AlbedoTable) | None): the
    interface's own albedo E_R+T lit from above and from below
    (:func:`~mi_brdfs.scattering.multiscatter.dielectric_tables`), which an
    :class:`InterfaceCompensation` of it needs (it then weighs the lobe as well). Parameter
    ``film`` (:class:`~mi_brdfs.plugins.cooktorrance_film.Film` | None): a thin film on the
    interface: its reflectance R per channel replaces F, refraction takes 1 − R (the film
    absorbs nothing: R + T = 1), and the choice between them is made by the mean of R; with
    the tables as well, E_R+T and the average transmittance are shifted per channel by what
    the film changes (:class:`~mi_brdfs.scattering.multiscatter_film.FilmShift`).
    """

    kind = "GlossyReflection"

    def __init__(self, kind, alpha_u, alpha_v, sample_visible, eta, specular, transmittance,
                 flags, tables=None, film=None):
        self.film = film
        #: the densest medium light arrives from (the film's branches depend on it)
        value = float(np.asarray(eta, np.float64).ravel()[0])
        self.n1_max = max(1.0, value)
        #: the film's colour from outside, tabulated where it can be (from inside it is the
        #: same at Snell's image of the cosine: :meth:`reflectance`)
        self.film_table = None if film is None else film.tabulate(eta, 0.0)
        self.distribution_kind, self.alpha_u, self.alpha_v = kind, alpha_u, alpha_v
        self.sample_visible, self.flags = sample_visible, flags
        # the relative index both ways (opaque: a changed η updates the kernel's inputs)
        self.eta, self.inv_eta = eta, dr.rcp(eta)
        dr.make_opaque(self.eta, self.inv_eta)
        self.specular, self.transmittance, self.tables = specular, transmittance, tables
        #: with the tables: the interface's average transmittance from above, 1 − F_avg(η),
        #: which the compensation's shares need, once per material
        if tables is not None:
            self.t_above = 1.0 - multiscatter.fresnel_average(self.eta, 0.0, nodes=32)
            dr.make_opaque(self.t_above)
        #: with the tables and a film: the film's shift of the tables, and where the film is
        #: the same everywhere and its colour integrated per channel, its nodes' ΔF once
        self.film_shift = self.film_deltas = None
        if tables is not None and film is not None:
            ranges = [properties.texture_range(a) for a in (alpha_u, alpha_v)]
            self.film_shift = multiscatter_film.FilmShift(
                kind, eta, multiscatter.uniform_alpha(alpha_u, alpha_v),
                None if None in ranges else (min(r[0] for r in ranges),
                                             max(r[1] for r in ranges)))
            if film.sensitivity is not None and not (film.thickness.is_spatially_varying() or
                                                     film.eta.is_spatially_varying()):
                self.film_deltas = self._film_deltas(dr.zeros(mi.SurfaceInteraction3f), True,
                                                     constant=True)

    def component_flags(self) -> dict:
        return {0: self.flags[0], 1: self.flags[1]}

    @staticmethod
    def sides(ctx):
        """Which lobes the context enables: (reflection, refraction), bools."""
        return (ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0),
                ctx.is_enabled(mi.BSDFFlags.GlossyTransmission, 1))

    def enabled(self, ctx) -> bool:
        return any(self.sides(ctx))

    def distribution(self, si, active) -> microfacet.Distribution:
        """The microfacet distribution at ``si``."""
        return microfacet.Distribution(
            self.distribution_kind,
            *properties.roughness_at(self.alpha_u, self.alpha_v, si, active))

    def record(self, si, wo):
        """Reflection (component 0) or refraction (component 1, η the relative index)."""
        reflect = si.wi.z * wo.z > 0.0
        return (dr.select(reflect, mi.UInt32(lobes.flag("GlossyReflection")),
                          mi.UInt32(lobes.flag("GlossyTransmission"))),
                dr.select(reflect, mi.UInt32(0), mi.UInt32(1)),
                dr.select(reflect, 1.0, dr.select(si.wi.z > 0.0, self.eta, self.inv_eta)))

    def eval_pdf(self, ctx, si, wo, active):
        t = self._terms(ctx, si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        wi, G = si.wi, t.g1_wi * t.g1_wo
        value = t.factor * lobes.choose(
            t.reflect, lambda: t.F * t.D * G / (4.0 * dr.abs(wi.z)),
            lambda: dr.abs((1.0 - t.F) * t.D * G * t.eta * t.eta * t.cos_im * t.cos_om /
                           dr.maximum(wi.z * dr.square(t.cos_im + t.eta * t.cos_om), -1e30)))
        return dr.select(t.active, value, 0.0), dr.select(t.active, t.pdf, 0.0)

    def sample_weight(self, ctx, si, wo, active):
        """k·F̂·G1(ωo) with visible normals, k·F̂·(D/D_widened)·G·|ωo·h|/(|cosθi| cosθh) with
        D·cos (|ωi·h| for a refraction), in closed form; F̂ is 1 when both lobes are sampled
        (the choice by F cancels it), else F or 1 − F."""
        t = self._terms(ctx, si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        if not all(self.sides(ctx)):
            chosen = t.lobe_spec
        elif self.film is None:
            chosen = _chosen(t.lobe_f)
        else:  # chosen by the mean of R, weighted by R per channel
            chosen = _chosen(t.lobe_f) * t.lobe_spec / dr.maximum(t.lobe_f, 1e-30)
        if self.sample_visible:
            shape = t.g1_wo
        else:
            # |ωo·h| = |ωi·h| for a reflection, up to rounding: the one eval/pdf has
            cos_h = dr.abs(dr.select(t.reflect, t.cos_om, t.cos_im))
            shape = (t.D / dr.maximum(t.d_sample, 1e-30)) * t.g1_wi * t.g1_wo * cos_h / \
                dr.maximum(dr.abs(si.wi.z) * t.m.z, 1e-30)
        ok = t.active & (t.pdf > 0.0)
        return dr.select(ok, t.factor * (chosen * shape), 0.0), dr.select(ok, t.pdf, 0.0)

    def _terms(self, ctx, si, wo, active):
        """
        The generalised half vector h of ωi, ωo and at it D, F, Smith's G1 of both directions,
        the lobe's factor and the density of ωo (None where a scalar variant's lane is
        inactive): the one place that computes them, for :meth:`eval_pdf` and
        :meth:`sample_weight`.
        """
        has_r, has_t = self.sides(ctx)
        wi = si.wi
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
            return None
        distr = self.distribution(si, active)
        masking = microfacet.Smith(distr)
        t = SimpleNamespace(reflect=reflect, eta=eta, m=m, cos_im=cos_im, cos_om=cos_om,
                            active=active, D=distr.ndf(m),
                            g1_wi=masking.G1(wi, m, cos_im), g1_wo=masking.G1(wo, m, cos_om))
        # F: the bare interface's, or the film's per channel (then the choice takes its mean)
        t.F, f_pick = self.reflectance(si, cos_im, active)
        t.lobe_f = dr.select(reflect, f_pick, 1.0 - f_pick)
        t.lobe_spec = t.lobe_f if self.film is None else dr.select(reflect, t.F, 1.0 - t.F)
        # the density of the normal (visible normals of the turned ωi, or the widened D·cos),
        # the lobe's probability, and the Jacobian of ωo
        if self.sample_visible:
            pdf = t.D * t.g1_wi * dr.abs(cos_im) / dr.abs(cos_i)
        else:
            t.d_sample = distr.scaled(microfacet.walter_widening(cos_i)).ndf(m)
            pdf = microfacet.pdf_ndf(t.d_sample, m)
        if has_r and has_t:
            pdf = pdf * t.lobe_f
        t.pdf = pdf * lobes.choose(reflect, lambda: microfacet.reflection_jacobian(wo, m),
                                   lambda: microfacet.refraction_jacobian(wi, wo, m, eta))
        # the lobe's factor: ks, or kt (and 1/η² for radiance: Veach 1997, §5.2)
        t.factor = lobes.choose(reflect, lambda: properties.clip_at(self.specular, si, active),
                                lambda: self.refraction_factor(ctx, si, eta, active))
        return t

    def sample(self, ctx, si, sample1, sample2, active):
        """A microfacet normal, reflected about with probability F (``sample1``) when both
        lobes are enabled, else refracted through; not valid where that fails."""
        has_r, has_t = self.sides(ctx)
        wi = si.wi
        cos_i = wi.z
        # the microfacet normal, seen from ωi turned to the normal's side
        up = dr.select(cos_i < 0.0, -1.0, 1.0)
        m = self._sample_normal(si, mi.Vector3f(wi.x * up, wi.y * up, wi.z * up), active,
                                sample2)
        cos_im = vector.dot(wi, m)
        # a normal drawn from D·cos may face away from ωi: no sample (as G1(ωi) = 0 there)
        valid = cos_im * cos_i > 0.0
        F, cos_t, _, eta_ti = fresnel.dielectric(cos_im, self.eta)
        if self.film is not None:
            F = self.reflectance(si, cos_im, active, pick=True)
        pick_r = (sample1 <= F) if (has_r and has_t) else has_r
        wo = lobes.choose(pick_r, lambda: vector.reflect(wi, m),
                          lambda: vector.refract(wi, m, cos_t, eta_ti))
        # a reflection that left below the surface (or a refraction above it) is no sample,
        # nor is a refraction that float32 cannot represent (for η ≳ 100 at grazing facets,
        # Snell's vector form loses the unit length to cancellation)
        same_side = cos_i * wo.z > 0.0
        unit = dr.abs(vector.dot(wo, wo) - 1.0) < 1e-3
        return wo, valid & dr.select(pick_r, same_side, (cos_i * wo.z < 0.0) & unit)

    def reflectance(self, si, cos_im, active, pick: bool = False):
        """(F, the probability of choosing reflection) at the facet cosine ``cos_im`` (signed:
        from inside below 0): the bare interface's F twice, or the film's reflectance per
        channel and its mean; with ``pick``, the probability alone."""
        if self.film is None:
            F = fresnel.dielectric(cos_im, self.eta)[0]
            return F if pick else (F, F)
        outside = cos_im >= 0.0
        cos = dr.abs(cos_im)
        if self.film_table is None:
            n1, n3 = dr.select(outside, 1.0, self.eta), dr.select(outside, self.eta, 1.0)
            args = (si, cos, n1, n3, 0.0, active, self.n1_max)
            total = False
        else:
            # the film absorbs nothing, nor does either side: the stack reflects the same from
            # both sides of a refraction (Stokes' relations), so from inside the table from
            # outside is read at Snell's image of the cosine, and R = 1 where there is none
            cos_out2 = 1.0 - dr.square(self.eta) * (1.0 - dr.square(cos))
            total = (cos_im < 0.0) & (cos_out2 <= 0.0)
            args = (si, dr.select(outside, cos, dr.safe_sqrt(cos_out2)), 1.0, self.eta, 0.0,
                    active, self.n1_max, self.film_table)
        if pick:
            return dr.select(total, 1.0, self.film.mean_reflectance(*args))
        F = dr.select(total, 1.0, self.film.reflectance(*args))
        return F, dr.mean(F)

    def _sample_normal(self, si, wi_up, active, sample2):
        """A microfacet normal for ωi turned up (``wi_up``): visible normals, or D·cosθ of the
        widened α (Walter et al. 2007, §5.3)."""
        distr = self.distribution(si, active)
        if self.sample_visible:
            return distr.sample_visible(wi_up, sample2)
        return distr.scaled(microfacet.walter_widening(wi_up.z)).sample(sample2)

    def refraction_factor(self, ctx, si, eta, active):
        """kt, over η² in radiance transport (Veach 1997, §5.2: the radiance of refracted light
        scales with the squared index; importance does not)."""
        kt = properties.clip_at(self.transmittance, si, active)
        return kt / dr.square(eta) if ctx.mode == mi.TransportMode.Radiance else kt

    def weight(self, ctx, si, active):
        """E(μi) of ωi's side with the albedo tables (the compensation takes the rest), else
        1 (the lobe is then sampled alone)."""
        if self.tables is None:
            return mi.Float(1.0)
        e_i = self.albedo(si, dr.abs(si.wi.z), si.wi.z > 0.0, active)[0]
        return dr.clip(mean(e_i), 0.0, 1.0)

    def albedo(self, si, mu, above, active):
        """(E(μ), E_avg) of the side ``above`` (a mask) at the roughness at ``si``: Floats, or
        with a film spectra (per channel)."""
        alpha = lambda: multiscatter.equivalent_alpha(self.distribution(si, active))  # noqa: E731
        (e0, a0), (e1, a1) = (table(mu, alpha) for table in self.tables)
        e, e_avg = dr.select(above, e0, e1), dr.select(above, a0, a1)
        if self.film_shift is None:
            return e, e_avg
        de, de_avg = self.film_shift(self._film_deltas(si, active), mu, above, alpha)
        return e + de, e_avg + de_avg

    def _film_deltas(self, si, active, constant: bool = False):
        """The film's reflectance less the bare interface's at the film shift's nodes (at
        ``si``, or the material's where they were computed once)."""
        if self.film_deltas is not None:
            return self.film_deltas
        return self.film_shift.deltas(
            lambda c: self.film.reflectance(si, c, 1.0, self.eta, 0.0, active, self.n1_max,
                                            self.film_table), self.eta, constant)

    def shares(self, si, active):
        """(x_above, x_below): the compensation's refracted share lit from each side
        (:func:`~mi_brdfs.scattering.multiscatter.transmitted_shares`), per channel with a
        film."""
        alpha = lambda: multiscatter.equivalent_alpha(self.distribution(si, active))  # noqa: E731
        t_above, averages = self.t_above, [table.average(alpha) for table in self.tables]
        if self.film_shift is not None:
            deltas = self._film_deltas(si, active)
            t_above = t_above + self.film_shift.transmittance_shift(deltas)
            averages = [a + d for a, d in zip(averages,
                                              self.film_shift.averages(deltas, alpha))]
        return multiscatter.transmitted_shares(t_above, self.eta, *averages)


class InterfaceCompensation(lobes.Lobe):
    """
    Kulla & Conty's energy compensation of a :class:`MicrofacetInterface` ``source`` with its
    tables (their dielectric extension): the light single scattering loses, 1 − E(μi) of the
    albedo E_R+T on ωi's side, comes back through a lobe (1 − E(μi))(1 − E'(μo))/(π (1 −
    E'_avg)) on ωo's side, E' that side's albedo: the share 1 − x reflected, x refracted
    (reciprocal across the interface), times ks or kt (and 1/η² for radiance through
    refraction, as the single scattering). Sampled from the cosine hemisphere of the side it
    leaves on, chosen by that share; the same components as the source's.
    """

    def __init__(self, source: MicrofacetInterface):
        self.source = source

    def component_flags(self) -> dict:
        return self.source.component_flags()

    def enabled(self, ctx) -> bool:
        return self.source.enabled(ctx)

    def record(self, si, wo):
        return self.source.record(si, wo)

    def _at_wi(self, ctx, si, active):
        """(the probability that a sample reflects; (1 − E(μi))/π times the reflected share,
        and times the refracted share)."""
        has_r, has_t = self.source.sides(ctx)
        x_above, x_below = self.source.shares(si, active)
        x = dr.select(si.wi.z > 0.0, x_above, x_below)
        e_i = self.source.albedo(si, dr.abs(si.wi.z), si.wi.z > 0.0, active)[0]
        missing = dr.maximum(1.0 - e_i, 0.0) * dr.inv_pi
        q_reflect = (1.0 - mean(x)) if (has_r and has_t) else (1.0 if has_r else 0.0)
        return q_reflect, missing * (1.0 - x), missing * x

    def eval_pdf(self, ctx, si, wo, active):
        has_r, has_t = self.source.sides(ctx)
        wi = si.wi
        q_reflect, reflected, refracted = self._at_wi(ctx, si, active)
        reflect = wi.z * wo.z > 0.0
        active = active & (wi.z != 0.0) & (wo.z != 0.0)
        if not (has_r and has_t):
            active = active & (reflect if has_r else ~reflect)
        abs_cos_o = dr.abs(wo.z)
        e_o, avg_o = self.source.albedo(si, abs_cos_o, wo.z > 0.0, active)
        shape = dr.maximum(1.0 - e_o, 0.0) * abs_cos_o / dr.maximum(1.0 - avg_o, 1e-7)
        eta = dr.select(wi.z > 0.0, self.source.eta, self.source.inv_eta)
        value = lobes.choose(
            reflect, lambda: properties.clip_at(self.source.specular, si, active) *
            (reflected * shape),
            lambda: self.source.refraction_factor(ctx, si, eta, active) * (refracted * shape))
        pdf = dr.select(reflect, q_reflect, 1.0 - q_reflect) * abs_cos_o * dr.inv_pi
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        """The cosine hemisphere, on ωi's side where ``sample1`` < the reflected share."""
        q_reflect = self._at_wi(ctx, si, active)[0]
        wo = mi.warp.square_to_cosine_hemisphere(sample2)
        side = dr.select((sample1 < q_reflect) == (si.wi.z > 0.0), 1.0, -1.0)
        return mi.Vector3f(wo.x, wo.y, wo.z * side), True

    def weight(self, ctx, si, active):
        """1 − E(μi) of ωi's side: what single scattering misses."""
        e_i = self.source.albedo(si, dr.abs(si.wi.z), si.wi.z > 0.0, active)[0]
        return 1.0 - dr.clip(mean(e_i), 0.0, 1.0)


def mean(value):
    """The mean over the channels of a spectrum (a film's albedo), a Float as it is."""
    return value if isinstance(value, (int, float, mi.Float)) else dr.mean(value)


def _chosen(probability):
    """The weight factor of a lobe chosen with ``probability`` (F or 1 − F): 1, whose
    derivative in AD variants is that of log(probability), the lobe choice being made on
    detached values (as roughdielectric, so that gradients through sample() stay unbiased)."""
    if not dr.is_diff_v(mi.Float):
        return 1.0
    return dr.replace_grad(mi.Float(1.0), probability / dr.detach(probability))
