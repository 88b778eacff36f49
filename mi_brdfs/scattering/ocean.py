r"""
The terms of Cox & Munk's wind-roughened sea surface in drjit: the slope variances of the
wind speed, the Beckmann roughness they make, the bidirectional shadowing of Gaussian slopes
and the whitecaps' coverage. The plugin :mod:`mi_brdfs.plugins.ocean` puts them together with
the Fresnel reflectance of :mod:`.fresnel` and the distribution of :mod:`.microfacet`.

**Slopes** (Cox & Munk 1954, "Measurement of the roughness of the sea surface from photographs
of the sun's glitter", JOSA 44(11), eqs. 1-3, the clean surface's fits at wind speed U in m/s
at 12.5 m): isotropic, the slopes (zx, zy) are Gaussian with total mean square slope
σ² = 0.003 + 5.12·10⁻³ U, P = exp(−(zx² + zy²)/σ²)/(πσ²), each axis of variance σ²/2. With
tanθm = |z| and P(z) = D(m) cos⁴θm this is Beckmann's D of roughness α = σ (Walter et al. 2007,
eq. 25: exp(−tan²θm/α²)/(πα²cos⁴θm)). Anisotropic, along and across the wind σu² = 3.16·10⁻³ U
and σc² = 0.003 + 1.92·10⁻³ U, each the variance of one axis: P = exp(−zu²/(2σu²) −
zc²/(2σc²))/(2π σu σc) (the Gram-Charlier series without its skewness and peakedness terms),
Beckmann's anisotropic D with αu² = 2σu², αv² = 2σc².

**Shadowing** (Tsang, Kong & Shin 1985, *Theory of Microwave Remote Sensing*, as Mishchenko &
Travis 1997, "Satellite retrieval of aerosol properties over the ocean using polarization as
well as intensity of reflected sunlight", JGR 102(D14), eqs. 11-13, use it):
S = 1/(1 + Λ(ωi) + Λ(ωo)), Λ(μ) = ½[√((1 − μ²)/π) σ/μ e^{−μ²/(σ²(1 − μ²))} − erfc(μ/(σ√(1 −
μ²)))], which is Smith's Λ of the Beckmann distribution of α = σ
(:meth:`~mi_brdfs.scattering.microfacet.Distribution.smith_lambda`, with a = 1/(α tanθ)).

**Whitecaps** (Monahan & O'Muircheartaigh 1980, "Optimal power-law description of oceanic
whitecap coverage dependence on wind speed", J. Phys. Oceanogr. 10(12)): the share of the
surface they cover, W = 2.95·10⁻⁶ U^3.52, clipped to [0, 1] (1 from U = 37.25 m/s).
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

#: Cox & Munk's isotropic fit σ² = a + b U (clean surface).
ISOTROPIC = (0.003, 5.12e-3)
#: Their anisotropic fits: σu² = b U along the wind, σc² = a + b U across.
UPWIND = (0.0, 3.16e-3)
CROSSWIND = (0.003, 1.92e-3)
#: The least variance of one axis the anisotropic surface takes: the isotropic fit's per-axis
#: variance at U = 0 (0.003/2). σu² = 3.16·10⁻³ U reaches it at U = 0.47 m/s; below, the fit's
#: upwind variance tends to 0, a mirror along the wind, and is held here.
AXIS_VARIANCE_MIN = ISOTROPIC[0] / 2
#: Monahan & O'Muircheartaigh's W = a U^b.
MONAHAN = (2.95e-6, 3.52)


def variance(wind_speed):
    """σ², the isotropic total mean square slope, at ``wind_speed`` (m/s, ≥ 0)."""
    return ISOTROPIC[0] + ISOTROPIC[1] * wind_speed


def axis_variances(wind_speed):
    """(σu², σc²): the variances of the slope along and across the wind, each at least
    :data:`AXIS_VARIANCE_MIN`."""
    up = dr.maximum(UPWIND[0] + UPWIND[1] * wind_speed, AXIS_VARIANCE_MIN)
    cross = dr.maximum(CROSSWIND[0] + CROSSWIND[1] * wind_speed, AXIS_VARIANCE_MIN)
    return up, cross


def roughness(wind_speed, anisotropic: bool):
    """Beckmann's (αu, αv) of the slopes: (σ, None) isotropic (α² = σ², the total variance),
    (√(2σu²), √(2σc²)) along and across the wind (α² twice one axis' variance)."""
    if not anisotropic:
        return dr.sqrt(variance(wind_speed)), None
    up, cross = axis_variances(wind_speed)
    return dr.sqrt(2.0 * up), dr.sqrt(2.0 * cross)


def coverage(wind_speed):
    """Monahan & O'Muircheartaigh's whitecap coverage W(U), clipped to [0, 1]."""
    w = MONAHAN[0] * dr.power(dr.maximum(wind_speed, 0.0), MONAHAN[1])
    return dr.minimum(w, 1.0)


def to_wind(v, cos_phi, sin_phi):
    """``v`` in the frame whose x axis points along the wind, at azimuth φ (its cosine and
    sine) in the local frame: the rotation by −φ about the normal."""
    return mi.Vector3f(cos_phi * v.x + sin_phi * v.y, cos_phi * v.y - sin_phi * v.x, v.z)


def from_wind(v, cos_phi, sin_phi):
    """The inverse of :func:`to_wind`."""
    return mi.Vector3f(cos_phi * v.x - sin_phi * v.y, sin_phi * v.x + cos_phi * v.y, v.z)


def shadowing(distr, wi, wo):
    """S = 1/(1 + Λ(ωi) + Λ(ωo)) of Gaussian slopes (Tsang et al. 1985; Mishchenko & Travis
    1997): Smith's height-correlated masking-shadowing of ``distr`` (a Beckmann
    :class:`~mi_brdfs.scattering.microfacet.Distribution`), exact Λ; 1 at normal incidence,
    and finite at grazing (Λ grows as cotθ's inverse shrinks, S → 0)."""
    return 1.0 / (1.0 + distr.smith_lambda(wi) + distr.smith_lambda(wo))
