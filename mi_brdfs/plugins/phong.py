"""
The lecture's Phong reflectance model in its three forms (``normalized``, ``lecture``,
``original``) with a mirror (Phong) or halfway (Blinn-Phong) lobe, importance-sampled, finite and
consistent in float32 for every exponent from 0 to 1e30. The lobe terms live in
:mod:`mi_brdfs.scattering.phong`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..scattering import mixture
from ..scattering import phong as terms
from . import lobes, properties

PLUGIN = "phong"

#: Largest exponent accepted. The lobe is then 1e-15 rad wide, far below the 6e-8 rad spacing of
#: float32 directions: beyond n ≈ 1e12 the plugin already behaves as a mirror (see the class
#: docstring). The bound keeps n and (n+1)/(2π) finite in float32.
EXPONENT_MAX = 1e30

#: Floor of N·L in the ``original`` form's 1/(N·L) under importance transport, where L = ωi: the
#: model itself diverges for a light at the horizon (f → ∞ as N·L → 0 at fixed V); the floor
#: (0.006° above the horizon) keeps f·cosθo ≤ 1e4·ks instead of overflowing to Inf.
COS_LIGHT_MIN = 1e-4

AMBIENT_HINT = ("a path tracer has no ambient term: the environment provides it; add "
                "<emitter type=\"constant\"> with the ambient radiance to the scene instead")


def _exponent(props):
    """The exponent: a number (-> float) or a texture (-> mi.Texture), finite and ≥ 0."""
    return properties.number_or_texture(props, PLUGIN, "exponent", 30.0, 0.0, EXPONENT_MAX)


GLOSSY_FLAGS = lobes.flag("GlossyReflection", "FrontSide")
NONSYMMETRIC = lobes.flag("NonSymmetric")


def constants(form, lobe, n):
    """(n, 1/(n+1), specular factor, pdf factor (n+1)/(2π)) of the lobe, per lane of n."""
    # values set through mi.traverse are not validated: clamp them into the accepted range
    n = dr.clip(n, 0.0, EXPONENT_MAX)
    return (n, 1.0 / (n + 1.0), terms.specular_normalization(form, lobe, n),
            terms.pdf_normalization(n))


class Phong(mi.BSDF):
    r"""
    .. _bsdf-phong:

    Phong reflectance in the lecture's three forms (:monosp:`phong`)
    ----------------------------------------------------------------

    .. pluginparameters::

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - Diffuse albedo ρd, finite and within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

     * - specular_reflectance
       - |spectrum| or |texture|
       - Specular reflectance ks, finite and within [0, 1] (Default: 0.2)
       - |exposed|, |differentiable|

     * - exponent
       - |float| or |texture|
       - Phong exponent n, finite and within [0, 1e30]; 0 is a uniform lobe (Default: 30)
       - |exposed| (JIT variants, or as a texture), |differentiable|

     * - form
       - |string|
       - ``normalized`` (energy-conserving, reciprocal), ``lecture`` (f = ks cosⁿα as in the
         lecture notes) or ``original`` (Phong's 1975 shading model, not reciprocal)
         (Default: ``normalized``)
       -

     * - lobe
       - |string|
       - ``mirror``: cos α = R·V (Phong); ``halfway``: cos α = N·H (Blinn-Phong)
         (Default: ``mirror``)
       -

    With L the direction towards the light, V towards the viewer, R the mirror image of L
    and H = (L + V)/‖L + V‖:

    .. math::

        f_\text{normalized} &= \frac{\rho_d}{\pi} + k_s\,c_n \cos^n\alpha, &
        c_n &= \frac{n+2}{2\pi}\ \text{(mirror)},\
               \frac{(n+2)(n+4)}{8\pi\,(n + 2^{-n/2})}\ \text{(halfway)} \\
        f_\text{lecture} &= \frac{\rho_d}{\pi} + k_s \cos^n\alpha, \qquad
        f_\text{original} = \frac{\rho_d}{\pi} + k_s \frac{\cos^n\alpha}{N\cdot L}

    with cos α = max(0, R·V) or max(0, N·H). ``eval`` returns f·cosθo. The ``normalized``
    specular lobe reflects exactly ks at normal incidence (Lafortune & Willems 1994; Giesen
    2009 for the halfway lobe), so the model conserves energy iff ρd + ks ≤ 1 (a warning
    says so otherwise, values kept). ``lecture`` and ``original`` are the unnormalized forms
    of the notes: their specular albedo at normal incidence is 2πks/(n+2) and 2πks/(n+1)
    (mirror lobe), above ks for small n (a warning names the albedo where ρd + ks·E(0) > 1,
    values kept). ``original`` is not reciprocal: the plugin declares
    ``NonSymmetric`` and keeps L the light side in both transport modes (radiance: L = ωo,
    V = ωi; importance: L = ωi, V = ωo, with 1/(N·L) floored at N·L = 1e-4, where the
    model itself diverges). There is no ambient term and no distance
    attenuation: in a path tracer the environment and the light transport provide them (an
    ``ambient`` property is rejected: use ``<emitter type="constant">``).

    A lobe whose reflectance is the constant 0 is left out entirely (flags, components,
    sampling, cost): ks = 0 gives a diffuse-only BSDF, ρd = 0 a glossy-only one.

    **Sampling.** ``sample()`` picks the diffuse lobe (cosine-weighted hemisphere) or the
    specular one (cos α = u^(1/(n+1)) about R; for the halfway lobe H about N, then
    reflected, Jacobian 1/(4 V·H)) in proportion to their albedos at normal incidence with
    the textures' mean values; ``pdf()`` and ``bs.pdf`` are the mixture density, and
    samples below the horizon have weight 0. Every form samples the same way.

    **Float32.** The lobe is evaluated as exp(n·log1p(−(1 − cos α))) with 1 − cos α free of
    cancellation, and sampled with expm1 (:mod:`mi_brdfs.scattering.phong`), so that ``eval``
    and the sampled directions follow the float64 lobe far beyond the exponents where the
    textbook pow(R·V, n) and sqrt(1 − cos²θ) break down; ``validation/phong_float32.py``
    measures both against the float64 reference, exponent by exponent (``python
    validation/phong_float32.py``; docs/models.md quotes its table). The halfway lobe is less
    precise than the mirror lobe at large n:
    the half-vector of two float32 unit vectors is itself uncertain by about 3e-8 rad. Beyond
    n ≈ 1e12 the lobe (about sqrt(2/n) rad wide) spans only a few float32 directions: sampled
    directions snap to them and the lobe's shape is lost, but weights and densities stay
    consistent, so the plugin acts as a mirror of reflectance ks·cosθo (normalized form), with
    no NaN, Inf or negative value anywhere (grazing, V = −L, N·L → 0) up to n = 1e30.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="phong">
                <rgb name="diffuse_reflectance" value="0.4, 0.1, 0.1"/>
                <float name="specular_reflectance" value="0.5"/>
                <float name="exponent" value="100"/>
                <string name="lobe" value="halfway"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'phong', 'diffuse_reflectance': {'type': 'rgb', 'value': [0.4, 0.1, 0.1]},
             'specular_reflectance': 0.5, 'exponent': 100.0, 'lobe': 'halfway'}
    """

    def __init__(self, props):
        super().__init__(props)
        properties.reject(props, PLUGIN, "ambient", AMBIENT_HINT)
        #: ``normalized``, ``lecture`` or ``original``
        self.m_form = properties.choice(props, PLUGIN, "form", "normalized", terms.FORMS)
        #: ``mirror`` or ``halfway``
        self.m_lobe = properties.choice(props, PLUGIN, "lobe", "mirror", terms.LOBES)
        #: Diffuse albedo ρd and specular reflectance ks.
        self.m_diffuse_reflectance = properties.reflectance(props, PLUGIN,
                                                            "diffuse_reflectance", 0.5)
        self.m_specular_reflectance = properties.reflectance(props, PLUGIN,
                                                             "specular_reflectance", 0.2)
        #: Exponent n: a Float (updatable in JIT variants) or a texture.
        exponent = _exponent(props)
        self._textured_exponent = isinstance(exponent, mi.Texture)
        self.m_exponent = exponent if self._textured_exponent else mi.Float(exponent)
        if self.m_form == "normalized":
            properties.warn_sum(props, PLUGIN,
                                ("diffuse_reflectance", self.m_diffuse_reflectance),
                                ("specular_reflectance", self.m_specular_reflectance),
                                "the normalized form then reflects more light than it receives "
                                "(its albedo at normal incidence is their sum)")
        else:
            self._warn_unnormalised(props, exponent)

        # Lobes in component order; one whose reflectance is the constant 0 is left out.
        lobes.set_two_lobes(self, self.m_diffuse_reflectance, self.m_specular_reflectance,
                            GLOSSY_FLAGS | (NONSYMMETRIC if self.m_form == "original" else 0))
        mirror = self.m_lobe == "mirror"
        self._lobe_value = terms.mirror_lobe if mirror else terms.halfway_lobe
        self._lobe_sample = terms.sample_mirror if mirror else terms.sample_halfway
        self.parameters_changed([])

    def _warn_unnormalised(self, props, exponent):
        """Warn (values kept) where the ``lecture`` or ``original`` form, not normalised,
        reflects more than it receives at normal incidence: ρd + ks·E(0) > 1, with E(0) of the
        smallest exponent (the table above; E falls as n grows)."""
        n = (exponent if not self._textured_exponent else
             (properties.texture_range(exponent) or (None,))[0])
        d = properties.upper_bound(props, "diffuse_reflectance", self.m_diffuse_reflectance)
        s = properties.upper_bound(props, "specular_reflectance", self.m_specular_reflectance)
        if n is None or d is None or s is None:
            return  # a bound that cannot be known at load: nothing to say
        albedo = float(np.max(np.add(d, np.multiply(s, float(terms.specular_albedo(
            self.m_form, self.m_lobe, float(n)))))))
        if albedo > 1.0 + 1e-6:  # not for rounding: an <rgb> 0.8 is stored as 0.800000012
            properties.warn(PLUGIN, f"form = {self.m_form} reflects {albedo:g} > 1 of the light "
                                    f"at normal incidence (ρd + ks·E(0) at n = {float(n):g}: "
                                    f"the form is not normalised); values kept")

    eval, pdf = lobes.eval_half, lobes.pdf_half
    _enabled = lobes.two_lobes_enabled
    eval_diffuse_reflectance = lobes.two_lobes_diffuse_reflectance

    sample, eval_pdf = lobes.two_lobes_sample, lobes.two_lobes_eval_pdf

    def _sample_glossy(self, si, sample2, consts):
        """ωo from the glossy lobe: cosⁿ about R, or H about N."""
        return self._lobe_sample(si.wi, sample2, consts[1])

    def _glossy_probability(self, si):
        """The probability of sampling the glossy lobe: constant per BSDF."""
        return self._p_glossy

    def _eval_pdf(self, ctx, si, wo, active, enabled, consts=None):
        """(f·cosθo, mixture pdf of :meth:`sample`) at ``wo`` for the ``enabled`` lobes
        (diffuse, glossy)."""
        has_diffuse, has_glossy = enabled
        cos_theta_i, cos_theta_o = si.wi.z, wo.z
        active = active & (cos_theta_i > 0) & (cos_theta_o > 0)  # one-sided, like `diffuse`
        if has_diffuse:
            # ρd/π·cosθo, sampled by the cosine-weighted hemisphere
            pdf = dr.inv_pi * cos_theta_o
            value = self.m_diffuse_reflectance.eval(si, active) * pdf
        if has_glossy:
            # ks·c·cosⁿα·cosθo (over N·L for the original form), and the lobe's own density
            n, _, norm, pdf_norm = consts or self._lobe_constants(si, active)
            lobe, pdf_s = self._lobe_value(si.wi, wo, n, pdf_norm)
            value_s = self.m_specular_reflectance.eval(si, active) * (
                norm * lobe * self._projection(ctx, cos_theta_i, cos_theta_o))
            if has_diffuse:  # both lobes: their sum, and the mixture of both strategies
                value, pdf = value + value_s, mixture.pdf(self._p_glossy, pdf_s, pdf)
            else:
                value, pdf = value_s, pdf_s
        return lobes.finish(value, pdf, active)

    def _projection(self, ctx, cos_theta_i, cos_theta_o):
        """cosθo, divided by N·L in the ``original`` form (L: the light's side)."""
        if self.m_form != "original":
            return cos_theta_o
        if ctx.mode == mi.TransportMode.Importance:  # L = ωi, floored where f diverges
            return cos_theta_o / dr.maximum(cos_theta_i, COS_LIGHT_MIN)
        return 1.0  # radiance: L = ωo, so cosθo / (N·L) = 1

    def _lobe_constants(self, si, active):
        if self._textured_exponent:
            return constants(self.m_form, self.m_lobe, self.m_exponent.eval_1(si, active))
        return self._constants

    _glossy_params = _lobe_constants

    def parameters_changed(self, keys=()):
        """Precompute the lobe constants and the lobe choice probability."""
        n = self.m_exponent
        if not self._textured_exponent:
            self._constants = constants(self.m_form, self.m_lobe, n)
        n_mean = dr.clip(dr.detach(n.mean() if self._textured_exponent else n), 0.0,
                         EXPONENT_MAX)
        # Lobe choice by albedo weights, from the textures' means (as Mitsuba's roughplastic and
        # Mitsuba 0.6's phong): constant per BSDF, so nothing to evaluate per call.
        w_d = dr.detach(self.m_diffuse_reflectance.mean())
        w_s = dr.detach(self.m_specular_reflectance.mean()) * terms.specular_albedo(
            self.m_form, self.m_lobe, n_mean)
        self._p_glossy = mi.Float(mixture.probability(w_s, w_d))
        # opaque: a changed parameter updates the kernel's inputs instead of recompiling it
        dr.make_opaque(self._p_glossy, *([] if self._textured_exponent else self._constants))

    def traverse(self, cb):
        # Only the parameters of lobes that exist: the lobe structure is fixed at load time.
        if self._diffuse is not None:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance,
                   mi.ParamFlags.Differentiable)
        if self._glossy is not None:
            cb.put("specular_reflectance", self.m_specular_reflectance,
                   mi.ParamFlags.Differentiable)
            if self._textured_exponent or dr.is_jit_v(mi.Float):  # a float cannot be updated
                cb.put("exponent", self.m_exponent, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"Phong[\n  form = {self.m_form},\n  lobe = {self.m_lobe},\n"
                f"  diffuse_reflectance = {properties.indent(self.m_diffuse_reflectance)},\n"
                f"  specular_reflectance = {properties.indent(self.m_specular_reflectance)},\n"
                f"  exponent = {properties.indent(self.m_exponent)}\n]")
