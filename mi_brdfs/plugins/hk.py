"""
Hanrahan & Krueger's layered BSDF, Mitsuba 0.6's ``hk`` carried over: the single-scattering
term of a slab (:mod:`mi_brdfs.scattering.hk`, float64 in :mod:`mi_brdfs.reference.hk`), its
unscattered beam (a null interaction), the interface's mirror reflection where η ≠ 1, and an
optional Lambertian base.
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..scattering import hk as layer
from ..scattering import hk_orders
from ..scattering.fresnel import IOR_MAX
from . import lobes, properties

PLUGIN = "hk"
#: Mitsuba 0.6's defaults: σs = σa = 0.5 per unit length, thickness 1, isotropic phase.
DEFAULTS = {"sigma_s": 0.5, "sigma_a": 0.5}


class Slab:
    """The layer's parameters as the lobes evaluate them at a point."""

    def __init__(self, sigma_s, sigma_a, rho, thickness, g, eta, base, orders=None):
        self.sigma_s, self.sigma_a, self.rho = sigma_s, sigma_a, rho
        self.thickness, self.g, self.eta, self.base = thickness, g, eta, base
        #: ``scattering = all``: the higher orders (:class:`hk_orders.Orders`), else None.
        self.orders = orders

    def at(self, si, active):
        """(albedo, τ, ρ) at ``si`` (spectra)."""
        s = properties.clip_at(self.sigma_s, si, active, 0.0, math.inf)
        a = properties.clip_at(self.sigma_a, si, active, 0.0, math.inf)
        t = s + a
        albedo = dr.select(t > 0, s / dr.select(t > 0, t, 1.0), 0.0)
        rho = properties.clip_at(self.rho, si, active) if self.base else 0.0
        return albedo, t * self.thickness, rho


def _flip(w, below):
    return mi.Vector3f(w.x, w.y, dr.select(below, -w.z, w.z))


