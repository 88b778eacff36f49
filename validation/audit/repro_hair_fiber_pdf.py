"""
Reproducer: ``hair``'s ``pdf()`` integrates to less than 1 although every sample succeeds, because
its longitudinal lobes are evaluated with approximations of the Bessel function I0 that lose part
of the lobe's mass (Mitsuba 3.9.1, ``include/mitsuba/core/warp.h``, ``detail::i0``,
``detail::log_i0`` and ``square_to_rough_fiber_pdf``, which ``Hair::longitudinal_scattering``
calls).

``sample()`` draws each lobe's longitudinal angle exactly (the inverse CDF
``cos = 1 + v log(u + (1 - u) exp(-2/v))`` of d'Eon et al. 2011's lobe, src/bsdfs/hair.cpp lines
275-280), so the density of the samples integrates to 1. ``pdf()`` evaluates that lobe as
``exp(-s) I0(c) kappa / (2 sinh kappa) / (2 pi)`` with

* ``i0(x)``: the first 11 terms of the series sum (x^2/4)^k / (k!)^2, which falls short of I0 by
  up to half a percent just below x = 12, where ``log_i0`` switches, and
* ``log_i0(x) = x + 0.5 (log(1 / (2 pi x)) + 1 / (8 x))`` above x = 12: the asymptotic expansion
  log I0 = x - log(2 pi x)/2 + 1/(8x) + ..., with half of its 1/(8x) term (pbrt-v3's ``LogI0``
  has the same expression).

Kappa = 1/v is 11.8, 47.3 and 2.95 for the R, TT and TRT lobes of the default hair
(longitudinal roughness 0.3), so c = kappa cos(theta_i) cos(theta_o) crosses both ranges.

The reproducer shows, with mitsuba, drjit and numpy only:

  A. the integral over the sphere of ``mi.warp.square_to_rough_fiber_pdf`` for those kappas,
     against the same integral with numpy's exact ``np.i0`` (float64) and with a float64 copy of
     the two approximations: Mitsuba's deficit is the approximations' alone;
  B. the hair's own pdf integrated over the sphere at the audit's incident directions, against
     the prediction sum_p P(p) * (integral of lobe p's longitudinal pdf) with P(p) the lobe
     selection probabilities of Hair::attenuation_pdf (computed here in float64): the whole
     deficit of pdf() is the longitudinal lobes' missing mass, and with exact I0 the prediction
     is 1.

Exits 1 while the defect is present (a lobe's integral is more than 1e-3 from 1), 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")

BETA_M = 0.3                               # hair's default longitudinal roughness
V0 = (0.726 * BETA_M + 0.812 * BETA_M ** 2 + 3.7 * BETA_M ** 20) ** 2
V = [V0, 0.25 * V0, 4 * V0, 4 * V0]       # Hair::update, lobes R, TT, TRT, residual
ALPHA = np.radians(2.0)                    # scale_tilt
TILT = [-2 * ALPHA, ALPHA, 4 * ALPHA, 0.0]  # reframe_with_scales, applied to theta_i
ETA = 1.55
SIGMA_A = 1.3 * np.array([0.419, 0.697, 1.37]) + 0.2 * np.array([0.187, 0.4, 1.05])
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])
X, W = np.polynomial.legendre.leggauss(4000)   # nodes in sin(theta_o) on [-1, 1]


def mitsuba_lobe_integral(kappa, theta_i):
    """2 pi x the integral over sin(theta_o) of Mitsuba's fibre pdf (it does not depend on phi)."""
    wo = mi.Vector3f(mi.Float(np.sqrt(1 - X ** 2).astype(np.float32)),
                     mi.Float(X.astype(np.float32)), mi.Float(np.zeros_like(X, np.float32)))
    wi = mi.Vector3f(float(np.cos(theta_i)), float(np.sin(theta_i)), 0.0)
    p = mi.warp.square_to_rough_fiber_pdf(wo, wi, mi.Vector3f(0, 1, 0), float(kappa))
    return 2 * np.pi * float(np.sum(W * np.array(p, dtype=np.float64)))


def i0_series(x):
    k = np.arange(11)
    fact = np.array([np.prod(np.arange(1, j + 1, dtype=np.float64)) for j in k])
    return np.sum((x[:, None] ** 2 / 4) ** k / fact ** 2, axis=1)


