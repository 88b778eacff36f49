"""
mi_brdfs in six steps: render with a Python BSDF plugin, then check it the way the package does.

Run it as a script (outputs go to ``--out``, default ``./tutorial-out``)::

    python docs/tutorial.py            # about 15 s on two cores
    python docs/tutorial.py --quick    # small images and sample counts: about 10 s
    MI_BRDFS_TUTORIAL_QUICK=1 python docs/tutorial.py

or open it as a notebook: the ``# %%`` markers are cells for VS Code, Jupytext and Spyder.
The test suite runs it (``tests/test_tutorial.py``), so every call below works as shown.

1. set a variant and register the plugins;
2. render a scene that uses a plugin, write EXR + PNG;
3. the white furnace test;
4. the χ² test of the sampler;
5. a plugin against Mitsuba's built-in: pointwise and side by side;
6. fit one model to another by automatic differentiation.
"""

# %% [markdown]
# ## 0. Settings
#
# `--quick` (or `MI_BRDFS_TUTORIAL_QUICK=1`) shrinks resolutions and sample counts so that the
# whole tutorial runs in seconds; the numbers are then noisier, not different.

# %%
import argparse
import os
from pathlib import Path

parser = argparse.ArgumentParser(description="The mi_brdfs tutorial, end to end.")
parser.add_argument("--quick", action="store_true", help="small images and sample counts")
parser.add_argument("--out", default="tutorial-out", help="output folder (default: %(default)s)")
# parse_known_args: a notebook kernel passes arguments of its own
args, _ = parser.parse_known_args()
QUICK = args.quick or os.environ.get("MI_BRDFS_TUTORIAL_QUICK", "0") not in ("", "0")
OUT = Path(args.out)
OUT.mkdir(parents=True, exist_ok=True)

RES, SPP = (64, 16) if QUICK else (256, 256)           # step 2: the render
FURNACE_RES, FURNACE_SPP = (32, 16) if QUICK else (64, 64)
CHI2_SAMPLES = 200_000 if QUICK else 1_000_000
COMPARE_RES, COMPARE_SPP = (48, 8) if QUICK else (128, 64)
FIT_STEPS, FIT_PAIRS = (200, 4096) if QUICK else (800, 16384)
print(f"settings: {'quick' if QUICK else 'full'}, outputs in {OUT}")

# %% [markdown]
# ## 1. The variant, and why everything happens in Python
#
# The plugins are Python classes. `mi_brdfs.use_variant` sets a Mitsuba variant and registers
# them there with `mi.register_bsdf`, which only affects *this Python process*: Mitsuba's own
# `mitsuba` executable is a separate C++ program and cannot load them, so scenes that use them
# are rendered from Python (as below, or with `mi-brdfs render scene.xml`).
#
# Import `mi_brdfs` before `mitsuba` where you can: it then points Dr.Jit at a libLLVM that
# works before Dr.Jit loads one. `llvm_ad_rgb` is a JIT variant with automatic differentiation,
# which steps 4 (χ²) and 6 (the fit) need; `fallback=False` stops here with one line when this
# machine has no usable LLVM (by default `use_variant` would warn and use `scalar_rgb`).

# %%
import mi_brdfs  # first: it chooses the libLLVM before drjit loads
import mitsuba as mi
import numpy as np

variant = mi_brdfs.use_variant("llvm_ad_rgb", fallback=False)
print(f"variant {variant}, plugins: {', '.join(mi_brdfs.register())}")

# %% [markdown]
# ## 2. Render a scene with a plugin
#
# Once registered, a plugin is used like any built-in: `{'type': 'cooktorrance', ...}` in
# `mi.load_dict`, or `<bsdf type="cooktorrance">` in an XML file loaded with `mi.load_file`.
# Here: a gold Cook-Torrance sphere (Beckmann α = 0.2, V-cavity masking, exact Fresnel; Cook &
# Torrance 1982, "A Reflectance Model for Computer Graphics") over a grey floor, lit by an area
# light and a dim sky — the same scene as `scenes/material.xml`.

