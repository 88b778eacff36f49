"""
What the plugins' ``mi.BSDF`` classes share beyond the maths: the lobe flags, the choice between
two lobes when sampling (the one-sample mixture of :mod:`mi_brdfs.scattering.mixture`), the sample
record of a one-lobe diffuse model, and the methods several classes take as they are.

Everything here looks ``mi.*`` up when it is called, so one definition serves every variant, and
its meaning is the same in each: a Python ``bool`` mask is configuration (or a scalar variant's
one lane), anything else an array traced for all lanes.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .properties import is_zero


def flag(*names: str) -> int:
    """The integer OR of ``mi.BSDFFlags`` members given by name."""
    value = 0
    for name in names:
        value |= int(getattr(mi.BSDFFlags, name))
    return value


def choose(mask, a, b):
    """
    ``select(mask, a(), b())``. Where ``mask`` is a Python bool only the branch needed is
    computed; else both are traced, as every lane may need either.
    """
    if type(mask) is bool:
        return a() if mask else b()
    return dr.select(mask, a(), b())


def none(active) -> bool:
    """
    Whether it is known that no lane is active (Mitsuba's ``dr::none_or<false>``): only for a
    Python bool, i.e. in scalar variants, where Mitsuba calls a method once per ray and the
    rest of the method would divide by the zero cosines that made the lane inactive. A JIT
    variant traces every lane and is never told this.
    """
    return type(active) is bool and not active


def depolarize(value):
    """A spectrum as the variant returns BSDF values: a depolarizing Mueller matrix in polarized
    variants, itself elsewhere."""
    return mi.depolarizer(value) if mi.is_polarized else value


def new_sample():
    """A zeroed ``mi.BSDFSample3f`` (a default-constructed one has width-0 fields in JIT
    variants, which fail inside ``mi.render``)."""
    return dr.zeros(mi.BSDFSample3f)


def vector(v):
    """A direction as ``mi.Vector3f``: the built-ins also take lists and tuples."""
    return v if isinstance(v, mi.Vector3f) else mi.Vector3f(v)


def point2(u):
    """A 2D sample as ``mi.Point2f``: the built-ins also take lists and tuples."""
    return u if isinstance(u, mi.Point2f) else mi.Point2f(u)


def weight(value, pdf, active):
    """The sample weight f·cosθo / pdf, 0 where inactive or the pdf is 0."""
    ok = active & (pdf > 0)
    return dr.select(ok, value / dr.select(ok, pdf, 1.0), 0.0)


def finish(value, pdf, active):
    """(f·cosθo, pdf) as ``eval_pdf`` returns them: depolarized, and 0 where inactive."""
    return dr.select(active, depolarize(value), 0.0), dr.select(active, pdf, 0.0)


# Methods that several plugin classes share. nanobind allows a single base class (the variant's
# mi.BSDF), so a plugin takes them as class attributes (``eval = lobes.eval_half``), not
# from a mixin.

def eval_half(self, ctx, si, wo, active=True):
    """``eval`` of a plugin whose ``eval_pdf`` does the work (in JIT variants the unused pdf
    is not computed: the trace drops it)."""
    return self.eval_pdf(ctx, si, wo, active)[0]


def pdf_half(self, ctx, si, wo, active=True):
    """``pdf`` of a plugin whose ``eval_pdf`` does the work."""
    return self.eval_pdf(ctx, si, wo, active)[1]


# -------------------------------------------------------------------------------------------------
# One diffuse lobe (lambert, orennayar)
# -------------------------------------------------------------------------------------------------

def cosine_sample(bs, sample2):
    """
    Fill ``bs`` for a one-lobe diffuse model: ωo from the cosine-weighted hemisphere, pdf
    cosθo/π, component 0; returns (ωo, pdf).
    """
    bs.wo = wo = mi.warp.square_to_cosine_hemisphere(point2(sample2))
    bs.pdf = pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
    bs.eta = 1.0
    bs.sampled_type = mi.UInt32(flag("DiffuseReflection"))
    bs.sampled_component = mi.UInt32(0)
    return wo, pdf


def diffuse_sample(self, ctx, si, sample1, sample2, active=True):
    """
    ``sample`` of a one-lobe diffuse model: ωo from the cosine-weighted hemisphere, and the
    weight f·cosθo / pdf that the class's ``_sample_weight(si, wo, active)`` gives (ρ for
    Lambert, where the cosines and π cancel).
    """
    bs = new_sample()
    if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
        return bs, mi.Spectrum(0.0)
    active = active & (si.wi.z > 0)  # one-sided: the local frame's z is cosθ
    if none(active):
        return bs, mi.Spectrum(0.0)
    wo, pdf = cosine_sample(bs, sample2)
    weight = self._sample_weight(si, wo, active)
    return bs, dr.select(active & (pdf > 0), depolarize(weight), 0.0)


def diffuse_eval(self, ctx, si, wo, active=True):
    """``eval`` of a one-lobe diffuse model: 0 where the context disables the lobe, else the
    class's ``_eval_pdf(si, wo, active)``."""
    if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
        return mi.Spectrum(0.0)
    return self._eval_pdf(si, wo, active)[0]


def diffuse_pdf(self, ctx, si, wo, active=True):
    """``pdf`` of a one-lobe diffuse model (:func:`diffuse_eval`)."""
    if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
        return mi.Float(0.0)
    return self._eval_pdf(si, wo, active)[1]


