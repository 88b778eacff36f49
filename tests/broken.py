"""
Deliberately broken BSDFs, to show that each check can fail: ``broken`` is a Lambert (ρ = 0.5)
with exactly one defect, chosen by its ``defect`` property, so that each check is also shown to
be specific (the other checks still pass on it where they should):

=============  ==========================================================================
``defect``     what is wrong
=============  ==========================================================================
``none``       nothing: a correct Lambert (control)
``pdf``        samples the hemisphere uniformly but reports the cosine pdf (χ²)
``weight``     the sample weight lacks the cosine: f/pdf instead of f·cosθo/pdf (consistency)
``bspdf``      bs.pdf is twice pdf(bs.wo) (consistency)
``energy``     f = 1.5/π: albedo 1.5 (energy)
``reciprocal`` f = (2/π) ρ cosθi: depends on the incident side only (reciprocity)
``nan``        eval and pdf are 0/0 = NaN for cosθo < 1e-3 (stability, positivity)
``negative``   eval is negative for φo < 0 (positivity)
``eval``       eval() is 3× f·cosθo (albedo 1.5), sample() weights are right (energy, consistency)
=============  ==========================================================================
"""

import drjit as dr
import mitsuba as mi

DEFECTS = ("none", "pdf", "weight", "bspdf", "energy", "reciprocal", "nan", "negative", "eval")


