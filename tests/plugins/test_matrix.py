"""
The matrix every plugin joins: in scalar and llvm variants, RGB, mono, spectral and polarized,
each plugin loads with a reflectance of every texture kind (a constant, <rgb>, a spectrum, a
bitmap, a checkerboard, a mesh attribute), evaluates and samples it to finite, non-negative
values at a mesh's hit point, and renders a tiny image of a mesh carrying it, finite and lit.
Whole rows of this matrix were broken before (spectral bitmaps, mesh attributes on multi-lobe
plugins, compensated conductors in polarized variants).

The scalar variants run every (plugin, texture kind) cell. In llvm variants every cell is
traced into the row's render kernel, which LLVM compiles for about a third of a second per cell
on an empty kernel cache, so the default suite runs each plugin once in each llvm variant, with
a texture kind that turns with the plugin and the variant, and so covers every pair of the
three axes (plugin x kind in the scalar variants, plugin x variant and kind x variant in the
llvm ones): a pairwise covering design (Cohen et al. 1997, "The AETG System: An Approach to
Testing Based on Combinatorial Design"), which catches every fault that two of the axes cause
together, as each of those above did (``make test`` renders the llvm cells in llvm_ad_rgb,
and every cell in the scalar variants, scalar_spectral_polarized among them; ``make test-slow``
in llvm_ad_mono, llvm_ad_spectral and llvm_ad_spectral_polarized: see tests/tiers.py). ``make test-slow`` (``make test-full``) also runs every cell in every llvm
variant.
"""

import mitsuba as mi
import numpy as np
import pytest
from conftest import set_variant
from helpers import merl_file

from mi_brdfs import registry

SCALAR = ["scalar_rgb", "scalar_spectral_polarized"]
LLVM = ["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral", "llvm_ad_spectral_polarized"]
VARIANTS = SCALAR + LLVM

#: Each plugin, the reflectance the matrix varies, and further parameters (a second lobe or
#: the compensation, so that the mixture and its weights see the texture too)
PLUGINS = {
    "lambert": ("reflectance", {}),
    "orennayar": ("reflectance", {"form": "full"}),
    "phong": ("diffuse_reflectance", {}),
    "ward": ("specular_reflectance", {}),
    "ashikhmin": ("diffuse_reflectance", {}),
    "lafortune": ("specular_reflectance_0", {"cx_1": 1.0, "cy_1": 1.0, "cz_1": 1.0}),
    "cooktorrance": ("diffuse_reflectance", {"multiscatter": True, "shadowing": "smith",
                                             "specular_reflectance": 0.5}),
    # the thin film's code in every variant (a plugin's second row: "type" names the plugin)
    "cooktorrance-film": ("specular_reflectance", {"type": "cooktorrance", "alpha": 0.2,
                                                   "film_thickness": 300.0, "film_eta": 1.4}),
    "merl": ("scale", {"filename": str(merl_file())}),
    # 16 terms of the series, not the paper reading's 128, each unrolled into the kernel (LLVM
    # compiles a cell in about 6 s instead of 9): the matrix tests the textures' and variants'
    # plumbing, tests/plugins/test_he_plugin.py the series
    "he": ("diffuse_reflectance", {"specular_reflectance": 0.8, "sigma0": 0.05, "terms": 16}),
    "rtls": ("f_iso", {"f_geo": 0.02}),
    "rpv": ("rho_0", {"k": 0.6, "g": -0.2}),
    "hapke": ("w", {"B_0": 1.0, "h": 0.06}),
    "ocean": ("whitecaps", {"wind_speed": 10.0, "wind_direction": 30.0}),
    "hk": ("sigma_s", {"eta": 1.5, "g": 0.5}),
    # every order over a base, the base's reflectance textured (the row above textures σs;
    # a textured medium's tables: tests/scattering/test_hk_orders.py)
    "hk-all": ("diffuse_reflectance", {"type": "hk", "scattering": "all", "eta": 1.5,
                                       "g": 0.5}),
}


def texture_kinds() -> dict:
    """One reflectance of every texture kind, in the current variant."""
    grid = np.linspace(0.1, 0.7, 48).reshape(4, 4, 3).astype(np.float32)
    return {"constant": 0.4,
            "rgb": {"type": "rgb", "value": [0.2, 0.4, 0.6]},
            "spectrum": {"type": "spectrum", "value": [(400.0, 0.2), (700.0, 0.6)]},
            "bitmap": {"type": "bitmap", "bitmap": mi.Bitmap(grid)},
            "checkerboard": {"type": "checkerboard", "color0": 0.2, "color1": 0.6},
            "mesh_attribute": {"type": "mesh_attribute", "name": "vertex_color"}}


def square(bsdf=None):
    """A unit square mesh in z = 0 with uv and a vertex attribute ``vertex_color``."""
    props = mi.Properties()
    if bsdf is not None:
        props["bsdf"] = bsdf
    mesh = mi.Mesh("square", 4, 2, props, has_vertex_normals=False, has_vertex_texcoords=True)
    params = mi.traverse(mesh)
    params["vertex_positions"] = [-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0]
    params["faces"] = [0, 1, 2, 0, 2, 3]
    params["vertex_texcoords"] = [0, 0, 1, 0, 1, 1, 0, 1]
    params.update()
    mesh.add_attribute("vertex_color", 3, [0.3, 0.5, 0.7] * 4)
    return mesh


