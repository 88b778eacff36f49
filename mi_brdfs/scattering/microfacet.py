r"""
Microfacet terms for Beckmann and GGX surfaces, isotropic and anisotropic: the distribution D,
Smith's masking (exactly, and as Mitsuba's ``microfacet.h`` computes it), the V-cavity masking
of Cook & Torrance, the sampling of microfacet normals (by D·cosθ and by the distribution of
visible normals) and the densities that go with them.

Conventions (Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces"):
directions are unit vectors in the local frame, pointing away from the surface; ``m`` is a
microfacet normal; α is the roughness, for Beckmann the RMS slope (Cook & Torrance's m):

.. math::

    D_\mathrm{B}(m) = \frac{e^{-\tan^2\theta_m/\alpha^2}}{\pi\alpha^2\cos^4\theta_m}, \qquad
    D_\mathrm{GGX}(m) = \frac{1}{\pi\alpha^2\cos^4\theta_m\,(1 + \tan^2\theta_m/\alpha^2)^2},

both normalised as ∫ D(m) cosθm dωm = 1 (Walter eqs. 25 and 33). Smith's masking
G1(v, m) = χ⁺(v·m / v·n) / (1 + Λ(v)) with, for a = 1 / (α tanθv),

.. math::

    \Lambda_\mathrm{B} = \frac{\operatorname{erf}(a) - 1}{2} + \frac{e^{-a^2}}{2a\sqrt\pi},
    \qquad
    \Lambda_\mathrm{GGX} = \frac{\sqrt{1 + \alpha^2\tan^2\theta_v} - 1}{2}

(Walter eqs. 27 and 34; Heitz 2014, "Understanding the Masking-Shadowing Function", eqs. 72
and 86). Mitsuba 3 replaces the Beckmann G1 by Walter's rational approximation (eq. 27,
< 0.35 % error): :meth:`Distribution.smith_g1_mitsuba` reproduces it, for fidelity with
``roughconductor``.
The V-cavity masking (Cook & Torrance 1982; Heitz 2014 §4.2) is
G1(v, m) = min(1, 2 (n·m)(n·v) / (v·m)) and G = min(G1(ωi), G1(ωo)).

**Anisotropy.** A :class:`Distribution` has the roughness αu, αv along the local frame's x
and y axes (the surface's tangent and bitangent). Then tan²θm/α² becomes
(mx²/αu² + my²/αv²)/mz², πα² becomes π αu αv, and α² tan²θv in Λ becomes ((αu vx)² + (αv vy)²)/vz² (Heitz 2014,
"Understanding the Masking-Shadowing Function", on anisotropic distributions: the anisotropic
slope distribution is the isotropic one of unit roughness, stretched by αu and αv); αu = αv
is the isotropic case.

The terms that do not depend on the distribution (the V-cavity masking, the densities and the
Jacobians) are plain functions.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi

from .vector import dot

BECKMANN, GGX = "beckmann", "ggx"
DISTRIBUTIONS = (BECKMANN, GGX)

#: Smallest roughness the terms are evaluated at, as Mitsuba's ``MicrofacetDistribution``
#: clamps it: below, D = 1/(πα²) at the peak exceeds 3e7 and the lobe is narrower than the
#: spacing of float32 directions near the normal (about 6e-8 rad, one ulp of cosθ = 1).
ALPHA_MIN = 1e-4

#: Mitsuba's D cut-off: D is 0 where D·cosθm ≤ 1e-20, which removes the underflowing tails
#: (and every microfacet below the horizon, where cosθm ≤ 0).
D_COS_MIN = 1e-20

# Denominators that can be exactly 0 in degenerate lanes (cosθ = 0) are floored at _TINY: a
# JIT lane would otherwise hold NaN (masked, but visible to AD), and a scalar variant, where
# Float is a Python float, would raise ZeroDivisionError.
_TINY = 1e-30

_INV_SQRT_PI = 0.5641895835477563


def mitsuba_type(kind: str):
    """The ``mi.MicrofacetType`` of 'beckmann' or 'ggx'."""
    return {BECKMANN: mi.MicrofacetType.Beckmann, GGX: mi.MicrofacetType.GGX}[kind]


class Distribution:
    """
    A microfacet distribution: Beckmann or GGX (``kind``), with roughness ``alpha_u`` along the
    local x axis and ``alpha_v`` along y (``alpha_v`` None: isotropic, α = ``alpha_u``), both
    already clamped to :data:`ALPHA_MIN`. Its methods are D, Smith's Λ and G1 (exact, and as
    Mitsuba computes G1) and the samplers of microfacet normals (D·cosθ, visible normals of
    Smith's and of the V-cavity's masking). The isotropic case computes D and Λ with the same
    operations as the pair (α, α); only the D·cosθ sampler has a form of its own for it.
    """

    def __init__(self, kind: str, alpha_u, alpha_v=None):
        self.kind = kind
        self.anisotropic = alpha_v is not None
        self.alpha_u = alpha_u
        self.alpha_v = alpha_v if self.anisotropic else alpha_u

    def scaled(self, factor) -> "Distribution":
        """The distribution with both roughnesses multiplied by ``factor`` (Walter's widening)."""
        return Distribution(self.kind, self.alpha_u * factor,
                            self.alpha_v * factor if self.anisotropic else None)

    def ndf(self, m):
        """D(m), per unit solid angle of microfacet normals; 0 below the horizon."""
        au, av = self.alpha_u, self.alpha_v
        cos2 = dr.square(m.z)
        # sin²θm/α² from the x, y components: exact near the normal, where 1 - cos²θ cancels
        slope2 = dr.square(m.x / au) + dr.square(m.y / av)
        if self.kind == BECKMANN:
            d = dr.exp(-slope2 / dr.maximum(cos2, _TINY)) / \
                dr.maximum(dr.pi * (au * av) * dr.square(cos2), _TINY)
        else:
            d = 1.0 / dr.maximum(dr.pi * (au * av) * dr.square(slope2 + cos2), _TINY)
        return dr.select(d * m.z > D_COS_MIN, d, 0.0)

    def _tan2_alpha2(self, v):
        """(α² sin²θv, α² tan²θv) of a unit vector ``v``, with α projected on its azimuth."""
        xy = dr.square(self.alpha_u * v.x) + dr.square(self.alpha_v * v.y)
        return xy, xy / dr.maximum(dr.square(v.z), _TINY)

    def smith_lambda(self, v):
        """Smith's Λ(v), exact (Beckmann with erf); 0 at normal incidence."""
        _, t2 = self._tan2_alpha2(v)
        if self.kind == BECKMANN:
            a = dr.rsqrt(t2)  # 1/(α tanθ): +inf at normal incidence, where Λ = 0 exactly
            # e^{-a²}/a: a = inf gives 0/inf = 0; the floor only keeps a = 0 (tangent) finite
            return 0.5 * (dr.erf(a) - 1.0) + \
                0.5 * _INV_SQRT_PI * dr.exp(-dr.square(a)) / dr.maximum(a, _TINY)
        return 0.5 * (dr.sqrt(1.0 + t2) - 1.0)

    def smith_g1(self, v, m):
        """Smith's masking G1(v, m) = χ⁺ / (1 + Λ(v)), exact for both distributions."""
        return _facing(1.0 / (1.0 + self.smith_lambda(v)), v, dot(v, m))

    def smith_g1_mitsuba(self, v, m, vm=None):
        """
        G1(v, m) as Mitsuba 3 computes it: for Beckmann Walter's rational approximation
        (3.535a + 2.181a²)/(1 + 2.276a + 2.577a²), 1 for a ≥ 1.6 (< 0.35 % error); for GGX
        the exact form, as :meth:`smith_g1`. ``vm``: v·m where the caller has it.
        """
        xy, t2 = self._tan2_alpha2(v)
        if self.kind == BECKMANN:
            a = dr.rsqrt(t2)
            a2 = dr.square(a)
            g1 = dr.select(a >= 1.6, 1.0,
                           (3.535 * a + 2.181 * a2) / (1.0 + 2.276 * a + 2.577 * a2))
        else:
            g1 = 2.0 / (1.0 + dr.sqrt(1.0 + t2))
        g1 = dr.select(xy == 0, 1.0, g1)
        if vm is None:  # (None or a value: configuration, not data)
            vm = dot(v, m)
        return _facing(g1, v, vm)

    def sample(self, u):
        """
        A microfacet normal with density D(m) cosθm (:func:`pdf_ndf`) from ``u`` in [0, 1)²
        (Walter eqs. 28 and 35): tan²θm = −α² ln(1 − u₁) (Beckmann) or α² u₁/(1 − u₁) (GGX),
        φm = 2π u₂. Anisotropic: the slope (cos 2πu₂, sin 2πu₂)·r of unit roughness,
        r² = −ln(1 − u₁) or u₁/(1 − u₁), is stretched to (αu cos 2πu₂, αv sin 2πu₂)·r (Heitz
        2014), so φm follows the stretched slope and α² in tan²θm is αu² cos²2πu₂ + αv²
        sin²2πu₂.

        sinθm is taken from tan²θm, not as sqrt(1 − cos²θm): in float32 the latter rounds to
        0 for α ≲ 1e-3 (cosθm rounds to 1 for a large share of the samples), which would put
        every such sample on the mirror direction; tan²θm keeps them apart down to α = 1e-4.
        """
        sin_phi, cos_phi = dr.sincos(dr.two_pi * u.y)
        if self.anisotropic:
            sx, sy = self.alpha_u * cos_phi, self.alpha_v * sin_phi  # the stretched slope
            a2 = dr.fma(sx, sx, sy * sy)
            inv = dr.rsqrt(a2)
            cos_phi, sin_phi = sx * inv, sy * inv
        else:
            a2 = self.alpha_u * self.alpha_u
        if self.kind == BECKMANN:
            tan2 = -a2 * dr.log(1.0 - u.x)
        else:  # u₁ < 1, but the floor keeps a scalar variant from dividing by 0 at u₁ = 1
            tan2 = a2 * u.x / dr.maximum(1.0 - u.x, _TINY)
        cos_theta = dr.rsqrt(1.0 + tan2)
        sin_theta = dr.sqrt(tan2) * cos_theta
        return mi.Vector3f(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)

    def mitsuba(self):
        """Mitsuba's ``MicrofacetDistribution`` of the same kind and α, sampling visible
        normals."""
        return mi.MicrofacetDistribution(mitsuba_type(self.kind), self.alpha_u, self.alpha_v,
                                         True)

    def sample_visible(self, wi, u):
        """
        A microfacet normal from the distribution of visible normals of ``wi``, density
        :func:`pdf_visible` with the exact :meth:`smith_g1` (Heitz & d'Eon 2014). This is
        Mitsuba's own exact sampler (Jakob's numerical inversion for Beckmann, Heitz 2018 for
        GGX), the one ``roughconductor`` uses.
        """
        m, _ = self.mitsuba().sample(wi, u)
        return m

    def sample_vcavity_visible(self, wi, u, u_facet):
        r"""
        A microfacet normal from the distribution of visible normals of ``wi`` under V-cavity
        masking, density :func:`pdf_visible` with :func:`vcavity_g1` (Heitz & d'Eon 2014, §5):
        draw m with density D(m) cosθm (:meth:`sample`, from ``u``); m and its mirror image
        m' = (−mx, −my, mz) are the two facets of one V-groove; pick m' with probability
        ⟨ωi·m'⟩ / (⟨ωi·m⟩ + ⟨ωi·m'⟩) (⟨⟩ clamps at 0), decided by ``u_facet`` in [0, 1).

        Why that density: m is reached from m (kept) and from m' (flipped), each drawn with
        D(m) cosθm, so p(m) = 2 D(m) cosθm ⟨ωi·m⟩ / (⟨ωi·m⟩ + ⟨ωi·m'⟩). Where both facets face
        ωi the denominator is ωi·m + ωi·m' = 2 cosθm cosθi and p(m) = D(m) (ωi·m) / cosθi
        (G1 = 1); where m' faces away, p(m) = 2 D(m) cosθm = D(m) (ωi·m) G1(ωi, m) / cosθi
        with G1 = 2 cosθm cosθi / (ωi·m) < 1. The sample weight of the V-cavity lobe is then
        F·G/G1(ωi) ≤ F, where the Smith visible normals leave it G_V-cavity/G1_Smith.
        """
        m = self.sample(u)
        kept = dot(wi, m)
        flipped = 2.0 * wi.z * m.z - kept  # ωi·m'
        kept_p, flipped_p = dr.maximum(kept, 0.0), dr.maximum(flipped, 0.0)
        flip = u_facet * dr.maximum(kept_p + flipped_p, _TINY) < flipped_p
        return mi.Vector3f(dr.select(flip, -m.x, m.x), dr.select(flip, -m.y, m.y), m.z)


class Smith:
    """
    Smith's separable masking-shadowing of a :class:`Distribution`, G = G1(ωi)·G1(ωo) (Walter
    et al. 2007, eq. 23), with G1 as Mitsuba 3 computes it (:meth:`Distribution.
    smith_g1_mitsuba`), its visible normals (Heitz & d'Eon 2014) and their sample weight.
    """

    name = "smith"

    def __init__(self, distr: Distribution):
        self.distr = distr

    def G1(self, v, m, vm=None):
        """G1(v, m); ``vm``: v·m where the caller has it."""
        return self.distr.smith_g1_mitsuba(v, m, vm)

    def G(self, wi, wo, m, cos_im, cos_om):
        """G(ωi, ωo, m), given ωi·m and ωo·m."""
        return self.G1(wi, m, cos_im) * self.G1(wo, m, cos_om)

    def sample_visible(self, wi, u, u_facet):
        """A visible normal of ``wi`` (``u_facet`` unused: Smith's sampler needs no choice)."""
        return self.distr.sample_visible(wi, u)

    def visible_weight(self, wi, wo, m, cos_im, cos_om):
        """G/G1(ωi) of a reflection sampled by :meth:`sample_visible`: G1(ωo), in closed form
        (D and 4 cosθi cancel against its density)."""
        return self.G1(wo, m, cos_om)


class VCavity:
    """
    The V-cavity masking-shadowing of Cook & Torrance 1982 (:func:`vcavity_g`), its visible
    normals (:meth:`Distribution.sample_vcavity_visible`, Heitz & d'Eon 2014, §5) and their
    sample weight; defined for directions above the surface only.
    """

    name = "vcavity"

    def __init__(self, distr: Distribution):
        self.distr = distr

    def G1(self, v, m, vm=None):
        """G1(v, m) (:func:`vcavity_g1`)."""
        return vcavity_g1(v, m)

    def G(self, wi, wo, m, cos_im, cos_om):
        """G(ωi, ωo, m) (:func:`vcavity_g`, symmetric in ωi, ωo to the last bit)."""
        return vcavity_g(wi, wo, m)

    def sample_visible(self, wi, u, u_facet):
        """A visible normal of ``wi``: one of the two facets of a V-groove, by ``u_facet``."""
        return self.distr.sample_vcavity_visible(wi, u, u_facet)

    def visible_weight(self, wi, wo, m, cos_im, cos_om):
        """G/G1(ωi) of a reflection sampled by :meth:`sample_visible` (≤ 1)."""
        return self.G(wi, wo, m, cos_im, cos_om) / dr.maximum(self.G1(wi, m, cos_im), _TINY)


#: The masking-shadowing models by name.
MASKING = {"smith": Smith, "vcavity": VCavity}


def _facing(g1, v, vm):
    """χ⁺: a microfacet is seen only from its front (``vm`` = v·m), and only from the side of
    the surface."""
    return dr.select(vm * v.z > 0, g1, 0.0)


def vcavity_g1(v, m):
    """
    The V-cavity masking of one direction: min(1, 2 (n·m)(n·v) / (v·m)); 0 for the back of the
    facet, for v below the surface and for facets below the horizon (which do not exist).
    """
    vm = dot(v, m)
    g1 = dr.minimum(1.0, 2.0 * m.z * v.z / dr.maximum(vm, _TINY))
    return dr.select((vm > 0) & (v.z > 0) & (m.z > 0), g1, 0.0)


def vcavity_g(wi, wo, m):
    """
    Cook & Torrance's masking-shadowing G = min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·L)/(V·H)) for the
    reflection half-vector ``m``, i.e. min(G1(ωi), G1(ωo)) of :func:`vcavity_g1`. V·H = L·H
    there; their mean stands for both, which keeps G symmetric in ωi, ωo to the last bit (with
    ωi·m alone, float32 rounding breaks reciprocity at grazing angles).
    """
    vm = 0.5 * (dot(wi, m) + dot(wo, m))
    g = dr.minimum(1.0, 2.0 * m.z * dr.minimum(wi.z, wo.z) / dr.maximum(vm, _TINY))
    return dr.select((vm > 0) & (wi.z > 0) & (wo.z > 0), g, 0.0)


def pdf_ndf(d, m):
    """The density of :meth:`Distribution.sample` per unit solid angle of m: D(m) cosθm."""
    return d * m.z


def pdf_visible(d, g1_wi, wi, m):
    """
    The density of visible normals of ``wi``: G1(wi, m) |wi·m| D(m) / cosθi (Heitz eq. 2), for
    Smith's G1 (:meth:`Distribution.sample_visible`) or the V-cavity's
    (:meth:`Distribution.sample_vcavity_visible`).
    """
    return d * g1_wi * dr.abs(dot(wi, m)) / dr.maximum(wi.z, _TINY)


def pdf_visible_reflection(d, g1_wi, wi):
    """
    The density of ωo = reflect(ωi, m) for m drawn by :meth:`Distribution.sample_visible` or
    :meth:`Distribution.sample_vcavity_visible` (with their G1): :func:`pdf_visible`
    times :func:`reflection_jacobian`, where |ωi·m| = |ωo·m| cancels: D(m) G1(ωi, m) / (4 cosθi).
    """
    return d * g1_wi / dr.maximum(4.0 * wi.z, _TINY)


def reflection_jacobian(wo, m):
    """|∂ωm/∂ωo| = 1 / (4 |ωo·m|) of the reflection ωo = reflect(ωi, m) (Walter eq. 14)."""
    return 1.0 / dr.maximum(4.0 * dr.abs(dot(wo, m)), _TINY)


def refraction_jacobian(wi, wo, m, eta):
    """
    |∂ωm/∂ωo| = η² |ωo·m| / (ωi·m + η ωo·m)² of the refraction of ωi into ωo through the facet
    m, η the relative index in the direction of travel (Walter et al. 2007, eq. 17).
    """
    cos_om = dot(wo, m)
    denom = dot(wi, m) + eta * cos_om
    return dr.abs(eta * eta * cos_om) / dr.maximum(dr.square(denom), _TINY)


def walter_widening(cos_theta_i):
    """
    The factor 1.2 − 0.2 sqrt|cosθi| by which Walter et al. 2007 (§5.3) widen α when they draw
    microfacet normals from D·cosθm for a rough dielectric, to keep the sample weights of
    grazing directions small; Mitsuba's ``roughdielectric`` does the same. The density is then
    that of the widened D: it enters the pdf, and the weight carries D/D_widened.
    """
    return 1.2 - 0.2 * dr.sqrt(dr.abs(cos_theta_i))
