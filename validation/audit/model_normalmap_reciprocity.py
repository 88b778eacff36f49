"""
normalmap is not reciprocal, by construction: a float64 implementation of the model, and the
asymmetry it predicts, against Mitsuba 3.9.1's ``normalmap`` (``src/bsdfs/normalmap.cpp``).

The model (``NormalMap::eval``, ``frame``; ``normalmap_helpers.h``):

* shading normal n from the map (2·t − 1), *mirrored* (−nx, −ny, nz) when ωi lies on its back side
  (``flip_invalid_normals``): the frame depends on ωi;
* the nested BSDF evaluated in the frame of n: its value f_n(ωi', ωo')·cosθo', where θo' is measured
  from n, not from the geometric normal: Veach (1997), "Robust Monte Carlo Methods for Light
  Transport Simulation", §5.3 (shading normals make a BSDF non-reciprocal: the adjoint BSDF with
  shading normals carries the factor |ωi·Ns||ωo·Ng| / (|ωi·Ng||ωo·Ns|));
* zero unless cosθo and cosθo' have the same sign;
* times the shadowing term of Conty Estevez, Lecocq and Stein (2019), "A Microfacet-Based Shadowing
  Function to Solve the Bump Terminator Problem", Ray Tracing Gems ch. 12, applied to ωo only:
  2 / (1 + sqrt(1 + α² tan²θo)), α² = min(tan²θn / 8, 1).

The nested BSDFs: Lambert (ρ/π), and the Beckmann microfacet conductor of Walter et al. (2007),
"Microfacet Models for Refraction through Rough Surfaces", eq. 20, with the Beckmann D in its
anisotropic form (Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based
BRDFs", JCGT 3(2)) and Walter's rational approximation of the Smith G1 (eq. 27), F = 1 (η = 0,
k = 1).

The reciprocity check takes f(a, b) = eval(wi=a, wo=b) / cosθ_b, with the *geometric* cosine. This
script shows that (1) the float64 model reproduces Mitsuba's f(a, b) and f(b, a) at every pair,
so the asymmetry is the model's; (2) the nested BSDFs are reciprocal in the shading frame, and where
both orders use the same frame and neither is masked, f(a, b) / f(b, a) equals Veach's factor
[cosθ'_b / cosθ_b · S(b)] / [cosθ'_a / cosθ_a · S(a)] exactly (to float32 rounding); (3) the
other asymmetric pairs are those where the frame flip or the one-sided mask differs between the
two orders. Exit status 0 when all three hold.

Uses mitsuba and numpy only.
"""

import sys

import drjit as dr
import mitsuba as mi
import numpy as np

RHO, AU, AV = 0.5, 0.05, 0.3