class Scattered(lobes.Lobe):
    """
    The scattered light (and the base), reflected and, without a base, transmitted:
    component 0. Sampled from a mixture of Henyey-Greenstein's lobe of g about −ωi (the
    unrefracted forward direction: the phase function itself where η = 1; over a base only
    where g < 0, as it then points back up) and the cosine-weighted hemispheres of both sides
    (of the reflecting side alone over a base).
    """

    kind = "GlossyReflection"

    def __init__(self, slab: Slab):
        self.slab, self.component = slab, 0
        # over a base a forward lobe would point into it: there, the cosine alone for g ≥ 0
        self.p_hg = 0.25 + 0.5 * abs(slab.g) if not slab.base or slab.g < 0 else 0.0
        self.p_r = (1.0 - self.p_hg) * (1.0 if slab.base else 0.5)
        names = ("GlossyReflection", "FrontSide") if slab.base else \
            ("GlossyReflection", "GlossyTransmission", "FrontSide", "BackSide")
        self.flags = lobes.flag(*names)

    def enabled(self, ctx) -> bool:
        return self._asked(ctx, "GlossyReflection") or self._asked(ctx, "GlossyTransmission")

    def _asked(self, ctx, kind) -> bool:
        return ctx.is_enabled(getattr(mi.BSDFFlags, kind), self.component) and \
            (kind == "GlossyReflection" or not self.slab.base)

    def value(self, ctx, si, wo, active):
        below = si.wi.z < 0
        wi, wo_ = _flip(si.wi, below), _flip(wo, below)
        albedo, tau, rho = self.slab.at(si, active)
        s = self.slab
        f = layer.single(wi, wo_, albedo, tau, s.g, s.eta, rho, s.base)
        if s.orders is not None:
            f = f + s.orders.value(wi, wo_, albedo, tau, rho) * dr.abs(wo_.z)
        keep = dr.select(wo_.z > 0, self._asked(ctx, "GlossyReflection"),
                         self._asked(ctx, "GlossyTransmission"))
        return dr.select(keep & active & (wi.z > 0) & (wo_.z != 0), f, 0.0)

    def density(self, si, wo):
        """The mixture's density at ``wo``."""
        same = wo.z * si.wi.z > 0
        cosine = dr.abs(wo.z) * dr.inv_pi
        p_side = dr.select(same, self.p_r, 1.0 - self.p_hg - self.p_r)
        return self.p_hg * layer.hg(-dr.dot(si.wi, wo), self.slab.g) + p_side * cosine

    def eval_pdf(self, ctx, si, wo, active):
        ok = active & (si.wi.z != 0) & (wo.z != 0)
        if self.slab.base:
            ok = ok & (si.wi.z > 0) & (wo.z > 0)
        if lobes.none(ok):
            return mi.Spectrum(0.0), mi.Float(0.0)
        value = dr.select(ok, self.value(ctx, si, wo, ok), 0.0)
        return value, dr.select(ok, self.density(si, wo), 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        wo_hg, _ = layer.sample_hg(-si.wi, self.slab.g, sample2)
        cos = mi.warp.square_to_cosine_hemisphere(sample2)
        same = sample1 < self.p_hg + self.p_r
        side = dr.select(same, dr.sign(si.wi.z), -dr.sign(si.wi.z))
        wo_cos = mi.Vector3f(cos.x, cos.y, cos.z * side)
        return dr.select(sample1 < self.p_hg, wo_hg, wo_cos), True

    def record(self, si, wo):
        kind = dr.select(wo.z * si.wi.z > 0, lobes.flag("GlossyReflection"),
                         lobes.flag("GlossyTransmission"))
        return mi.UInt32(kind), mi.UInt32(self.component), mi.Float(1.0)

    def weight(self, ctx, si, active):
        """T_i (a (1 − e^{−τ/μi'}) + ρ e^{−τ/μi'}): the light the slab scatters, estimated."""
        albedo, tau, rho = self.slab.at(si, active)
        mu, t, _ = layer.inside(si.wi, self.slab.eta)
        through = dr.exp(-tau / mu)
        return dr.mean(t * (albedo * (1.0 - through) + rho * through))


class Unscattered(lobes.DeltaLobe):
    """The beam through the slab, T² e^{−τ/μi'} along −ωi: a null interaction (Mitsuba 0.6's
    ``hk`` likewise), component 1; absent over a base."""

    kind, component = "Null", 1
    flags = lobes.flag("Null", "FrontSide", "BackSide")

    def __init__(self, slab: Slab):
        self.slab = slab

    def delta_value(self, si, active):
        _, tau, _ = self.slab.at(si, active)
        if self.slab.orders is not None:
            return layer.unscattered_all(si.wi, tau, self.slab.eta)[0]
        return layer.unscattered(si.wi, tau, self.slab.eta)

    def sample(self, ctx, si, sample1, sample2, active):
        return -si.wi, si.wi.z != 0

    def record(self, si, wo):
        return mi.UInt32(lobes.flag("Null")), mi.UInt32(self.component), mi.Float(1.0)


class Mirror(lobes.DeltaLobe):
    """The interface's mirror reflection F(μi, η), where η ≠ 1: the last component."""

    kind = "DeltaReflection"

    def __init__(self, slab: Slab, component: int):
        self.slab, self.component = slab, component
        names = ("DeltaReflection", "FrontSide") + (() if slab.base else ("BackSide",))
        self.flags = lobes.flag(*names)

    def delta_value(self, si, active):
        f, _, _, _ = mi.fresnel(dr.abs(si.wi.z), self.slab.eta)
        if self.slab.orders is not None and not self.slab.base:
            _, tau, _ = self.slab.at(si, active)
            return f + layer.unscattered_all(si.wi, tau, self.slab.eta)[1]
        return mi.UnpolarizedSpectrum(f)

    def sample(self, ctx, si, sample1, sample2, active):
        ok = (si.wi.z > 0) if self.slab.base else (si.wi.z != 0)
        return mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z), ok


