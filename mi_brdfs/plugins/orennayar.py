"""
Oren & Nayar's rough diffuse reflectance (1994) in its ``qualitative`` and ``full`` forms,
sampled by the cosine-weighted hemisphere. The terms live in :mod:`mi_brdfs.scattering.orennayar`.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi

from ..scattering import orennayar as terms
from . import lobes, properties

PLUGIN = "orennayar"

#: Largest σ accepted: the standard deviation of a facet's slope angle, which lies within
#: [0, π/2] (the model's coefficients stay finite beyond, but mean nothing there).
SIGMA_MAX = math.pi / 2



class RoughDiffuse(lobes.Diffuse):
    """
    The lobe ρ/π·factor of Oren-Nayar's ``form`` and ``sigma`` (a Float or a texture),
    sampled by the cosine-weighted hemisphere as the Lambertian lobe it generalises: computed
    as it computes, so that σ = 0 (factor exactly 1) is bit-identical to it.
    """

    def __init__(self, reflectance, sigma, form: str):
        super().__init__(reflectance)
        self.sigma, self.form = sigma, form

    def factor(self, si, wo, rho, active):
        """f/(ρ/π) at (ωi, ωo): exactly 1 where σ = 0."""
        sigma = self.sigma.eval_1(si, active) if isinstance(self.sigma, mi.Texture) \
            else self.sigma
        # values set through mi.traverse are not validated: clamp them into the accepted range
        sigma = dr.clip(sigma, 0.0, SIGMA_MAX)
        factor = terms.factor(self.form, sigma, si.wi, wo, rho)
        # the full form as written goes negative at grazing forward scattering: 0 there
        return dr.maximum(factor, 0.0) if self.form == "full" else factor

    def value(self, si, wo, active):
        """(ρ/π·cosθo)·factor, in lambert's order of operations."""
        rho = self.rho(si, active)
        return rho * dr.inv_pi * wo.z * self.factor(si, wo, rho, active)

    def sample_weight(self, ctx, si, wo, active):
        """ρ·factor (ρ alone at σ = 0, as lambert)."""
        rho = self.rho(si, active)
        return rho * self.factor(si, wo, rho, active), mi.warp.square_to_cosine_hemisphere_pdf(wo)


def _sigma(props):
    """σ: a number (-> float) or a texture (-> mi.Texture), finite and within [0, π/2]."""
    return properties.number_or_texture(props, PLUGIN, "sigma", 0.2, 0.0, SIGMA_MAX, "radians")


class OrenNayar(mi.BSDF):
    r"""
    .. _bsdf-orennayar:

    Oren-Nayar rough diffuse reflectance (:monosp:`orennayar`)
    ----------------------------------------------------------

    .. pluginparameters::

     * - reflectance
       - |spectrum| or |texture|
       - ρ, the albedo of each facet, finite and within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

     * - sigma
       - |float| or |texture|
       - σ, the standard deviation of the facets' slope angle in radians, within [0, π/2];
         0 is Lambert (Default: 0.2)
       - |exposed| (JIT variants, or as a texture), |differentiable|

     * - form
       - |string|
       - ``qualitative`` (the paper's simplified model) or ``full`` (with the
         interreflection term) (Default: ``qualitative``)
       -

    With α = max(θi, θo), β = min(θi, θo), Δφ = φi − φo (Oren & Nayar 1994, §4.4):

    .. math::

        f_\text{qualitative} = \frac{\rho}{\pi}\Big(A + B\max(0, \cos\Delta\phi)
            \sin\alpha\tan\beta\Big), \quad A = 1 - \frac{\sigma^2}{2(\sigma^2 + 0.33)},
            \quad B = \frac{0.45\,\sigma^2}{\sigma^2 + 0.09}

    and ``full`` adds the paper's C2, C3 terms and the interreflection term
    0.17 ρ²/π σ²/(σ² + 0.13) (1 − cos Δφ (2β/π)²) (:mod:`mi_brdfs.scattering.orennayar`
    writes all of them). ``eval`` returns f·cosθo; the model is one-sided and reciprocal.
    At σ = 0 it is Lambert's ρ/π, computed as ``lambert`` computes it (bit-identical renders
    in JIT variants).

    **Relation to Mitsuba 0.6's** ``roughdiffuse``: its ``alpha`` is a Beckmann RMS slope,
    which it converts as σ = α/√2; ``alpha`` = 0.2 there is ``sigma`` = 0.1414 here, and
    its ``useFastApprox`` = true is ``form`` = ``qualitative``.

    **Sampling.** The cosine-weighted hemisphere, as Mitsuba 0.6: the weight is ρ·factor,
    at most ρ(A + B) ≤ 1.45 ρ (qualitative), so rough surfaces render with little more noise
    than Lambert's.

    **Polarized variants.** The model describes no polarization: ``eval`` and the sample
    weights are depolarizers (the Mueller matrix with the value in its first element alone), as
    Mitsuba's ``diffuse`` returns them.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="orennayar">
                <rgb name="reflectance" value="0.7, 0.5, 0.3"/>
                <float name="sigma" value="0.5"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'orennayar', 'reflectance': {'type': 'rgb', 'value': [0.7, 0.5, 0.3]},
             'sigma': 0.5}
    """

    def __init__(self, props):
        super().__init__(props)
        #: Facet albedo ρ.
        self.m_reflectance = properties.reflectance(props, PLUGIN, "reflectance", 0.5)
        #: σ: a Float (updatable in JIT variants) or a texture.
        sigma = _sigma(props)
        self._textured_sigma = isinstance(sigma, mi.Texture)
        self.m_sigma = sigma if self._textured_sigma else mi.Float(sigma)
        #: ``qualitative`` or ``full``
        self.m_form = properties.choice(props, PLUGIN, "form", "qualitative", terms.FORMS)
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

    def parameters_changed(self, keys=()):
        """The lobe, from the parameters as they are now (a number σ opaque: a new value
        updates the kernels' inputs, not their code)."""
        if not self._textured_sigma:
            dr.make_opaque(self.m_sigma)
        self.lobes = lobes.Mixture([RoughDiffuse(self.m_reflectance, self.m_sigma, self.m_form)])

    # one lobe: ωo from the cosine-weighted hemisphere, pdf cosθo/π
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def traverse(self, cb):
        cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)
        if self._textured_sigma or dr.is_jit_v(mi.Float):  # a Python float cannot be updated
            cb.put("sigma", self.m_sigma, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"OrenNayar[\n  form = {self.m_form},\n"
                f"  reflectance = {properties.indent(self.m_reflectance)},\n"
                f"  sigma = {properties.indent(self.m_sigma)}\n]")
