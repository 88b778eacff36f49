"""
bilambertian of eradiate-mitsuba 0.5.0 ignores the lobe a context selects in sample(): with
ctx.component = 0 (its diffuse reflection) it still samples its transmission lobe, and with
ctx.component = 1 its reflection, in proportion r/(r + t) as for the default context.
bilambertian.cpp (v0.5.0) computes has_reflect and has_transmit from the context (lines
64-65) but uses them only to return early when both are off; the lobe is chosen from sample1
alone (lines 90-91). BSDFContext::is_enabled is how an integrator or a mixture asks one lobe.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_bilambertian_component.py
Exits 1 while a sample reports a lobe the context did not select.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "bilambertian", "reflectance": 0.7, "transmittance": 0.2})
rng = np.random.default_rng(0)
n = 100_000
bad = False
for component in (0, 1):
    ctx = mi.BSDFContext()
    ctx.component = component
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    bs, weight = bsdf.sample(ctx, si, mi.Float(rng.random(n)),
                             mi.Point2f(rng.random(n), rng.random(n)))
    ok = np.array(weight)[0] > 0
    other = int(np.sum(ok & (np.array(bs.sampled_component) != component)))
    print(f"ctx.component = {component}: {other} of {int(ok.sum())} successful samples report "
          f"the other lobe")
    bad |= other > 0
sys.exit(1 if bad else 0)
