"""
blendbsdf of Mitsuba 3.7.1 (as eradiate-mitsuba 0.5.0 ships it), the audit's "textured weight"
configuration (diffuse + conductor, weight a checkerboard of 0.2 and 0.8; 0.8 at the check's
uv): with ctx.component = 1 (the conductor's mirror lobe, as blendbsdf numbers its lobes:
a's, then b's) every sample reports sampled_component 0. src/bsdfs/blendbsdf.cpp (v0.5.0 of
the fork, Mitsuba 3.7.1) lines 116-125: sample() shifts ctx.component down by a's component
count for b (line 120) and returns b's BSDFSample3f unchanged, without shifting
sampled_component back up; the default context's branch does the same (lines 141-146).

The Dirac-weight defect of Mitsuba 3.9.1's blendbsdf (validation/audit/
repro_blendbsdf_delta_weight.py, which exits 0 under 3.7.1) is not in this build: its
sample() returns each nested BSDF's own weight (lines 134-146), not the mixture's, so the
albedos of the lobes one by one add up to the whole, as printed.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_blendbsdf_component_offset.py
Exits 1 while a sample of ctx.component = 1 reports another component.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "blendbsdf", "a": {"type": "diffuse"}, "b": {"type": "conductor"},
                     "weight": {"type": "checkerboard",
                                "color0": {"type": "rgb", "value": [0.2] * 3},
                                "color1": {"type": "rgb", "value": [0.8] * 3}}})
n = 200_000
rng = np.random.default_rng(0)
si = dr.zeros(mi.SurfaceInteraction3f, n)
si.wi = mi.Vector3f(mi.Float(np.zeros(n)), mi.Float(np.zeros(n)), mi.Float(np.ones(n)))
si.uv = mi.Point2f(0.5, 0.5)
si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
albedo, bad = {}, False
for component in (None, 0, 1):
    ctx = mi.BSDFContext()
    if component is not None:
        ctx.component = component
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n).astype(np.float32)),
                             mi.Point2f(rng.random((2, n)).astype(np.float32)))
    weight = np.broadcast_to(np.array(weight, dtype=np.float64)[0], n)
    sampled = np.broadcast_to(np.array(bs.sampled_component), n)
    albedo[component] = weight.mean()
    if component is not None:
        ok = weight > 0
        other = ok & (sampled != component)
        print(f"ctx.component = {component}: {int(other.sum())} of {int(ok.sum())} successful "
              f"samples report another component (e.g. "
              f"{int(sampled[other][0]) if other.any() else '-'})")
        bad |= bool(other.any())
print(f"albedo at normal incidence: all lobes {albedo[None]:.5f}, lobe 0 + lobe 1 = "
      f"{albedo[0]:.5f} + {albedo[1]:.5f} = {albedo[0] + albedo[1]:.5f}")
sys.exit(1 if bad else 0)
