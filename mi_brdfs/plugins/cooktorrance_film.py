"""
The thin film of :mod:`~mi_brdfs.plugins.cooktorrance` (``film_thickness``, ``film_eta``): a
layer of real index over the conductor or the dielectric, which replaces the Fresnel term of
the microfacet lobes by the film's reflectance at the microfacet's cosine
(:mod:`mi_brdfs.scattering.thinfilm`): exact at the sampled wavelengths in spectral variants,
integrated against the channels' sensitivities in RGB and mono ones, a Mueller matrix in
polarized ones. The lobes call :class:`Film`; without ``film_thickness`` (or with the
constant 0) there is no :class:`Film` and no film code in the kernel.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..scattering import fresnel, thinfilm, thinfilm_table
from . import properties

#: Largest film thickness (nm) and film index the plugin takes: 100 µm is far beyond where
#: interference colours wash out (a few µm), an index of 100 beyond any material's.
THICKNESS_MAX, FILM_ETA_MAX = 1e5, 100.0


def read(props, plugin: str, fresnel_kind: str):
    """The :class:`Film` of the properties, or None where ``film_thickness`` is absent or the
    constant 0; ``film_eta`` without ``film_thickness``, and a film with a Fresnel term
    other than ``exact``, are refused (one line each)."""
    if "film_thickness" not in props:
        properties.reject(props, plugin, "film_eta", "needs film_thickness as well (without a "
                                                     "film its index does nothing)")
        return None
    thickness = properties.texture(props, plugin, "film_thickness", 0.0, lo=0.0,
                                   hi=THICKNESS_MAX, scalar=True)
    eta = properties.texture(props, plugin, "film_eta", 1.33, lo=0.0, hi=FILM_ETA_MAX,
                             lo_open=True, scalar=True)
    if fresnel_kind != "exact":
        raise ParameterError(plugin, "film_thickness", props["film_thickness"],
                             f"needs fresnel = \"exact\" (not \"{fresnel_kind}\"): the film's "
                             f"reflectance replaces the exact Fresnel term")
    if properties.is_zero(thickness):
        return None
    return Film(thickness, eta)


class Film:
    """
    The film's textures (``thickness`` in nm, ``eta`` relative to the exterior, as the
    base's η) and what the lobes ask of it. In RGB and mono variants the channels'
    :class:`~mi_brdfs.scattering.thinfilm.Sensitivity`, built once per plugin.
    """

    def __init__(self, thickness, eta):
        self.thickness, self.eta = thickness, eta
        #: the smallest film index where known at load (else 0): a film at least as dense as
        #: the medium the light comes from has no evanescent branch in the kernel
        rng = properties.texture_range(eta)
        self.eta_min = 0.0 if rng is None else rng[0]
        self.sensitivity = None if mi.is_spectral else thinfilm.Sensitivity()

    def tabulate(self, base_eta, base_k):
        """
        A :class:`~mi_brdfs.scattering.thinfilm_table.ColourTable` of the film's colour lit
        from outside over a base of index ``base_eta`` + i``base_k`` (numbers or textures),
        where everything it depends on is known at load in an RGB or mono variant: the base's
        and the film's indices constant, the thickness's range known and within the table's
        reach, and neither an index nor the thickness differentiated (``mi.traverse`` with a
        gradient enabled: the table holds numbers, and a fit that moves the thickness would
        build one at every step); else None (the kernel then sums the series itself). A
        thickness that is one number takes a table of that thickness alone.
        """
        rng, eta = properties.texture_range(self.thickness), properties.texture_range(self.eta)
        if self.sensitivity is None or rng is None or eta is None or eta[0] != eta[1] or \
                self.eta.is_spatially_varying() or \
                properties.differentiated([self.eta, self.thickness, base_eta, base_k]):
            return None
        n2 = eta[0]
        if rng[1] * n2 / thinfilm_table.OPTICAL_STEP > thinfilm_table.MAX_NODES:
            return None
        uniform = rng[0] == rng[1] and not self.thickness.is_spatially_varying()
        base = [_channels(v, self.sensitivity.channels) for v in (base_eta, base_k)]
        if base[0] is None or base[1] is None:
            return None
        index = tuple(complex(e, k) for e, k in zip(*base))
        return thinfilm_table.ColourTable(
            thinfilm_table.build(self.sensitivity.channels, 1.0, n2, index, rng[1], uniform), n2)

    def _at(self, si, active):
        """(thickness, film index) at ``si``, clipped into range."""
        d = properties.clip(self.thickness.eval_1(si, active), 0.0, THICKNESS_MAX)
        n2 = properties.clip(self.eta.eval_1(si, active), 1e-4, FILM_ETA_MAX)
        return d, n2

    def reflectance(self, si, cos1, n1, eta3, k3, active, n1_max: float = 1.0, table=None):
        """The film's unpolarized reflectance per channel (``mi.UnpolarizedSpectrum``) at
        incidence cosine ``cos1`` from the medium ``n1`` (1 outside, the base's η inside, at
        most ``n1_max``) over ``eta3`` + i``k3`` (per channel, or one Float); from
        :meth:`tabulate`'s ``table`` where there is one (lit from outside: n1 = 1)."""
        if table is not None:
            d = None if table.uniform else self._at(si, active)[0]
            return mi.UnpolarizedSpectrum(table(cos1, d))
        d, n2 = self._at(si, active)
        return self._reflectance(si, cos1, n1, eta3, k3, d, n2, n1_max)

    def mean_reflectance(self, si, cos1, n1, eta3, k3, active, n1_max: float = 1.0,
                         table=None):
        """The mean over the channels of :meth:`reflectance` (from the table alone where
        there is one: a quarter of its reads)."""
        if table is not None:
            return table.mean(cos1, None if table.uniform else self._at(si, active)[0])
        return dr.mean(self.reflectance(si, cos1, n1, eta3, k3, active, n1_max))

    def _reflectance(self, si, cos1, n1, eta3, k3, d, n2, n1_max):
        """:meth:`reflectance` computed in the kernel: exact, or the series of the colours."""
        if self.sensitivity is None:
            rs, rp = thinfilm.amplitudes(cos1, n1, n2, eta3, k3, d, si.wavelengths,
                                         evanescent=n1_max > self.eta_min)
            return mi.UnpolarizedSpectrum(0.5 * (thinfilm._abs2(rs) + thinfilm._abs2(rp)))
        channels = thinfilm.colour(cos1, n1, n2, eta3, k3, d, self.sensitivity,
                                   evanescent=n1_max > self.eta_min)
        return mi.UnpolarizedSpectrum([0.5 * (rs + rp) for rs, rp in channels])

    def _wavelengths(self, si):
        """The sampled wavelengths, or in RGB and mono variants each channel's mean one."""
        if self.sensitivity is None:
            return si.wavelengths
        return mi.UnpolarizedSpectrum(*(float(v) for v in self.sensitivity.mean_wavelength))

    def average(self, si, eta3, k3, active, nodes: int = 5):
        """F_avg = 2∫₀¹ R(μ) μ dμ of the film on a conductor, per channel, by a Gauss-Legendre
        rule (as :func:`~mi_brdfs.scattering.multiscatter.fresnel_average`); in RGB and mono
        variants at each channel's mean wavelength (the compensation's colour; a film that
        absorbs nothing over a perfect mirror reflects everything at every wavelength)."""
        d, n2 = self._at(si, active)
        wavelengths = self._wavelengths(si)
        total = 0.0
        x, w = np.polynomial.legendre.leggauss(nodes)
        for xj, wj in zip(x, w):
            mu = 0.5 * (float(xj) + 1.0)
            rs, rp = thinfilm.amplitudes(mi.Float(mu), 1.0, n2, eta3, k3, d, wavelengths)
            total = total + (0.5 * float(wj) * mu) * (thinfilm._abs2(rs) + thinfilm._abs2(rp))
        return mi.UnpolarizedSpectrum(total)

    def mueller(self, si, wi, wo, m, eta3, k3, radiance: bool, active):
        """The Mueller matrix of the film's reflection at the facet ``m``, in the Stokes frames
        of the directions (:func:`~mi_brdfs.scattering.fresnel.rotate_reflection`); at each
        channel's mean wavelength in mono variants, exact in spectral ones."""
        d, n2 = self._at(si, active)
        wo_hat = wo if radiance else wi
        cos1 = dr.clip(fresnel.dot(wo_hat, m), 0.0, 1.0)
        rs, rp = thinfilm.amplitudes(cos1, 1.0, n2, eta3, k3, d, self._wavelengths(si))
        return fresnel.rotate_reflection(thinfilm.mueller(rs, rp), wi, wo, m, radiance)


def _channels(value, channels: int):
    """The per-channel values of a number or a texture that is the same everywhere (evaluated
    once), else None."""
    if isinstance(value, (int, float)):
        return [float(value)] * channels
    if not isinstance(value, mi.Texture):
        v = np.array(value, np.float64).ravel()
        return [float(v[0])] * channels
    if value.is_spatially_varying():
        return None
    v = np.array(value.eval(dr.zeros(mi.SurfaceInteraction3f)), np.float64).ravel()
    return [float(x) for x in (v if v.size == channels else np.repeat(v[:1], channels))]
