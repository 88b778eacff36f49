"""
ocean_grasp of eradiate-mitsuba 0.5.0 samples its diffuse lobe (component 0: whitecaps) when
the context selects only its glint (ctx.component = 1): sample() draws foam first, with the
probability of the whitecap coverage, whatever the context (ocean_grasp.cpp v0.5.0 lines
296-303: sample_foam from sample1 alone, then sample_diffuse = sample_foam || ...; has_diffuse,
lines 265-266, only sets the split between the water's lobes, lines 288-293). The coverage of
Monahan's formula, 2.95e-6 · U^3.52 (include/mitsuba/eradiate/oceanprops.h lines 330-336), is
8.5e-4 at 5 m/s: that fraction of the samples reports component 0 and sampled_type
DiffuseReflection. pdf() adds the foam's cosine density whatever the context as well (lines
467-482, 496), but eval() leaves the whitecaps out unless the context enables them (line
376): those samples carry the glint's value at a cosine-drawn direction. At the default 0.1 m/s the coverage is 9e-10 and it is
not seen.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_ocean_grasp_component.py
Exits 1 while a sample reports a lobe the context did not select.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
wind = 5.0
bsdf = mi.load_dict({"type": "ocean_grasp", "wavelength": 550.0, "wind_speed": wind})
n = 1_000_000
rng = np.random.default_rng(0)
ctx = mi.BSDFContext()
ctx.component = 1
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.wi = mi.Vector3f(0.0, 0.0, 1.0)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n).astype(np.float32)),
                         mi.Point2f(rng.random((2, n)).astype(np.float32)))
ok = np.array(weight)[0] > 0
other = ok & (np.array(bs.sampled_component) != 1)
print(f"ctx.component = 1 (glint), normal incidence, wind {wind} m/s: {int(other.sum())} of "
      f"{int(ok.sum())} successful samples report component 0 (fraction "
      f"{other.sum() / ok.sum():.2e}; whitecap coverage 2.95e-6 · U^3.52 = "
      f"{2.95e-6 * wind ** 3.52:.2e})")
sys.exit(1 if other.any() else 0)
