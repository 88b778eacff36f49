"""
bs.pdf against pdf(bs.wo) for Mitsuba's roughdielectric and roughconductor, decomposed with a
float64 evaluation of the same pdf (the formulas of src/bsdfs/roughdielectric.cpp pdf(),
src/bsdfs/roughconductor.cpp pdf() and include/mitsuba/render/microfacet.h at v3.9.1):

  a) bs.pdf        vs p64(wo*):  wo* = the exact (float64) reflection/refraction of wi about the
                                 float32 microfacet normal m that sample() drew -- sample()'s
                                 own float32 arithmetic;
  b) pdf(bs.wo)    vs p64(bs.wo): pdf()'s float32 arithmetic at the float32 direction;
  c) p64(wo*)      vs p64(bs.wo): the exact model at two directions that differ only by the
                                 rounding of wo to float32 -- the conditioning of the pdf;
  d) bs.pdf        vs pdf(bs.wo): what a consistency check measures (≈ a + b + c);
  e) (c) with wi, wo* and bs.wo renormalised to unit length in float64: how much of (c) is the
     formulas' sensitivity to the lengths of float32 directions (|v| − 1 ~ 1e-8).

and the componentwise condition number of log p over its six float inputs (wi, wo),
κ = Σ_k |x_k ∂log p64/∂x_k| (rounding a coordinate to float32 perturbs it by ≤ u|x_k|, the
length of a direction included), u = 2^-24. It also counts samples with weight > 0 and a
negative/NaN bs.pdf.

Only mitsuba, drjit and numpy. Prints a table; exits 0 (it is a measurement, not a test).
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
U = 2.0 ** -24
COMPONENTWISE = False    # κ normwise: every coordinate perturbed by u (absolute)
ETA = 1.5046 / 1.000277          # roughdielectric's default int_ior (bk7) / ext_ior (air)


# ---------------------------------------------------------------- float64 model (Mitsuba's)
def D64(kind, a, m):
    c2 = m[:, 2] ** 2
    with np.errstate(all="ignore"):
        if kind == "beckmann":
            d = np.exp(-(m[:, 0] ** 2 + m[:, 1] ** 2) / a ** 2 / c2) / (np.pi * a * a * c2 * c2)
        else:
            d = 1 / (np.pi * a * a * ((m[:, 0] ** 2 + m[:, 1] ** 2) / a ** 2 + c2) ** 2)
    return np.where(d * m[:, 2] > 1e-20, d, 0.0)


def G1_64(kind, a, v, m):
    xy = a * a * (v[:, 0] ** 2 + v[:, 1] ** 2)
    with np.errstate(all="ignore"):
        t = xy / v[:, 2] ** 2
        if kind == "beckmann":
            s = 1 / np.sqrt(t)
            g = np.where(s >= 1.6, 1.0, (3.535 * s + 2.181 * s * s) / (1 + 2.276 * s + 2.577 * s * s))
        else:
            g = 2 / (1 + np.sqrt(1 + t))
    g = np.where(xy == 0, 1.0, g)
    return np.where(np.einsum("ij,ij->i", v, m) * v[:, 2] <= 0, 0.0, g)


def fresnel64(c, eta):
    """Mitsuba's fresnel(cos_theta_i, eta)[0] for a real relative index (signed cosine)."""
    e = np.where(c >= 0, eta, 1 / eta)
    c = np.abs(c)
    s2t = (1 - c * c) / (e * e)
    with np.errstate(all="ignore"):
        ct = np.sqrt(np.maximum(1 - s2t, 0))
        rs = (c - e * ct) / (c + e * ct)
        rp = (e * c - ct) / (e * c + ct)
        f = 0.5 * (rs * rs + rp * rp)
    return np.where(s2t >= 1, 1.0, f)


def pdf_m64(kind, a, visible, wi, m):
    if visible:
        return D64(kind, a, m) * G1_64(kind, a, wi, m) * np.abs(np.einsum("ij,ij->i", wi, m)) / wi[:, 2]
    return D64(kind, a, m) * m[:, 2]


