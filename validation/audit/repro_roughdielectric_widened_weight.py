"""
roughdielectric with sample_visible=false: sample() returns weights that are not
eval(bs.wo)/pdf(bs.wo), and its sampled albedo exceeds 1 at grazing incidence.

With sample_visible=false, RoughDielectric::sample() draws microfacet normals from a
*widened* distribution (alpha scaled by 1.2 - 0.2 sqrt|cos theta_i|, Walter et al. 2007,
section 5.3) and bs.pdf / pdf() use that widened density consistently, but the weight is
computed as G(wi, wo, m) (wi.m) / (cos theta_i cos theta_m), which equals f cos theta_o / pdf
only when normals are drawn from the *unwidened* D(m) cos theta_m. The factor D(m)/D'(m)
(D' = the widened distribution) is missing.

The script (mitsuba, drjit, numpy only) prints, for Beckmann and GGX at alpha = 0.3:
  * the relative error between the weight and eval/pdf (should be ~1e-6);
  * that weight * D(m)/D'(m) equals eval/pdf (the missing factor);
  * E(theta) = mean weight in importance transport, which is <= 1 for a dielectric interface
    (reflected + transmitted fraction), with sample_visible=false and =true (must agree), and
    with sample_visible=false's weights multiplied by the missing D(m)/D'(m) (agrees).
Exit status 1 while the defect is present, 0 once fixed.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

for v in ("llvm_ad_rgb", "llvm_rgb", "cuda_ad_rgb", "cuda_rgb"):
    if v in mi.variants():
        mi.set_variant(v)
        break
else:
    sys.exit("needs a JIT (llvm or cuda) RGB variant")

N = 400_000
ETA = 1.5046 / 1.000277          # roughdielectric's default int_ior / ext_ior


def sample(bsdf, theta_deg, mode, seed):
    rng = np.random.default_rng(seed)
    t = np.radians(theta_deg)
    si = dr.zeros(mi.SurfaceInteraction3f, N)
    si.wi = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
    ctx = mi.BSDFContext(mode)
    u1 = mi.Float(rng.random(N).astype(np.float32))
    u2 = mi.Point2f(rng.random((2, N)).astype(np.float32))
    bs, w = bsdf.sample(ctx, si, u1, u2)
    val, pdf = bsdf.eval_pdf(ctx, si, bs.wo)
    return (np.array(w)[0].astype(np.float64), np.array(val)[0].astype(np.float64),
            np.array(pdf, np.float64), np.array(bs.wo, np.float64).T, float(np.cos(t)),
            float(np.sin(t)))


def load(kind, visible):
    return mi.load_dict({"type": "roughdielectric", "distribution": kind, "alpha": 0.3,
                         "sample_visible": visible})


def missing_factor(T, wo, ci, si_):
    """D(m)/D'(m) at the (generalised) half vector m of each sample (wi = (sin, 0, cos))."""
    wi = np.array([si_, 0.0, ci])
    refl = wo[:, 2] > 0
    m = wi[None, :] + wo * np.where(refl, 1.0, ETA)[:, None]
    m /= np.linalg.norm(m, axis=1, keepdims=True)
    m *= np.sign(m[:, 2:3])
    d = mi.MicrofacetDistribution(T, 0.3, False)
    dw = mi.MicrofacetDistribution(T, 0.3, False)
    dw.scale_alpha(mi.Float(1.2) - 0.2 * dr.sqrt(mi.Float(np.float32(ci))))
    M = mi.Vector3f(m.T.astype(np.float32))
    with np.errstate(all="ignore"):
        f = np.array(d.eval(M), np.float64) / np.array(dw.eval(M), np.float64)
    return np.where(np.isfinite(f), f, 0.0)


failed = False
for kind in ("beckmann", "ggx"):
    T = mi.MicrofacetType.Beckmann if kind == "beckmann" else mi.MicrofacetType.GGX
    # 1) weight against eval/pdf at theta_i = 60 deg (radiance transport, the default)
    w, val, pdf, wo, ci, si_ = sample(load(kind, False), 60.0, mi.TransportMode.Radiance, 1)
    ok = (w > 0) & (pdf > 0)
    ratio = val[ok] / pdf[ok]
    rel = np.abs(w[ok] - ratio) / ratio
    rel_fixed = np.abs(w[ok] * missing_factor(T, wo[ok], ci, si_) - ratio) / ratio
    print(f"{kind}, alpha 0.3, sample_visible=false, theta_i = 60 deg: |weight - eval/pdf| / "
          f"(eval/pdf): median {np.median(rel):.3g}, max {rel.max():.3g}; "
          f"with weight * D(m)/D'(m): median {np.median(rel_fixed):.2g}")
    failed |= bool(np.median(rel) > 1e-3)

    # 2) sampled albedo in importance transport (fraction of energy scattered, <= 1)
    for theta in (60.0, 87.0, 89.0):
        e = {}
        for visible in (False, True):
            w, _, _, wo, ci, si_ = sample(load(kind, visible), theta, mi.TransportMode.Importance, 2)
            e[visible] = (w.mean(), w.std() / np.sqrt(N))
            if not visible:
                wf = w * missing_factor(T, wo, ci, si_)
                e["fixed"] = (wf.mean(), wf.std() / np.sqrt(N))
        diff = e[False][0] - e[True][0]
        sig = np.hypot(e[False][1], e[True][1])
        gain = e[False][0] - 1.0
        print(f"   theta_i = {theta:4.1f} deg, importance transport: E from sample() = "
              f"{e[False][0]:.4f} +- {e[False][1]:.4f} (sample_visible=false) vs "
              f"{e[True][0]:.4f} +- {e[True][1]:.4f} (sample_visible=true): "
              f"difference {diff:+.4f} = {diff / sig:+.1f} sigma"
              + ("  [> 1: creates energy]" if gain > 5 * e[False][1] else "")
              + f"; false with D/D' restored: {e['fixed'][0]:.4f} +- {e['fixed'][1]:.4f}")
        failed |= bool(abs(diff) > 6 * sig) or bool(gain > 5 * e[False][1])

print("DEFECT PRESENT" if failed else "ok: weights equal eval/pdf and both samplers agree")
sys.exit(1 if failed else 0)
