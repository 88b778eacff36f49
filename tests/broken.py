"""
Deliberately broken BSDFs, to show that each check can fail. Each is a Lambert with one
defect; register them with :func:`register_broken` in the current variant.
"""

import drjit as dr
import mitsuba as mi


def register_broken():
    """Register the broken plugins in the current variant and return their ids."""

    class UniformSampledCosinePdf(mi.BSDF):
        """Samples the hemisphere uniformly but reports the cosine pdf (χ² must reject it)."""

        def __init__(self, props):
            super().__init__(props)
            self.m_flags = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [self.m_flags]

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = mi.warp.square_to_uniform_hemisphere(sample2)
            bs.pdf = mi.warp.square_to_cosine_hemisphere_pdf(bs.wo)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            ok = active & (si.wi.z > 0) & (bs.pdf > 0)
            return bs, dr.select(ok, mi.Spectrum(0.5), mi.Spectrum(0.0))

        def eval(self, ctx, si, wo, active=True):
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, mi.Spectrum(0.5 * dr.inv_pi) * wo.z, mi.Spectrum(0.0))

        def pdf(self, ctx, si, wo, active=True):
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, mi.warp.square_to_cosine_hemisphere_pdf(wo), 0.0)

        def to_string(self):
            return "UniformSampledCosinePdf[]"

    mi.register_bsdf("broken_pdf", UniformSampledCosinePdf)
    return ["broken_pdf"]