class HK(mi.BSDF):
    r"""
    .. _bsdf-hk:

    Hanrahan-Krueger layer (:monosp:`hk`)
    -------------------------------------

    .. pluginparameters::

     * - sigma_s
       - |spectrum| or |texture|
       - The medium's scattering coefficient σs per unit length, ≥ 0 (Default: 0.5)
       - |exposed|, |differentiable|

     * - sigma_a
       - |spectrum| or |texture|
       - The medium's absorption coefficient σa per unit length, ≥ 0 (Default: 0.5)
       - |exposed|, |differentiable|

     * - thickness
       - |float|
       - The slab's thickness d, in the units of σs and σa, > 0 (Default: 1)

     * - g
       - |float|
       - Henyey-Greenstein's asymmetry parameter of the phase function, within [−0.99, 0.99]
         (Default: 0, isotropic)

     * - eta
       - |float|
       - The relative index η of the slab's faces, within [1, 4] (Default: 1, index-matched,
         as Mitsuba 0.6's ``hk``)

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - The reflectance ρ of a Lambertian base under the slab, within [0, 1] (Default: 0:
         no base, the light leaves through the back)
       - |exposed|, |differentiable|

     * - scattering
       - |string|
       - ``single``: the model of Hanrahan & Krueger's paper, at most one event inside;
         ``all``: every order of scattering and every internal reflection (Default:
         ``single``)

    A slab of thickness d of a homogeneous medium (σt = σs + σa, albedo a = σs/σt, optical
    depth τ = σt d, Henyey-Greenstein phase function p of g) under a smooth interface of
    relative index η (Hanrahan & Krueger 1993, "Reflection from Layered Surfaces due to
    Subsurface Scattering", SIGGRAPH, §3-4). A beam refracted into the slab (Snell's law: μ' =
    √(1 − (1 − μ²)/η²), Fresnel transmittance T = 1 − F(μ, η)) is attenuated as e^{−σt z/μ'};
    the light scattered once, integrated over depth (Chandrasekhar 1960, "Radiative
    Transfer", §46; Hanrahan & Krueger eqs. 20-23), leaves through the top or the bottom:

    .. math::

        f_r = \frac{a\,p(\cos\Theta)\,T_i T_o}{\eta^2}
              \frac{1 - e^{-\tau(1/\mu_i' + 1/\mu_o')}}{\mu_i' + \mu_o'}, \qquad
        f_t = \frac{a\,p(\cos\Theta)\,T_i T_o}{\eta^2}
              \frac{e^{-\tau/\mu_o'} - e^{-\tau/\mu_i'}}{\mu_o' - \mu_i'},

    Θ the angle between the refracted incident and outgoing beams inside the slab, 1/η² the n²
    law of radiance through both crossings. Over a base (ρ > 0 somewhere) the slab is opaque:
    no transmission, and the base adds ρ T_i T_o e^{−τ(1/μi' + 1/μo')}/(πη²). Without one the
    slab is free-standing, the same interface on both faces, and symmetric: light from below
    sees the same layer. Beside the scattered light, the unscattered: the beam through the
    slab, T_i² e^{−τ/μi'} along −ωi (a parallel slab shifts the beam, does not turn it), a
    null interaction; and, where η ≠ 1, the mirror reflection F(μi, η). ``single`` counts
    paths with at most one event inside (a scattering or the base) and no internal
    reflection, as the paper's first-order term.

    **All orders** (``scattering = all``): the closed form above plus the rest — second and
    higher orders, internal reflections at the faces, the light between the slab and its
    base — by the discrete-ordinates adding-doubling method with a Fourier series in azimuth
    (van de Hulst 1980, "Multiple Light Scattering"; Wiscombe 1976, JQSRT 16; Prahl 1995, "The
    adding-doubling method"; Jakob et al. 2014, "A Comprehensive Framework for Rendering
    Layered Materials"), in float64 at load (``mi_brdfs.reference.hk_doubling``) over a grid
    of albedo, optical depth and the two cosines, for the layer's g, η and base
    (``mi_brdfs.scattering.hk_orders``: the grid, the modes kept, the interpolation) — or,
    for a medium that is the same over the whole surface and not differentiated, at its own
    albedo and depth (the cosines alone interpolated, cheaper to evaluate); the
    unscattered beams of the internal reflections (through the slab and back along the
    mirror) as closed-form geometric series. The tables promise f·cosθo within 3.5 % of its
    largest value at the incidence, and within 3.5 % in the median of each value, measured
    against the adding-doubling at the very albedo and depth between the nodes
    (``tests/scattering/test_hk_orders.py``); they are tested against the float64 random walk
    of ``mi_brdfs.reference.hk`` (``tests/plugins/test_hk_all.py``: the light in bands of μo
    and azimuth within that error plus the walk's noise; the white furnace of a conservative
    slab) and validated against ``volpath`` at full depth. Building the grid takes from a
    fraction of a second at load (g = 0: one Fourier mode; over a base) to several seconds
    (a free slab with g beyond ±0.7: more modes, twice the quadrature nodes), once per process
    and layer (g, η, base). The gradients through σs and σa (``mi.traverse``) are the
    interpolation's own: a first fit step compiles its kernels for about a minute on an empty
    kernel cache (about 140 small kernels in drjit's reverse mode), later ones are fast.

    ``mi_brdfs.reference.hk`` is the model in float64 with a float64 random walk of the
    whole transport, against which the single term is tested
    (``tests/reference/test_hk_reference.py``); the plugin is validated against Mitsuba's
    own volumetric path tracer (``volpath`` on the same slab built as a scene, ``max_depth``
    limited to single scattering for ``single``, 256 for ``all``, over a grid of albedo,
    optical thickness, g and η: ``mi-brdfs validate --only hk``, docs/validation.md).

    **Components.** 0: the scattered light, glossy reflection and (without a base)
    transmission; 1: the unscattered beam (null), without a base; last: the mirror reflection
    (delta), where η ≠ 1. Sample weights and values are reciprocal: the slab has the same
    medium on both sides.

    **Sampling.** Component 0 is drawn from a mixture of Henyey-Greenstein's lobe of g about
    −ωi (share 0.25 + 0.5·abs(g): the phase function itself where η = 1, so that a forward- or
    back-scattering layer is sampled along its peak; over a base only where g < 0, since a
    forward lobe would point into the base) and the cosine-weighted hemispheres of both sides
    (of the reflecting side alone over a base), with its exact density; the delta components
    in proportion to their values, against an estimate of the scattered share. Against the
    cosine-weighted hemispheres alone it converges faster where single scattering shapes the
    lobe, and about as fast where multiple scattering has made it broad (``make bench``,
    section "Hanrahan-Krueger").

    **Polarized variants.** The model describes no polarization: values are depolarizers.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="hk">
                <float name="sigma_s" value="1.0"/>
                <float name="sigma_a" value="0.1"/>
                <float name="thickness" value="0.5"/>
                <float name="g" value="0.6"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'hk', 'sigma_s': 1.0, 'sigma_a': 0.1, 'thickness': 0.5, 'g': 0.6}
    """

    def __init__(self, props):
        super().__init__(props)
        self.m_sigma_s, self.m_sigma_a = (
            properties.texture(props, PLUGIN, name, DEFAULTS[name], 0.0, math.inf)
            for name in ("sigma_s", "sigma_a"))
        self.m_thickness = properties.number(props, PLUGIN, "thickness", 1.0, 0.0, math.inf,
                                             lo_open=True)
        self.m_g = properties.number(props, PLUGIN, "g", 0.0, -0.99, 0.99)
        self.m_eta = properties.number(props, PLUGIN, "eta", 1.0, 1.0, IOR_MAX)
        self.m_rho = properties.reflectance(props, PLUGIN, "diffuse_reflectance", 0.0)
        self.m_scattering = properties.choice(props, PLUGIN, "scattering", "single",
                                              ("single", "all"))
        self.m_base = not properties.is_zero(self.m_rho)
        self.m_orders = hk_orders.Orders(self.m_g, self.m_eta, self.m_base) \
            if self.m_scattering == "all" else None
        self.parameters_changed()

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def _constant_medium(self):
        """Each channel's (albedo, optical depth) where σs and σa are constants (a number, or
        in RGB and mono variants an RGB value); else None."""
        textures = (self.m_sigma_s, self.m_sigma_a)
        kinds = ("UniformSpectrum",) + (() if mi.is_spectral else ("SRGBReflectanceSpectrum",))
        if any(t.class_name() not in kinds for t in textures):
            return None
        si = dr.zeros(mi.SurfaceInteraction3f)
        n = dr.size_v(mi.UnpolarizedSpectrum)
        s, a = (np.broadcast_to(np.clip(np.array(mi.unpolarized_spectrum(t.eval(si)),
                                                 np.float64).ravel(), 0.0, None), (n,))
                for t in textures)
        total = s + a
        albedo = np.where(total > 0, s / np.where(total > 0, total, 1.0), 0.0)
        return [(float(x), float(t * self.m_thickness)) for x, t in zip(albedo, total)]

    def parameters_changed(self, keys=()):
        if self.m_orders is not None:
            self.m_orders.fix(self._constant_medium(),
                              properties.differentiated((self.m_sigma_s, self.m_sigma_a)))
        slab = Slab(self.m_sigma_s, self.m_sigma_a, self.m_rho, self.m_thickness, self.m_g,
                    self.m_eta, self.m_base, self.m_orders)
        parts = [Scattered(slab)] + ([] if self.m_base else [Unscattered(slab)])
        if self.m_eta != 1.0:
            parts.append(Mirror(slab, len(parts)))
        self.lobes = lobes.Mixture(parts, two_sided=not self.m_base)
        self.m_components, self.m_flags = lobes.components(parts)

    def traverse(self, cb):
        for name in ("sigma_s", "sigma_a"):
            cb.put(name, getattr(self, f"m_{name}"), mi.ParamFlags.Differentiable)
        cb.put("diffuse_reflectance", self.m_rho, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"HK[\n  sigma_s = {properties.indent(self.m_sigma_s)},\n"
                f"  sigma_a = {properties.indent(self.m_sigma_a)},\n"
                f"  thickness = {self.m_thickness},\n  g = {self.m_g},\n  eta = {self.m_eta},\n"
                f"  scattering = {self.m_scattering},\n"
                f"  diffuse_reflectance = {properties.indent(self.m_rho)}\n]")