def register_broken():
    """Register ``broken`` in the current variant."""

    class Broken(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.defect = props.get("defect", "none")
            assert self.defect in DEFECTS, self.defect
            self.m_flags = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [self.m_flags]

        def _f(self, wi, wo):
            """f (without cosine) for directions above the surface."""
            if self.defect == "energy":
                return mi.Float(1.5 * dr.inv_pi)
            if self.defect == "reciprocal":
                return 2 * dr.inv_pi * 0.5 * wi.z
            if self.defect == "negative":
                return dr.select(wo.y < 0, -0.5 * dr.inv_pi, 0.5 * dr.inv_pi)
            return mi.Float(0.5 * dr.inv_pi)

        def _pdf(self, wo):
            if self.defect == "pdf":
                return mi.warp.square_to_cosine_hemisphere_pdf(wo)  # but samples uniformly
            return mi.warp.square_to_cosine_hemisphere_pdf(wo)

        def _eval_pdf(self, si, wo, active):
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            value, pdf = self._f(si.wi, wo) * wo.z, self._pdf(wo)
            if self.defect == "nan":
                bad = wo.z < 1e-3
                value = dr.select(bad, mi.Float(float("nan")), value)
                pdf = dr.select(bad, mi.Float(float("nan")), pdf)
                ok = ok | (active & (si.wi.z > 0) & bad & (wo.z >= 0))
            return dr.select(ok, mi.Spectrum(value), 0.0), dr.select(ok, pdf, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            if self.defect == "pdf":
                bs.wo = mi.warp.square_to_uniform_hemisphere(sample2)
            else:
                bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
            value, pdf = self._eval_pdf(si, bs.wo, active)
            bs.pdf = 2 * pdf if self.defect == "bspdf" else pdf
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            ok = active & (si.wi.z > 0) & (pdf > 0)
            weight = value / dr.select(ok, pdf, 1.0)
            if self.defect == "weight":
                weight = weight / dr.maximum(bs.wo.z, 1e-6)
            return bs, dr.select(ok, weight, 0.0)

        def eval(self, ctx, si, wo, active=True):
            return self.eval_pdf(ctx, si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            return self._eval_pdf(si, wo, active)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            value, pdf = self._eval_pdf(si, wo, active)
            return (value * 3.0 if self.defect == "eval" else value), pdf

        def to_string(self):
            return f"Broken[defect={self.defect}]"

    mi.register_bsdf("broken", Broken)
    return "broken"


def broken(defect):
    return {"type": "broken", "defect": defect}


def register_wrapper(name, inner, sample=None, value=None, pdf_of=None):
    """
    Register ``name``: a BSDF that hands every call to ``inner`` (a loaded BSDF) except what
    is replaced: ``sample(inner, ctx, si, s1, s2, active)`` for sample(), ``value(inner, ctx,
    si, wo, active)`` for eval() (and eval_pdf's value), ``pdf_of(ctx, si, wo, active)`` for
    pdf() (and eval_pdf's pdf). For defects that live in one method of a real model.
    """
    class Wrapper(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.m_flags, self.m_components = inner.m_flags, list(inner.m_components)

        def sample(self, ctx, si, s1, s2, active=True):
            if sample is not None:
                return sample(inner, ctx, si, s1, s2, active)
            return inner.sample(ctx, si, s1, s2, active)

        def eval(self, ctx, si, wo, active=True):
            if value is not None:
                return value(inner, ctx, si, wo, active)
            return inner.eval(ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):
            if pdf_of is not None:
                return pdf_of(ctx, si, wo, active)
            return inner.pdf(ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    mi.register_bsdf(name, Wrapper)
    return {"type": name}


GRADIENT_DEFECTS = ("none", "eval_detached", "eval_sign", "pdf_scaled", "weight_detached",
                    "weight_sign")


def register_broken_gradients():
    """
    Register ``gradbroken``: ρ cosθo/π (``reflectance``, traversable and differentiable),
    sampled from the cosine-weighted hemisphere with probability ρ, else uniformly, so that
    eval, pdf and the weights all depend on ρ; with exactly one defect in a derivative
    (``defect``, :data:`GRADIENT_DEFECTS`), its values unchanged:

    ``eval_detached`` eval computed from a detached ρ; ``eval_sign`` eval's derivative negated;
    ``pdf_scaled`` pdf's derivative 1.2 times; ``weight_detached`` the weight detached (as a
    renderer may, on purpose); ``weight_sign`` the weight's derivative negated.
    """

    def flip(x):
        return dr.replace_grad(x, 2.0 * dr.detach(x) - x)  # the same value, −∂x

    class GradBroken(mi.BSDF):
        def __init__(self, props):
            super().__init__(props)
            self.defect = props.get("defect", "none")
            assert self.defect in GRADIENT_DEFECTS, self.defect
            self.m_reflectance = props.get_texture("reflectance", 0.5)
            self.m_flags = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [self.m_flags]

        def _rho(self, si, active):
            return mi.Float(self.m_reflectance.eval_1(si, active))

        def _eval_pdf(self, si, wo, active):
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            rho = self._rho(si, ok)
            f_rho = dr.detach(rho) if self.defect == "eval_detached" else rho
            value = mi.Spectrum(f_rho * dr.inv_pi * wo.z)
            if self.defect == "eval_sign":
                value = flip(value)
            pdf = rho * wo.z * dr.inv_pi + (1.0 - rho) * dr.inv_two_pi
            if self.defect == "pdf_scaled":
                pdf = dr.replace_grad(pdf, 1.2 * pdf)
            return dr.select(ok, value, 0.0), dr.select(ok, pdf, 0.0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs = dr.zeros(mi.BSDFSample3f)
            cosine = sample1 < dr.detach(self._rho(si, active))
            bs.wo = dr.select(cosine, mi.warp.square_to_cosine_hemisphere(sample2),
                              mi.warp.square_to_uniform_hemisphere(sample2))
            value, bs.pdf = self._eval_pdf(si, bs.wo, active)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.DiffuseReflection)
            ok = active & (bs.pdf > 0)
            weight = dr.select(ok, value / dr.select(ok, bs.pdf, 1.0), 0.0)
            if self.defect == "weight_detached":
                weight = dr.detach(weight)
            elif self.defect == "weight_sign":
                weight = flip(weight)
            return bs, weight

        def eval(self, ctx, si, wo, active=True):
            return self._eval_pdf(si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            return self._eval_pdf(si, wo, active)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            return self._eval_pdf(si, wo, active)

        def traverse(self, cb):
            cb.put("reflectance", self.m_reflectance, mi.ParamFlags.Differentiable)

        def to_string(self):
            return f"GradBroken[defect={self.defect}]"

    mi.register_bsdf("gradbroken", GradBroken)
    return "gradbroken"