def normal_map_data(n=16):
    """The audit's 16×16 normal map (mi_brdfs/audit/build.py), encoded as n·0.5 + 0.5."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, 2 * np.pi, n))
    nx, ny = 0.5 * np.sin(u), 0.5 * np.cos(v)
    nz = np.ones_like(nx)
    norm = np.sqrt(nx ** 2 + ny ** 2 + nz ** 2)
    return (np.stack([nx, ny, nz], -1) / norm[..., None] * 0.5 + 0.5).astype(np.float32)


def texture():
    return {"type": "bitmap", "raw": True, "filter_type": "bilinear",
            "bitmap": mi.Bitmap(normal_map_data())}


# ------------------------------------------------------------------ float64 model
def frame(n_map, wi):
    """The shading frame of NormalMap::frame for incident directions wi (m, 3)."""
    n = np.broadcast_to(n_map, wi.shape).copy()
    flip = wi[:, 2] * (wi @ n_map) <= 0
    n[flip, 0] *= -1
    n[flip, 1] *= -1
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    s = np.array([1.0, 0, 0]) - n * n[:, :1]
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    return s, np.cross(n, s), n, flip


def to_local(f, v):
    s, t, n, _ = f
    return np.stack([(v * s).sum(1), (v * t).sum(1), (v * n).sum(1)], 1)


def shadow(n, w):
    tan2 = lambda v: (1 - v[:, 2] ** 2) / v[:, 2] ** 2
    a2 = np.minimum(0.125 * tan2(n), 1.0)
    return 2 / (1 + np.sqrt(1 + a2 * tan2(w)))


def lambert(wi, wo):  # f·cosθo in the local frame
    return np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), RHO / np.pi * wo[:, 2], 0.0)


def beckmann_conductor(wi, wo):  # Walter et al. 2007 eq. 20 and 27, anisotropic Beckmann D
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    c2 = h[:, 2] ** 2
    D = np.exp(-((h[:, 0] / AU) ** 2 + (h[:, 1] / AV) ** 2) / c2) / (np.pi * AU * AV * c2 * c2)

    def g1(v):
        xy = (AU * v[:, 0]) ** 2 + (AV * v[:, 1]) ** 2
        with np.errstate(divide="ignore"):
            a = np.abs(v[:, 2]) / np.sqrt(xy)
        r = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1 + 2.276 * a + 2.577 * a * a))
        return np.where((v * h).sum(1) * v[:, 2] <= 0, 0.0, r)
    ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    return np.where(ok, D * g1(wi) * g1(wo) / (4 * wi[:, 2]), 0.0)  # f·cosθo, F = 1


def model_eval(nested, n_map, wi, wo):
    """NormalMap::eval in float64: (f·cosθo in the world frame, frame, wi', wo')."""
    f = frame(n_map, wi)
    wi_, wo_ = to_local(f, wi), to_local(f, wo)
    active = wo[:, 2] * wo_[:, 2] > 0
    value = np.where(active, nested(wi_, wo_) * shadow(f[2], wo), 0.0)
    return value, f, wi_, wo_


# ------------------------------------------------------------------ Mitsuba
def mitsuba_eval(bsdf, wi, wo):
    m = len(wi)
    si = dr.zeros(mi.SurfaceInteraction3f, m)
    si.wi = mi.Vector3f(*(mi.Float(wi[:, k].astype(np.float32)) for k in range(3)))
    si.uv = mi.Point2f(0.5, 0.5)
    si.n = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    si.dp_du, si.dp_dv = mi.Vector3f(1, 0, 0), mi.Vector3f(0, 1, 0)
    w = mi.Vector3f(*(mi.Float(wo[:, k].astype(np.float32)) for k in range(3)))
    return np.array(bsdf.eval(mi.BSDFContext(), si, w), dtype=np.float64)[0]


def main():
    mi.set_variant("llvm_ad_rgb")
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.uv = mi.Point2f(0.5, 0.5)
    n_map = np.array(mi.load_dict(texture()).eval(si), dtype=np.float64).ravel()[:3] * 2 - 1
    print(f"normal map at uv (0.5, 0.5): n = {np.round(n_map / np.linalg.norm(n_map), 4)} "
          f"(tilt {np.degrees(np.arccos(n_map[2] / np.linalg.norm(n_map))):.1f}°)")

    rng = np.random.default_rng(0)
    n = 200_000

    def hemisphere():
        v = rng.normal(size=(n, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        v[:, 2] = np.abs(v[:, 2])
        return v
    a, b = hemisphere(), hemisphere()
    keep = (a[:, 2] > 1e-3) & (b[:, 2] > 1e-3)
    a, b = a[keep], b[keep]
    a = a.astype(np.float32).astype(np.float64)
    b = b.astype(np.float32).astype(np.float64)
    ok_all = True
    for name, nested, spec in (
            ("diffuse", lambert, {"type": "diffuse"}),
            ("roughconductor αu=0.05 αv=0.3", beckmann_conductor,
             {"type": "roughconductor", "alpha_u": AU, "alpha_v": AV})):
        bsdf = mi.load_dict({"type": "normalmap", "normalmap": texture(), "bsdf": spec})
        e_ab, e_ba = mitsuba_eval(bsdf, a, b), mitsuba_eval(bsdf, b, a)
        m_ab, f_ab, a1, b1 = model_eval(nested, n_map, a, b)
        m_ba, f_ba, b2, a2 = model_eval(nested, n_map, b, a)
        # (1) the model reproduces Mitsuba, both orders (relative to the larger value of the pair)
        scale = np.maximum.reduce([np.abs(e_ab), np.abs(e_ba), np.abs(m_ab), np.abs(m_ba)])
        big = scale > 1e-6 * scale.max()
        err = np.maximum(np.abs(e_ab - m_ab), np.abs(e_ba - m_ba))[big] / scale[big]
        # reciprocity measure of the check: f = eval / cosθo (geometric)
        F_ab, F_ba = e_ab / b[:, 2], e_ba / a[:, 2]
        s = np.maximum(F_ab, F_ba)
        asym = np.where(s > 0, np.abs(F_ab - F_ba) / np.where(s > 0, s, 1), 0)
        # (2) same frame (no flip difference), both orders active: Veach's factor
        same = f_ab[3] == f_ba[3]
        active = (m_ab > 0) & (m_ba > 0) & (e_ab > 0) & (e_ba > 0)
        cls = same & active & big
        # nested BSDF reciprocal in the common frame: f_n(a', b')/cos b' == f_n(b', a')/cos a'
        fn_ab = nested(a1, b1) / b1[:, 2]
        fn_ba = nested(b2, a2) / a2[:, 2]
        nested_asym = np.abs(fn_ab - fn_ba)[cls] / np.maximum(fn_ab, fn_ba)[cls]
        veach = ((b1[:, 2] / b[:, 2] * shadow(f_ab[2], b))
                 / (a2[:, 2] / a[:, 2] * shadow(f_ba[2], a)))
        with np.errstate(divide="ignore", invalid="ignore"):
            veach_err = np.abs((F_ab / F_ba) / veach - 1)[cls]
        # away from the horizon of the shading frame (cosθ' > 1e-2 both ways) float32 is exact
        # to ~1e-5; closer, cosθ' itself carries the float32 rounding of the frame rotation
        tame = (np.minimum(np.abs(b1[:, 2]), np.abs(a2[:, 2])) > 1e-2)[cls]
        # (3) the rest: the frame flip or the one-sided mask differs between the two orders
        rest = big & ~cls & (asym > 1e-4)
        flipped = rest & ~same
        one_sided = rest & same & ((m_ab > 0) != (m_ba > 0))
        print(f"\nnormalmap on {name}: {len(a)} pairs, asymmetry > 1e-4 in "
              f"{(asym > 1e-4).mean():.1%} (max {asym.max():.3g})")
        print(f"  (1) float64 model vs Mitsuba, both orders: max relative difference "
              f"{err.max():.2e} over {int(big.sum())} pairs")
        print(f"  (2) {int(cls.sum())} pairs in the same frame, unmasked: nested BSDF asymmetry "
              f"in the shading frame max {nested_asym.max():.2e}; f(a,b)/f(b,a) vs Veach's "
              f"shading-normal factor (which ranges {veach[cls].min():.3g} … "
              f"{veach[cls].max():.3g}): relative difference median {np.median(veach_err):.1e},"
              f" max {veach_err[tame].max():.1e} where cosθ' > 0.01 ({int(tame.sum())} pairs), "
              f"max {veach_err.max():.1e} overall")
        print(f"  (3) {int(rest.sum())} other asymmetric pairs: {int(flipped.sum())} with the "
              f"frame flipped in one order only (flip_invalid_normals: the frame depends on "
              f"ωi), {int(one_sided.sum())} zero in one order only (one-sided mask "
              f"cosθo·cosθo' > 0, or the nested BSDF's own hemisphere test); model = Mitsuba "
              f"there too (1)")
        ok = (err.max() < 1e-3 and nested_asym.max() < 1e-9 and veach_err[tame].max() < 1e-4
              and flipped.sum() + one_sided.sum() == rest.sum())
        ok_all &= ok
    print("\nthe asymmetry is the model's (shading normal, flipped frame, one-sided mask, "
          "shadowing of ωo only)" if ok_all else "\nNOT EXPLAINED")
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
