"""
Reproducer: ``roughplastic``'s ``pdf()`` / ``eval_pdf()`` are not masked to the hemisphere in
vectorized (JIT) variants (Mitsuba 3.9.1, ``src/bsdfs/roughplastic.cpp``).

``RoughPlastic::pdf`` computes ``active &= cos_theta_i > 0 && cos_theta_o > 0`` but returns
``result`` without ``dr::select(active, result, 0.f)`` (``roughconductor`` does mask). The early
``return 0.f`` only fires when *no* lane is active, i.e. in scalar variants. In llvm/cuda variants:

  A. for ``wo`` below the horizon, ``pdf()`` returns the full specular (visible-normal) density
     -- not even weighted by the specular sampling probability, because ``t_i`` is gathered with
     the mask ``active`` (which includes ``cos_theta_o > 0``), reads 0, and makes
     ``prob_specular = 1``;
  B. so ``pdf()`` integrates to more than 1 over the sphere (1.178 for GGX α = 0.5 at normal
     incidence), while only 0.978 of the samples succeed: Mitsuba's own χ² harness refuses the
     BSDF ("PDF integrates to a value greater than 1.0");
  C. at ``cos_theta_i = 0`` (``wi`` on the horizon) ``pdf()`` divides by ``4 * cos_theta_i`` = 0
     and returns NaN (scalar variant, ``roughconductor``, ``plastic``, ``diffuse``: 0).

Uses only mitsuba, drjit and numpy. Exits 1 while the defect is present, 0 once fixed.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

CONFIG = {"type": "roughplastic", "distribution": "ggx", "alpha": 0.5}


def interaction(wi, n):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f([float(x) for x in wi])
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    return si


def pdf_at(bsdf, wi, wo):
    """pdf() and eval_pdf()'s pdf at one (wi, wo) pair, evaluated alone (one lane)."""
    si, wo = interaction(wi, 1), mi.Vector3f([float(x) for x in wo])
    ctx = mi.BSDFContext()
    return (float(bsdf.pdf(ctx, si, wo)[0]), float(bsdf.eval_pdf(ctx, si, wo)[1][0]),
            float(mi.unpolarized_spectrum(bsdf.eval(ctx, si, wo)).x[0]))


def main():
    bad = False
    below = np.array([1.0, 0.0, -0.05]) / np.linalg.norm([1.0, 0.0, -0.05])  # θo = 92.9°
    tangent = np.array([1.0, 0.0, 0.0])

    mi.set_variant("scalar_rgb")
    b = mi.load_dict(CONFIG)
    ctx, si = mi.BSDFContext(), mi.SurfaceInteraction3f()
    si.n, si.sh_frame, si.wi = [0, 0, 1], mi.Frame3f([0, 0, 1]), [0, 0, 1]
    scalar_below = b.pdf(ctx, si, below)
    si.wi = tangent
    scalar_tangent = b.pdf(ctx, si, tangent)
    print(f"scalar_rgb : pdf(wi=n, wo below horizon) = {scalar_below}, "
          f"pdf(wi=wo on the horizon) = {scalar_tangent}   (the intended 0)")

    mi.set_variant("llvm_ad_rgb")
    b = mi.load_dict(CONFIG)
    rc = mi.load_dict({"type": "roughconductor", "distribution": "ggx", "alpha": 0.5})

    # A. a direction below the horizon
    p, pe, e = pdf_at(b, (0, 0, 1), below)
    print(f"[A] llvm_ad_rgb, wi = n, wo = {np.round(below, 4)} (below the horizon): "
          f"pdf = {p:.6g}, eval_pdf.pdf = {pe:.6g}, eval = {e:.3g}; "
          f"roughconductor pdf = {pdf_at(rc, (0, 0, 1), below)[0]:.3g}  (expected 0)")
    bad |= p != 0.0 or pe != 0.0

    # B. integral of pdf() over the sphere vs the fraction of samples that succeed
    n = 1500
    z = (np.arange(n) + 0.5) / n * 2 - 1
    phi = (np.arange(n) + 0.5) / n * 2 * np.pi
    Z, P = np.meshgrid(z, phi)
    r = np.sqrt(1 - Z ** 2)
    wo = mi.Vector3f(*(np.ravel(a).astype(np.float32) for a in (r * np.cos(P), r * np.sin(P), Z)))
    pdf = np.array(b.pdf(mi.BSDFContext(), interaction((0, 0, 1), n * n), wo), dtype=np.float64)
    cell = (2.0 / n) * (2 * np.pi / n)
    upper, lower = pdf[Z.ravel() > 0].sum() * cell, pdf[Z.ravel() < 0].sum() * cell
    m = 1_000_000
    rng = np.random.default_rng(0)
    s1, s2 = rng.random(m).astype(np.float32), rng.random((2, m)).astype(np.float32)
    bs, w = b.sample(mi.BSDFContext(), interaction((0, 0, 1), m), mi.Float(s1), mi.Point2f(s2))
    ok = np.array(dr.any(mi.unpolarized_spectrum(w) != 0))
    spec = np.array(bs.sampled_component) == 0
    print(f"[B] GGX α=0.5, wi = n: ∫pdf over the sphere = {upper + lower:.4f} "
          f"(upper hemisphere {upper:.4f}, lower {lower:.4f}); "
          f"samples with weight > 0: {ok.mean():.4f}; specular samples {spec.mean():.4f}, "
          f"of which {(~ok & spec).sum() / max(spec.sum(), 1):.4f} fail below the horizon "
          f"(expected: ∫pdf = {ok.mean():.4f}, lower hemisphere 0)")
    bad |= upper + lower > 1.0 + 1e-3 or lower > 1e-6

    # C. wi on the horizon (cos θi = 0)
    p, pe, e = pdf_at(b, tangent, tangent)
    p2 = pdf_at(b, tangent, (0, 0, 1))[0]
    print(f"[C] wi = (1, 0, 0) (cos θi = 0): pdf(wo = wi) = {p}, eval_pdf.pdf = {pe}, "
          f"pdf(wo = n) = {p2}, eval = {e}; roughconductor pdf = "
          f"{pdf_at(rc, tangent, tangent)[0]}  (expected 0)")
    bad |= not (np.isfinite(p) and np.isfinite(pe) and np.isfinite(p2) and p == 0 and p2 == 0)

    print("DEFECT PRESENT" if bad else "fixed: pdf() is 0 outside the hemisphere")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
