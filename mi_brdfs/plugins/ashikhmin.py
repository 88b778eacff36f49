"""
Ashikhmin & Shirley's anisotropic Phong reflectance model (2000): a Phong-like glossy lobe of
the half vector with Schlick's Fresnel factor, over a non-Lambertian diffuse term that keeps
the sum energy-conserving, importance-sampled with the paper's half-vector sampler. The terms
live in :mod:`mi_brdfs.scattering.ashikhmin`.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from ..scattering import ashikhmin as terms
from ..scattering import vector
from . import lobes, properties

PLUGIN = "ashikhmin"

GLOSSY_FLAGS = lobes.flag("GlossyReflection", "FrontSide")
ANISOTROPIC = lobes.flag("Anisotropic")
DIFFERENTIABLE = mi.ParamFlags.Differentiable
DISCONTINUOUS = mi.ParamFlags.Differentiable | mi.ParamFlags.Discontinuous


def _constant(tex) -> float | None:
    """The value of a texture known to be one constant everywhere, else None."""
    rng = properties.texture_range(tex)
    if rng is None or tex.is_spatially_varying() or rng[0] != rng[1]:
        return None
    return rng[0]


class Substrate(lobes.CosineLobe):
    """The diffuse term Rd (1 − Rs)·28/(23π)(1 − (1 − cosθi/2)⁵)(1 − (1 − cosθo/2)⁵)·cosθo,
    sampled by the cosine-weighted hemisphere; ``rs``, ``rd``: the reflectance textures."""

    def __init__(self, rs, rd):
        self.rs, self.rd = rs, rd

    def diffuse_reflectance(self, si, active):
        """Rd (1 − Rs): the term's albedo, but for its factor 1 − (1 − cosθi/2)⁵."""
        return properties.clip_at(self.rd, si, active) * (
            1.0 - properties.clip_at(self.rs, si, active))

    def value(self, si, wo, active):
        return self.diffuse_reflectance(si, active) * (terms.diffuse(si.wi.z, wo.z) * wo.z)

    def weight(self, ctx, si, active):
        """Its albedo at cosθi (:func:`~mi_brdfs.scattering.ashikhmin.albedo_bounds`)."""
        return _bounds(self.rs, self.rd, si, active)[1]


class Glossy(lobes.Lobe):
    """
    The specular term of exponents ``nu``, ``nv`` (textures, the same one when isotropic) and
    Schlick's Fresnel of ``rs``, sampled by the paper's half vector; ``rd`` weighs it against
    the substrate.
    """

    kind = "GlossyReflection"

    def __init__(self, rs, rd, nu, nv, component: int, flags: int):
        self.rs, self.rd, self.nu, self.nv = rs, rd, nu, nv
        self.component, self.flags = component, flags

    def exponents(self, si, active):
        """(nu, nv) at ``si``; values set through ``mi.traverse`` are clamped into range."""
        nu = dr.clip(self.nu.eval_1(si, active), 0.0, terms.EXPONENT_MAX)
        if self.nv is self.nu:
            return nu, nu
        return nu, dr.clip(self.nv.eval_1(si, active), 0.0, terms.EXPONENT_MAX)

    def eval_pdf(self, ctx, si, wo, active):
        wi = si.wi
        active = active & (wi.z > 0) & (wo.z > 0)  # one-sided
        # ρs·cosθo, from the density of ωi reflected about the sampled half vector
        pdf, k_dot_h = terms.lobe(wi, wo, *self.exponents(si, active))
        value = terms.specular(pdf, terms.fresnel(k_dot_h, properties.clip_at(self.rs, si, active)),
                               wi.z, wo.z)
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        """ωi reflected about a half vector drawn as the paper draws it."""
        return vector.reflect(si.wi, terms.sample_half(sample2, *self.exponents(si, active))), \
            True

    def weight(self, ctx, si, active):
        """The bound of its albedo at cosθi (:func:`~mi_brdfs.scattering.ashikhmin.
        albedo_bounds`): towards grazing incidence, where the substrate vanishes, the glossy
        lobe takes every sample."""
        return _bounds(self.rs, self.rd, si, active)[0]


