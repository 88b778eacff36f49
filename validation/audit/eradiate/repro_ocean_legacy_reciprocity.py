"""
ocean_legacy of eradiate-mitsuba 0.5.0 (λ = 550 nm, default wind 0.1 m/s) is not reciprocal,
though it does not declare NonSymmetric: at a = (θ 82.3°, φ 0.9°), b = (θ 64.6°, φ -91.1°),
f(a, b) and f(b, a) differ by 42 %. The asymmetry is all in its diffuse component (ctx.component
= 0: whitecaps, whose coverage is 9e-10 at this wind, and the water-leaving 'underlight' of the
6S ocean model, Vermote et al. 1997, https://doi.org/10.1109/36.581987); the glint component
(1) is 0 at this pair. The underlight multiplies the water's reflectance by the Fresnel
transmittance of the sun's direction into the water and of the view's out of it, two
different functions of the two directions (ocean_legacy.cpp, v0.5.0, eval_underlight lines
489-490: t_d from the downwelling table at wi, t_u from the upwelling table at wo), so the
model itself is not reciprocal; the plugin does not say so in its flags.

Run: .venv-eradiate/bin/python validation/audit/eradiate/repro_ocean_legacy_reciprocity.py
Exits 1 while the diffuse component is not reciprocal (relative asymmetry > 1e-3).
"""
import sys

import drjit as dr
import mitsuba as mi
import numpy as np

mi.set_variant("llvm_ad_rgb")


def direction(theta, phi):
    t, p = np.radians(theta), np.radians(phi)
    return [float(np.sin(t) * np.cos(p)), float(np.sin(t) * np.sin(p)), float(np.cos(t))]


def f(bsdf, wi, wo, component=None):
    si = dr.zeros(mi.SurfaceInteraction3f, 2)
    si.wi = mi.Vector3f(*wi)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    ctx = mi.BSDFContext()
    if component is not None:
        ctx.component = component
    return float(np.array(bsdf.eval(ctx, si, mi.Vector3f(*wo)))[0, 0]) / wo[2]


bsdf = mi.load_dict({"type": "ocean_legacy", "wavelength": 550.0})
a, b = direction(82.3, 0.9), direction(64.6, -91.1)
asym = {}
for component, name in ((None, "all"), (0, "diffuse (whitecaps, underlight)"), (1, "glint")):
    fab, fba = f(bsdf, a, b, component), f(bsdf, b, a, component)
    asym[component] = abs(fab - fba) / max(abs(fab), abs(fba), 1e-30)
    print(f"{name}: f(a,b) = {fab:.6g}, f(b,a) = {fba:.6g}, relative asymmetry "
          f"{asym[component]:.3g}")
sys.exit(1 if asym[0] > 1e-3 else 0)
