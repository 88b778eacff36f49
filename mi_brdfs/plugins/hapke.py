"""
Hapke's bidirectional reflectance of a particulate (regolith) surface (Hapke 2012), with
Eradiate's plugin and parameter names: the model in :mod:`mi_brdfs.scattering.hapke`, sampled
from a density tabulated from the float64 reference (:mod:`mi_brdfs.reference.hapke`) where
the parameters are constant, else from the cosine-weighted hemisphere.
"""

from __future__ import annotations

import functools

import drjit as dr
import mitsuba as mi

from ..reference import hapke as reference
from ..scattering import hapke as model
from . import empirical, lobes, properties

PLUGIN = "hapke"
#: The parameters, their defaults (Eradiate's: src/bsdfs/hapke.cpp of eradiate-mitsuba 0.5.0)
#: and ranges (Eradiate's; theta in degrees).
PARAMETERS = {"w": (0.5, 1.0), "b": (0.2, 1.0), "c": (0.5, 1.0), "theta": (30.0, 90.0),
              "B_0": (0.0, 1.0), "h": (0.0, 1.0)}
#: The grid of :meth:`mi_brdfs.reference.hapke.Hapke.max_albedo` for the warning at load:
#: 8 incident angles (the last at 88.9°), 32 × 32 outgoing directions.
GRID = (8, 32, 32)


def clip(values) -> tuple:
    """Each parameter's value clipped into its range."""
    return tuple(min(max(v, 0.0), PARAMETERS[name][1]) for name, v in zip(PARAMETERS, values))


@functools.lru_cache(maxsize=64)
def max_albedo(*values: tuple) -> tuple[float, float]:
    """(the largest directional albedo, θi in degrees) of the float64 model on :data:`GRID`."""
    return reference.Hapke(*values).max_albedo(*GRID)


class Surface(empirical.Surface):
    """The six parameters (textures) as the lobe uses them; constant ones clipped into
    range."""

    plugin = PLUGIN

    def clip(self, values):
        return clip(values)

    def _at(self, si, active):
        return [properties.clip_at(tex, si, active, 0.0, PARAMETERS[name][1])
                for name, tex in self.textures.items()]

    def value(self, si, wo, active):
        """f·cosθo per channel, each parameter clipped into its range."""
        return model.brdf(*self._at(si, active), si.wi, wo) * wo.z

    def level(self, si, active):
        """w/2: the mean level of the single-scattering albedo's reflectance, an estimate of
        the albedo."""
        return 0.5 * dr.mean(properties.clip_at(self.textures["w"], si, active))

    def reference(self):
        return reference.Hapke(*self.constants)