def diffuse_eval_pdf(self, ctx, si, wo, active=True):
    """``eval_pdf`` of a one-lobe diffuse model (:func:`diffuse_eval`)."""
    if not ctx.is_enabled(mi.BSDFFlags.DiffuseReflection):
        return mi.Spectrum(0.0), mi.Float(0.0)
    return self._eval_pdf(si, wo, active)


# -------------------------------------------------------------------------------------------------
# A diffuse and a glossy lobe (phong, ward, ashikhmin)
# -------------------------------------------------------------------------------------------------

def set_two_lobes(self, diffuse, specular, glossy_flags: int) -> None:
    """
    The components of a two-lobe reflection model, in order (diffuse, glossy), of the lobes
    whose reflectance is not the constant 0 (a lobe that is 0 is left out entirely); their
    indices in ``self._diffuse``, ``self._glossy`` (None: absent).
    """
    set_lobes(self, not is_zero(diffuse), not is_zero(specular), glossy_flags)


def set_lobes(self, has_diffuse: bool, has_glossy: bool, glossy_flags: int) -> None:
    """:func:`set_two_lobes` for a model that decides itself which of its lobes exist."""
    self._diffuse = self._glossy = None
    components = []
    if has_diffuse:
        self._diffuse = len(components)
        components.append(flag("DiffuseReflection", "FrontSide"))
    if has_glossy:
        self._glossy = len(components)
        components.append(glossy_flags)
    self.m_components = components  # a copy crosses to C++: assign, don't append
    self.m_flags = 0
    for c in components:
        self.m_flags |= c


def two_lobes_enabled(self, ctx):
    """Which lobes of :func:`set_two_lobes` the context asks for: (diffuse, glossy), bools."""
    return (self._diffuse is not None and
            ctx.is_enabled(mi.BSDFFlags.DiffuseReflection, self._diffuse),
            self._glossy is not None and
            ctx.is_enabled(mi.BSDFFlags.GlossyReflection, self._glossy))


def two_lobes_diffuse_reflectance(self, si, active=True):
    """``eval_diffuse_reflectance`` of :func:`set_two_lobes`'s models: ρd, or 0 without it."""
    if self._diffuse is None:
        return mi.Spectrum(0.0)
    return self.m_diffuse_reflectance.eval(si, active)


def glossy_or_diffuse(self, bs, sample1, sample2, p_glossy, lobes, glossy):
    """
    Fill ``bs`` for a model of :func:`set_two_lobes`: ωo from ``glossy()`` or from the
    cosine-weighted hemisphere (``sample2``), the glossy one where ``sample1`` < ``p_glossy``
    when both of ``lobes`` (diffuse, glossy: enabled) are; the lobe's type and component
    index, η = 1.
    """
    has_diffuse, has_glossy = lobes
    pick = (sample1 < p_glossy) if has_diffuse and has_glossy else has_glossy
    bs.wo = choose(pick, glossy, lambda: mi.warp.square_to_cosine_hemisphere(sample2))
    bs.sampled_type = dr.select(pick, mi.UInt32(flag("GlossyReflection")),
                                mi.UInt32(flag("DiffuseReflection")))
    bs.sampled_component = dr.select(pick, mi.UInt32(self._glossy or 0),
                                     mi.UInt32(self._diffuse or 0))
    bs.eta = 1.0
    return bs


def two_lobes_sample(self, ctx, si, sample1, sample2, active=True):
    """
    ``sample`` of a model of :func:`set_two_lobes` whose class gives
    ``_glossy_params(si, active)`` (what its glossy lobe needs at ``si``, computed once),
    ``_sample_glossy(si, sample2, params)`` → ωo, ``_glossy_probability(si)`` and
    ``_eval_pdf(ctx, si, wo, active, enabled, params)`` → (f·cosθo, mixture pdf of ``sample``):
    ωo from the glossy lobe where ``sample1`` < the probability (both lobes enabled), else
    from the cosine-weighted hemisphere; bs.pdf is the mixture density at ωo and the weight
    f·cosθo / pdf, 0 below the horizon.
    """
    bs, sample2 = new_sample(), point2(sample2)
    enabled = self._enabled(ctx)
    if not (enabled[0] or enabled[1]):
        return bs, mi.Spectrum(0.0)
    active = active & (si.wi.z > 0)  # one-sided: the local frame's z is cosθ
    if none(active):
        return bs, mi.Spectrum(0.0)
    params = self._glossy_params(si, active) if enabled[1] else None
    glossy_or_diffuse(self, bs, sample1, sample2, self._glossy_probability(si), enabled,
                      lambda: self._sample_glossy(si, sample2, params))
    value, bs.pdf = self._eval_pdf(ctx, si, bs.wo, active, enabled, params)
    return bs, weight(value, bs.pdf, active)


def two_lobes_eval_pdf(self, ctx, si, wo, active=True):
    """``eval_pdf`` of a model of :func:`two_lobes_sample`: its ``_eval_pdf`` for the lobes
    the context enables."""
    enabled = self._enabled(ctx)
    if not (enabled[0] or enabled[1]):
        return mi.Spectrum(0.0), mi.Float(0.0)
    return self._eval_pdf(ctx, si, vector(wo), active, enabled)
