"""
Reproducer: ``hair``'s ``sample()`` puts every sample of the residual lobe p >= P_MAX (= 3) in
the fibre's normal plane (``wo.y == 0`` exactly), while ``pdf()`` and ``eval()`` spread that lobe
over the longitudinal distribution M_3 (Mitsuba 3.9.1, ``src/bsdfs/hair.cpp``, ``Hair::sample``).

``Hair::sample`` initialises ``sin_theta_ip = cos_theta_ip = 0`` and fills them only for
``p < P_MAX`` (loop ``for (size_t j = 0; j < P_MAX; j++)``, lines 264-272). For ``p == P_MAX``
both stay 0, so ``sin_theta_o = -cos_theta * sin_theta_ip + sin_theta * cos_phi * cos_theta_ip``
(line 287) is exactly 0. pbrt-v3 (``HairBSDF::Sample_f``) and Mitsuba's own ``eval()``/``pdf()``
use the untilted incident angle for p = P_MAX (``reframe_with_scales``' ``default`` case).

The reproducer measures, at several incident directions (the fibre runs along local +y):
  A. the fraction of successful samples with wo.y == 0 exactly, against the probability that
     pdf() gives to the band |wo.y| < 1e-6 (~2e-6 x the integral of pdf over the circle y = 0);
  B. Mitsuba's own chi2 harness (mitsuba.chi2, res 101/201) at wi = (0.995, 0, 0.0995) -- the
     fibre seen near its silhouette (h ~ -1), where the residual lobe carries 0.26 % of the samples
     for the default (brown) hair.
Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
from mitsuba.chi2 import ChiSquareTest, SphericalDomain  # noqa: E402

CONFIGS = [{"type": "hair"},                                              # brown (default)
           {"type": "hair", "eumelanin": 0.2, "pheomelanin": 0.4}]        # the docs' blonde
WIS = [(0.0, 0.0, 1.0), (0.7071068, 0.0, 0.7071068), (0.995037, 0.0, 0.0995037),
       (0.6, 0.6, 0.5291503)]
EPS = 1e-6


def interaction(wi, n):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f([float(x) for x in wi])
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def band_probability(bsdf, wi, eps=EPS, m=20_000):
    """P(|wo.y| < eps) under pdf(): 2 eps x integral over phi of pdf on the circle wo.y = 0
    (solid angle = d(wo.y) d(phi) around the fibre axis y)."""
    phi = (np.arange(m) + 0.5) / m * 2 * np.pi
    wo = mi.Vector3f(mi.Float(np.cos(phi).astype(np.float32)), mi.Float(np.zeros(m, np.float32)),
                     mi.Float(np.sin(phi).astype(np.float32)))
    p = np.array(bsdf.pdf(mi.BSDFContext(), interaction(wi, m), wo), dtype=np.float64)
    return 2 * eps * p.mean() * 2 * np.pi


def main():
    bad = False
    rng = np.random.default_rng(0)
    n = 1_000_000
    print("A. samples exactly on the circle wo.y = 0 vs. what pdf() gives a band |wo.y| < 1e-6")
    for cfg in CONFIGS:
        bsdf = mi.load_dict(cfg)
        for wi in WIS:
            u = rng.random((n, 3), dtype=np.float32)
            bs, w = bsdf.sample(mi.BSDFContext(), interaction(wi, n), mi.Float(u[:, 0]),
                                mi.Point2f(mi.Float(u[:, 1]), mi.Float(u[:, 2])))
            ok = np.array(mi.unpolarized_spectrum(w))[0] > 0
            y = np.array(bs.wo.y)[ok]
            frac = float(np.mean(y == 0.0))
            expect = band_probability(bsdf, wi)
            flag = frac > 10 * expect + 5 / n
            bad |= flag
            name = "brown" if len(cfg) == 1 else "blonde"
            print(f"   {name:6s} wi = {tuple(round(x, 3) for x in wi)}: {frac:.5f} of the samples "
                  f"have wo.y == 0; pdf() gives |wo.y| < 1e-6 a probability {expect:.1e}"
                  f"{'   <-- defect' if flag else ''}")

    print("B. mitsuba.chi2 at wi = (0.995, 0, 0.0995), default hair")
    bsdf = mi.load_dict(CONFIGS[0])
    wi = (0.995037, 0.0, 0.0995037)

    def sample_func(s):
        bs, w = bsdf.sample(mi.BSDFContext(), interaction(wi, dr.width(s)), s[0],
                            mi.Point2f(s[1], s[2]))
        ok = dr.any(mi.unpolarized_spectrum(w) != 0)
        return dr.select(ok, bs.wo, mi.Vector3f(0, 0, 1)), dr.select(ok, mi.Float(1), mi.Float(0))

    def pdf_func(wo):
        return bsdf.pdf(mi.BSDFContext(), interaction(wi, dr.width(wo)), wo)

    for res, ires in ((101, 4), (201, 16)):
        for seed in (0, 1):
            t = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                              pdf_func=pdf_func, sample_dim=3, sample_count=1_000_000,
                              res=res, ires=ires, seed=seed)
            passed = t.run(significance_level=0.01, quiet=True)
            bad |= not passed
            print(f"   res {res}, ires {ires}, seed {seed}: p = {t.p_value:.3g} "
                  f"{'passed' if passed else 'REJECTED'}")
    print("DEFECT PRESENT" if bad else "ok")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
