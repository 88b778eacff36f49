"""
The plugins take every argument form Mitsuba's built-ins take, and work inside Mitsuba's
composite BSDFs (twosided, blendbsdf, normalmap) as the built-ins do: the kinds of cases that
Mitsuba's own tests (src/bsdfs/tests in mitsuba-renderer/mitsuba3) use for ``diffuse``,
``roughconductor``, ``twosided``, ``blendbsdf`` and ``normalmap``, written for our plugins.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

PLUGINS = [{"type": "lambert"}, {"type": "phong"},
           {"type": "cooktorrance", "alpha": 0.3, "diffuse_reflectance": 0.2},
           {"type": "ward", "alpha_u": 0.1, "alpha_v": 0.3}, {"type": "orennayar", "form": "full"}]
#: Each of ours with the built-in that computes the same (for the composite BSDFs)
PAIRS = [({"type": "lambert", "reflectance": 0.6}, {"type": "diffuse", "reflectance": 0.6}),
         ({"type": "cooktorrance", "shadowing": "smith", "material": "Au", "alpha": 0.3},
          {"type": "roughconductor", "material": "Au", "alpha": 0.3}),
         # upstream's normalmap tests nest an anisotropic GGX aluminium
         ({"type": "cooktorrance", "shadowing": "smith", "material": "Al", "distribution": "ggx",
           "alpha_u": 0.4, "alpha_v": 0.1},
          {"type": "roughconductor", "material": "Al", "distribution": "ggx", "alpha_u": 0.4,
           "alpha_v": 0.1})]
IDS = ["lambert", "cooktorrance", "cooktorrance-anisotropic"]
#: The rough dielectric with its built-in (not in twosided, which takes no transmission)
GLASS = ({"type": "cooktorrance", "transmission": True, "alpha": 0.3},
         {"type": "roughdielectric", "alpha": 0.3})


def _si(wi=(0, 0, 1)):
    si = mi.SurfaceInteraction3f()
    si.p, si.n = [0, 0, 0], [0, 0, 1]
    si.sh_frame = mi.Frame3f(si.n)
    si.wi = wi
    return si


def _flat(x):
    return np.ravel(np.array(x, dtype=np.float64))


@pytest.mark.parametrize("spec", PLUGINS, ids=lambda s: s["type"])
def test01_directions_as_lists_and_tuples(variants_rgb, spec):
    """wo as a list, a tuple or by keyword, sample2 as a tuple or a list: the same values as
    with Mitsuba's own types."""
    bsdf, ctx = mi.load_dict(spec), mi.BSDFContext()
    si = _si([0.3, 0.2, dr.sqrt(1 - 0.13)])
    wo = [0.1, -0.4, float(dr.sqrt(1 - 0.17))]
    want_f, want_p = bsdf.eval_pdf(ctx, si, mi.Vector3f(wo))
    assert _flat(want_f).max() > 0 and _flat(want_p).max() > 0
    for form in (wo, tuple(wo)):
        np.testing.assert_array_equal(_flat(bsdf.eval(ctx, si, form)), _flat(want_f))
        np.testing.assert_array_equal(_flat(bsdf.eval(ctx, si, wo=form)), _flat(want_f))
        np.testing.assert_array_equal(_flat(bsdf.pdf(ctx, si, wo=form)), _flat(want_p))
        f, p = bsdf.eval_pdf(ctx, si, wo=form)
        np.testing.assert_array_equal(_flat(f), _flat(want_f))
    bs_want, w_want = bsdf.sample(ctx, si, 0.4, mi.Point2f(0.3, 0.6))
    for form in ((0.3, 0.6), [0.3, 0.6]):
        bs, w = bsdf.sample(ctx, si, 0.4, form)
        np.testing.assert_array_equal(_flat(bs.wo), _flat(bs_want.wo))
        np.testing.assert_array_equal(_flat(w), _flat(w_want))


def test02_eval_pdf_along_the_plane(variant_scalar_rgb):
    """As Mitsuba's diffuse test: wo = [sin θ, 0, cos θ] as a list, pdf cosθ/π, eval ρ cosθ/π."""
    bsdf, ctx, si = mi.load_dict({"type": "lambert"}), mi.BSDFContext(), _si()
    for theta in np.linspace(0, np.pi / 2, 20):
        wo = [float(np.sin(theta)), 0.0, float(np.cos(theta))]
        assert bsdf.pdf(ctx, si, wo=wo) == pytest.approx(wo[2] / np.pi, abs=1e-7)
        assert bsdf.eval(ctx, si, wo=wo)[0] == pytest.approx(0.5 * wo[2] / np.pi, abs=1e-7)