def pdf_rd64(kind, a, visible, wi, wo):
    ci, co = wi[:, 2], wo[:, 2]
    refl = ci * co > 0
    eta = np.where(ci > 0, ETA, 1 / ETA)
    m = wi + wo * np.where(refl, 1.0, eta)[:, None]
    with np.errstate(all="ignore"):
        m = m / np.linalg.norm(m, axis=1, keepdims=True)
        m = m * np.sign(m[:, 2:3])
        im, om = np.einsum("ij,ij->i", wi, m), np.einsum("ij,ij->i", wo, m)
        ok = (ci != 0) & (im * ci > 0) & (om * co > 0)
        jac = np.where(refl, 1 / (4 * om), eta * eta * om / (im + eta * om) ** 2)
        a_s = a if visible else a * (1.2 - 0.2 * np.sqrt(np.abs(ci)))
        wis = wi * np.sign(ci)[:, None]
        p = pdf_m64(kind, a_s, visible, wis, m)
        f = fresnel64(im, ETA)
        p = p * np.where(refl, f, 1 - f) * np.abs(jac)
    return np.where(ok, p, 0.0)


def pdf_rc64(kind, a, visible, wi, wo):
    with np.errstate(all="ignore"):
        m = wi + wo
        m = m / np.linalg.norm(m, axis=1, keepdims=True)
        im, om = np.einsum("ij,ij->i", wi, m), np.einsum("ij,ij->i", wo, m)
        ok = (wi[:, 2] > 0) & (wo[:, 2] > 0) & (im > 0) & (om > 0)
        if visible:
            p = D64(kind, a, m) * G1_64(kind, a, wi, m) / (4 * wi[:, 2])
        else:
            p = D64(kind, a, m) * m[:, 2] / (4 * om)
    return np.where(ok, p, 0.0)


def cond_log(f, wi, wo, h=1e-9):
    """Componentwise condition number of log p(wi, wo) over its six float inputs:
    sum_k |x_k · d log p / d x_k| (central differences in float64, no renormalisation: float32
    rounding perturbs every coordinate independently, so the length of a direction too)."""
    k = 0
    for which in (0, 1):
        for c in range(3):
            a, b = wi.copy(), wo.copy()
            x = a if which == 0 else b
            step = np.zeros_like(x)
            step[:, c] = h
            with np.errstate(all="ignore"):
                if which == 0:
                    g = (np.log(f(a + step, b)) - np.log(f(a - step, b))) / (2 * h)
                else:
                    g = (np.log(f(a, b + step)) - np.log(f(a, b - step))) / (2 * h)
            k = k + np.abs(g) * (np.abs(x[:, c]) if COMPONENTWISE else 1.0)
    return k


# ---------------------------------------------------------------- float32 Mitsuba side
def directions(rng, n):
    """The consistency check's incident set: uniform hemisphere, plus near-grazing ones."""
    z = rng.random(n)
    z[: n // 10] = 10 ** rng.uniform(-4, -1.5, n // 10)        # cosθi in [1e-4, 3e-2]
    phi = 2 * np.pi * rng.random(n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], 1).astype(np.float32)