def float64_lobe_integral(kappa, theta_i, exact):
    """The same integral in float64, with np.i0 or with Mitsuba's two approximations."""
    c = kappa * np.cos(theta_i) * np.sqrt(1 - X ** 2)
    s = kappa * np.sin(theta_i) * X
    if exact:
        p = np.exp(-s) * np.i0(c) * kappa / (2 * np.sinh(kappa))
    else:
        log_i0 = np.where(c > 12, c + 0.5 * (np.log(1 / (2 * np.pi * c)) + 1 / (8 * c)),
                          np.log(i0_series(c)))
        p = np.where(kappa > 10, np.exp(-s + log_i0 - kappa + 0.6931 + np.log(0.5 * kappa)),
                     np.exp(-s) * np.exp(log_i0) * kappa / (2 * np.sinh(kappa)))
    return float(np.sum(W * p))


def lobe_probabilities(wi):
    """Hair::attenuation_pdf in float64: luminance of A_p, normalised."""
    sin_i, cos_i = wi[1], np.sqrt(1 - wi[1] ** 2)
    gamma_i = np.arccos(np.clip(wi[2] / np.hypot(wi[0], wi[2]), -1, 1)) * (1 if wi[0] < 0 else -1)
    h = np.sin(gamma_i)
    cos_t = np.sqrt(1 - (sin_i / ETA) ** 2)
    sin_gt = h / (np.sqrt(ETA ** 2 - sin_i ** 2) / cos_i)
    t = np.exp(-SIGMA_A * 2 * np.sqrt(1 - sin_gt ** 2) / cos_t)
    c = cos_i * np.sqrt(1 - h ** 2)
    ct = np.sqrt(max(0.0, 1 - (1 - c * c) / ETA ** 2))
    f = 0.5 * (((c - ETA * ct) / (c + ETA * ct)) ** 2 + ((ETA * c - ct) / (ETA * c + ct)) ** 2)
    a = [np.full(3, f), (1 - f) ** 2 * t]
    a.append(a[1] * t * f)
    a.append(a[2] * f * t / (1 - t * f))
    lum = np.array([LUMINANCE @ x for x in a])
    return lum / lum.sum(), np.arcsin(sin_i)


def hair_pdf_integral(bsdf, wi, n_phi=2048):
    """The hair's pdf() over the sphere: Gauss-Legendre in sin(theta_o), uniform in phi_o."""
    x = X[::4]                      # 1000 nodes suffice for the widest lobes here
    w = W[::4] * 4 * (2 / np.sum(W[::4] * 4))
    phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * np.pi
    sx, ph = np.meshgrid(x, phi, indexing="ij")
    cx = np.sqrt(1 - sx ** 2)
    wo = mi.Vector3f(*(mi.Float(a.ravel().astype(np.float32))
                       for a in (cx * np.cos(ph), sx, cx * np.sin(ph))))
    si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wo))
    si.wi = mi.Vector3f(*map(float, wi))
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    p = np.array(bsdf.pdf(mi.BSDFContext(), si, wo), dtype=np.float64).reshape(sx.shape)
    return float(np.sum(w[:, None] * p) * 2 * np.pi / n_phi)


def main():
    bad = False
    print("A. integral of the fibre pdf over the sphere (Mitsuba float32 | float64 with "
          "Mitsuba's I0 approximations | float64 with exact I0)")
    for v, name in zip(V[:3], ("R", "TT", "TRT")):
        for theta in (0.0, 30.0, 60.0):
            t = np.radians(theta)
            got = mitsuba_lobe_integral(1 / v, t)
            approx, exact = (float64_lobe_integral(1 / v, t, e) for e in (False, True))
            flag = abs(got - 1) > 1e-3
            bad |= flag
            print(f"   {name:3s} kappa = {1 / v:6.2f}, theta_i = {theta:4.0f} deg: {got:.5f} | "
                  f"{approx:.5f} | {exact:.6f}{'   <-- defect' if flag else ''}")
    print("B. hair (default) pdf() over the sphere vs sum_p P(p) x lobe p's integral")
    bsdf = mi.load_dict({"type": "hair"})
    for theta in (0.0, 45.0, 80.0):
        t = np.radians(theta)
        wi = np.array([np.sin(t), 0.0, np.cos(t)])       # the audit's incident directions
        prob, theta_i = lobe_probabilities(wi)
        lobes = [mitsuba_lobe_integral(1 / V[p], theta_i + TILT[p]) for p in range(4)]
        exact = [float64_lobe_integral(1 / V[p], theta_i + TILT[p], True) for p in range(4)]
        predicted, fixed = float(prob @ np.array(lobes)), float(prob @ np.array(exact))
        measured = hair_pdf_integral(bsdf, wi)
        print(f"   theta = {theta:2.0f} deg: pdf() integrates to {measured:.5f}; predicted "
              f"{predicted:.5f} (P(p) = {np.round(prob, 4).tolist()}); with exact I0: "
              f"{fixed:.5f}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
