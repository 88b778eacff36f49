"""
What the semi-empirical reflectance models of Earth observation and planetary science share
(``rtls``, ``rpv``, ``hapke``): a :class:`Surface` gives the model's f·cosθo from its textures
and its float64 reference (``mi_brdfs.reference``) at constant parameters; :func:`lobe` makes
the one lobe of such a plugin: sampled from a density tabulated from that reference
(:class:`mi_brdfs.measured.warp.Sampler`, which follows a hot spot) where every texture is the
same everywhere, else from the cosine-weighted hemisphere; either way with a pdf of 0 where f
is 0 (a model clamped at 0), so that the pdf is the density of the samples that succeed.
"""

from __future__ import annotations

from collections import OrderedDict

import drjit as dr
import mitsuba as mi

from ..measured import warp
from . import lobes, properties

#: The tabulated samplers of this process by (variant, plugin, constant values, shape
#: parameters): the latest :data:`KEPT` (an optimisation moves the parameters at every step).
_samplers: OrderedDict = OrderedDict()
KEPT = 16


def sampler(key: tuple, density) -> warp.Sampler:
    """The sampler of ``key`` (in this variant) from the cache, tabulated where it is not there
    from the float64 function ``density()`` returns, f(wi, wo) → (...) (one channel)."""
    key = (mi.variant(), *key)
    if key not in _samplers:
        _samplers[key] = warp.Sampler(*warp.density(density()))
        while len(_samplers) > KEPT:
            _samplers.popitem(last=False)
    _samplers.move_to_end(key)
    return _samplers[key]


def given(names, values) -> str:
    """The constant parameters as a warning at load names them: "a = 0.1, b = 0.2/0.3/0.4"
    (one value per channel where they differ)."""
    return ", ".join(f"{name} = {'/'.join(f'{x:g}' for x in v)}"
                     for name, v in zip(names, values))


def constant(tex) -> float | None:
    """The value of a texture that is the same everywhere (its mean over the channels), or
    None for one that varies over the surface or cannot say."""
    if tex.is_spatially_varying():
        return None
    try:
        return properties.as_float(tex.mean())
    except RuntimeError:  # mesh_attribute and others without a mean
        return None


def channels(props, name: str, tex) -> list[float] | None:
    """A parameter's value per channel where the scene gives a float or an <rgb>, else its
    constant value (:func:`constant`), None where it varies over the surface."""
    T = mi.Properties.Type
    if name in props and props.type(name) in (T.Float, T.Integer):
        return [float(props[name])]
    if name in props and props.type(name) == T.Color:
        return [float(c) for c in props[name]]
    value = constant(tex)
    return None if value is None else [value]


class Surface:
    """
    A model's parameters as its lobe uses them: ``textures`` (name → texture) and ``shape``
    (floats). Subclasses set :attr:`plugin` and give :meth:`value` (f·cosθo), :meth:`level`
    (an estimate of the albedo, the cosine lobe's weight in a mixture) and :meth:`reference`
    (the float64 model at :attr:`constants`, with ``brdf(wi, wo)`` → (..., channels)).
    """

    plugin = ""

    def __init__(self, textures: dict, shape: tuple = ()):
        self.textures, self.shape = textures, shape
        values = [constant(tex) for tex in textures.values()]
        #: the textures' constant values (:meth:`clip`), None where one varies
        self.constants = None if any(v is None for v in values) else self.clip(values)

    def clip(self, values: list) -> tuple:
        """The constant values as the model reads them (default: unchanged)."""
        return tuple(values)

    def value(self, si, wo, active):
        raise NotImplementedError

    def level(self, si, active):
        raise NotImplementedError

    def reference(self):
        raise NotImplementedError

    def sampler(self) -> warp.Sampler:
        """The sampler of the model at the constant values (shared by every surface of the
        same values in this variant), built from the float64 reference."""
        def mean_brdf():
            model = self.reference()
            return lambda wi, wo: model.brdf(wi, wo).mean(axis=-1)

        return sampler((self.plugin, *self.constants, *self.shape), mean_brdf)


def _reflects(value):
    """Where f·cosθo is positive in some channel: elsewhere (a clamp made f 0) a sample drawn
    there fails and its pdf is 0. A polarized value is a depolarizer's Mueller matrix: its
    (0, 0) element is f·cosθo."""
    return dr.any(mi.unpolarized_spectrum(value) > 0)


class _Clamped:
    """What both samplings share: the value from the :class:`Surface`, and a pdf of 0 where f
    is 0 (:func:`_reflects`)."""

    def __init__(self, surface: Surface):
        self.surface, self.component = surface, 0

    def value(self, si, wo, active):
        return self.surface.value(si, wo, active)

    def eval_pdf(self, ctx, si, wo, active):
        value, pdf = super().eval_pdf(ctx, si, wo, active)
        return value, dr.select(_reflects(value), pdf, 0.0)


class Tabulated(_Clamped, lobes.TabulatedLobe):
    """The model where its parameters are constant: sampled from its tabulated density."""

    @property
    def sampler(self) -> warp.Sampler:
        """Built when first needed (``eval`` alone needs none: a fit builds none)."""
        return self.surface.sampler()

    def sample_alone(self, ctx, si, sample1, sample2, active):
        """The tabulated lobe's own (it reads the density its draw returns, not eval_pdf)."""
        wo, ok, weight, pdf = super().sample_alone(ctx, si, sample1, sample2, active)
        return wo, ok, weight, dr.select(_reflects(weight), pdf, 0.0)

    def weight(self, ctx, si, active):
        return self.sampler.albedo(si.wi)


class Cosine(_Clamped, lobes.CosineLobe):
    """The model where a parameter varies over the surface: sampled from the cosine-weighted
    hemisphere."""

    kind, flags = "GlossyReflection", lobes.flag("GlossyReflection", "FrontSide")

    def weight(self, ctx, si, active):
        return self.surface.level(si, active)


def lobe(surface: Surface) -> lobes.Mixture:
    """The plugin's lobes: one, tabulated where ``surface``'s textures are all constant."""
    return lobes.Mixture([Cosine(surface) if surface.constants is None else Tabulated(surface)])
