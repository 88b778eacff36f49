"""
The Ross-Thick Li-Sparse-Reciprocal kernel model of the MODIS BRDF/albedo product (Lucht,
Schaaf & Strahler 2000; Wanner, Li & Strahler 1995), with Eradiate's plugin and parameter
names: its kernels in :mod:`mi_brdfs.scattering.rtls`, clamped at 0, sampled from a density
tabulated from the float64 reference (:mod:`mi_brdfs.reference.rtls`) where the kernel weights
are constant, else from the cosine-weighted hemisphere.
"""

from __future__ import annotations

import functools

import drjit as dr
import mitsuba as mi

from ..reference import rtls as reference
from ..scattering import rtls as kernels
from . import empirical, lobes, properties

PLUGIN = "rtls"
#: The kernel weights' defaults: Eradiate's (its C++ code; RAMI4ATM's Sentinel-2A band 8A).
DEFAULTS = {"f_iso": 0.209741, "f_vol": 0.081384, "f_geo": 0.004140}
#: The range of each of the crowns' shape parameters h, r, b.
SHAPE_RANGE = (1e-3, 1e3)
#: The grid of :meth:`mi_brdfs.reference.rtls.RTLS.negative_share` for the warning at load:
#: cosθ's nodes reach 89.92°, where the defaults are negative.
GRID = (32, 16)


@functools.lru_cache(maxsize=64)
def negative(f_iso: tuple, f_vol: tuple, f_geo: tuple, h: float, r: float, b: float):
    """(share, lowest BRF, (θi, θo, φ)) of the float64 model below 0 on :data:`GRID`."""
    return reference.RTLS(f_iso, f_vol, f_geo, h, r, b).negative_share(*GRID)


class Surface(empirical.Surface):
    """The kernel weights (textures) and the crowns' shape h, r, b as the lobe uses them;
    constant weights clipped into [0, 1]."""

    plugin = PLUGIN

    def clip(self, values):
        return tuple(min(max(v, 0.0), 1.0) for v in values)

    def value(self, si, wo, active):
        """f·cosθo = max(BRF, 0)/π·cosθo, per channel; each weight clipped into [0, 1]."""
        f_iso, f_vol, f_geo = (properties.clip_at(tex, si, active)
                               for tex in self.textures.values())
        h, r, b = self.shape
        brf = kernels.brf(f_iso, f_vol, f_geo, si.wi, wo, h / b, b / r)
        return dr.maximum(brf, 0.0) * (dr.inv_pi * wo.z)

    def level(self, si, active):
        """f_iso: the BRF's mean level, an estimate of the albedo."""
        return dr.mean(properties.clip_at(self.textures["f_iso"], si, active))

    def reference(self):
        return reference.RTLS(*self.constants, *self.shape)