def cells(variant: str, full: bool = False) -> list:
    """The (plugin, texture kind) cells a variant runs: all of them in scalar variants (and with
    ``full``); in llvm variants each plugin once, the i-th with the kind of index i + the
    variant's index (modulo the kinds): each plugin and each kind in every llvm variant."""
    kinds = list(KINDS)
    if full or variant not in LLVM:
        return [(p, k) for p in PLUGINS for k in kinds]
    v = LLVM.index(variant)
    return [(p, kinds[(i + v) % len(kinds)]) for i, p in enumerate(PLUGINS)]


#: The texture kinds, by name (the values are made in the variant under test).
KINDS = ("constant", "rgb", "spectrum", "bitmap", "checkerboard", "mesh_attribute")


def load(plugin: str, kind: str):
    param, extra = PLUGINS[plugin]
    return mi.load_dict({"type": plugin, **extra, param: texture_kinds()[kind]})


def test01_every_plugin_is_in_the_matrix():
    assert {extra.get("type", p) for p, (_, extra) in PLUGINS.items()} == \
        set(registry.PLUGINS)
    assert tuple(texture_kinds()) == KINDS


def test01b_the_cells_cover_every_pair():
    """Every cell in each scalar variant; every plugin and every kind in each llvm variant."""
    for v in SCALAR:
        assert sorted(cells(v)) == sorted(cells(LLVM[0], full=True)), v
    for v in LLVM:
        assert {p for p, _ in cells(v)} == set(PLUGINS), v
        assert {k for _, k in cells(v)} == set(KINDS), v


def check_cells(chosen, direct: bool):
    """With ``direct``, load, eval_pdf and sample each cell at a hit on the mesh: finite, and
    non-negative where the value is a spectrum (a Mueller matrix has negative elements by
    nature). Then render a tiny image of one mesh per cell under a constant sky, Mitsuba tracing
    each cell's eval_pdf and sample symbolically into one kernel: each mesh finite,
    non-negative and lit."""
    if direct:
        scene = mi.load_dict({"type": "scene", "s": square()})
        si = scene.ray_intersect(mi.Ray3f([0.1, 0.2, 1.0], [0.0, 0.0, -1.0]))
        si.wi = mi.Vector3f(0.3, 0.1, 0.95)
        ctx = mi.BSDFContext()
    for plugin, kind in chosen if direct else ():
        bsdf = load(plugin, kind)
        f, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(-0.2, 0.3, 0.93))
        _, weight = bsdf.sample(ctx, si, 0.4, mi.Point2f(0.3, 0.6))
        for value in (f, pdf, weight):
            a = np.array(value)
            assert np.isfinite(a).all(), (plugin, kind)
            assert mi.is_polarized or (a >= 0).all(), (plugin, kind)
    image = render_row([load(plugin, kind) for plugin, kind in chosen])
    for i, cell in enumerate(chosen):
        tile = image[:, 2 * i:2 * i + 2]
        assert np.isfinite(tile).all() and (tile >= 0).all() and tile.max() > 0, cell


def render_row(bsdfs, res: int = 2):
    """One render of a row of unit squares seen from above, the i-th carrying ``bsdfs[i]``:
    columns [res·i, res·i + res) of the image are that square's (one kernel for the row, not
    one per BSDF)."""
    shapes = {}
    for i, bsdf in enumerate(bsdfs):
        mesh = square(bsdf)
        params = mi.traverse(mesh)
        # squares edge to edge, taller than the view: no pixel sees the sky past a square
        x = np.array(params["vertex_positions"]).reshape(-1, 3) * [0.5, 0.75, 1.0]
        params["vertex_positions"] = (x + [i - (len(bsdfs) - 1) / 2, 0, 0]).ravel()
        params.update()
        shapes[f"cell{i}"] = mesh
    half = len(bsdfs) / 2  # the orthographic view spans [-1, 1] x [-1/aspect, 1/aspect]
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "direct"},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 2], target=[0, 0, 0],
                                                              up=[0, 1, 0])
                   @ mi.ScalarTransform4f().scale([half, half, 1]),
                   "film": {"type": "hdrfilm", "width": res * len(bsdfs), "height": res,
                            "rfilter": {"type": "box"},
                            "pixel_format": "luminance" if mi.is_monochromatic else "rgb"}},
        "sky": {"type": "constant", "radiance": 1.0}, **shapes})
    return np.array(mi.render(scene, spp=2))


@pytest.mark.parametrize("variant", VARIANTS)
def test02_every_plugin_with_every_texture_kind(variant):
    """Scalar variants: every cell, called directly and rendered. llvm variants: their cells
    (:func:`cells`), rendered only: a direct call compiles a kernel per cell, about as long
    as the render's, which traces the same eval_pdf and sample; the suite calls the plugins
    directly in llvm variants everywhere else."""
    set_variant(variant)
    check_cells(cells(variant), direct=variant not in LLVM)


@pytest.mark.slow
@pytest.mark.parametrize("variant", LLVM)
def test03_every_cell_in_every_llvm_variant(variant):
    """The whole product (make test-full): about a minute of compilation per variant."""
    set_variant(variant)
    check_cells(cells(variant, full=True), direct=True)


@pytest.mark.parametrize("variant", ["scalar_rgb", "llvm_ad_rgb"])
def test04_the_row_render_sees_each_square_alone(variant):
    """What check_cells relies on: a black square (reflectance 0) between lit ones is black in
    exactly its own columns, no pixel seeing the sky beside it, so a cell that renders nothing
    is caught in its own columns."""
    set_variant(variant)
    lit = {"type": "lambert", "reflectance": 0.5}
    image = render_row([mi.load_dict(lit), mi.load_dict(dict(lit, reflectance=0.0)),
                        mi.load_dict(lit)])
    assert image.shape[:2] == (2, 6)
    assert (image[:, 2:4] == 0).all()
    assert (image[:, :2] > 0).all() and (image[:, 4:] > 0).all()
