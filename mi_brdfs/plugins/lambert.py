"""The Lambertian BRDF f = ρ/π, importance-sampled with the cosine-weighted hemisphere."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from . import _common

V = _common.variant_tools()
# Bound once per variant: in scalar variants these are looked up at every call otherwise.
Spectrum, Float = mi.Spectrum, mi.Float
cosine_hemisphere_pdf = mi.warp.square_to_cosine_hemisphere_pdf
DIFFUSE = _common.flag("DiffuseReflection")
FLAGS = _common.flag("DiffuseReflection", "FrontSide")


class Lambert(mi.BSDF):
    r"""
    .. _bsdf-lambert:

    Lambertian reflectance (:monosp:`lambert`)
    ------------------------------------------

    .. pluginparameters::

     * - reflectance
       - |spectrum| or |texture|
       - Diffuse albedo ρ, finite and within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

    The ideal diffuse reflector of the lectures:

    .. math::

        f(\omega_i, \omega_o) = \frac{\rho}{\pi}, \qquad
        \texttt{eval} = \frac{\rho}{\pi} \cos\theta_o, \qquad
        p(\omega_o) = \frac{\cos\theta_o}{\pi}, \qquad
        \text{weight} = \rho .

    Its directional albedo is ρ at every incident angle. The plugin is one-sided (0 when either
    direction is below the surface), like Mitsuba's ``diffuse``, and computes exactly what
    ``diffuse`` computes, in the same order, so both render bit-identical images in JIT variants.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="lambert">
                <rgb name="reflectance" value="0.2, 0.25, 0.7"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'lambert', 'reflectance': {'type': 'rgb', 'value': [0.2, 0.25, 0.7]}}
    """

    def __init__(self, props):
        super().__init__(props)
        #: Diffuse albedo ρ.
        self.m_reflectance = _common.reflectance(props, "lambert", "reflectance", 0.5)
        self.m_flags = FLAGS
        self.m_components = [FLAGS]
        self.parameters_changed()

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = V.new_sample()
        active = active & (si.wi.z > 0)  # one-sided: the local frame's z is cosθ
        if V.none(active) or not ctx.is_enabled(DIFFUSE):
            return bs, Spectrum(0.0)
        # ωo from the cosine-weighted hemisphere, pdf cosθo/π
        wo, pdf = V.cosine_sample(bs, sample2)
        # weight = f·cosθo / pdf = (ρ/π·cosθo) / (cosθo/π) = ρ
        weight = V.spectrum(self._rho(si, active))
        return bs, V.select(active & (pdf > 0), V.depolarize(weight), 0.0)

    eval, pdf, eval_pdf = V.diffuse_methods()

    def _eval_pdf(self, si, wo, active):
        """(f·cosθo, pdf) at ``wo``, for eval, pdf and eval_pdf."""
        wo = V.vector(wo)
        active = active & (si.wi.z > 0) & (wo.z > 0)  # one-sided, like `diffuse`
        if V.none(active):
            return Spectrum(0.0), Float(0.0)
        # f·cosθo = ρ/π·cosθo; pdf: the cosine-weighted hemisphere's
        value = V.scale(self._rho_over_pi(si, active), wo.z)
        pdf = cosine_hemisphere_pdf(wo)
        return V.select(active, V.depolarize(value), 0.0), V.select(active, pdf, 0.0)

    def _rho(self, si, active):
        """ρ at ``si``: per-channel floats when constant in a scalar RGB variant, else a
        spectrum."""
        return self._rho_channels or self.m_reflectance.eval(si, active)

    def _rho_over_pi(self, si, active):
        """ρ/π, the BRDF, in the same form as :meth:`_rho` (channels rounded to float32, as
        ``diffuse`` computes ρ·(1/π) in float32)."""
        return self._rho_pi_channels or self.m_reflectance.eval(si, active) * dr.inv_pi

    def eval_diffuse_reflectance(self, si, active=True):
        return self.m_reflectance.eval(si, active)

    def traverse(self, cb):
        cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=()):
        # a constant ρ is read once where the variant allows it (see _common.variant_tools)
        self._rho_channels = self._rho_pi_channels = None
        if V.per_channel:
            self._rho_channels = _common.constant_channels(self.m_reflectance)
        if self._rho_channels is not None:
            self._rho_pi_channels = [float(np.float32(c) * np.float32(dr.inv_pi))
                                     for c in self._rho_channels]

    def to_string(self):
        return f"Lambert[\n  reflectance = {_common.indent(self.m_reflectance)}\n]"