# %%
T = mi.ScalarTransform4f
scene = mi.load_dict({
    "type": "scene",
    "integrator": {"type": "path", "max_depth": 6},
    "sensor": {
        "type": "perspective",
        "fov": 30,
        "to_world": T().look_at(origin=[0, 1.2, 4.5], target=[0, 0.05, 0], up=[0, 1, 0]),
        "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
        "sampler": {"type": "independent", "sample_count": SPP},
    },
    "light": {
        "type": "rectangle",
        "to_world": T().translate([-1.8, 3.5, 1.8]).rotate([1, 0, 0], 90).scale(1.2),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [6, 6, 6]}},
    },
    "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [0.2, 0.22, 0.25]}},
    "sphere": {
        "type": "sphere",
        "radius": 0.8,
        "bsdf": {"type": "cooktorrance", "material": "Au", "alpha": 0.2},
    },
    "floor": {
        "type": "rectangle",
        "to_world": T().translate([0, -0.8, 0]).rotate([1, 0, 0], -90).scale(6),
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.35}},
    },
})
image = np.array(mi.render(scene, spp=SPP, seed=0))

# %% [markdown]
# Write the linear image as a float32 EXR (for comparisons and compositing) and an sRGB PNG
# (to look at). `mi_brdfs.imageio` writes atomically: no reader ever sees half a file.
# `mi.Bitmap(image).write("x.exr")` does the same with Mitsuba alone.

# %%
from mi_brdfs.imageio import write_exr, write_png

write_exr(OUT / "cooktorrance.exr", image, {"spp": SPP, "variant": variant})
write_png(OUT / "cooktorrance.png", image)
print(f"render: {image.shape[1]}×{image.shape[0]} px, {SPP} spp, mean = {image.mean():.5f}, "
      f"non-finite pixels = {int((~np.isfinite(image)).sum())}")
print(f"wrote {OUT / 'cooktorrance.exr'} and {OUT / 'cooktorrance.png'}")

# %% [markdown]
# The same scene as a file: `scenes/material.xml` declares `<default name="res">`,
# `spp` and `max_depth`, overridden as keyword arguments (the `-D name=value` of the command
# line), and its sphere's `<bsdf id="material">` can be swapped for any BSDF — a dict, an XML
# fragment, or a string `'plugin key=value ...'`:
#
# ```python
# scene = mi_brdfs.scenes.load_scene("material", res=128, spp=64,
#                                    bsdfs={"material": "cooktorrance material=Au alpha=0.2"})
# ```
#
# Steps 5 and 6 render it that way.

# %% [markdown]
# ## 3. The white furnace test
#
# Put the BSDF on a sphere inside a uniform white environment (radiance 1) and render one
# bounce (`scenes/furnace.xml`). Each pixel on the sphere is then the directional albedo
# E(θ) = ∫ f cosθo dωo at the angle θ under which the camera sees it, and the background is 1.
# A BSDF that reflects all light (Lambert with ρ = 1) makes the sphere vanish: the image mean
# is 1. A darker mean is energy the model loses, a brighter one energy it creates.
#
# `check_furnace` renders it and compares the image mean with the mean *predicted* from the
# BSDF's albedo curve, so it checks the plugin inside the renderer (sampling, weights, no NaN),
# not only on paper. It passes when |Δ| ≤ 0.005 and no pixel is NaN or infinite.

# %%
from mi_brdfs.checks import check_furnace

for name, spec in (("lambert", "lambert reflectance=1"),
                   ("cooktorrance", "cooktorrance alpha=0.8 fresnel=none")):
    r = check_furnace(spec, spp=FURNACE_SPP, res=FURNACE_RES)
    render = r.details["render"]
    print(f"furnace {name}: mean = {render.mean:.5f}, predicted = {render.expected:.5f}, "
          f"passed = {r.passed}")
    print(f"  {r.message}")
    write_png(OUT / f"furnace-{name}.png", render.image)

# %% [markdown]
# Lambert with ρ = 1 gives 1: nothing is lost. The rough Cook-Torrance sphere without Fresnel
# (a perfect mirror at every microfacet) is darker, most of all at its rim: the model scatters
# once off the microfacets, and the light that its masking term removes — light that would
# bounce again between the facets — is lost. That is a property of single-scattering
# microfacet models, not a bug (Heitz et al. 2016, "Multiple-Scattering Microfacet BSDFs with
# the Smith Model"); the check passes because the render matches what E(θ) predicts.
# `check_energy` asks the other question: is E(θ) ≤ 1 at every angle?

# %% [markdown]
# ## 4. The χ² test of the sampler
#
# A path tracer draws directions with `sample()` and weighs them with `eval()/pdf()`. If
# `sample()` does not draw with the density `pdf()` reports, renders converge to a wrong image,
# slightly and silently. Pearson's χ² test (as Mitsuba's own test suite runs it,
# `mitsuba.chi2`) draws many directions, histograms them over the sphere, and compares the
# histogram with the integral of `pdf()` over each cell.
#
# The **p-value** is the probability of a χ² statistic at least as large as the one observed
# *if* `sample()` and `pdf()` agree. Under that hypothesis p is uniformly distributed in
# [0, 1]: p = 0.05 and p = 0.8 are equally good. Only a tiny p (here < 0.01) rejects, and it
# means the mismatch is real: more samples make it smaller still, not larger.