def _bounds(rs, rd, si, active):
    """The lobes' albedo bounds at cosθi, from the reflectances' means over channels (Rd
    None: no substrate)."""
    rs_mean = dr.mean(properties.clip_at(rs, si, active))
    rd_mean = 0.0 if rd is None else dr.mean(properties.clip_at(rd, si, active))
    return terms.albedo_bounds(rs_mean, rd_mean, si.wi.z)


class Ashikhmin(mi.BSDF):
    r"""
    .. _bsdf-ashikhmin:

    Ashikhmin-Shirley anisotropic Phong reflectance (:monosp:`ashikhmin`)
    ---------------------------------------------------------------------

    .. pluginparameters::

     * - exponent, nu, nv
       - |float| or |texture|
       - Phong-like exponents of the glossy lobe: ``exponent`` for an isotropic surface, or
         ``nu`` along the tangent and ``nv`` along the bitangent (the highlight is narrow
         along a direction whose exponent is large), finite and within [0, 10³⁰]; 0 is a
         uniform distribution of half vectors (Default: 100)
       - |exposed|, |differentiable|, |discontinuous|

     * - specular_reflectance
       - |spectrum| or |texture|
       - Rs, the specular reflectance at normal incidence (Schlick's R0), finite and within
         [0, 1] (Default: 0.04, a dielectric of index 1.5 such as plastic)
       - |exposed|, |differentiable|

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - Rd, the substrate's albedo, finite and within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

     * - preset
       - |string|
       - A published fit that fills every parameter the scene does not give (explicit ones
         win). ``ngan:<material>`` names Ngan et al. 2005's Ashikhmin-Shirley fit, which has
         no exact form in this plugin: the error says what differs (docs/presets.md)
         (Default: none)
       -

    With k1 = ωi, k2 = ωo, h their half vector at azimuth φh and k·h = ωi·h
    (Ashikhmin & Shirley 2000, the specular and the diffuse term):

    .. math::

        f = \frac{\sqrt{(n_u+1)(n_v+1)}}{8\pi}
            \frac{(n\cdot h)^{n_u\cos^2\phi_h + n_v\sin^2\phi_h}}
                 {(k\cdot h)\max(\cos\theta_i, \cos\theta_o)}\,F(k\cdot h)
          + \frac{28 R_d}{23\pi}(1 - R_s)
            \Big(1 - \big(1 - \tfrac{\cos\theta_i}{2}\big)^5\Big)
            \Big(1 - \big(1 - \tfrac{\cos\theta_o}{2}\big)^5\Big)

    with F(k·h) = Rs + (1 − Rs)(1 − k·h)⁵. ``eval`` returns f·cosθo; the model is one-sided
    (0 when either direction is below the surface) and reciprocal. It conserves energy, as
    the paper claims, for every Rs, Rd in [0, 1] and at every incidence, grazing included:
    the specular albedo is at most Rs + (1 − Rs)(1 − cosθi/2)⁵ and the diffuse albedo is
    exactly Rd (1 − Rs)(1 − (1 − cosθi/2)⁵) (:mod:`mi_brdfs.scattering.ashikhmin`), so
    Rd + Rs ≤ 1 is not needed; the largest albedo measured, with Rs = 1 and a sharp lobe at
    normal incidence, is just below 1 (``validation/REPORT.md``). The glossy lobe is never
    0 (F reaches 1 at grazing even where Rs = 0); the diffuse one is left out where Rd is
    the constant 0 or Rs the constant 1. The component of the glossy lobe is
    ``Anisotropic`` where ``nu`` and ``nv`` are given and are not the same constant.

    **Sampling.** The glossy lobe draws the half vector with the paper's density
    √((nu+1)(nv+1))/(2π) (n·h)^(nu cos²φh + nv sin²φh), by its formulas for φh and cosθh,
    and reflects ωi about it (density per ωo: that over 4 k·h), the diffuse lobe draws the
    cosine-weighted hemisphere. ``sample()`` picks the glossy lobe with probability
    ws/(ws + wd), ws = Rs + (1 − Rs)(1 − cosθi/2)⁵ and wd = Rd (1 − Rs)(1 − (1 −
    cosθi/2)⁵) with the textures' values at the hit point (mean over channels): the bounds
    of the lobes' albedos at this
    incidence, so that towards grazing incidence, where the diffuse term vanishes, the
    glossy lobe takes every sample. ``pdf()`` and ``bs.pdf`` are the mixture density;
    samples below the horizon have weight 0.

    **Float32.** The exponent is taken from the half vector's components
    ((nu hx² + nv hy²)/(hx² + hy²), as the paper writes it without trigonometry, finite at
    h = n) and the lobe as
    exp(e·log1p(−(1 − cosθh))), so that exponents from 0 to 10⁶ and beyond give no NaN or
    Inf at any direction, grazing ones included.

    **Polarized variants.** The model describes no polarization: ``eval`` and the sample
    weights are depolarizers (the Mueller matrix with the value in its first element alone), as
    Mitsuba's ``diffuse`` returns them.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="ashikhmin">
                <float name="nu" value="10"/>
                <float name="nv" value="1000"/>
                <rgb name="diffuse_reflectance" value="0.3, 0.1, 0.1"/>
                <float name="specular_reflectance" value="0.05"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'ashikhmin', 'nu': 10.0, 'nv': 1000.0,
             'diffuse_reflectance': {'type': 'rgb', 'value': [0.3, 0.1, 0.1]},
             'specular_reflectance': 0.05}
    """

    def __init__(self, props):
        super().__init__(props)
        properties.preset(props, PLUGIN)  # a preset's parameters, where the scene gives none
        #: Exponents along the tangent and the bitangent: one texture twice when isotropic.
        names, exponents = properties.isotropic_or_pair(props, PLUGIN, "exponent", ("nu", "nv"),
                                                        100.0, hi=terms.EXPONENT_MAX)
        self.m_nu, self.m_nv = exponents[0], exponents[-1]
        self._separate = len(names) == 2
        anisotropic = self._separate and (_constant(self.m_nu) is None
                                          or _constant(self.m_nu) != _constant(self.m_nv))
        self.m_specular_reflectance = properties.reflectance(props, PLUGIN,
                                                             "specular_reflectance", 0.04)
        self.m_diffuse_reflectance = properties.reflectance(props, PLUGIN,
                                                            "diffuse_reflectance", 0.5)
        # Lobes in component order: the diffuse one, Rd (1 − Rs)·…, is 0 where Rd ≡ 0 or Rs ≡ 1
        self._has_diffuse = not (properties.is_zero(self.m_diffuse_reflectance)
                                 or _constant(self.m_specular_reflectance) == 1.0)
        self._glossy_flags = GLOSSY_FLAGS | (ANISOTROPIC if anisotropic else 0)
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

    # the substrate (cosine-weighted hemisphere) and the glossy lobe, mixed by their albedos
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """The lobes, from the parameters as they are now."""
        # components: the substrate first; sampling: the glossy lobe first
        rs, rd = self.m_specular_reflectance, self.m_diffuse_reflectance
        substrate = [Substrate(rs, rd)] if self._has_diffuse else []
        glossy = Glossy(rs, rd if self._has_diffuse else None, self.m_nu, self.m_nv,
                        len(substrate), self._glossy_flags)
        self.lobes = lobes.Mixture([glossy] + substrate)

    def traverse(self, cb):
        # Only the parameters of lobes that exist: the lobe structure is fixed at load time.
        if self._has_diffuse:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance, DIFFERENTIABLE)
        cb.put("specular_reflectance", self.m_specular_reflectance, DIFFERENTIABLE)
        if self._separate:
            cb.put("nu", self.m_nu, DISCONTINUOUS)
            cb.put("nv", self.m_nv, DISCONTINUOUS)
        else:
            cb.put("exponent", self.m_nu, DISCONTINUOUS)

    def to_string(self):
        if self._separate:
            exponents = (f"  nu = {properties.indent(self.m_nu)},\n"
                         f"  nv = {properties.indent(self.m_nv)},\n")
        else:
            exponents = f"  exponent = {properties.indent(self.m_nu)},\n"
        return (f"Ashikhmin[\n{exponents}"
                f"  specular_reflectance = {properties.indent(self.m_specular_reflectance)},\n"
                f"  diffuse_reflectance = {properties.indent(self.m_diffuse_reflectance)}\n]")
