"""
Conditioning check: ``pplastic``'s asymmetry f(a, b) != f(b, a) in polarized variants (max 0.06
at theta = 89.9 deg in the audit) is float32 rounding, not a non-reciprocal model.

The model (Baek et al. 2018, "Simultaneous Acquisition of Polarimetric SVBRDF and Normals",
ACM TOG 37(6), §4, Eq. 4-6: a microfacet specular Mueller matrix plus a depolarized diffuse
term between two Fresnel transmissions, as Mitsuba's pplastic documents it) is reciprocal in
intensity (the M00 element): the specular part is F(wi.h) D G / (4 cos_i cos_o) with a
symmetric G, and the diffuse part is rho/pi * T(theta_i) T(theta_o), because the power
transmittance through an interface is the same in both directions (T_out(theta) =
T_in(theta_t), Stokes relations).

Mitsuba (src/bsdfs/pplastic.cpp, PolarizedPlastic::eval, polarized branch) computes the exit
transmission Ti = mueller::specular_transmission(|cos theta_t|, 1/eta) from the INTERNAL cosine
cos theta_t of the camera-side direction (the light-side To uses the external cosine). Near
grazing, T ~ k cos(theta) while cos(theta_t) = sqrt(1 - (1 - cos^2)/eta^2) depends on
cos^2(theta) only through a term 2e-7 of its float32 rounding: one ulp of cos theta_t moves
cos^2 theta by ~2 eta^2 cos_t eps ~ 1.3e-7, i.e. a relative error ~ 3e-8 / cos^2(theta) on T.
At cos = 1.7e-3 (89.9 deg) that is several percent -- on one of the two orders only, hence the
asymmetry. The unpolarized variants use (1 - F(cos_i))(1 - F(cos_o)) and are symmetric to 1e-7.

This script: (1) measures the asymmetry of Mitsuba's polarized pplastic per bin of the smaller
cosine, (2) compares each order with a float64 evaluation of the model at the same float32
directions, (3) shows the error follows eps32 / cos^2. Uses mitsuba, drjit and numpy.
Exits 0 when the asymmetry is explained by conditioning (float64 model reciprocal, error of the
error within 20 eps32 (1/cos_wi^2 + 1/cos_wo)), else 1.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

ETA = 1.49 / 1.000277     # pplastic default: polypropylene / air
RHO = 0.5
EPS32 = 2.0 ** -24


def fresnel_R(c, eta):
    s2t = (1 - c * c) / eta ** 2
    ct = np.sqrt(np.maximum(0.0, 1 - s2t))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def diffuse_f64(ci, co):
    """The model's diffuse f (not times cos), float64: rho/pi (1 - R(ci)) (1 - R(co))."""
    return RHO / np.pi * (1 - fresnel_R(ci, ETA)) * (1 - fresnel_R(co, ETA))


def main():
    mi.set_variant("llvm_ad_spectral_polarized")
    bsdf = mi.load_dict({"type": "pplastic"})
    rng = np.random.default_rng(1)
    n = 400_000

    def dirs(k):
        # cos theta log-uniform in [1e-3, 1] to probe grazing angles densely
        z = 10 ** rng.uniform(-3, 0, k)
        p = rng.uniform(0, 2 * np.pi, k)
        s = np.sqrt(1 - z * z)
        return np.stack([s * np.cos(p), s * np.sin(p), z], 1).astype(np.float32)

    a, b = dirs(n), dirs(n)

    def f(wi, wo, component):
        ctx = mi.BSDFContext()
        if component is not None:
            ctx.component = component
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(*[mi.Float(wi[:, k]) for k in range(3)])
        si.n = mi.Vector3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        si.wavelengths = mi.UnpolarizedSpectrum(550.0)   # pplastic's parameters are constant in wavelength
        v = mi.unpolarized_spectrum(bsdf.eval(ctx, si, mi.Vector3f(*[mi.Float(wo[:, k])
                                                                     for k in range(3)])))
        return np.array(v)[0].astype(np.float64) / wo[:, 2].astype(np.float64)

    ok = True
    cmin = np.minimum(a[:, 2], b[:, 2]).astype(np.float64)
    bins = [1e-3, 3e-3, 1e-2, 3e-2, 1e-1, 1.0]
    for comp, name in ((None, "whole BSDF"), (0, "specular (component 0)"),
                       (1, "diffuse (component 1)")):
        fab, fba = f(a, b, comp), f(b, a, comp)
        scale = np.maximum(np.abs(fab), np.abs(fba))
        asym = np.where(scale > 0, np.abs(fab - fba) / np.where(scale > 0, scale, 1), 0)
        print(f"{name}: max relative asymmetry per bin of min(cos a, cos b):")
        for lo, hi in zip(bins[:-1], bins[1:]):
            m = (cmin >= lo) & (cmin < hi)
            bound = 20 * EPS32 / lo ** 2
            print(f"   cos in [{lo:g}, {hi:g}): max asym {asym[m].max():.2e}   "
                  f"(20 eps32/cos^2 = {min(bound, 1):.1e})")
        if comp == 0:
            # the specular part is reciprocal up to float32 rounding of the grazing cosine
            ok &= bool(np.all(asym <= np.maximum(1e-4, 20 * EPS32 / cmin)))
        if comp == 1:
            ref = diffuse_f64(a[:, 2].astype(np.float64), b[:, 2].astype(np.float64))
            err_ab = np.abs(fab - ref) / ref  # f(a, b): wi = a is the camera side
            err_ba = np.abs(fba - ref) / ref  # f(b, a): wi = b
            ca = a[:, 2].astype(np.float64)
            cb = b[:, 2].astype(np.float64)
            err = np.concatenate([err_ab, err_ba])
            c_wi, c_wo = np.concatenate([ca, cb]), np.concatenate([cb, ca])
            print("   diffuse vs float64 model at the same float32 directions (both orders):")
            for lo, hi in zip(bins[:-1], bins[1:]):
                m1 = (c_wi >= lo) & (c_wi < hi) & (c_wo > 0.1)
                m2 = (c_wo >= lo) & (c_wo < hi) & (c_wi > 0.1)
                print(f"   cos in [{lo:g}, {hi:g}): max rel. error with wi there (wo > 0.1) "
                      f"{err[m1].max():.2e}; with wo there (wi > 0.1) {err[m2].max():.2e}")
            # Ti from the internal cosine of wi: eps/cos_wi^2; To from the external cosine of wo:
            # eps/cos_wo (T ~ k cos near grazing)
            ratio = err / (EPS32 * (1 / c_wi ** 2 + 1 / c_wo))
            print(f"   max of error / (eps32 (1/cos_wi^2 + 1/cos_wo)): {ratio.max():.2f}")
            ok &= ratio.max() < 20
            # the float64 model is reciprocal by construction: diffuse_f64(a, b) == diffuse_f64(b, a)
            ok &= np.allclose(diffuse_f64(ca, cb), diffuse_f64(cb, ca), rtol=1e-14, atol=0)
    print("asymmetry explained by float32 conditioning of the internal cosine"
          if ok else "NOT explained by conditioning")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