# %%
from mi_brdfs.checks import chi2_bsdf

theta = np.radians(50.0)  # incidence, in the BSDF's local frame (z = the normal)
r = chi2_bsdf("cooktorrance alpha=0.3 distribution=ggx", wi=(np.sin(theta), 0.0, np.cos(theta)),
              sample_count=CHI2_SAMPLES, seed=0)
print(f"chi2 p-value = {r.value:.4g}, passed = {r.passed}")
print(f"  {r.message}")

# %% [markdown]
# ## 5. The plugin against Mitsuba's built-in
#
# `cooktorrance` with `shadowing=smith` computes what Mitsuba's `roughconductor` computes. Two
# ways to show it: pointwise, `check_equal` evaluates both BSDFs (eval, pdf, and `sample()`
# with the same random numbers) at 10⁵ random direction pairs and reports the largest relative
# difference (float32 rounding is about 1e-7); and in an image, `compare` renders the material
# scene with each, with the same seed, and measures the difference against the *noise floor*:
# the same metrics between two renders of A with different seeds.

# %%
from mi_brdfs.checks import check_equal
from mi_brdfs.compare import compare, write_outputs

ours = "cooktorrance shadowing=smith material=Au alpha=0.3"
builtin = "roughconductor material=Au alpha=0.3"
r = check_equal(ours, builtin)
print(f"largest relative difference = {r.value:.3g}, passed = {r.passed}")
print(f"  {r.message}")

result = compare("material", swap_a={"material": ours}, swap={"material": builtin},
                 spp=COMPARE_SPP, defines={"res": COMPARE_RES},
                 labels=("cooktorrance", "roughconductor"))
print(result.summary())
print(f"compare: A vs B RMSE = {result.ab.rmse:.3g}, noise floor RMSE = {result.noise.rmse:.3g}")

# %% [markdown]
# "within noise" means no metric of A against B exceeds 3× its noise floor. The side-by-side
# figure (A | B | B − A | FLIP error map) and the EXRs need matplotlib (`pip install
# 'mi-brdfs[plots]'`).

# %%
import importlib.util

if importlib.util.find_spec("matplotlib"):
    for path in write_outputs(result, OUT / "compare.png"):
        print(f"wrote {path}")
else:
    print("matplotlib is not installed: no comparison figure")

# %% [markdown]
# ## 6. Fit one model to another
#
# `mi_brdfs.fit.fit` adjusts a model's continuous parameters so that its `eval()` matches a
# target's, with Mitsuba's automatic differentiation (`mi.traverse` and `mi.ad.Adam`). Which
# Blinn-Phong exponent best imitates a Beckmann lobe of α = 0.2? Walter et al. (2007,
# "Microfacet Models for Refraction through Rough Surfaces", §5.2) give n = 2/α² − 2 = 48 as
# the exponent whose *distribution of normals* matches; the fit answers for the whole BRDF
# (masking included), under the error metric of the `mi_brdfs.fit` docstring.

# %%
from mi_brdfs.fit import fit

alpha = 0.2
target = f"cooktorrance alpha={alpha} fresnel=none"
fitted = fit(target, "phong lobe=halfway diffuse_reflectance=0", steps=FIT_STEPS, pairs=FIT_PAIRS)
print(fitted.summary())
print(f"fitted exponent = {fitted.parameters['exponent']:.4g} "
      f"(Walter et al. 2007: 2/α² − 2 = {2 / alpha**2 - 2:g})")

# %% [markdown]
# The fitted BSDF is a spec like any other (`fitted.command_line()`, `fitted.xml()` for a scene
# file): render it beside its target. The two differ where Blinn-Phong cannot follow the
# microfacet model, above all at grazing angles (the albedo error above): at the full settings
# the difference stands well above the noise floor; with `--quick`'s few samples it may not.

# %%
side = compare("material", swap_a={"material": target}, swap={"material": fitted.spec},
               spp=COMPARE_SPP, defines={"res": COMPARE_RES},
               labels=("cooktorrance", "fitted phong"), with_flip=False)
print(f"fit render: {side.verdict()}")
write_png(OUT / "fit-target.png", side.a)
write_png(OUT / "fit-phong.png", side.b)

# %%
print(f"tutorial done: outputs in {OUT}")
