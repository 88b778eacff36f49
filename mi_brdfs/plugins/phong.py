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


class Glossy(lobes.Lobe):
    """
    The specular lobe ks·c·cosⁿα·cosθo (over N·L for the ``original`` form) of a ``form`` and
    ``lobe`` (mirror or halfway), sampled by cosⁿ about R (or H about N, then reflected).
    ``exponent``: a Float or a texture.
    """

    kind = "GlossyReflection"

    def __init__(self, specular, form: str, lobe: str, exponent, component: int, flags: int):
        self.specular, self.form, self.lobe = specular, form, lobe
        self.exponent, self.component, self.flags = exponent, component, flags
        mirror = lobe == "mirror"
        self.lobe_value = terms.mirror_lobe if mirror else terms.halfway_lobe
        self.lobe_sample = terms.sample_mirror if mirror else terms.sample_halfway
        #: the constants of a uniform exponent, once per parameter change (opaque: a changed
        #: exponent updates the kernel's inputs instead of recompiling it)
        self.constants = None
        if not isinstance(exponent, mi.Texture):
            self.constants = constants(form, lobe, exponent)
            dr.make_opaque(*self.constants)

    def _constants(self, si, active):
        if self.constants is None:
            return constants(self.form, self.lobe, self.exponent.eval_1(si, active))
        return self.constants

    def eval_pdf(self, ctx, si, wo, active):
        cos_theta_i, cos_theta_o = si.wi.z, wo.z
        active = active & (cos_theta_i > 0) & (cos_theta_o > 0)  # one-sided, like `diffuse`
        # ks·c·cosⁿα·cosθo (over N·L for the original form), and the lobe's own density
        n, _, norm, pdf_norm = self._constants(si, active)
        lobe, pdf = self.lobe_value(si.wi, wo, n, pdf_norm)
        value = properties.clip_at(self.specular, si, active) * (
            norm * lobe * self._projection(ctx, cos_theta_i, cos_theta_o))
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def _projection(self, ctx, cos_theta_i, cos_theta_o):
        """cosθo, divided by N·L in the ``original`` form (L: the light's side)."""
        if self.form != "original":
            return cos_theta_o
        if ctx.mode == mi.TransportMode.Importance:  # L = ωi, floored where f diverges
            return cos_theta_o / dr.maximum(cos_theta_i, COS_LIGHT_MIN)
        return 1.0  # radiance: L = ωo, so cosθo / (N·L) = 1

    def sample(self, ctx, si, sample1, sample2, active):
        """cosⁿ about R, or H about N and ωi reflected about it."""
        return self.lobe_sample(si.wi, sample2, self._constants(si, active)[1]), True

    def weight(self, ctx, si, active):
        """mean(ks)·E(0): the lobe's albedo at normal incidence (as Mitsuba 0.6's phong)."""
        n = self._constants(si, active)[0]
        return dr.mean(properties.clip_at(self.specular, si, active)) * \
            terms.specular_albedo(self.form, self.lobe, n)


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

     * - preset
       - |string|
       - A published fit that fills every parameter the scene does not give (explicit ones
         win): ``ngan:<material>``, Ngan et al. 2005's Blinn-Phong fit to a MERL material
         (``lobe`` ``halfway``, ``form`` ``normalized``); docs/presets.md lists the materials
         and the conversion (Default: none)
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
    the textures' values at the hit point (mean over channels); ``pdf()`` and ``bs.pdf`` are
    the mixture density, and
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

    **Polarized variants.** The model describes no polarization: ``eval`` and the sample
    weights are depolarizers (the Mueller matrix with the value in its first element alone), as
    Mitsuba's ``diffuse`` returns them.

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
        properties.preset(props, PLUGIN)  # a preset's parameters, where the scene gives none
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
        self._has = (not properties.is_zero(self.m_diffuse_reflectance),
                     not properties.is_zero(self.m_specular_reflectance))
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

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

    # the diffuse lobe (cosine-weighted hemisphere) and the glossy one, mixed by their albedos
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobes, from the parameters as they are now."""
        # components: the diffuse lobe first; sampling: the glossy one first
        has_diffuse, has_glossy = self._has
        terms_ = [lobes.Diffuse(self.m_diffuse_reflectance)] if has_diffuse else []
        if has_glossy:
            flags = GLOSSY_FLAGS | (NONSYMMETRIC if self.m_form == "original" else 0)
            terms_.insert(0, Glossy(self.m_specular_reflectance, self.m_form, self.m_lobe,
                                    self.m_exponent, int(has_diffuse), flags))
        self.lobes = lobes.Mixture(terms_)

    def traverse(self, cb):
        # Only the parameters of lobes that exist: the lobe structure is fixed at load time.
        if self._has[0]:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance,
                   mi.ParamFlags.Differentiable)
        if self._has[1]:
            cb.put("specular_reflectance", self.m_specular_reflectance,
                   mi.ParamFlags.Differentiable)
            if self._textured_exponent or dr.is_jit_v(mi.Float):  # a float cannot be updated
                cb.put("exponent", self.m_exponent, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"Phong[\n  form = {self.m_form},\n  lobe = {self.m_lobe},\n"
                f"  diffuse_reflectance = {properties.indent(self.m_diffuse_reflectance)},\n"
                f"  specular_reflectance = {properties.indent(self.m_specular_reflectance)},\n"
                f"  exponent = {properties.indent(self.m_exponent)}\n]")
