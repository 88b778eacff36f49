"""
What every plugin of the package shares: reading and validating properties, and the few
primitives whose best implementation differs between scalar and JIT variants.

Property readers raise :class:`mi_brdfs.ParameterError` with one line naming the plugin, the
parameter, the value and what is allowed. Mitsuba wraps an exception raised in a plugin
constructor into its own ``RuntimeError`` (with the scene location); the CLI unwraps it again.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import Description, ParameterError
from ..scattering import floats

# -------------------------------------------------------------------------------------------------
# Variant primitives
# -------------------------------------------------------------------------------------------------


def variant_tools() -> SimpleNamespace:
    """
    The few primitives whose best form differs between scalar and JIT variants, for the
    current variant (a plugin module calls this once at import: :mod:`mi_brdfs.registry`
    imports it afresh in every variant).

    In JIT variants a BSDF method is traced once for all lanes: ``select`` is ``dr.select``,
    both branches of ``choose`` are traced, and a new ``BSDFSample3f`` must come from
    ``dr.zeros`` (a default-constructed one has width-0 fields that fail in ``mi.render``). In
    scalar variants Mitsuba calls the method once per ray with Python floats and bools, so a
    Python conditional picks the one branch needed and ``none`` allows an early return.
    """
    jit = dr.is_jit_v(mi.Float)
    if jit:
        def select(mask, a, b):
            return dr.select(mask, a, b)

        def choose(mask, a, b):
            """select(mask, a(), b()): both are traced, as every lane may need either (only
            one where ``mask`` is a Python bool)."""
            if type(mask) is bool:
                return a() if mask else b()
            return dr.select(mask, a(), b())

        def new_sample():
            return dr.zeros(mi.BSDFSample3f)

        def none(mask):
            return False  # unknowable while a kernel is traced symbolically
    else:
        def select(mask, a, b):
            return a if mask else type(a)(b)

        def choose(mask, a, b):
            """select(mask, a(), b()), computing only the one needed."""
            return a() if mask else b()

        new_sample = mi.BSDFSample3f

        def none(mask):
            return not mask

    colour = mi.UnpolarizedSpectrum
    Vector3f, Point2f = mi.Vector3f, mi.Point2f

    def vector(v):
        """A direction as ``mi.Vector3f``: the built-ins also take lists and tuples."""
        return v if type(v) is Vector3f else Vector3f(v)

    if jit:
        def direction(v):
            """A direction for the terms: ``mi.Vector3f`` (lists and tuples converted)."""
            return vector(v)

        def to_mitsuba(v):
            """A direction from the terms as ``mi.Vector3f`` (for ``bs.wo``)."""
            return v
    else:
        # the terms compiled for floats read directions as floats.Vec3 (5× cheaper to read)
        to_mitsuba, Vec3, new = floats.to_mitsuba, floats.Vec3, object.__new__

        def direction(v):
            """A direction for the terms: :class:`~mi_brdfs.scattering.floats.Vec3` (this
            variant's ``mi.Vector3f`` unpacked directly, the common case: 2× faster; it keeps
            the vector, which to_mitsuba gives back)."""
            if type(v) is Vector3f:
                d = new(Vec3)
                d.x, d.y, d.z = v
                d.source = v
                return d
            return floats.to_vec3(v)

    def point2(u):
        """A 2D sample as ``mi.Point2f``: the built-ins also take lists and tuples."""
        return u if type(u) is Point2f else Point2f(u)

    def specialise_class(cls):
        """A plugin class as this variant runs it: itself in JIT variants, its methods compiled
        for Python floats in scalar ones (:func:`~mi_brdfs.scattering.floats.specialise_class`)."""
        return cls if jit else floats.specialise_class(cls)

    def configure(obj, values, nones=()):
        """Compile ``obj``'s eval_pdf and sample for its configuration in scalar variants
        (:func:`~mi_brdfs.scattering.floats.configure`); nothing in JIT variants, where the
        trace drops what is switched off."""
        if not jit:
            floats.configure(obj, values, nones)

    def terms(module):
        """A module of :mod:`mi_brdfs.scattering` as this variant runs it: itself in JIT
        variants, compiled for Python floats in scalar ones (:mod:`~mi_brdfs.scattering.floats`)."""
        return module if jit else floats.specialise(module)

    def spectrum(value):
        """A spectrum, or a colour from a list of per-channel floats."""
        return colour(*value) if type(value) is list else value

    def scale(value, a, b=1.0):
        """(value·a)·b for a spectrum, or for a list of per-channel floats (a constant
        spectrum read by :func:`constant_channels`), which gives one colour."""
        if type(value) is list:
            return colour(*[c * a * b for c in value])
        return value * a * b

    UInt32 = mi.UInt32
    glossy_flag, diffuse_flag = flag("GlossyReflection"), flag("DiffuseReflection")

    cosine_hemisphere = mi.warp.square_to_cosine_hemisphere
    cosine_hemisphere_pdf = mi.warp.square_to_cosine_hemisphere_pdf
    Spectrum, Float = mi.Spectrum, mi.Float

    def glossy_or_diffuse(bs, sample1, sample2, p_glossy, has_diffuse, has_glossy, glossy,
                          glossy_index, diffuse_index):
        """
        Fill ``bs`` for a two-lobe reflection model (``phong``, ``ward``): ωo from
        ``glossy()`` or from the cosine-weighted hemisphere (``sample2``), with both lobes on
        the glossy one where ``sample1`` < ``p_glossy``; the lobe's type and component index
        (None: that lobe is absent), η = 1.
        """
        pick = (sample1 < p_glossy) if has_diffuse and has_glossy else has_glossy
        bs.wo = to_mitsuba(choose(pick, glossy, lambda: cosine_hemisphere(sample2)))
        bs.sampled_type = select(pick, UInt32(glossy_flag), UInt32(diffuse_flag))
        bs.sampled_component = select(pick, UInt32(glossy_index or 0), UInt32(diffuse_index or 0))
        bs.eta = 1.0
        return bs

    def cosine_sample(bs, sample2):
        """
        Fill ``bs`` for a one-lobe diffuse model (``lambert``, ``orennayar``): ωo from the
        cosine-weighted hemisphere, pdf cosθo/π, component 0; returns (ωo, pdf).
        """
        bs.wo = wo = cosine_hemisphere(point2(sample2))
        bs.pdf = pdf = cosine_hemisphere_pdf(wo)
        bs.eta = 1.0
        bs.sampled_type = UInt32(diffuse_flag)
        bs.sampled_component = UInt32(0)
        return wo, pdf

    def diffuse_methods():
        """``eval``, ``pdf`` and ``eval_pdf`` of a one-lobe diffuse model, each 0 where the
        context disables the lobe, else the class's ``_eval_pdf(si, wo, active)``."""
        def eval(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(diffuse_flag):
                return Spectrum(0.0)
            return self._eval_pdf(si, wo, active)[0]

        def pdf(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(diffuse_flag):
                return Float(0.0)
            return self._eval_pdf(si, wo, active)[1]

        def eval_pdf(self, ctx, si, wo, active=True):
            if not ctx.is_enabled(diffuse_flag):
                return Spectrum(0.0), Float(0.0)
            return self._eval_pdf(si, wo, active)

        return eval, pdf, eval_pdf

    def weight(value, pdf, active):
        """The sample weight f·cosθo / pdf, 0 where inactive or the pdf is 0."""
        ok = active & (pdf > 0)
        return select(ok, value / select(ok, pdf, 1.0), 0.0)

    return SimpleNamespace(
        jit=jit,
        glossy_or_diffuse=glossy_or_diffuse,
        cosine_sample=cosine_sample,
        diffuse_methods=diffuse_methods,
        weight=weight,
        select=select,
        choose=choose,
        new_sample=new_sample,
        # Mitsuba's dr::none_or<false>(mask): true only where it is known that no lane is
        # active, i.e. in scalar variants for a false mask; an early return there saves the rest.
        none=none,
        # Whether a constant spectrum can be read once as per-channel Python floats (scalar RGB
        # and mono variants; spectral ones evaluate spectra at each call's wavelengths), so that
        # the terms run on floats and one colour is built per call.
        per_channel=not jit and not mi.is_spectral,
        scale=scale,
        terms=terms,
        specialise_class=specialise_class,
        configure=configure,
        vector=vector,
        direction=direction,
        to_mitsuba=to_mitsuba,
        point2=point2,
        spectrum=spectrum,
        # Mueller matrices in polarized variants; the identity elsewhere.
        depolarize=mi.depolarizer if mi.is_polarized else (lambda value: value),
    )


def constant_channels(tex) -> list[float] | None:
    """A constant texture's value per channel as Python floats (where
    ``variant_tools().per_channel``), else None."""
    if tex.is_spatially_varying():
        return None
    return [float(c) for c in mi.unpolarized_spectrum(tex.eval(mi.SurfaceInteraction3f()))]


def flag(*names: str) -> int:
    """The integer OR of ``mi.BSDFFlags`` members given by name."""
    value = 0
    for name in names:
        value |= int(getattr(mi.BSDFFlags, name))
    return value


# Methods that several plugin classes share. nanobind allows a single base class (the variant's
# mi.BSDF), so a plugin takes them as class attributes (``eval = _common.eval_half``), not
# from a mixin.

def eval_half(self, ctx, si, wo, active=True):
    """``eval`` of a plugin whose ``eval_pdf`` does the work (in JIT variants the unused pdf
    is not computed: the trace drops it)."""
    return self.eval_pdf(ctx, si, wo, active)[0]


def pdf_half(self, ctx, si, wo, active=True):
    """``pdf`` of a plugin whose ``eval_pdf`` does the work."""
    return self.eval_pdf(ctx, si, wo, active)[1]


def set_two_lobes(self, diffuse, specular, glossy_flags: int) -> None:
    """
    The components of a two-lobe reflection model (``phong``, ``ward``), in order (diffuse,
    glossy), of the lobes whose reflectance is not the constant 0 (a lobe that is 0 is left
    out entirely); their indices in ``self._diffuse``, ``self._glossy`` (None: absent).
    """
    self._diffuse = self._glossy = None
    components = []
    if not is_zero(diffuse):
        self._diffuse = len(components)
        components.append(flag("DiffuseReflection", "FrontSide"))
    if not is_zero(specular):
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


# -------------------------------------------------------------------------------------------------
# Property readers
# -------------------------------------------------------------------------------------------------

_T = None


def _types():
    global _T
    if _T is None:
        _T = mi.Properties.Type
    return _T


def _as_float(value) -> float:
    """A Python float from a Python scalar or a width-1 drjit array."""
    return float(np.asarray(value, dtype=np.float64).ravel()[0])


#: Textures whose every value is the value of one of their nested textures.
SELECTING_TEXTURES = ("Checkerboard",)


def texture_range(tex) -> tuple[float, float] | None:
    """
    The (min, max) a texture can return, where that can be known cheaply, else ``None``.

    Exact for constant textures (``uniform``, ``srgb``), for ``bitmap`` (its pixel data, after
    Mitsuba's sRGB linearisation) and for textures that only select among nested textures
    (:data:`SELECTING_TEXTURES`: ``checkerboard``), from their nested textures' ranges; ``None``
    for others (``mesh_attribute``, textures written in Python), whose values depend on the
    shape or on code that cannot be inspected at load time.
    """
    if tex.class_name() in SELECTING_TEXTURES:
        children = []

        class Collect(mi.TraversalCallback):
            def put(self, key, obj, *flags):
                if isinstance(obj, mi.Texture):
                    children.append(obj)

        tex.traverse(Collect())
        ranges = [texture_range(child) for child in children]
        if not ranges or any(r is None for r in ranges):
            return None
        return (min(r[0] for r in ranges), max(r[1] for r in ranges))
    if not tex.is_spatially_varying():
        try:
            mean = _as_float(tex.mean())
        except RuntimeError:  # no mean either (mesh_attribute: values live on the shape)
            return None
        try:
            hi = _as_float(tex.max())
        except RuntimeError:  # Texture::max() is not implemented by every texture
            hi = mean
        # A constant texture's minimum is not exposed; its mean bounds it from above, which
        # catches negative uniform values (the only way to get one: <rgb> is checked by Mitsuba).
        return (min(mean, hi), hi)
    params = mi.traverse(tex)
    if "data" in params:
        data = np.asarray(params["data"])
        if np.issubdtype(data.dtype, np.integer):
            # 8/16-bit storage: normalised values (sRGB-decoded at lookup), within [0, 1] by design
            scale = float(np.iinfo(data.dtype).max)
            return (float(data.min()) / scale, float(data.max()) / scale) if data.size else None
        data = data.astype(np.float64)
        if data.size:
            finite = np.isfinite(data)
            if not finite.all():
                return (math.nan, math.nan)
            return (float(data.min()), float(data.max()))
    return None


_clamped_classes: dict = {}


def clamped(tex, lo: float, hi: float):
    """
    ``tex`` with every value clamped into [``lo``, ``hi``] when it is evaluated: for textures
    whose range cannot be known at load time (see :func:`texture_range`), so that no value
    outside a parameter's range (a negative or energy-creating reflectance) reaches the model.
    Its parameters are the nested texture's, under the same names (``mi.traverse``).
    """
    variant = mi.variant()
    if variant not in _clamped_classes:
        _clamped_classes[variant] = _clamped_class()
    return _clamped_classes[variant](tex, lo, hi)


def _clamped_class():
    """The clamping texture class of the current variant's ``mi.Texture``."""

    class Clamped(mi.Texture):
        def __init__(self, nested, lo, hi):
            super().__init__(mi.Properties())
            self.nested, self.lo, self.hi = nested, lo, hi

        def eval(self, si, active=True):
            return dr.clip(self.nested.eval(si, active), self.lo, self.hi)

        def eval_1(self, si, active=True):
            return dr.clip(self.nested.eval_1(si, active), self.lo, self.hi)

        def eval_3(self, si, active=True):
            return dr.clip(self.nested.eval_3(si, active), self.lo, self.hi)

        def mean(self):
            return dr.clip(self.nested.mean(), self.lo, self.hi)

        def is_spatially_varying(self):
            return True  # as far as anyone can tell: never evaluated without a shape

        def traverse(self, cb):
            self.nested.traverse(cb)

        def parameters_changed(self, keys=()):
            self.nested.parameters_changed(keys)

        def to_string(self):
            return f"Clamped[{self.lo:g}, {self.hi:g}] {indent(self.nested)}"

    return Clamped


def _range_text(lo: float, hi: float, lo_open: bool) -> str:
    if math.isinf(hi):
        return f"must be finite and {'>' if lo_open else '≥'} {lo:g}"
    return f"must be finite and within {'(' if lo_open else '['}{lo:g}, {hi:g}]"


def _in_range(x: float, lo: float, hi: float, lo_open: bool) -> bool:
    return math.isfinite(x) and (x > lo if lo_open else x >= lo) and x <= hi


def texture(props, plugin: str, name: str, default: float, lo: float = 0.0, hi: float = 1.0,
            lo_open: bool = False):
    """
    A spectrally or spatially varying parameter: a float, ``<rgb>``, ``<spectrum>`` or any
    texture, with every value finite and within [``lo``, ``hi``] (``(lo, hi]`` with ``lo_open``).

    Values bounded by 1 are read with ``get_texture`` (reflectances, which Mitsuba upsamples as
    such); others with ``get_unbounded_texture`` (η, k, α), which accepts RGB values above 1.

    A texture whose range can be known at load (:func:`texture_range`) is checked then; one
    whose range cannot (``mesh_attribute``, a texture written in Python) is returned wrapped
    by :func:`clamped`, so that its values are clamped into range at each evaluation.

    Returns → mi.Texture. Raises ParameterError for values out of range or not finite, and for
    properties that are neither numbers nor colours nor textures.
    """
    T = _types()
    allowed = _range_text(lo, hi, lo_open)
    getter = props.get_texture if hi <= 1.0 else props.get_unbounded_texture
    if name in props:
        kind = props.type(name)
        if kind in (T.Float, T.Integer):
            value = float(props[name])
            if not _in_range(value, lo, hi, lo_open):
                raise ParameterError(plugin, name, value, allowed)
        elif kind == T.Color:
            # Checked here, before Mitsuba's own check, so the message names plugin and parameter.
            value = [float(c) for c in props[name]]
            if not all(_in_range(c, lo, hi, lo_open) for c in value):
                raise ParameterError(plugin, name, value, allowed + " in every channel")
        elif kind in (T.Spectrum, T.Object):
            tex = getter(name, default)
            rng = texture_range(tex)
            if rng is None:  # unknowable at load: clamped into range at each evaluation
                return clamped(tex, lo, hi)
            if not (_in_range(rng[0], lo, hi, lo_open) and _in_range(rng[1], lo, hi, lo_open)):
                shown = Description(f"a texture with values in [{rng[0]:g}, {rng[1]:g}]")
                raise ParameterError(plugin, name, shown, allowed)
            return tex
        else:
            raise ParameterError(plugin, name, props[name],
                                 "must be a float, <rgb>, <spectrum> or a texture")
    return getter(name, default)


def reflectance(props, plugin: str, name: str, default: float):
    """A reflectance: :func:`texture` with values in [0, 1]."""
    return texture(props, plugin, name, default, 0.0, 1.0)


def roughness(props, plugin: str, default: float = 0.1):
    """
    (α_u, α_v) textures from ``alpha`` (the same texture twice) or from ``alpha_u`` and
    ``alpha_v``, as Mitsuba's ``roughconductor`` reads them: finite and ≥ 0, both or neither
    of the pair, not together with ``alpha``; warns where a value is below the clamp
    :data:`mi_brdfs.scattering.microfacet.ALPHA_MIN` of the microfacet terms.
    """
    from ..scattering.microfacet import ALPHA_MIN
    given = [name for name in ("alpha_u", "alpha_v") if name in props]
    if given:
        if "alpha" in props:
            raise ParameterError(plugin, given[0], props[given[0]],
                                 "must not be given together with alpha (give alpha for an "
                                 "isotropic surface, alpha_u and alpha_v for an anisotropic one)")
        if len(given) == 1:
            other = "alpha_v" if given[0] == "alpha_u" else "alpha_u"
            raise ParameterError(plugin, given[0], props[given[0]],
                                 f"needs {other} as well (an anisotropic surface has both)")
        names = given
    else:
        names = ["alpha"]
    alphas = [texture(props, plugin, name, default, lo=0.0, hi=math.inf) for name in names]
    for name, tex in zip(names, alphas):
        low = texture_range(tex)
        if low is not None and low[0] < float(np.float32(ALPHA_MIN)):  # 1e-4 held in float32
            warn(plugin, f"{name} = {low[0]:g} is clamped to {ALPHA_MIN:g}, as in Mitsuba's "
                         f"microfacet models")
    return alphas[0], alphas[-1]


def number_or_texture(props, plugin: str, name: str, default: float, lo: float, hi: float,
                      unit: str = ""):
    """
    A parameter given as a number (-> float) or a texture (-> mi.Texture, with
    :func:`texture`'s checks), finite and within [``lo``, ``hi``]; a colour is refused (one
    value per point is meant). ``unit`` is named in the error (e.g. "radians").
    """
    T = _types()
    if name in props and props.type(name) not in (T.Float, T.Integer):
        if props.type(name) != T.Object:
            raise ParameterError(plugin, name, props[name], "must be a float or a texture"
                                 + (f" ({unit})" if unit else ""))
        return texture(props, plugin, name, default, lo, hi)
    return number(props, plugin, name, default, lo, hi)


def alpha_at(alpha_u, alpha_v, si, active):
    """
    α of :func:`roughness`'s textures at ``si``, clamped to
    :data:`mi_brdfs.scattering.microfacet.ALPHA_MIN` as Mitsuba clamps it: a number when
    isotropic (``alpha_v`` is ``alpha_u``), else the pair (αu, αv).
    """
    from ..scattering.microfacet import ALPHA_MIN
    a_u = dr.maximum(alpha_u.eval_1(si, active), ALPHA_MIN)
    return a_u if alpha_v is alpha_u else (a_u, dr.maximum(alpha_v.eval_1(si, active), ALPHA_MIN))


def constant_alpha(alpha_u, alpha_v):
    """α of :func:`roughness`'s textures as Python floats (clamped), when neither varies over the
    surface (for scalar variants, read once); else None."""
    from ..scattering.microfacet import ALPHA_MIN
    textures = (alpha_u,) if alpha_v is alpha_u else (alpha_u, alpha_v)
    if any(tex.is_spatially_varying() for tex in textures):
        return None
    si = mi.SurfaceInteraction3f()
    const = tuple(max(float(tex.eval_1(si)), ALPHA_MIN) for tex in textures)
    return const if len(const) > 1 else const[0]


def number(props, plugin: str, name: str, default: float, lo: float = -math.inf,
           hi: float = math.inf, lo_open: bool = False) -> float:
    """A plain number (not a texture), finite and within [``lo``, ``hi``]."""
    if name not in props:
        return float(default)
    T = _types()
    if props.type(name) not in (T.Float, T.Integer):
        raise ParameterError(plugin, name, props[name], "must be a number")
    value = float(props[name])
    if not _in_range(value, lo, hi, lo_open):
        raise ParameterError(plugin, name, value, _range_text(lo, hi, lo_open))
    return value


def choice(props, plugin: str, name: str, default: str, choices) -> str:
    """A string among ``choices`` (case-sensitive, as Mitsuba's own options)."""
    if name not in props:
        return default
    value = props[name]
    if not isinstance(value, str) or value not in choices:
        raise ParameterError(plugin, name, value,
                             "must be one of " + ", ".join(f'"{c}"' for c in choices))
    return value


def boolean(props, plugin: str, name: str, default: bool) -> bool:
    if name not in props:
        return default
    value = props[name]
    if not isinstance(value, bool):
        raise ParameterError(plugin, name, value, "must be a boolean (true or false)")
    return value


def reject(props, plugin: str, name: str, hint: str) -> None:
    """Refuse a property the plugin deliberately does not take, saying what to do instead."""
    if name in props:
        raise ParameterError(plugin, name, props[name], hint)


def is_zero(tex) -> bool:
    """Whether a texture is the constant 0 (so the lobe it scales can be left out entirely)."""
    rng = texture_range(tex)
    return rng is not None and not tex.is_spatially_varying() and rng[0] == 0.0 == rng[1]


def upper_bound(props, name: str, tex) -> list[float] | None:
    """Per-channel upper bound of a parameter where it is cheap to know, else None."""
    T = _types()
    if name in props and props.type(name) in (T.Float, T.Integer):
        return [float(props[name])]
    if name in props and props.type(name) == T.Color:
        return [float(c) for c in props[name]]
    rng = texture_range(tex)
    return None if rng is None else [rng[1]]


def warn_sum(props, plugin: str, a, b, consequence: str) -> None:
    """
    Warn (values kept) where two reflectances, ``a`` and ``b`` as (name, texture), can add up
    to more than 1 in some channel, saying the ``consequence``.
    """
    bounds = [upper_bound(props, name, tex) for name, tex in (a, b)]
    if bounds[0] is None or bounds[1] is None:
        return
    total = float(np.max(np.add(*bounds)))  # per channel; one value stands for every channel
    if total > 1.0 + 1e-6:  # not for rounding: an <rgb> 0.8 is stored as 0.800000012
        warn(plugin, f"{a[0]} + {b[0]} reaches {total:g} > 1: {consequence}; values kept")


def warn(plugin: str, message: str) -> None:
    """A one-line warning from a plugin (values kept), shown by the CLI as such."""
    import warnings

    from ..errors import MiBrdfsWarning
    warnings.warn(f"{plugin}: {message}", MiBrdfsWarning, stacklevel=3)


def indent(obj, amount: int = 2) -> str:
    """``str(obj)`` with every line after the first indented, as Mitsuba's ``string::indent``."""
    return str(obj).replace("\n", "\n" + " " * amount)
