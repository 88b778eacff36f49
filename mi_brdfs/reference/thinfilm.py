r"""
Reflectance and transmittance of a stack of thin layers in float64, by the characteristic
(transfer) matrix of Born & Wolf, "Principles of Optics", §1.6.2-1.6.4: independent of the Airy
summation of :mod:`mi_brdfs.scattering.thinfilm`, and for any number of layers.

A plane wave of vacuum wavelength λ arrives from a medium of real index n₁ at incidence cosine
cosθ₁ on layers j = 2 … l−1 of complex index n_j = η_j + iκ_j and thickness d_j (the same unit
as λ), over a substrate n_l (complex: a conductor, or a dielectric). Phases run as e^(−iωt), so
that absorption is κ > 0 (Born & Wolf's convention; Mitsuba's ``fresnel_polarized`` returns the
complex conjugates). With the invariant n₁ sinθ₁, each medium has

.. math::

    q_j = n_j\cos\theta_j = \sqrt{n_j^2 - n_1^2\sin^2\theta_1}\quad(\operatorname{Im} q_j \ge 0),
    \qquad p_j = q_j \;(s), \quad p_j = q_j / n_j^2 \;(p),

and each layer the characteristic matrix, β_j = 2π d_j q_j / λ,

.. math::

    M_j = \begin{pmatrix}\cos\beta_j & -\tfrac{i}{p_j}\sin\beta_j\\
                         -i p_j\sin\beta_j & \cos\beta_j\end{pmatrix},\qquad
    M = M_2 M_3 \cdots M_{l-1},

whence (Born & Wolf, 1.6.(56)-(58))

.. math::

    r = \frac{(m_{11} + m_{12}p_l)p_1 - (m_{21} + m_{22}p_l)}
             {(m_{11} + m_{12}p_l)p_1 + (m_{21} + m_{22}p_l)},\qquad
    t = \frac{2p_1}{(m_{11} + m_{12}p_l)p_1 + (m_{21} + m_{22}p_l)},

R = |r|² and T = Re(p_l)/p₁·|t|² (0 where the substrate's wave is evanescent). For p light r
is the ratio of the magnetic amplitudes, which equals Born & Wolf's r∥ of the electric field
(1.5.(21)); without layers r is the Fresnel amplitude of the bare interface.
"""

from __future__ import annotations

import numpy as np


def _q(n, n1, cos1):
    """n cosθ in a medium of index n (complex), the root with Im ≥ 0 (a decaying wave)."""
    sin2 = 1.0 - np.asarray(cos1, np.complex128) ** 2
    q = np.sqrt(np.asarray(n, np.complex128) ** 2 - (n1 * n1) * sin2)
    return np.where(q.imag < 0.0, -q, q)


def stack(cos1, wavelength, n1, layers, substrate) -> dict:
    """
    The stack's response, NumPy arrays broadcast over ``cos1`` (incidence cosines in (0, 1])
    and ``wavelength``: a dict with the complex amplitudes ``rs``, ``rp``, ``ts``, ``tp`` and
    ``Rs``, ``Rp``, ``Ts``, ``Tp``, ``R`` = (Rs + Rp)/2, ``T`` = (Ts + Tp)/2.

    ``n1``: the real index of the incident medium. ``layers``: a sequence of (index, thickness)
    pairs from the incident side down, complex indices allowed, thicknesses in the unit of
    ``wavelength``. ``substrate``: the index below the last layer (complex allowed).
    """
    cos1 = np.asarray(cos1, np.float64)
    wavelength = np.asarray(wavelength, np.float64)
    n1 = float(n1)
    out = {}
    for pol in ("s", "p"):
        def p_of(n):
            q = _q(n, n1, cos1)
            return q if pol == "s" else q / np.asarray(n, np.complex128) ** 2
        p1, pl = p_of(n1), p_of(substrate)
        m11 = m22 = np.ones(np.broadcast(cos1, wavelength).shape, np.complex128)
        m12 = m21 = np.zeros_like(m11)
        for n, d in layers:
            pj = p_of(n)
            beta = 2.0 * np.pi * float(d) * _q(n, n1, cos1) / wavelength
            c, s = np.cos(beta), np.sin(beta)
            a11, a12, a21, a22 = c, -1j * s / pj, -1j * pj * s, c
            m11, m12, m21, m22 = (m11 * a11 + m12 * a21, m11 * a12 + m12 * a22,
                                  m21 * a11 + m22 * a21, m21 * a12 + m22 * a22)
        top, bottom = (m11 + m12 * pl) * p1, m21 + m22 * pl
        r = (top - bottom) / (top + bottom)
        t = 2.0 * p1 / (top + bottom)
        out["r" + pol], out["t" + pol] = r, t
        out["R" + pol] = np.abs(r) ** 2
        out["T" + pol] = np.real(pl) / np.real(p1) * np.abs(t) ** 2
    out["R"] = 0.5 * (out["Rs"] + out["Rp"])
    out["T"] = 0.5 * (out["Ts"] + out["Tp"])
    return out


def film(cos1, wavelength, film_eta, thickness, base, n1: float = 1.0) -> dict:
    """:func:`stack` of one film of real index ``film_eta`` and ``thickness`` over ``base``."""
    return stack(cos1, wavelength, n1, [(film_eta, thickness)], base)
