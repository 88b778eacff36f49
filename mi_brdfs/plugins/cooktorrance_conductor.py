"""
The lobes of :mod:`~mi_brdfs.plugins.cooktorrance` without transmission: the Cook-Torrance
microfacet lobe ks·F·D·G/(4 cosθi cosθo) (:class:`MicrofacetReflection`, one-sided; pbrt-v4's
``ConductorBxDF`` and Mitsuba's ``roughconductor`` are the same lobe) and Kulla & Conty's
energy compensation of it (:class:`Compensation`), mixed with the paper's optional Lambertian
base (:class:`~mi_brdfs.plugins.lobes.Diffuse`) by :class:`~mi_brdfs.plugins.lobes.Mixture`.

Every method works in the local frame (normal +z), takes ``si.wi`` and ``wo`` as Mitsuba hands
them, and looks ``mi.*`` up when it is called, so that one class serves every variant.
"""

from __future__ import annotations

from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np

from ..reference import multiscatter as reference
from ..scattering import fresnel, microfacet, multiscatter, vector
from . import lobes, properties

#: F of each ``fresnel`` setting, per spectrum (``none``: F ≡ 1, no term).
FRESNEL_TERMS = {"exact": fresnel.exact, "schlick": fresnel.schlick, "none": None}


class MicrofacetReflection(lobes.Lobe):
    """
    ks·F(ωi·m)·D(m)·G(ωi, ωo, m)/(4 cosθi cosθo), m the half vector, sampled by microfacet
    normals reflected: the visible normals of its masking (Heitz & d'Eon 2014) or D·cosθm
    (Walter et al. 2007). Component 0, ``flags``.

    Parameter ``kind`` (str): 'beckmann' or 'ggx'. Parameter ``alpha_u``, ``alpha_v``
    (mi.Texture): the roughness, the same texture when isotropic. Parameter ``masking``
    (str): 'smith' or 'vcavity' (:data:`~mi_brdfs.scattering.microfacet.MASKING`). Parameter
    ``fresnel`` (str): 'exact', 'schlick' or 'none'. Parameter ``sample_visible`` (bool).
    Parameter ``eta``, ``k`` (mi.Texture | None): the complex index (None with ``fresnel``
    'none'). Parameter ``specular`` (mi.Texture): ks. Parameter ``table``
    (multiscatter.AlbedoTable | None): the lobe's own albedo E(μ) with F ≡ 1, which a
    :class:`Compensation` of it needs (it then weighs the lobe as well). Parameter ``film``
    (:class:`~mi_brdfs.plugins.cooktorrance_film.Film` | None): a thin film over the base,
    whose reflectance replaces the exact F (``fresnel`` 'exact').
    """

    kind = "GlossyReflection"

    def __init__(self, kind, alpha_u, alpha_v, masking, fresnel, sample_visible, eta, k,
                 specular, flags, table=None, film=None):
        self.film = film
        #: the film's colour tabulated where it can be (RGB and mono variants)
        self.film_table = None if film is None else film.tabulate(eta, k)
        self.distribution_kind, self.alpha_u, self.alpha_v = kind, alpha_u, alpha_v
        self.masking, self.sample_visible = microfacet.MASKING[masking], sample_visible
        self.fresnel, self.fresnel_term = fresnel, FRESNEL_TERMS[fresnel]
        self.eta, self.k, self.specular = eta, k, specular
        self.flags, self.table = flags, table
        #: F_avg where the index is the same everywhere (no texture): computed once, not per
        #: lookup. In RGB and mono variants a constant per channel; in spectral variants a
        #: table over the visible wavelengths (:class:`SpectralAverage`), looked up at the
        #: sampled ones (the quadrature inside every lookup made a compensated conductor's
        #: kernel about three times larger than the rest of it, and as slow to compile).
        self.f_avg = self.f_avg_table = None
        if table is not None and fresnel != "none" and film is None and \
                not (eta.is_spatially_varying() or k.is_spatially_varying()):
            if mi.is_spectral:
                self.f_avg_table = SpectralAverage(self)
            else:
                self.f_avg = self._fresnel_average(dr.zeros(mi.SurfaceInteraction3f), True)
                dr.make_opaque(self.f_avg)

    def distribution(self, si, active) -> microfacet.Distribution:
        """The microfacet distribution at ``si``."""
        return microfacet.Distribution(
            self.distribution_kind,
            *properties.roughness_at(self.alpha_u, self.alpha_v, si, active))

    def eval_pdf(self, ctx, si, wo, active):
        t = self._terms(si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        # f·cosθo = ks F D G / (4 cosθi cosθo) · cosθo
        value = self._reflect(ctx, si, wo, t, t.D * t.G / (4.0 * si.wi.z), t.active)
        return dr.select(t.active, value, 0.0), dr.select(t.active, t.pdf, 0.0)

    def sample_weight(self, ctx, si, wo, active):
        """ks·F times, in closed form where D and 4 cosθi cancel: G/G1(ωi) (visible normals:
        :meth:`~mi_brdfs.scattering.microfacet.Smith.visible_weight`) or
        G·(ωo·m)/(cosθi cosθm) (D·cos)."""
        t = self._terms(si, wo, active)
        if t is None:
            return mi.Spectrum(0.0), mi.Float(0.0)
        if self.sample_visible:
            shape = t.masking.visible_weight(si.wi, wo, t.m, t.cos_im, t.cos_om)
        else:
            shape = t.G * t.cos_om / dr.maximum(si.wi.z * t.m.z, 1e-30)
        ok = t.active & (t.pdf > 0)
        return dr.select(ok, self._reflect(ctx, si, wo, t, shape, ok), 0.0), \
            dr.select(t.active, t.pdf, 0.0)

    def _terms(self, si, wo, active):
        """
        D, G, the masking and the density of ωo at the half vector m of ωi, ωo above the
        surface (None where a scalar variant's lane is inactive): the one place that computes
        them, for :meth:`eval_pdf` and :meth:`sample_weight`.
        """
        wi = si.wi
        m = vector.half_vector(wi, wo)
        cos_im, cos_om = vector.dot(wi, m), vector.dot(wo, m)
        # one-sided, and both directions see the front of the facet (false only when rounding
        # makes ωi + ωo vanish: grazing, nearly opposite directions)
        active = active & (wi.z > 0) & (wo.z > 0) & (cos_im > 0) & (cos_om > 0)
        if lobes.none(active):
            return None
        distr = self.distribution(si, active)
        masking = self.masking(distr)
        D = distr.ndf(m)
        G = masking.G(wi, wo, m, cos_im, cos_om)
        # the density of ωo: visible normals or D·cosθm, through the reflection's Jacobian
        if self.sample_visible:
            pdf = microfacet.pdf_visible_reflection(D, masking.G1(wi, m, cos_im), wi)
        else:
            pdf = microfacet.pdf_ndf(D, m) * microfacet.reflection_jacobian(wo, m)
        return SimpleNamespace(m=m, cos_im=cos_im, cos_om=cos_om, D=D, G=G, masking=masking,
                               pdf=pdf, active=active)

    def sample(self, ctx, si, sample1, sample2, active):
        """ωi reflected about a microfacet normal: visible normals of the masking (``sample1``
        picks the V-cavity's facet), or D·cosθm."""
        distr = self.distribution(si, active)
        if self.sample_visible:
            m = self.masking(distr).sample_visible(si.wi, sample2, sample1)
        else:
            m = distr.sample(sample2)
        wo = vector.reflect(si.wi, m)
        return wo, wo.z > 0

    def weight(self, ctx, si, active):
        """mean(ks·F(cosθi)); with the albedo table, mean(ks·F_avg)·E(μi) (F_avg, which a
        compensation needs anyway, stands for F(cosθi))."""
        if self.table is None:
            return dr.mean(self._ks_f(si, si.wi.z, 1.0, active))
        ks_f_avg = properties.clip_at(self.specular, si, active)
        if self.fresnel != "none":
            ks_f_avg = ks_f_avg * self.fresnel_average(si, active)
        return dr.mean(ks_f_avg) * self.albedo(si, si.wi.z, active)[0]

    def albedo(self, si, mu, active):
        """(E(μ), E_avg) of the lobe with F ≡ 1 (from its table) at the roughness at ``si``."""
        return self.table(mu, lambda: multiscatter.equivalent_alpha(
            self.distribution(si, active)))

    def fresnel_average(self, si, active):
        """F_avg of the Fresnel term at ``si``, per channel (None for ``fresnel`` 'none')."""
        if self.fresnel == "none":
            return None
        if self.f_avg is not None:
            return self.f_avg
        if self.f_avg_table is not None:
            return self.f_avg_table(si.wavelengths)
        return self._fresnel_average(si, active)

    def _fresnel_average(self, si, active, nodes: int = 5):
        eta = properties.clip_at(self.eta, si, active, 0.0, fresnel.IOR_MAX)
        k = properties.clip_at(self.k, si, active, 0.0, fresnel.IOR_MAX)
        if self.film is not None:
            return self.film.average(si, eta, k, active, nodes)
        if self.fresnel == "exact":
            return multiscatter.fresnel_average(eta, k, nodes)
        return multiscatter.schlick_average(fresnel.r0(eta, k))

    def _reflect(self, ctx, si, wo, t, factor, active):
        """ks·factor·F at the facet of the terms ``t``: F per channel, and in polarized variants
        with ``fresnel`` 'exact' the Mueller matrix of the reflection
        (:func:`~mi_brdfs.scattering.fresnel.polarized_reflection`), as ``roughconductor``."""
        if not (mi.is_polarized and self.fresnel == "exact"):
            return self._ks_f(si, t.cos_im, factor, active)
        eta = properties.clip_at(self.eta, si, active, 0.0, fresnel.IOR_MAX)
        k = properties.clip_at(self.k, si, active, 0.0, fresnel.IOR_MAX)
        radiance = ctx.mode == mi.TransportMode.Radiance
        if self.film is None:
            F = fresnel.polarized_reflection(si.wi, wo, t.m, eta, k, radiance)
        else:
            F = self.film.mueller(si, si.wi, wo, t.m, eta, k, radiance, active)
        # F scaled per channel: the product with the diagonal matrix of ks·factor
        scale = mi.UnpolarizedSpectrum(properties.clip_at(self.specular, si, active) * factor)
        return F @ mi.Spectrum(scale)

    def _ks_f(self, si, cos_theta, factor, active):
        """ks·factor·F(cosθ), F at the cosine between ωi and the facet normal."""
        value = properties.clip_at(self.specular, si, active) * factor
        if self.film is not None:
            return value * self.film.reflectance(
                si, cos_theta, 1.0, properties.clip_at(self.eta, si, active, 0.0,
                                                       fresnel.IOR_MAX),
                properties.clip_at(self.k, si, active, 0.0, fresnel.IOR_MAX), active,
                table=self.film_table)
        if self.fresnel_term is not None:
            value = value * self.fresnel_term(
                cos_theta, properties.clip_at(self.eta, si, active, 0.0, fresnel.IOR_MAX),
                properties.clip_at(self.k, si, active, 0.0, fresnel.IOR_MAX))
        return value


class Compensation(lobes.CosineLobe):
    """
    Kulla & Conty's energy compensation (2017, after Kelemen & Szirmay-Kalos 2001) of a
    :class:`MicrofacetReflection` ``source`` that has its albedo table: the light the single
    scattering loses, given back by ks·F_ms·(1 − E(μi))(1 − E(μo))/(π (1 − E_avg))
    (:mod:`~mi_brdfs.scattering.multiscatter`), the same component as the source's; sampled
    from the cosine-weighted hemisphere, whose density (1 − E(μo)) cosθo is close to.
    """

    kind = "GlossyReflection"

    def __init__(self, source: MicrofacetReflection):
        self.source, self.component, self.flags = source, source.component, source.flags
        #: F_ms/(π (1 − E_avg)) where the roughness and F_avg are constants as well
        self.factor = None
        if source.table.row is not None and (source.fresnel == "none" or
                                             source.f_avg is not None):
            self.factor = _factor(source.fresnel_average(None, True), source.table.row_average)
            dr.make_opaque(self.factor)

    def _scale(self, si, active):
        """(ks·F_ms·(1 − E(μi))/(π (1 − E_avg)), E_avg): what the lobe's value takes of ωi."""
        e_i, e_avg = self.source.albedo(si, si.wi.z, active)
        factor = self.factor if self.factor is not None else \
            _factor(self.source.fresnel_average(si, active), e_avg)
        ks = properties.clip_at(self.source.specular, si, active)
        return ks * (factor * dr.maximum(1.0 - e_i, 0.0)), e_avg

    def value(self, si, wo, active):
        e_o = self.source.albedo(si, wo.z, active)[0]
        return self._scale(si, active)[0] * (dr.maximum(1.0 - e_o, 0.0) * wo.z)

    def weight(self, ctx, si, active):
        """Its albedo: mean(ks·F_ms)·(1 − E(μi))."""
        scale, e_avg = self._scale(si, active)
        return dr.mean(scale) * (dr.pi * dr.maximum(1.0 - e_avg, 0.0))


def _factor(f_avg, e_avg):
    """F_ms/(π (1 − E_avg)): the compensation's factor besides ks and the (1 − E)s; F_ms = 1
    without a Fresnel term (``f_avg`` None)."""
    factor = multiscatter.lobe(0.0, 0.0, e_avg)
    return factor if f_avg is None else factor * multiscatter.multiple_fresnel(f_avg, e_avg)


class SpectralAverage:
    """
    F_avg of an index that is the same everywhere, as a function of the wavelength: tabulated
    at every :data:`STEP` nm of Mitsuba's visible range [MI_CIE_MIN, MI_CIE_MAX] by a 32-node
    rule (computed once), and interpolated linearly at the wavelengths a lookup samples. The
    error is the interpolation's: h²/8 of F_avg's second derivative in λ, and where the index
    is itself tabulated (a named conductor's) up to the step times the jump of F_avg's slope
    at each of its nodes: within 2e-5 for gold
    (``tests/plugins/test_cooktorrance_multiscatter.py::test15_spectral_f_avg_table``),
    below the 5-node rule's 7e-5 that a lookup would use.
    In JIT variants the table is built with drjit operations from the textures of η and k, so
    that a derivative with respect to them (``mi.traverse``) reaches F_avg through it; in scalar
    variants, which have no derivatives, by the float64 reference's quadrature.
    """

    #: The table's step (nm): 1881 nodes; the error at a kink is proportional to it.
    STEP = 0.25

    def __init__(self, lobe):
        self.lo = mi.MI_CIE_MIN
        self.n = int(round((mi.MI_CIE_MAX - self.lo) / self.STEP)) + 1
        lam = self.lo + self.STEP * np.arange(self.n)  # node j in lane j, in every channel
        if dr.is_jit_v(mi.Float):
            si = dr.zeros(mi.SurfaceInteraction3f, self.n)
            si.wavelengths = mi.UnpolarizedSpectrum(mi.Float(lam))
            self.table = mi.Float(lobe._fresnel_average(si, True, 32)[0])
            dr.make_opaque(self.table)
            return
        # scalar variants (no derivatives): η and k node by node, F_avg by the float64 reference
        si, index = dr.zeros(mi.SurfaceInteraction3f), np.empty((2, self.n))
        for j, wavelength in enumerate(lam):
            si.wavelengths = mi.UnpolarizedSpectrum(wavelength)
            index[:, j] = [float(tex.eval(si)[0]) for tex in (lobe.eta, lobe.k)]
        index = np.clip(index, 0.0, fresnel.IOR_MAX)
        self.table = [float(v) for v in reference.fresnel_average(lobe.fresnel, *index, 32)]

    def __call__(self, wavelengths):
        """F_avg at each channel's wavelength (clamped to the table's range)."""
        out = []
        for c in range(len(wavelengths)):
            x = dr.clip((wavelengths[c] - self.lo) / self.STEP, 0.0, self.n - 1.0)
            i = dr.minimum(mi.UInt32(x), self.n - 2)  # x ≥ 0: truncation is the floor
            t = x - mi.Float(i)
            out.append(dr.lerp(self._at(i), self._at(i + 1), t))
        return mi.UnpolarizedSpectrum(out)

    def _at(self, i):
        return dr.gather(mi.Float, self.table, i) if dr.is_jit_v(mi.Float) else self.table[i]
