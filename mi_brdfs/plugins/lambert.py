"""The Lambertian BRDF f = ρ/π, importance-sampled with the cosine-weighted hemisphere."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from . import lobes, properties

FLAGS = lobes.flag("DiffuseReflection", "FrontSide")


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
        self.m_reflectance = properties.reflectance(props, "lambert", "reflectance", 0.5)
        self.m_flags = FLAGS
        self.m_components = [FLAGS]

    # ωo from the cosine-weighted hemisphere, pdf cosθo/π
    sample = lobes.diffuse_sample
    eval, pdf = lobes.diffuse_eval, lobes.diffuse_pdf
    eval_pdf = lobes.diffuse_eval_pdf

    def _sample_weight(self, si, wo, active):
        """f·cosθo / pdf = (ρ/π·cosθo) / (cosθo/π) = ρ."""
        return self.m_reflectance.eval(si, active)

    def _eval_pdf(self, si, wo, active):
        """(f·cosθo, pdf) at ``wo``, for eval, pdf and eval_pdf."""
        wo = lobes.vector(wo)
        active = active & (si.wi.z > 0) & (wo.z > 0)  # one-sided, like `diffuse`
        # f·cosθo = ρ/π·cosθo, in diffuse's order of operations; pdf: the cosine-weighted
        # hemisphere's
        value = self.m_reflectance.eval(si, active) * dr.inv_pi * wo.z
        pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return lobes.finish(value, pdf, active)

    def eval_diffuse_reflectance(self, si, active=True):
        return self.m_reflectance.eval(si, active)

    def traverse(self, cb):
        cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

    def to_string(self):
        return f"Lambert[\n  reflectance = {properties.indent(self.m_reflectance)}\n]"
