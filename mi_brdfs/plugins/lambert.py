"""The Lambertian BRDF f = ρ/π, importance-sampled with the cosine-weighted hemisphere."""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from . import _common


def build() -> type:
    """Define the ``lambert`` plugin class on the current variant's ``mi.BSDF``."""
    tools = _common.variant_tools()
    select, new_sample, none = tools.select, tools.new_sample, tools.none
    depolarize = tools.depolarize
    DIFFUSE = _common.flag("DiffuseReflection")
    FLAGS = _common.flag("DiffuseReflection", "FrontSide")
    # Bound once: scalar variants call these per ray, and each `mi.` lookup costs ~0.1 µs there.
    Spectrum, Float, UInt32 = mi.Spectrum, mi.Float, mi.UInt32
    cosine_hemisphere = mi.warp.square_to_cosine_hemisphere
    cosine_hemisphere_pdf = mi.warp.square_to_cosine_hemisphere_pdf
    INV_PI = dr.inv_pi
    # Scalar RGB and mono variants: Mitsuba calls the plugin once per ray, where one operation
    # on a colour costs ~0.3 µs and on a Python float ~0.02 µs; a constant ρ is read once
    # (parameters_changed) and ρ/π·cosθo computed per channel on floats, rounded exactly as
    # float32 arithmetic rounds it (so that the plugin stays bit-identical to `diffuse`).
    flat_ok = not tools.jit and not mi.is_spectral and not mi.is_polarized

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

        Its directional albedo is ρ at every incident angle. The plugin is one-sided (0 when
        either direction is below the surface), like Mitsuba's ``diffuse``, and computes exactly
        what ``diffuse`` computes, in the same order, so both render bit-identical images.

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
            #: Scalar variants, constant ρ: ρ/π per channel rounded to float32, as Python
            #: floats, else None (see flat_ok).
            self._rho_pi = None
            self.parameters_changed()

        def _eval_pdf(self, si, wo, active):
            """f·cosθo and the cosine-hemisphere pdf of ``wo``; the only place with the maths."""
            # Local shading frame: cosθ is the z coordinate.
            cos_theta_i, cos_theta_o = si.wi.z, wo.z
            active = active & (cos_theta_i > 0) & (cos_theta_o > 0)  # one-sided, like `diffuse`
            if none(active):
                return Spectrum(0.0), Float(0.0)
            if self._rho_pi is not None:
                # float32 products: a product of two float32 values is exact in a Python float,
                # and Mitsuba rounds it to float32 once, as float32 arithmetic would
                return (Spectrum(*[c * cos_theta_o for c in self._rho_pi]),
                        cosine_hemisphere_pdf(wo))
            value = self.m_reflectance.eval(si, active) * INV_PI * cos_theta_o
            pdf = cosine_hemisphere_pdf(wo)
            return select(active, depolarize(value), 0.0), select(active, pdf, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = new_sample()
            active = active & (si.wi.z > 0)
            if none(active) or not ctx.is_enabled(DIFFUSE):
                return bs, Spectrum(0.0)
            bs.wo = wo = cosine_hemisphere(sample2)
            bs.pdf = pdf = cosine_hemisphere_pdf(wo)
            bs.eta = 1.0
            bs.sampled_type = UInt32(DIFFUSE)
            bs.sampled_component = UInt32(0)
            # f·cosθo / pdf = (ρ/π·cosθo) / (cosθo/π) = ρ
            weight = self.m_reflectance.eval(si, active)
            return bs, select(active & (pdf > 0), depolarize(weight), 0.0)

        def eval(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(DIFFUSE):
                return Spectrum(0.0)
            return self._eval_pdf(si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(DIFFUSE):
                return Float(0.0)
            return self._eval_pdf(si, wo, active)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(DIFFUSE):
                return Spectrum(0.0), Float(0.0)
            return self._eval_pdf(si, wo, active)

        def eval_diffuse_reflectance(self, si, active=True):
            return self.m_reflectance.eval(si, active)

        def traverse(self, cb):
            cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

        def parameters_changed(self, keys=()):
            """Read a constant ρ once as per-channel floats where that is valid (flat_ok)."""
            self._rho_pi = None
            if not flat_ok or self.m_reflectance.is_spatially_varying():
                return
            rho = self.m_reflectance.eval(mi.SurfaceInteraction3f())
            self._rho_pi = [float(np.float32(c) * np.float32(INV_PI)) for c in rho]

        def to_string(self):
            return f"Lambert[\n  reflectance = {_common.indent(self.m_reflectance)}\n]"

    return Lambert
