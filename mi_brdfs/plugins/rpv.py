"""
The Rahman-Pinty-Verstraete model (Rahman, Pinty & Verstraete 1993), with Eradiate's plugin
and parameter names: its formula in :mod:`mi_brdfs.scattering.rpv`, sampled from a density
tabulated from the float64 reference (:mod:`mi_brdfs.reference.rpv`) where the parameters
are constant, else from the cosine-weighted hemisphere; a warning at load where the model's
directional albedo exceeds 1.
"""

from __future__ import annotations

import functools

import drjit as dr
import mitsuba as mi

from ..reference import rpv as reference
from ..scattering import rpv as model
from . import empirical, lobes, properties

PLUGIN = "rpv"
#: Each parameter's default (Eradiate's: its C++ code) and range: ρ0 a reflectance; k ≥ 0
#: keeps M finite where the cosines are held (:data:`mi_brdfs.scattering.rpv.COS_MIN`);
#: −1 < g < 1 and ρc ≤ 2 keep F and H, and the BRF, non-negative. ρc's default is ρ0's texture.
RANGES = {"rho_0": (0.1, 0.0, 1.0), "k": (0.1, 0.0, 3.0), "g": (0.0, -0.999, 0.999),
          "rho_c": (0.1, 0.0, 2.0)}


@functools.lru_cache(maxsize=64)
def energy(rho_0: tuple, k: tuple, g: tuple, rho_c: tuple):
    """(θi from which E > 1 or None, E(89°), E at the horizon) of the float64 model with the
    cosines held at COS_MIN (:meth:`mi_brdfs.reference.rpv.RPV.energy`)."""
    return reference.RPV(rho_0, k, g, rho_c).energy(model.COS_MIN)


class Surface(empirical.Surface):
    """ρ0, k, g, ρc (textures) as the lobe uses them; constant values clipped into
    :data:`RANGES`."""

    plugin = PLUGIN

    def clip(self, values):
        return tuple(min(max(v, lo), hi) for v, (_, lo, hi) in zip(values, RANGES.values()))

    def value(self, si, wo, active):
        """f·cosθo = BRF/π·cosθo, per channel; each parameter clipped into its range."""
        rho_0, k, g, rho_c = (properties.clip_at(tex, si, active, lo, hi)
                              for tex, (_, lo, hi) in zip(self.textures.values(),
                                                          RANGES.values()))
        return model.brf(rho_0, k, g, rho_c, si.wi, wo) * (dr.inv_pi * wo.z)

    def level(self, si, active):
        """ρ0: the BRF's level, an estimate of the albedo."""
        return dr.mean(properties.clip_at(self.textures["rho_0"], si, active))

    def reference(self):
        return reference.RPV(*self.constants)


