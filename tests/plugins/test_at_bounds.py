"""
Every plugin at the ends of its parameters' ranges, in scalar_rgb, where the terms compute with
Python floats: there ``dr.select`` evaluates both of its branches, so a division it guards
raises ZeroDivisionError unless its denominator is made safe (``he`` with σ0 = 0 once raised
in every call). eval, pdf, eval_pdf and sample at normal, oblique, grazing and opposite
directions must return finite values, without an exception.
"""

import math

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import merl_file

from mi_brdfs import registry

S = math.sqrt(0.5)
DIRECTIONS = [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (S, 0.0, S), (-S, 0.0, S), (0.0, 0.0, -1.0)]
SAMPLES = [(0.0, (0.0, 0.0)), (0.5, (0.5, 0.5)), (0.99999994, (0.99999994, 0.99999994)),
           (0.3, (0.0, 0.99999994))]

#: Each plugin at the ends of its ranges (0 where allowed), in the forms that change the terms.
BOUNDS = {
    "lambert": [{"reflectance": 0.0}, {"reflectance": 1.0}],
    "orennayar": [{"sigma": s, "form": f} for s in (0.0, math.pi / 2)
                  for f in ("qualitative", "full")],
    "phong": [{"exponent": n, "lobe": lobe, "form": "original", "specular_reflectance": 1.0,
               "diffuse_reflectance": 0.0} for n in (0.0, 1e30) for lobe in ("mirror",
                                                                             "halfway")],
    "ward": [{"alpha_u": a, "alpha_v": b, "form": f, "diffuse_reflectance": 0.0}
             for a, b in ((0.0, 0.0), (0.0, 1e3)) for f in ("balanced", "original", "duer")],
    "ashikhmin": [{"nu": a, "nv": b, "specular_reflectance": 1.0, "diffuse_reflectance": 1.0}
                  for a, b in ((0.0, 0.0), (0.0, 1e30))],
    "lafortune": [{"cx_0": c, "cy_0": c, "cz_0": z, "exponent_0": n, "diffuse_reflectance": 0.0,
                   "specular_reflectance_0": 1.0}
                  for c, z in ((0.0, 0.0), (1e30, 1e30)) for n in (0.0, 1e30)],
    "cooktorrance": [dict({"alpha": a}, **extra) for a in (0.0, 1e3) for extra in (
        {"material": "none", "shadowing": "vcavity", "fresnel": "schlick"},
        {"eta": 1e6, "k": 1e6, "multiscatter": True, "shadowing": "smith"},
        {"transmission": True, "eta": 1e-6, "distribution": "ggx"},
        {"transmission": True, "eta": 1e6, "sample_visible": False})],
    "merl": [{"filename": str(merl_file()), "scale": s} for s in (0.0, 1e3)],
    "he": [{"sigma0": 0.0, "diffuse_reflectance": 1.0, "specular_reflectance": 0.0},
           {"sigma0": 0.0, "tau": 1e-3, "variant": "holzschuch"},
           {"sigma0": 1e3, "tau": 1e4, "variant": "paper"},
           {"sigma0": 1e3, "tau": 1e-3}, {"sigma0": 0.05, "tau": 1e4, "material": "Au"}],
    "rtls": [{"f_iso": f, "f_vol": f, "f_geo": f, "h": h, "r": r, "b": b}
             for f in (0.0, 1.0) for h, r, b in ((1e-3, 1e3, 1e-3), (1e3, 1e-3, 1e3))],
    "rpv": [{"rho_0": 0.0, "k": 0.0, "g": -0.999, "rho_c": 0.0},
            {"rho_0": 1.0, "k": 0.0, "g": 0.999, "rho_c": 2.0},
            {"rho_0": 1.0, "k": 3.0, "g": -0.999, "rho_c": 2.0}],
    "hapke": [{"w": 0.0, "b": 0.0, "c": 0.0, "theta": 0.0, "B_0": 0.0, "h": 0.0},
              {"w": 1.0, "b": 1.0, "c": 1.0, "theta": 90.0, "B_0": 1.0, "h": 1.0},
              {"w": 1.0, "b": 0.0, "c": 1.0, "theta": 0.0, "B_0": 1.0, "h": 0.0},
              {"w": 1.0, "b": 1.0, "c": 0.0, "theta": 90.0, "B_0": 0.0, "h": 1.0}],
    "ocean": [{"wind_speed": 0.0, "eta": 1e-6, "k": 0.0, "ext_ior": 1e6},
              {"wind_speed": 0.0, "wind_direction": 0.0, "eta": 1e6, "k": 1e6, "ext_ior": 1e-6},
              {"wind_speed": 37.54, "whitecaps": 1.0, "wind_direction": 90.0},
              {"wind_speed": 37.54, "whitecaps": True, "shadowing": False}],
    "hk": [{"sigma_s": s, "sigma_a": a, "thickness": t, "g": g, "eta": eta}
           for s, a in ((0.0, 0.0), (1e6, 0.0), (0.0, 1e6), (1e6, 1e6))
           for t, g, eta in ((1e-6, -0.99, 1.0), (1e6, 0.99, 1e6))] +
          [{"sigma_s": 1e6, "thickness": 1e6, "g": 0.99, "eta": 1e6, "diffuse_reflectance": 1.0},
           {"sigma_s": 0.0, "thickness": 1e-6, "eta": 1.0, "diffuse_reflectance": 1.0}],
}


def test01_every_plugin_is_here():
    assert set(BOUNDS) == set(registry.PLUGINS)


@pytest.mark.filterwarnings("ignore")  # energy and clamping warnings: values kept, as meant
@pytest.mark.parametrize("plugin", sorted(BOUNDS))
def test02_finite_at_the_bounds_in_scalar_rgb(variant_scalar_rgb, plugin):
    ctx = mi.BSDFContext()
    for params in BOUNDS[plugin]:
        bsdf = mi.load_dict(dict(type=plugin, **params))
        si = dr.zeros(mi.SurfaceInteraction3f)
        for wi in DIRECTIONS:
            si.wi = mi.Vector3f(wi)
            values = []
            for wo in DIRECTIONS:
                wo = mi.Vector3f(wo)
                values += [bsdf.eval(ctx, si, wo), bsdf.pdf(ctx, si, wo),
                           *bsdf.eval_pdf(ctx, si, wo)]
            for s1, s2 in SAMPLES:
                bs, weight = bsdf.sample(ctx, si, s1, mi.Point2f(*s2))
                values += [weight, bs.pdf]
            assert all(np.isfinite(np.array(v, dtype=np.float64)).all() for v in values), \
                (plugin, params, wi)
