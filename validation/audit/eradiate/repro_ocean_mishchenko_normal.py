"""
ocean_mishchenko, ocean_grasp and maignan of eradiate-mitsuba 0.5.0 return Inf
or NaN at normal incidence for views within about 1e-4 rad of the normal: the very centre of
the sun glint seen from above. Cox & Munk's (1954) slope distribution and Fresnel's reflectance
are finite and smooth there; the value at exactly wo = wi = +z and at 1e-3 rad are finite
(0.0557), so the non-finite values come from the implementation. Of the terms of eval
(ocean_mishchenko.cpp, v0.5.0, lines 235-262: the Beckmann D, the height-correlated G, the
Fresnel factor), the only one that depends on the plane of wi and wo,
which is undefined as they meet at the pole, is the Fresnel Mueller matrix of Mishchenko &
Travis (1997), fresnel_sunglint_polarized (include/mitsuba/eradiate/oceanprops.h, v0.5.0,
lines 457-555): it rebuilds both directions from their azimuths (atan2 of near-zero
components) and scales by coeff = 1 / |wi × wo|⁴ (lines 521-525), whose guard against
collinear directions tests exact equality. maignan (maignan.cpp line 166), which has no
microfacet term at all, and ocean_grasp (ocean_grasp.cpp line 223) call the same function and
are Inf at exactly the same offsets: that function is the cause.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_ocean_mishchenko_normal.py
Exits 1 while eval is not finite there.
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")
offsets = np.array([0.0, 1e-6, 1e-5, 1e-4, 1e-3, 5e-2])
wo = np.stack([np.sin(offsets), 0 * offsets, np.cos(offsets)], 1).astype(np.float32)
SPECS = [{"type": "ocean_mishchenko", "wind_speed": 0.1},
         {"type": "ocean_mishchenko", "wind_speed": 5.0},
         # the same Fresnel Mueller matrix in ocean_grasp's glint and in maignan
         {"type": "ocean_grasp", "wavelength": 550.0, "wind_speed": 5.0},
         {"type": "maignan", "C": 5.0, "ndvi": 0.6}]
bad = False
for spec in SPECS:
    bsdf = mi.load_dict(spec)
    si = dr.zeros(mi.SurfaceInteraction3f, len(wo))
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    value = np.array(bsdf.eval(mi.BSDFContext(), si,
                               mi.Vector3f(*(np.ascontiguousarray(wo[:, k]) for k in range(3)))))
    for off, v in zip(offsets, value[0]):
        print(f"{spec}, wi = +z, wo {off:g} rad from it: eval = {v}")
    bad |= not bool(np.all(np.isfinite(value)))
sys.exit(1 if bad else 0)