@pytest.mark.parametrize("pair", PAIRS, ids=IDS)
def test03_inside_twosided(variants_rgb, pair):
    """twosided(ours) = twosided(built-in), on both sides, for eval, pdf and sample."""
    ours, theirs = (mi.load_dict({"type": "twosided", "bsdf": b}) for b in pair)
    ctx = mi.BSDFContext()
    for wi in ([0.3, 0.2, 0.932738], [0.3, 0.2, -0.932738]):
        si = _si(wi)
        wo = [-0.2, 0.1, 0.974679 if wi[2] > 0 else -0.974679]
        for a, b in ((ours.eval(ctx, si, wo), theirs.eval(ctx, si, wo)),
                     (ours.pdf(ctx, si, wo), theirs.pdf(ctx, si, wo)),
                     (ours.sample(ctx, si, 0.5, [0.3, 0.7])[1],
                      theirs.sample(ctx, si, 0.5, [0.3, 0.7])[1])):
            np.testing.assert_allclose(_flat(a), _flat(b), rtol=2e-6, atol=1e-7)
        assert _flat(ours.eval(ctx, si, wo)).max() > 0


@pytest.mark.parametrize("pair", PAIRS + [GLASS], ids=IDS + ["cooktorrance-transmission"])
def test04_inside_blendbsdf(variants_rgb, pair):
    """blendbsdf(conductor, ours): the blend of both, all components and each one alone."""
    weight = 0.3
    blend = mi.load_dict({"type": "blendbsdf", "weight": weight,
                          "nested1": {"type": "diffuse"}, "nested2": pair[0]})
    ours, other = mi.load_dict(pair[0]), mi.load_dict({"type": "diffuse"})
    ctx, si = mi.BSDFContext(), _si([0.3, 0.2, 0.932738])
    wo = [-0.2, 0.1, 0.974679]
    want = (1 - weight) * _flat(other.eval(ctx, si, wo)) + weight * _flat(ours.eval(ctx, si, wo))
    np.testing.assert_allclose(_flat(blend.eval(ctx, si, wo)), want, rtol=2e-6)
    # component by component: ours comes after the diffuse's one component
    part = mi.BSDFContext()
    part.component = 1
    np.testing.assert_allclose(_flat(blend.eval(part, si, wo)),
                               weight * _flat(ours.eval(mi.BSDFContext(), si, wo)), rtol=2e-6)
    bs, w = blend.sample(ctx, si, 0.9, (0.4, 0.6))  # sample1 ≥ 1 − weight picks ours
    assert np.isfinite(_flat(w)).all() and _flat(w).max() > 0


@pytest.mark.parametrize("pair", PAIRS + [GLASS], ids=IDS + ["cooktorrance-transmission"])
def test05_inside_normalmap(variants_rgb, pair):
    """normalmap(ours) = normalmap(built-in) for a tilted normal, and with a normal that ωi sees
    from behind: 0 without flip_invalid_normals, the flipped normal's value with it."""
    def normalmap(bsdf, normal, flip=True):
        n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
        return mi.load_dict({"type": "normalmap", "flip_invalid_normals": flip,
                             "normalmap": {"type": "srgb", "color": list(n * 0.5 + 0.5)},
                             "nested_bsdf": bsdf})
    ctx, wo = mi.BSDFContext(), [0.0, 0.0, 1.0]
    for normal, wi in (([0.2, 0.0, 0.8], [0.3, 0.2, 0.932738]),
                       ([1.0, 1.0, 1.0], [-0.666667, -0.666667, 0.333333])):
        si = _si(wi)
        for flip in (True, False):
            ours, theirs = (normalmap(b, normal, flip) for b in pair)
            for a, b in ((ours.eval(ctx, si, wo), theirs.eval(ctx, si, wo)),
                         (ours.eval_pdf(ctx, si, wo)[1], theirs.eval_pdf(ctx, si, wo)[1]),
                         (ours.sample(ctx, si, 0.5, (0.3, 0.6))[1],
                          theirs.sample(ctx, si, 0.5, (0.3, 0.6))[1])):
                np.testing.assert_allclose(_flat(a), _flat(b), rtol=2e-6, atol=1e-8)
            if normal[0] == 1.0 and not flip:  # ωi behind the mapped normal: nothing
                assert _flat(ours.eval(ctx, si, wo)).max() == 0
            else:
                assert _flat(ours.eval(ctx, si, wo)).max() > 0