class RTLS(mi.BSDF):
    r"""
    .. _bsdf-rtls:

    Ross-Thick Li-Sparse-Reciprocal reflectance (:monosp:`rtls`)
    ------------------------------------------------------------

    .. pluginparameters::

     * - f_iso
       - |spectrum| or |texture|
       - The isotropic kernel's weight, within [0, 1] (Default: 0.209741)
       - |exposed|, |differentiable|

     * - f_vol
       - |spectrum| or |texture|
       - The volumetric (Ross-Thick) kernel's weight, within [0, 1] (Default: 0.081384)
       - |exposed|, |differentiable|

     * - f_geo
       - |spectrum| or |texture|
       - The geometric (Li-Sparse-Reciprocal) kernel's weight, within [0, 1] (Default:
         0.004140)
       - |exposed|, |differentiable|

     * - h, r, b
       - |float|
       - The crowns' shape: h the height of their centres over b, their vertical radius; r
         their horizontal radius. Only h/b and b/r matter. Each within [0.001, 1000]
         (Default: h = 2, r = 1, b = 1: MODIS's h/b = 2, b/r = 1)

    The semi-empirical model of the MODIS BRDF/albedo product: the bidirectional reflectance
    factor BRF = π·f is linear in three kernels (Lucht, Schaaf & Strahler 2000, "An Algorithm
    for the Retrieval of Albedo from Space Using Semiempirical BRDF Models", IEEE TGRS 38(2),
    §III, eqs. 37-44; Wanner, Li & Strahler 1995, "On the derivation of kernels for
    kernel-driven models of bidirectional reflectance", JGR 100(D10), §3):

    .. math::

        \mathrm{BRF} = f_{iso} + f_{vol} K_{vol}(\theta_i, \theta_o, \phi)
            + f_{geo} K_{geo}(\theta_i, \theta_o, \phi), \qquad
        f = \max(\mathrm{BRF}, 0)/\pi,

    θi the sun's zenith (ωi), θo the viewer's (ωo), φ their relative azimuth and ξ the phase
    angle, cos ξ = ωi·ωo: the hot spot, where the sun is behind the observer, is at ωo = ωi.
    K_vol is Ross-Thick (Roujean et al. 1992, JGR 97(D18), normalised by Wanner et al. 1995,
    eq. 13), ((π/2 − ξ) cos ξ + sin ξ)/(cosθi + cosθo) − π/4: scattering by a thick layer of
    leaves. K_geo is Li-Sparse-Reciprocal (Lucht et al. 2000, eqs. 39-44), O − secθi' −
    secθo' + ½(1 + cos ξ') secθi' secθo', the shadows of sparse spheroidal crowns, O their
    overlap, on angles tanθ' = (b/r) tanθ. Both kernels are 0 at θi = θo = 0. BRF and the
    white-sky albedo f_iso + 0.189184 f_vol − 1.377622 f_geo (Lucht et al. 2000, Table 1)
    are what the field reports; ``mi_brdfs.reference.rtls`` is the model in float64.

    **Negative values: clamped at 0, with a warning.** The model is a linear fit, and K_geo →
    −∞ as the view grazes away from the hot spot (at normal incidence K_geo = O − ½ −
    ½ secθo): every f_geo > 0 makes the BRF negative near the horizon (the defaults below 0
    beyond θo ≈ 89.5° at normal incidence), and f_vol > 7.2 f_iso makes it so where K_vol
    reaches its least, −0.139 (forward scattering, θi = θo ≈ 34°). The plugin evaluates
    max(BRF, 0)/π, which keeps every value and sample weight non-negative. Where the three
    weights are the same everywhere, it warns at load, in one line, naming them, the share
    of direction pairs where the clamp acts
    (weighted by cosθi cosθo, the white-sky measure) and the lowest BRF with its directions,
    from the float64 model on a grid of 32 cosines (to 89.92°) and 16 azimuths. At the hot
    spot K_geo = sec²θ − secθ grows without bound towards the horizon instead: the values are
    finite at every pair (the cosines are held at 10⁻⁶ or above), exact backscatter and θi =
    θo = 0 included. The model's own albedo stays bounded at grazing incidence (its +∞ hot
    spot and −∞ elsewhere cancel: 0.33 for the defaults at θi = 89.99°); the clamp keeps the
    hot spot alone, so the directional albedo E(θi) grows without bound as θi → 90° for
    every f_geo > 0 (float64 quadrature, defaults: 0.27 at 80°, 0.32 at 89°, 0.94 at 89.9°,
    8.2 at 89.99°; f_iso = 0.2, f_vol = 0.1, f_geo = 0.04, h = 3, b = 2: above 1 from about
    85°). The warning at load does not say this.

    **Sampling.** Where the weights are the same everywhere, ωo is drawn from a density
    tabulated per incident angle through the half vector from the float64 model (the sampler
    of ``merl``, ``mi_brdfs.measured.warp``, with an exact pdf and a tenth of it the
    cosine's), which follows the hot spot; built when first needed and again when
    ``mi.traverse`` sets new weights (the density is not differentiated). Where a weight
    varies over the surface, ωo is drawn from the cosine-weighted hemisphere, as Eradiate
    samples. Where the clamp makes f 0, a sample drawn there fails (weight 0) and the pdf is
    0, so that the pdf is the density of the samples that succeed, as Mitsuba's χ² test
    counts them. One component, glossy reflection, front side only (0 for either direction below
    the surface).

    **Eradiate.** The parameters are those of Eradiate's ``rtls`` (src/bsdfs/rtls.cpp in
    its Mitsuba fork), with the defaults its code takes: f_vol = 0.081384, f_geo = 0.004140;
    its docstring lists the two the other way round. Its ``mi.traverse`` exposes the three
    weights, not h, r and b, though its docstring marks them exposed; here too only the
    weights are (h, r and b shape the tabulated density). Its kernels are the same formulas,
    without the clamp (negative values and sample weights) and with cosine sampling.
    Compared with Eradiate's own values (``tests/plugins/test_rtls_eradiate.py``, against the
    table validation/eradiate/rtls.json that ``make eradiate-values`` writes with
    ``eradiate-mitsuba`` 0.5.0 in a virtual environment of its own): 705 direction pairs (θi,
    θo from 0° to 89°, the principal plane and three other azimuths; exact backscatter at θ =
    1°, 3°, …, 89°, three azimuths each; 60 random pairs) for four parameter sets (the
    defaults; f_iso = 0.2, f_vol = 0.1, f_geo = 0.03; the same with h = 3, b = 2; f_iso =
    0.01, f_vol = 0.2, f_geo = 0). Where Eradiate's float32 value (scalar_rgb) is finite and
    non-negative, 2423 of the 2820, eval equals it within float32 rounding; at the hot spot
    Eradiate's D = √(tan²θi' + tan²θo' − 2 tanθi' tanθo' cos φ) cancels and its values are up
    to 1.1·10⁻⁴ (relative) off the float64 model (θi = θo = 60°, f_geo = 0.03), the plugin's
    within 1.1·10⁻⁶. At 341 Eradiate is negative, and the plugin 0: eval down to −0.71 (θi =
    89°, θo = 30°, forward); with f_geo = 0.03 where θi or θo is 85° or more on this grid
    (75° for h = 3, b = 2; none for the defaults, negative beyond 89.5° only), for the
    volume-driven set at 28 forward pairs with θi, θo within 10°-60°. At 56 (14 per set)
    Eradiate returns NaN, all exact backscatter, at θ from 1° to 87°; its float64 variant
    (scalar_mono_double) at 76 pairs per set, exact backscatter all. The plugin is finite
    there, within 10⁻⁶ of the float64 model.

    **The field's quantities.** ``mi-brdfs plot pp`` draws the BRF in the principal plane and
    ``mi-brdfs furnace`` prints the black-sky and white-sky albedos; docs/earth-observation.md
    measures them against Lucht et al.'s kernel integrals (the black-sky polynomials within
    0.025 of the float64 quadrature up to θ = 75°) and shows ``mi-brdfs fit TARGET --model rtls
    --metric ngan`` landing on MODIS's linear inversion of the kernels
    (``mi_brdfs.reference.rtls.invert``).

    **Polarized variants.** The model describes no polarization: values are depolarizers.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="rtls">
                <float name="f_iso" value="0.2"/>
                <float name="f_vol" value="0.1"/>
                <float name="f_geo" value="0.03"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'rtls', 'f_iso': 0.2, 'f_vol': 0.1, 'f_geo': 0.03}
    """

    def __init__(self, props):
        super().__init__(props)
        for name, default in DEFAULTS.items():
            setattr(self, f"m_{name}", properties.reflectance(props, PLUGIN, name, default))
        self.m_h, self.m_r, self.m_b = (properties.number(props, PLUGIN, name, default,
                                                          *SHAPE_RANGE)
                                        for name, default in (("h", 2.0), ("r", 1.0),
                                                              ("b", 1.0)))
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        self._warn_negative(props)

    def _weights(self):
        return self.m_f_iso, self.m_f_vol, self.m_f_geo

    def _warn_negative(self, props):
        """Warn (the clamp documented) where the model goes below 0 for constant weights."""
        values = [empirical.channels(props, name, tex)
                  for name, tex in zip(DEFAULTS, self._weights())]
        if any(v is None for v in values):
            return
        share, low, (ti, to, phi) = negative(*(tuple(v) for v in values),
                                             self.m_h, self.m_r, self.m_b)
        if low < 0:
            given = empirical.given(DEFAULTS, values)
            properties.warn(PLUGIN, f"{given}: the kernel model's BRF goes below 0 on "
                                    f"{100 * share:.2g} % of the direction pairs (weighted by "
                                    f"cosθi cosθo), down to {low:.3g} at θi = {ti:.2f}°, θo = "
                                    f"{to:.2f}°, φ = {phi:.0f}°; the plugin evaluates "
                                    f"max(BRF, 0)/π there")

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobe from the weights as they are now: tabulated where all three are the same
        everywhere (its sampler built when first needed, for their values then)."""
        surface = Surface(dict(zip(DEFAULTS, self._weights())), (self.m_h, self.m_r, self.m_b))
        self.lobes = empirical.lobe(surface)

    def traverse(self, cb):
        for name, tex in zip(DEFAULTS, self._weights()):
            cb.put(name, tex, mi.ParamFlags.Differentiable)

    def to_string(self):
        weights = ",\n".join(f"  {name} = {properties.indent(tex)}"
                             for name, tex in zip(DEFAULTS, self._weights()))
        return f"RTLS[\n{weights},\n  h = {self.m_h},\n  r = {self.m_r},\n  b = {self.m_b}\n]"