def study(plugin, kind, alpha, visible, n=200_000, seed=0, side=1):
    rng = np.random.default_rng(seed)
    wi = directions(rng, n)
    wi[:, 2] *= side
    u1 = rng.random(n).astype(np.float32)
    u2 = rng.random((n, 2)).astype(np.float32)
    bsdf = mi.load_dict({"type": plugin, "distribution": kind, "alpha": alpha,
                         "sample_visible": visible})
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(wi.T)
    ctx = mi.BSDFContext()
    bs, w = bsdf.sample(ctx, si, mi.Float(u1), mi.Point2f(u2.T))
    pdf = np.array(bsdf.pdf(ctx, si, bs.wo), np.float64)
    wo = np.array(bs.wo, np.float64).T
    bp = np.array(bs.pdf, np.float64)
    w = np.array(w, np.float64)[0]
    comp = np.array(bs.sampled_component)

    # the float32 microfacet normal sample() drew (same code, same inputs)
    T = mi.MicrofacetType.Beckmann if kind == "beckmann" else mi.MicrofacetType.GGX
    d = mi.MicrofacetDistribution(T, alpha, visible)
    wis = mi.Vector3f(wi.T)
    if plugin == "roughdielectric":
        if not visible:
            d.scale_alpha(1.2 - 0.2 * dr.sqrt(dr.abs(wis.z)))
        wis = dr.mulsign(wis, wis.z)
    m32 = np.array(d.sample(wis, mi.Point2f(u2.T))[0], np.float64).T

    wi64 = wi.astype(np.float64)
    im = np.einsum("ij,ij->i", wi64, m32)
    refl = comp == 0
    eta = np.where(wi64[:, 2] > 0, ETA, 1 / ETA)          # eta_ti = 1/eta
    wo_r = 2 * im[:, None] * m32 - wi64
    e_ti = 1 / eta
    with np.errstate(all="ignore"):
        ct = -np.sign(im) * np.sqrt(np.maximum(1 - e_ti ** 2 * (1 - im ** 2), 0))
    wo_t = m32 * (im * e_ti + ct)[:, None] - wi64 * e_ti[:, None]
    wo_x = np.where(refl[:, None], wo_r, wo_t)

    if plugin == "roughdielectric":
        f = lambda a, b: pdf_rd64(kind, alpha, visible, a, b)
    else:
        f = lambda a, b: pdf_rc64(kind, alpha, visible, a, b)
    p_x, p_32 = f(wi64, wo_x), f(wi64, wo)

    good = (w > 0) & np.isfinite(bp) & (bp > 0) & (p_x > 0) & (p_32 > 0)
    same_m = np.abs(wo_x - wo).max(1) < 1e-5
    bad = (w > 0) & (~np.isfinite(bp) | (bp < 0))
    neg_failed = (w == 0) & (bp < 0)
    r = lambda a, b: np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
    sel = good & same_m
    A, B, C, Dd = r(bp, p_x)[sel], r(pdf, p_32)[sel], r(p_x, p_32)[sel], r(bp, pdf)[sel]
    kappa = cond_log(f, wi64[sel], wo[sel])
    nz = lambda v: v / np.linalg.norm(v, axis=1, keepdims=True)
    E = r(f(nz(wi64[sel]), nz(wo_x[sel])), f(nz(wi64[sel]), nz(wo[sel])))
    i = int(np.argmax(Dd))
    print(f"{plugin:15s} {kind:8s} α={alpha:<4} visible={visible!s:5s} side={side:+d}: "
          f"{int(sel.sum())} samples ({int((good & ~same_m).sum())} m mismatches); "
          f"weight>0 with pdf<0/NaN: {int(bad.sum())}; pdf<0 with weight 0: {int(neg_failed.sum())}")
    print(f"    max rel: (a) bs.pdf vs p64(wo*) {A.max():.2e}  (b) pdf(wo) vs p64(wo) {B.max():.2e}"
          f"  (c) p64(wo*) vs p64(wo) {C.max():.2e}  (d) bs.pdf vs pdf(wo) {Dd.max():.2e}"
          f"  [(d) > 1e-3: {int((Dd > 1e-3).sum())}]  (e) renormalised: max {np.nanmax(E):.2e}"
          f" where (d) > 1e-3: {np.nanmax(E[Dd > 1e-3], initial=0):.2e}")
    print(f"    worst (d): cosθi={wi[sel][i, 2]:.2e} (d)={Dd[i]:.2e} (a)={A[i]:.1e} (b)={B[i]:.1e} "
          f"(c)={C[i]:.2e}; κ = {kappa[i]:.3g}, κu = {kappa[i] * U:.2e}")
    ratio = Dd / np.maximum(kappa * U, 1e-300)
    tol = np.maximum(1e-3, 16 * kappa * U)
    print(f"    (d)/(κu): 99.99th pct {np.percentile(ratio, 99.99):.2f}, max {ratio.max():.2f};"
          f" (d) > max(1e-3, 16κu): {int((Dd > tol).sum())}")
    return int((Dd > tol).sum()), int(bad.sum())


if __name__ == "__main__":
    rows = [("roughdielectric", k, 0.05, True) for k in ("beckmann", "ggx")] + \
           [("roughdielectric", k, 0.3, True) for k in ("beckmann", "ggx")] + \
           [("roughdielectric", k, 0.3, False) for k in ("beckmann", "ggx")] + \
           [("roughconductor", k, 0.05, True) for k in ("beckmann", "ggx")] + \
           [("roughconductor", k, 0.3, False) for k in ("beckmann", "ggx")]
    for row in rows:
        sides = (1, -1) if row[0] == "roughdielectric" else (1,)
        for s in sides:
            study(*row, side=s, seed=int(sys.argv[1]) if len(sys.argv) > 1 else 0)