class RPV(mi.BSDF):
    r"""
    .. _bsdf-rpv:

    Rahman-Pinty-Verstraete reflectance (:monosp:`rpv`)
    ---------------------------------------------------

    .. pluginparameters::

     * - rho_0
       - |spectrum| or |texture|
       - ρ0, the BRF's level, within [0, 1] (Default: 0.1)
       - |exposed|, |differentiable|

     * - k
       - |spectrum| or |texture|
       - The Minnaert exponent: a bowl (k < 1, brighter towards the horizon) or a bell
         (k > 1), within [0, 3] (Default: 0.1)
       - |exposed|, |differentiable|

     * - g
       - |spectrum| or |texture|
       - The Henyey-Greenstein asymmetry Θ: forward scattering for g > 0, backward for
         g < 0, within [−0.999, 0.999] (Default: 0)
       - |exposed|, |differentiable|

     * - rho_c
       - |spectrum| or |texture|
       - ρc of the hot-spot factor, within [0, 2] (Default: ρ0's texture itself)
       - |exposed| where given, |differentiable|

    The semi-empirical model of Rahman, Pinty & Verstraete (1993, "Coupled
    surface-atmosphere reflectance (CSAR) model 2. Semiempirical surface model usable with
    NOAA advanced very high resolution radiometer data", JGR 98(D11), 20791-20801, eqs.
    2-6), with ρc apart from ρ0 as Widlowski et al. (2006, JGR 111, D16107) and Eradiate use
    it:

    .. math::

        \mathrm{BRF} = \rho_0\, M\, F\, H, \qquad f = \mathrm{BRF}/\pi, \qquad
        M = [\cos\theta_i \cos\theta_o (\cos\theta_i + \cos\theta_o)]^{k-1},

        F = \frac{1 - \Theta^2}{[1 + \Theta^2 - 2\Theta\cos(\pi - \xi)]^{3/2}}, \qquad
        H = 1 + \frac{1 - \rho_c}{1 + G}, \qquad
        G = \sqrt{\tan^2\theta_i + \tan^2\theta_o - 2\tan\theta_i\tan\theta_o\cos\phi},

    θi the sun's zenith (ωi), θo the viewer's (ωo), φ their relative azimuth (0 when the
    viewer looks back along the sun's azimuth) and ξ the phase angle, cos ξ = cosθi cosθo +
    sinθi sinθo cos φ = ωi·ωo: ξ = 0 and G = 0 at the hot spot ωo = ωi, where the sun is
    behind the observer. π − ξ is the scattering angle, so that **g = Θ > 0 scatters
    forward and g < 0 backward** (towards the hot spot), as in the paper; Eradiate's code
    writes the same F with +2g cos ξ. With ρc = ρ0 (the default: the same texture) it is
    the paper's three-parameter model; k = 1, g = 0, ρc = 1 is Lambert's ρ0/π. The model
    is **reciprocal** (every factor is symmetric in ωi, ωo), and ``mi-brdfs check rpv``'s
    reciprocity check holds. ``mi_brdfs.reference.rpv`` is the model in float64, written
    with angles from the paper.

    **Non-negative and finite.** ρ0 ≥ 0, −1 < g < 1 and ρc ≤ 2 make every factor ≥ 0: values
    outside the ranges above are refused at load in one line (and clipped into them where
    a texture's range is unknown at load or a value is set through ``mi.traverse``). M is
    +∞ at the horizon for k < 1; the plugin holds the cosines at 10⁻⁶ or above (θ ≤
    89.99994°), so that M ≤ 5·10¹⁷ for k ≥ 0 and G ≤ 2·10⁶: every value and sample weight
    is finite at every pair, grazing (cosθ = 0), exact backscatter and θi = θo = 0 included.
    G is the distance between the tangent vectors ω_xy/cosθ (no cancellation at the hot
    spot) and F's denominator is written as two non-negative terms.

    **Energy: the model's, kept, with a warning at load.** For k < 1, M ~ cos^(k−1)θi and the
    directional albedo E(θi) = ∫ f cosθo dωo grows without bound towards grazing incidence
    (its white-sky albedo stays finite for k > −1/3); a strong backward or forward lobe can
    also take E above 1 elsewhere. That is energy creation (a furnace brighter than 1 at the
    silhouettes), and the plugin keeps it: the paper's model is what the data were fitted
    with, and it is used where E ≤ 1 (sun and view zeniths up to 60°-75° in the field). Where
    the four parameters are the same everywhere, it warns at load, in one line, with the
    parameters, the θi from which E exceeds 1, E(89°) and E at the horizon where the
    cosines are held (float64 quadrature of the reference, cached per parameter set); where
    k varies with a known range reaching below 1, it warns without numbers; otherwise
    (a k texture of unknown range) it does not warn. E(θi) for ρ0 = 0.1, g = 0, ρc = ρ0
    (``mi-brdfs furnace rpv k=0.6 --thetas 0,60,85,89``; the reference's quadrature):

    ====  ======  ======  ======  ======  ==============  ====================
    k     E(0°)   E(60°)  E(85°)  E(89°)  E > 1 from θi   E at cosθi = 10⁻⁶
    ====  ======  ======  ======  ======  ==============  ====================
    0.1   0.170   0.444   3.67    21.1    74.68°          2.3·10⁵
    0.3   0.156   0.316   1.45    5.08    82.14°          5.3·10³
    0.6   0.146   0.207   0.433   0.834   89.36°          41.9
    0.9   0.144   0.146   0.150   0.169   —               0.44
    1.0   0.145   0.131   0.107   0.102   —               0.100
    1.5   0.156   0.082   0.022   0.0091  —               6.7·10⁻⁵
    ====  ======  ======  ======  ======  ==============  ====================

    Eradiate's defaults (k = 0.1) are the first row: E(89°) = 21, as ``mi-brdfs check``
    measures Eradiate's own ``rpv``. ``mi-brdfs check rpv`` passes every check but energy
    for the defaults (E(89°) = 21.09 ± 0.02 from sample(): the model's, above), and every
    check with ρ0 = 0.2, k = 1.4, g = −0.3, ρc = 0.05.

    **Sampling.** Where the four parameters are the same everywhere, ωo is drawn from a
    density tabulated per incident angle through the half vector from the float64 model (the
    sampler of ``merl``, ``mi_brdfs.measured.warp``, with an exact pdf: bs.pdf = pdf(bs.wo)),
    which follows the hot spot and the forward or backward lobe; built when first needed and
    again when ``mi.traverse`` sets new values (the density is not differentiated). Where a
    parameter varies over the surface, ωo is drawn from the cosine-weighted hemisphere, as
    Eradiate samples. One component, glossy reflection, front side only (0 for either
    direction below the surface).

    **Eradiate.** The parameters, their meanings and defaults are those of Eradiate's ``rpv``
    (src/bsdfs/rpv.cpp in its Mitsuba fork): ρ0 = 0.1, k = 0.1, g = 0, ρc = ρ0's texture
    itself; its ``mi.traverse`` exposes rho_0, g, k and rho_c only where rho_c is given,
    and so does this plugin's (setting rho_0 moves ρc with it otherwise). Its formula is the
    paper's, with G from tangents and cos φ in float32, and without ranges (its values are
    +∞ or NaN at the horizon for k < 1). Compared with Eradiate's own values
    (``tests/plugins/test_rpv_eradiate.py``, against the table validation/eradiate/rpv.json
    that ``make eradiate-values`` writes with ``eradiate-mitsuba`` 0.5.0 in a virtual
    environment of its own): 705 direction pairs (θi, θo from 0° to 89°, the principal plane
    and three other azimuths; exact backscatter at θ = 1°, 3°, …, 89°, three azimuths each;
    60 random pairs) for four parameter sets (the defaults; the example below, Eradiate's;
    a bowl k = 0.6, g = 0.2, ρc = 0.3; a bell ρ0 = 0.2, k = 1.4, g = −0.3, ρc = 0.05).
    Eradiate is finite and non-negative at all 2820 in float32 (scalar_rgb) and float64, and
    eval equals it there: within float32 rounding and the directions' conditioning, but for
    Eradiate's G, which cancels near the hot spot in float32 and puts its values up to
    3.8·10⁻³ (relative) off the float64 model (θi = θo = 87°, φ = 0), the plugin's
    within 1.1·10⁻⁶; in float64 within 1.6·10⁻⁷ (its parameters are float32).

    **Polarized variants.** The model describes no polarization: values are depolarizers.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="rpv">
                <float name="rho_0" value="0.02"/>
                <float name="k" value="0.3"/>
                <float name="g" value="-0.12"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'rpv', 'rho_0': 0.02, 'k': 0.3, 'g': -0.12}
    """

    def __init__(self, props):
        super().__init__(props)
        for name, (default, lo, hi) in RANGES.items():
            if name != "rho_c" or name in props:
                tex = properties.texture(props, PLUGIN, name, default, lo, hi)
            else:
                tex = self.m_rho_0  # the paper's three-parameter model: ρc = ρ0
            setattr(self, f"m_{name}", tex)
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        self._warn_energy(props)

    def _parameters(self):
        return self.m_rho_0, self.m_k, self.m_g, self.m_rho_c

    def _warn_energy(self, props):
        """Warn (the model kept) where its directional albedo exceeds 1: with the numbers
        for constant parameters, else where k's known range goes below 1."""
        values = [empirical.channels(props, name if name in props else "rho_0", tex)
                  for name, tex in zip(RANGES, self._parameters())]
        if any(v is None for v in values):
            low = properties.texture_range(self.m_k)
            if low is not None and low[0] < 1.0:
                properties.warn(PLUGIN, f"k reaches {low[0]:g} < 1: the model's directional "
                                        f"albedo grows without bound towards grazing "
                                        f"incidence (it creates energy there); values kept")
            return
        start, e89, top = energy(*(tuple(v) for v in values))
        if start is not None:
            given = empirical.given(RANGES, values)
            properties.warn(PLUGIN, f"{given}: the model's directional albedo exceeds 1 (it "
                                    f"creates energy) from θi = {start:g}° on, E(89°) = "
                                    f"{e89:.3g}, up to {top:.3g} at the horizon (the cosines "
                                    f"held at {model.COS_MIN:g}); values kept")

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobe from the parameters as they are now: tabulated where all four are the same
        everywhere (its sampler built when first needed, for their values then)."""
        self.lobes = empirical.lobe(Surface(dict(zip(RANGES, self._parameters()))))

    def traverse(self, cb):
        """ρ0, k, g and ρc where it is a texture of its own (not ρ0's), as Eradiate's."""
        for name, tex in zip(RANGES, self._parameters()):
            if name != "rho_c" or tex is not self.m_rho_0:
                cb.put(name, tex, mi.ParamFlags.Differentiable)

    def to_string(self):
        return "RPV[\n" + ",\n".join(f"  {name} = {properties.indent(tex)}"
                                     for name, tex in zip(RANGES, self._parameters())) + "\n]"
