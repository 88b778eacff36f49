"""The Lambertian BRDF f = ρ/π, importance-sampled with the cosine-weighted hemisphere."""

from __future__ import annotations

import mitsuba as mi

from . import lobes, properties


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

    **Polarized variants.** The model describes no polarization: ``eval`` and the sample
    weights are depolarizers (the Mueller matrix with the value in its first element alone), as
    Mitsuba's ``diffuse`` returns them.

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
        self.lobes = lobes.Mixture([lobes.Diffuse(self.m_reflectance)])
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

    # one lobe: ωo from the cosine-weighted hemisphere, pdf cosθo/π, weight ρ
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def traverse(self, cb):
        cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

    def to_string(self):
        return f"Lambert[\n  reflectance = {properties.indent(self.m_reflectance)}\n]"
