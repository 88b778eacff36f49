"""
The shape every plugin has: a BSDF is a :class:`Mixture` of :class:`Lobe` s. A lobe is one term
of f with the strategy that samples it (a Lambertian base and the cosine-weighted hemisphere, a
microfacet lobe and its normals, a compensation lobe, each of Lafortune's cosine lobes); the
mixture picks one strategy per sample in proportion to the lobes' albedo estimates at ωi, and
its density is the mixture of theirs (Veach 1997, "Robust Monte Carlo Methods for Light
Transport Simulation", §9.2.4, the one-sample model), so that ``bs.pdf`` = ``pdf(bs.wo)`` and
the weight is f·cosθo over that density by construction.

A plugin class sets ``self.lobes`` (a :class:`Mixture`) and takes :func:`sample`, :func:`eval`,
:func:`pdf`, :func:`eval_pdf` and :func:`eval_diffuse_reflectance` as its methods
(``sample = lobes.sample``: nanobind allows a single base class, the variant's ``mi.BSDF``, so
they come as class attributes, not from a mixin).

Everything here looks ``mi.*`` up when it is called, so one definition serves every variant.
A Python ``bool`` mask is configuration (or a scalar variant's one lane), anything else an
array traced for all lanes.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..scattering import mixture
from .properties import clip_at


def flag(*names: str) -> int:
    """The integer OR of ``mi.BSDFFlags`` members given by name."""
    value = 0
    for name in names:
        value |= int(getattr(mi.BSDFFlags, name))
    return value


def none(active) -> bool:
    """
    Whether it is known that no lane is active (Mitsuba's ``dr::none_or<false>``): only for a
    Python bool, i.e. in scalar variants, where Mitsuba calls a method once per ray and the
    rest of the method would divide by the zero cosines that made the lane inactive. A JIT
    variant traces every lane and is never told this.
    """
    return type(active) is bool and not active


def choose(mask, a, b):
    """
    ``select(mask, a(), b())``. Where ``mask`` is a Python bool only the branch needed is
    computed; else both are traced, as every lane may need either.
    """
    if type(mask) is bool:
        return a() if mask else b()
    return dr.select(mask, a(), b())


def depolarize(value):
    """A lobe's value as the variant returns BSDF values: in polarized variants a spectrum
    becomes a depolarizing Mueller matrix (as Mitsuba's ``diffuse`` returns), and a Mueller
    matrix (a lobe that models polarization) stays as it is; elsewhere the value itself."""
    if mi.is_polarized and not isinstance(value, mi.Spectrum):
        return mi.depolarizer(mi.UnpolarizedSpectrum(value))
    return value


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


class Lobe:
    """
    One term of a BSDF and the strategy that samples it. A lobe answers for one component of
    the plugin (``component``, of type ``kind``, a ``mi.BSDFFlags`` name, and flags ``flags``),
    and works in the local frame (normal +z) with ``si.wi`` and ``wo`` as Mitsuba hands them.
    Subclasses give :meth:`eval_pdf`, :meth:`sample` and :meth:`weight`; the rest has
    defaults.
    """

    #: The index of the component the lobe answers for, its type and its flags.
    component: int = 0
    kind: str = "DiffuseReflection"
    flags: int = 0
    #: A delta lobe (:class:`DeltaLobe`): its density is a probability mass, not a density.
    delta: bool = False

    def enabled(self, ctx) -> bool:
        """Whether the context asks for this lobe (a Python bool: configuration)."""
        return ctx.is_enabled(getattr(mi.BSDFFlags, self.kind), self.component)

    def component_flags(self) -> dict:
        """{component index: its flags} of the components the lobe answers for."""
        return {self.component: self.flags}

    def eval_pdf(self, ctx, si, wo, active):
        """(f·|cosθo| of this term, density of :meth:`sample` at ``wo``), both 0 where not
        ``active`` or outside the lobe; f not depolarized (the mixture does it once)."""
        raise NotImplementedError

    def eval(self, ctx, si, wo, active):
        """f·|cosθo| of this term alone (what ``eval`` needs: no density, no weight)."""
        return self.eval_pdf(ctx, si, wo, active)[0]

    def sample(self, ctx, si, sample1, sample2, active):
        """(ωo, valid): a direction from the lobe's strategy, and where that succeeded.
        ``sample1`` ∈ [0, 1) is the lobe's own (rescaled by the mixture that picked it)."""
        raise NotImplementedError

    def weight(self, ctx, si, active):
        """The lobe's albedo at ωi, or a bound or estimate of it, as one number per lane (the
        mean over channels): the mixture samples the lobe in proportion to it."""
        raise NotImplementedError

    def record(self, si, wo):
        """(sampled_type, sampled_component, η) of a sample at ``wo``: the lobe's own type and
        component, η = 1 (a lobe that refracts says which it did)."""
        return mi.UInt32(flag(self.kind)), mi.UInt32(self.component), mi.Float(1.0)

    def sample_weight(self, ctx, si, wo, active):
        """(f·|cosθo|/pdf, pdf) at a sampled ``wo`` when the lobe is sampled alone; lobes whose
        weight has a closed form (where D or the cosine cancels) give it here."""
        value, pdf = self.eval_pdf(ctx, si, wo, active)
        return weight(value, pdf, active), pdf

    def sample_alone(self, ctx, si, sample1, sample2, active):
        """(ωo, valid, f·|cosθo|/pdf, pdf) when the lobe is sampled alone: :meth:`sample`, then
        :meth:`sample_weight`; a lobe whose sampler returns its density with ωo (a tabulated
        one) gives both at once here."""
        wo, valid = self.sample(ctx, si, sample1, sample2, active)
        active = active & valid
        if none(active):
            return wo, valid, mi.Spectrum(0.0), mi.Float(0.0)
        value, pdf = self.sample_weight(ctx, si, wo, active)
        return wo, valid, value, pdf

    def diffuse_reflectance(self, si, active):
        """The albedo of a diffuse term (``eval_diffuse_reflectance``), None for other lobes."""
        return None


class DeltaLobe(Lobe):
    """
    A lobe concentrated in one direction (a smooth surface's mirror reflection): f is a Dirac
    delta, so :meth:`eval_pdf` is 0 at every direction a caller can name, and a sample of it
    has the discrete probability of being picked as its ``bs.pdf`` and the lobe's weight over
    that probability as its sample weight (Mitsuba's ``plastic``: ``bs.pdf`` = the specular
    sampling probability). Subclasses give :meth:`delta_value`, ∫ f·cosθo dωo over the delta.
    """

    delta = True

    def delta_value(self, si, active):
        """The reflectance of the delta at ωi (a spectrum): the sample weight when the lobe is
        sampled alone."""
        raise NotImplementedError

    def eval_pdf(self, ctx, si, wo, active):
        return mi.Spectrum(0.0), mi.Float(0.0)

    def eval(self, ctx, si, wo, active):
        return mi.Spectrum(0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        return mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z), si.wi.z > 0

    def sample_alone(self, ctx, si, sample1, sample2, active):
        wo, valid = self.sample(ctx, si, sample1, sample2, active)
        ok = active & valid
        if none(ok):
            return wo, ok, mi.Spectrum(0.0), mi.Float(0.0)
        return wo, ok, dr.select(ok, self.delta_value(si, ok), 0.0), dr.select(ok, 1.0, 0.0)

    def weight(self, ctx, si, active):
        return dr.mean(self.delta_value(si, active))


class CosineLobe(Lobe):
    """
    A lobe sampled from the cosine-weighted hemisphere (density cosθo/π), one-sided: the
    Lambertian base and the terms smooth in ωo. Subclasses give :meth:`value`, f·cosθo where
    both directions are above the surface.
    """

    kind, flags = "DiffuseReflection", flag("DiffuseReflection", "FrontSide")

    def value(self, si, wo, active):
        raise NotImplementedError

    def eval_pdf(self, ctx, si, wo, active):
        active = active & (si.wi.z > 0) & (wo.z > 0)  # one-sided: the local frame's z is cosθ
        if none(active):
            return mi.Spectrum(0.0), mi.Float(0.0)
        pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return dr.select(active, self.value(si, wo, active), 0.0), dr.select(active, pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        return mi.warp.square_to_cosine_hemisphere(sample2), True


class TabulatedLobe(Lobe):
    """
    A one-sided glossy lobe sampled from a tabulated density (``self.sampler``, a
    :class:`mi_brdfs.measured.warp.Sampler`), which returns its density with each draw: sampled
    alone, the lobe evaluates it once. Subclasses give :meth:`value` and set ``sampler``.
    """

    kind, flags = "GlossyReflection", flag("GlossyReflection", "FrontSide")

    def value(self, si, wo, active):
        """f·cosθo where both directions are above the surface (not masked)."""
        raise NotImplementedError

    def eval_pdf(self, ctx, si, wo, active):
        active = active & (si.wi.z > 0) & (wo.z > 0)
        if none(active):
            return mi.Spectrum(0.0), mi.Float(0.0)
        value, pdf = self.value(si, wo, active), self.sampler.pdf(si.wi, wo, active)
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def eval(self, ctx, si, wo, active):
        active = active & (si.wi.z > 0) & (wo.z > 0)
        if none(active):
            return mi.Spectrum(0.0)
        return dr.select(active, self.value(si, wo, active), 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        wo, _, valid = self.sampler.sample(si.wi, sample1, sample2, active)
        return wo, valid

    def sample_alone(self, ctx, si, sample1, sample2, active):
        wo, pdf, valid = self.sampler.sample(si.wi, sample1, sample2, active)
        ok = active & valid & (si.wi.z > 0) & (pdf > 0)
        if none(ok):
            return wo, ok, mi.Spectrum(0.0), mi.Float(0.0)
        value = self.value(si, wo, ok) / dr.select(ok, pdf, 1.0)
        return wo, ok, dr.select(ok, value, 0.0), dr.select(ok, pdf, 0.0)


class Diffuse(CosineLobe):
    """The Lambertian lobe ρ/π (``reflectance``: a texture of ρ), in Mitsuba ``diffuse``'s
    order of operations, so that a plugin of this lobe alone is bit-identical to it."""

    def __init__(self, reflectance, component: int = 0):
        self.reflectance, self.component = reflectance, component

    def rho(self, si, active):
        """ρ at ``si``, clipped into [0, 1]."""
        return clip_at(self.reflectance, si, active)

    def value(self, si, wo, active):
        return self.rho(si, active) * dr.inv_pi * wo.z

    def weight(self, ctx, si, active):
        return dr.mean(self.rho(si, active))

    def sample_weight(self, ctx, si, wo, active):
        """ρ: the cosines and π cancel (what ``diffuse`` returns)."""
        pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        return self.rho(si, active), pdf

    def diffuse_reflectance(self, si, active):
        return self.rho(si, active)


class Mixture:
    """
    The lobes of one BSDF, in the order :meth:`sample` picks them with its first random number
    (the glossy lobes first, by convention); :meth:`sample` and :meth:`eval_pdf` run the lobes
    the context enables. ``two_sided``: ωi may come from below the surface (a
    transmitting interface); else the BSDF is 0 for ωi below, as Mitsuba's ``diffuse``.
    """

    def __init__(self, lobes, two_sided: bool = False):
        self.lobes, self.two_sided = list(lobes), two_sided

    def enabled(self, ctx) -> list:
        """The lobes the context asks for (configuration, not data)."""
        return [lobe for lobe in self.lobes if lobe.enabled(ctx)]

    def probabilities(self, ctx, si, lobes, active) -> list:
        """Each lobe's probability of being sampled: its weight over their sum. Not detached:
        the pdf is the density sample() realises, and so is its derivative."""
        return mixture.probabilities([lobe.weight(ctx, si, active) for lobe in lobes])

    def eval_pdf(self, ctx, si, wo, active=True, probabilities=None):
        """(f·|cosθo|, pdf of :meth:`sample`) at ``wo``: the enabled lobes' sum, and the
        mixture of their densities (a delta lobe's are 0 there: it only takes its
        probability from the others)."""
        lobes = self.enabled(ctx)
        if not lobes:
            return mi.Spectrum(0.0), mi.Float(0.0)
        wo = vector(wo)
        if len(lobes) == 1:
            value, pdf = lobes[0].eval_pdf(ctx, si, wo, active)
            return depolarize(value), pdf
        probs = probabilities or self.probabilities(ctx, si, lobes, active)
        values, pdfs = zip(*(lobe.eval_pdf(ctx, si, wo, active) for lobe in lobes))
        value = depolarize(values[0])
        for v in values[1:]:
            value = value + depolarize(v)
        return value, mixture.pdf(probs, pdfs)

    def eval(self, ctx, si, wo, active=True):
        """f·|cosθo|: the enabled lobes' sum, without their densities or weights (a tabulated
        sampler is not built for it)."""
        lobes = self.enabled(ctx)
        if not lobes:
            return mi.Spectrum(0.0)
        wo = vector(wo)
        value = None
        for lobe in lobes:
            v = depolarize(lobe.eval(ctx, si, wo, active))
            value = v if value is None else value + v
        return value

    def sample(self, ctx, si, sample1, sample2, active=True):
        """(BSDFSample3f, weight f·|cosθo|/pdf): ``sample1`` picks a lobe (and, rescaled, is
        that lobe's own), ``sample2`` draws ωo from it; bs.pdf is the mixture density at ωo."""
        bs, sample2 = dr.zeros(mi.BSDFSample3f), point2(sample2)
        lobes = self.enabled(ctx)
        if not lobes:
            return bs, mi.Spectrum(0.0)
        active = active & ((si.wi.z != 0) if self.two_sided else (si.wi.z > 0))
        if none(active):
            return bs, mi.Spectrum(0.0)
        if len(lobes) == 1:  # alone: the lobe's own weight, in closed form where it has one
            bs.wo, valid, value, bs.pdf = lobes[0].sample_alone(ctx, si, sample1, sample2,
                                                                active)
            bs.sampled_type, bs.sampled_component, bs.eta = lobes[0].record(si, bs.wo)
            return bs, dr.select(active & valid & (bs.pdf > 0), depolarize(value), 0.0)
        probs = self.probabilities(ctx, si, lobes, active)
        k, u = mixture.choose(probs, sample1)
        bs.wo, valid, bs.sampled_type, bs.sampled_component, bs.eta = _draw(
            lobes, k, lambda lobe: lobe.sample(ctx, si, u, sample2, active), si)
        active = active & valid
        value, bs.pdf = self.eval_pdf(ctx, si, bs.wo, active, probs)
        result = weight(value, bs.pdf, active)
        for j, lobe in enumerate(lobes):  # a delta picked: its probability and weight
            if lobe.delta and (not isinstance(k, int) or k == j):
                picked = (k == j) & active & (probs[j] > 0)
                bs.pdf = dr.select(picked, probs[j], bs.pdf)
                result = dr.select(picked, depolarize(lobe.delta_value(si, active)) /
                                   dr.maximum(probs[j], 1e-30), result)
        return bs, result

    def diffuse_reflectance(self, si, active=True):
        """The sum of the diffuse terms' albedos (0 without one)."""
        total = mi.Spectrum(0.0)
        for lobe in self.lobes:
            rho = lobe.diffuse_reflectance(si, active)
            if rho is not None:
                total = total + rho
        return total


def _draw(lobes, k, sample, si):
    """(ωo, valid, type, component, η) of lobe ``k`` (an index: a Python int in scalar
    variants, where only that lobe runs; a UInt32 else, where each lobe is traced and
    selected)."""
    if isinstance(k, int):
        wo, valid = sample(lobes[k])
        return (wo, valid, *lobes[k].record(si, wo))
    out = None
    for j, lobe in enumerate(lobes):
        wo, valid = sample(lobe)
        drawn = (wo, mi.Bool(valid), *lobe.record(si, wo))
        out = drawn if out is None else tuple(dr.select(k == j, a, b)
                                              for a, b in zip(drawn, out))
    return out


# The methods of a plugin class whose ``self.lobes`` is a Mixture (see the module docstring).

def sample(self, ctx, si, sample1, sample2, active=True):
    return self.lobes.sample(ctx, si, sample1, sample2, active)


def eval(self, ctx, si, wo, active=True):
    return self.lobes.eval(ctx, si, wo, active)


def pdf(self, ctx, si, wo, active=True):
    return self.lobes.eval_pdf(ctx, si, wo, active)[1]


def eval_pdf(self, ctx, si, wo, active=True):
    return self.lobes.eval_pdf(ctx, si, wo, active)


def eval_diffuse_reflectance(self, si, active=True):
    # The default, eval(wo = n)·π, would count the glossy lobes
    # (https://github.com/mitsuba-renderer/mitsuba3/pull/1896).
    return self.lobes.diffuse_reflectance(si, active)


def components(lobes) -> tuple[list[int], int]:
    """(m_components, m_flags) of lobes in component order (lobes sharing a component, such
    as a compensation and the lobe it compensates, give it once)."""
    flags = {}
    for lobe in lobes:
        for c, f in lobe.component_flags().items():
            flags[c] = flags.get(c, 0) | f
    listed = [flags[c] for c in sorted(flags)]
    total = 0
    for f in listed:
        total |= f
    return listed, total