class Hapke(mi.BSDF):
    r"""
    .. _bsdf-hapke:

    Hapke's regolith reflectance (:monosp:`hapke`)
    ----------------------------------------------

    .. pluginparameters::

     * - w
       - |spectrum| or |texture|
       - The single-scattering albedo of the particles, within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

     * - b
       - |spectrum| or |texture|
       - The double Henyey-Greenstein phase function's asymmetry, within [0, 1]
         (Default: 0.2)
       - |exposed|, |differentiable|

     * - c
       - |spectrum| or |texture|
       - The weight of its backward lobe, within [0, 1]: 0.5 symmetric, 1 all backward
         (Default: 0.5)
       - |exposed|, |differentiable|

     * - theta
       - |spectrum| or |texture|
       - The macroscopic roughness θ̄ in degrees, within [0, 90] (Default: 30)
       - |exposed|, |differentiable|

     * - B_0
       - |spectrum| or |texture|
       - The shadow-hiding opposition effect's amplitude, within [0, 1] (Default: 0)
       - |exposed|, |differentiable|

     * - h
       - |spectrum| or |texture|
       - The opposition effect's angular width, within [0, 1] (Default: 0)
       - |exposed|, |differentiable|

    The bidirectional reflectance of a particulate surface — a regolith, a powder, dust —
    after Hapke (2012, "Theory of Reflectance and Emittance Spectroscopy", 2nd ed., Cambridge
    University Press, eq. 12.55 with the porosity factor K = 1 and without the coherent
    backscatter term, as Eradiate's), f = r/cos i:

    .. math::

        r = \frac{w}{4\pi} \frac{\mu_{0e}}{\mu_{0e} + \mu_e}
            \left[p(g)\,(1 + B(g)) + H(\mu_{0e}) H(\mu_e) - 1\right] S(i, e, \psi),

    i the angle of incidence (ωi), e of emergence (ωo), g the phase angle (cos g = ωi·ωo: the
    opposition, where the source is behind the viewer, at ωo = ωi) and ψ their azimuth. p is
    the double Henyey-Greenstein phase function (1 − c)(1 − b²)/(1 + 2b cos g + b²)^{3/2} +
    c(1 − b²)/(1 − 2b cos g + b²)^{3/2}: c weights the backward lobe (Eradiate's convention,
    Hapke 2012 eq. 6.7b's form; eq. 6.7a's (1 + c')/2 is c' = 2c − 1). B(g) = B_0/(1 +
    tan(g/2)/h) is the shadow-hiding opposition effect (Hapke 1986, Icarus 67, 264-280), H
    Hapke's (2002, Icarus 157, 523-534, eq. 13) approximation of Chandrasekhar's H-function,
    within 0.97 % of the exact one at every w and cosine (measured against Chandrasekhar's
    integral; 2.885 against his 2.90781 at w = 1, μ = 1), and μ0e, μe, S the effective cosines
    and the shadowing of the macroscopic roughness θ̄ (Hapke 1984, "Bidirectional reflectance
    spectroscopy 3. Correction for macroscopic roughness", Icarus 59, 41-59, eqs. 45-51).
    ``mi_brdfs.reference.hapke`` is the model in float64, with angles; with the exact H its
    conservative (w = 1, b = 0, θ̄ = 0, B_0 = 0) albedo is 1 at every incidence, as
    Chandrasekhar's half-space reflects (0.986-0.993 with Hapke's H).

    **The opposition peak and the roughness limits: finite everywhere.** Eradiate's
    B_0/(1 + 1/h·tan(g/2)) is 0·∞ = NaN at g = 0 with h = 0, its default (src/bsdfs/hapke.cpp,
    eval_B); the plugin evaluates B = B_0 h/(h + tan(g/2)) with B(0) = B_0 at every h, the
    limit at g → 0, and takes tan(g/2) = ‖ωi − ωo‖/‖ωi + ωo‖ (exactly 0 at ωo = ωi). Where i
    = 0 or e = 0 the azimuth ψ is undefined: every term that reads it is multiplied there by
    sin i, E1(i) or E2(i), which are 0, and the shadowing's denominator 1 − f(ψ) + f(ψ)χ
    cos i/η(i) is 1 since χ cos i/η(i) = 1 at i = 0; the limits are the formulas at ψ = 0,
    which the plugin takes (the float64 reference at i = 10⁻⁷ and ψ = 0, π/2, π agrees
    within 10⁻⁶). S's cos i cancels f's 1/cos i and is left out: nothing divides by a
    grazing cosine; cosines are held at 10⁻⁶ or above. θ̄ is held at 89° (at 90° χ = 0 and
    tan θ̄ = ∞: Eradiate's values are NaN or 10⁻¹⁸ there). At every pair — exact
    backscatter, θi = 0, θo = 0, grazing — the values are finite and non-negative (every
    factor is: H ≥ 1, μ0e, μe > 0 measured on a grid up to θ̄ = 89°).

    **Energy: the model creates some where w is near 1 with a broad surge.** The directional
    albedo E(θi) (float64 quadrature of the reference, ``mi_brdfs.reference.hapke.Hapke
    .albedo``; ``mi-brdfs furnace hapke w=0.99 b=0.3 c=0.9 theta=0 B_0=1 h=1`` measures the
    same by Monte Carlo):

    ===========================================  =====  =====  =====  =====  =====
    parameters (others at the defaults)          0°     30°    60°    80°    89°
    ===========================================  =====  =====  =====  =====  =====
    defaults                                     0.104  0.109  0.112  0.119  0.125
    w = 0.99                                     0.556  0.563  0.539  0.560  0.584
    w = 0.99, θ̄ = 0, B_0 = 1, h = 0.06           0.768  0.782  0.826  0.879  0.922
    w = 0.99, b = 0.3, c = 0.9, θ̄ = 0, B_0 = 1,  0.988  0.997  1.030  1.082  1.154
    h = 1
    the same with θ̄ = 10°                        0.960  0.969  0.997  1.005  1.015
    w = 1, θ̄ = 0, B_0 = 1, h = 0.06              1.015  1.014  1.012  1.016  1.028
    ===========================================  =====  =====  =====  =====  =====

    The surge adds B_0 p(g) B(g)-weighted single scattering on top of a multiple scattering
    that alone conserves energy only with the exact H at w = 1: above 1 the model creates
    energy. The plugin keeps the values and, where the six parameters are the same
    everywhere, warns at load in one line with the largest E on 8 incident angles (to
    88.9°) and where it is. Macroscopic roughness lowers the albedo (shadowing).

    **Reciprocity: exact.** f(ωi, ωo) = f(ωo, ωi) within 3·10⁻¹² in float64 at random pairs:
    exchanging i and e exchanges μ0e and μe (Hapke 1984's two cases are each other's
    mirror), S's cos i cancels f's 1/cos i, and p, B and H(μ0e)H(μe) are symmetric. The
    factor μ0e/(μ0e + μe) makes r alone (the reflectance, not f) non-reciprocal, as a
    reflectance is.

    **Sampling.** Where the six parameters are the same everywhere, ωo is drawn from a
    density tabulated per incident angle from the float64 model (``mi_brdfs.measured.warp``,
    exact pdf), which follows the opposition surge; built when first needed and again when
    ``mi.traverse`` sets new values (the density is not differentiated). Where one varies
    over the surface, from the cosine-weighted hemisphere, as Eradiate samples. One
    component, glossy reflection, front side only.

    **Eradiate.** The parameters are those of Eradiate's ``hapke`` (src/bsdfs/hapke.cpp in
    its Mitsuba fork; eradiate-mitsuba 0.5.0's defaults w = 0.5, b = 0.2, c = 0.5, θ̄ = 30°,
    B_0 = 0, h = 0; theta in degrees; its traverse exposes all six), its ranges (each in
    [0, 1], θ̄ in [0, 90]°) and its formulas: the same H approximation, phase function
    convention and roughness; the float64 reference equals its float64 variant within
    10⁻¹⁴ wherever that is finite. Compared with Eradiate's own values
    (``tests/plugins/test_hapke_eradiate.py``, against validation/eradiate/hapke.json that
    ``make eradiate-values`` writes): 705 direction pairs for four sets (the defaults; the
    example below, a lunar-like regolith; a smooth surface, θ̄ = 0, of forward-scattering
    grains w = 0.6, b = 0.4, c = 0.3, B_0 = 0.5, h = 0.2; a bright one, w = 0.99, b = 0.3, c
    = 0.9, θ̄ = 10°, B_0 = 1, h = 1). Where Eradiate's value is finite, 2714 of 2820 in
    float32 (scalar_rgb), eval equals it within float32 rounding and the error of
    Eradiate's own angles: it takes g = acos(cos g) and ψ = acos(cos ψ) from the
    components, so that the table's float32-rounded directions (‖ω‖² − 1 up to 6·10⁻⁸)
    give g ≈ 3.5·10⁻⁴ at exact backscatter, and B falls by up to 0.3 % of the value there
    for h = 0.06 (0.14 % even in its float64 variant); near grazing its cos(atan(tan i))
    loses float32's relative precision. Where Eradiate is NaN — the defaults' h = 0 at g =
    0: 106 pairs in float32 (101 exact backscatter, 5 on the grid: nadir and
    principal-plane pairs whose g rounds to 0), 73 in float64 — the plugin is finite. No
    value of Eradiate is negative.

    The example's parameters are a lunar-like regolith: w = 0.3, b = 0.25, c = 0.7 (mostly
    backward), θ̄ = 20°, B_0 = 1, h = 0.06, of the order of the Moon's visible-light Hapke
    parameters mapped by Sato et al. (2014, "Resolved Hapke parameter maps of the Moon",
    JGR Planets 119, 1775-1805), with B_0 at Eradiate's bound of 1.

    **Polarized variants.** The model describes no polarization: values are depolarizers.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="hapke">
                <float name="w" value="0.3"/>
                <float name="b" value="0.25"/>
                <float name="c" value="0.7"/>
                <float name="theta" value="20"/>
                <float name="B_0" value="1"/>
                <float name="h" value="0.06"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'hapke', 'w': 0.3, 'b': 0.25, 'c': 0.7, 'theta': 20.0, 'B_0': 1.0,
             'h': 0.06}
    """

    def __init__(self, props):
        super().__init__(props)
        self.textures = {name: properties.texture(props, PLUGIN, name, default, 0.0, hi)
                         for name, (default, hi) in PARAMETERS.items()}
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        self._warn_energy(props)

    def _warn_energy(self, props):
        """Warn where constant parameters make the directional albedo exceed 1."""
        values = [empirical.channels(props, name, tex) for name, tex in self.textures.items()]
        if any(v is None for v in values):
            return
        n = max(len(v) for v in values)
        per_channel = [tuple(v[k if len(v) > 1 else 0] for v in values) for k in range(n)]
        albedo, theta = max(max_albedo(*clip(c)) for c in per_channel)
        if albedo > 1.0:
            given = empirical.given(PARAMETERS, values)
            properties.warn(PLUGIN, f"{given}: the model's directional albedo reaches "
                                    f"{albedo:.3g} > 1 at θi = {theta:.0f}° (float64 "
                                    f"quadrature): it creates energy; values kept")

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobe from the parameters as they are now: tabulated where all six are the same
        everywhere (its sampler built when first needed, for their values then)."""
        self.lobes = empirical.lobe(Surface(dict(self.textures)))

    def traverse(self, cb):
        for name, tex in self.textures.items():
            cb.put(name, tex, mi.ParamFlags.Differentiable)

    def to_string(self):
        lines = ",\n".join(f"  {name} = {properties.indent(tex)}"
                           for name, tex in self.textures.items())
        return f"Hapke[\n{lines}\n]"
