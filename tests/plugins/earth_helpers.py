"""
What the tests of the Earth-observation plugins (rtls, rpv, hapke, ocean) share: directions by
angle, the random pairs with exact backscatter and near-grazing views, the float64 reference's
f·cosθo, loading with or without the warnings at load, the one-line parameter errors and the
shape of a one-lobe plugin.
"""

import math
import warnings

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest
from helpers import random_directions

from mi_brdfs.errors import MiBrdfsWarning


def direction(theta, phi=0.0) -> np.ndarray:
    """Unit vectors (…, 3) at polar angles ``theta`` and azimuths ``phi`` (radians)."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
                    -1)


def hot_spot_pairs(rng, n):
    """Random pairs, a tenth exact backscatter (ωo = ωi), a tenth with ωo near grazing
    (cosθo in [10⁻³, 10⁻²])."""
    wi, wo = random_directions(rng, n, lower=False), random_directions(rng, n, lower=False)
    k = n // 10
    wo[:k] = wi[:k]
    wo[k:2 * k] = direction(np.arccos(rng.uniform(1e-3, 1e-2, k)), rng.uniform(0, 6.3, k))
    return wi, wo


def cos_reference(model):
    """The float64 model's f·cosθo (n, channels), as assert_matches_reference takes it."""
    return lambda wi, wo: model.brdf(wi, wo) * wo[:, 2:3]


def load_quietly(spec):
    """mi.load_dict without the plugin's warnings at load (energy, clamp)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        return mi.load_dict(spec)


def load_warnings(spec):
    """(the BSDF, the messages of the MiBrdfsWarnings its load gave)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bsdf = mi.load_dict(spec)
    return bsdf, [str(w.message) for w in caught if issubclass(w.category, MiBrdfsWarning)]


def assert_load_error(spec, message):
    """Loading ``spec`` raises, with ``message`` in the error."""
    with pytest.raises(RuntimeError) as e:
        mi.load_dict(spec)
    assert message in str(e.value)


def assert_one_glossy_lobe(bsdf, name, parameters):
    """One component, glossy reflection on the front side; the string starts ``name[`` and
    names every parameter; eval 0 and pdf finite below the surface."""
    assert bsdf.component_count() == 1
    assert bsdf.flags(0) == int(mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide)
    text = str(bsdf)
    assert text.startswith(f"{name}[") and all(f"{k} = " in text for k in parameters)
    si = dr.zeros(mi.SurfaceInteraction3f)
    si.wi = mi.Vector3f(0.0, 0.0, -1.0)
    assert float(dr.sum(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1)))) == 0.0
    assert math.isfinite(float(bsdf.pdf(mi.BSDFContext(), si, mi.Vector3f(0, 0, 1))))


def singular_pairs(theta_deg, cos_grazing):
    """Pairs at a model's singular places: exact backscatter at the zeniths ``theta_deg``
    (θi = θo = 0 first), normal incidence towards three grazing views (cosθo the two of
    ``cos_grazing`` and 0), and incidence at the first of them towards the same three."""
    w = direction(np.radians(theta_deg), 0.4)
    z = np.array([[0.0, 0.0, 1.0]])
    graze = np.array([[1.0, 0.0, cos_grazing[0]], [-1.0, 0.0, cos_grazing[1]], [0.0, 1.0, 0.0]])
    graze /= np.linalg.norm(graze, axis=1, keepdims=True)
    wi = np.concatenate([w, np.repeat(z, 3, 0), np.repeat(graze[:1], 3, 0)])
    wo = np.concatenate([w, graze, graze])
    return wi, wo
