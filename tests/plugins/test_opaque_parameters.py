"""
A parameter set through ``mi.traverse`` is an input of the kernels, not a literal traced into
their code: after a first change of the value, a second one launches only kernels the first
compiled (eval, pdf, eval_pdf and sample alike), as Mitsuba's own plugins keep their values
opaque (``dr::make_opaque`` in their constructors and ``parameters_changed``), and as the
sampler tabulated anew for new values (``rtls``, ``rpv``, ``hapke``, ``he``) keeps its tables
where drjit keeps its own arrays (on a 64-byte line: the kernels depend on where a table
starts). Otherwise new values compile new kernels: an optimisation or ``mi-brdfs explore``
recompiles at each step.
"""

import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.checks import batch

WI = batch.direction(0.5)
WO = np.array([[0.3, 0.1, 0.95], [-0.5, 0.2, 0.84], [0.0, -0.7, 0.71], [0.6, 0.6, 0.53]])
U1 = np.array([0.1, 0.4, 0.6, 0.9])
U2 = np.array([[0.2, 0.7], [0.5, 0.1], [0.8, 0.4], [0.3, 0.9]])


def checker(value, other):
    return {"type": "checkerboard", "color0": value, "color1": other}


# (BSDF, key in mi.traverse, two values set one after the other); a checkerboard's key is
# that of the square the lanes' uv = (0.5, 0.5) falls on
CASES = [
    ({"type": "orennayar"}, "sigma", (0.3, 0.5)),
    ({"type": "orennayar", "sigma": checker(0.2, 0.4)}, "sigma.color1.value", (0.3, 0.5)),
    ({"type": "he"}, "sigma0", (0.25, 0.35)),
    ({"type": "he"}, "tau", (2.0, 4.0)),
    ({"type": "rtls"}, "f_iso.value", (0.25, 0.3)),
    ({"type": "rtls"}, "f_vol.value", (0.05, 0.1)),
    ({"type": "rtls"}, "f_geo.value", (0.01, 0.02)),
    ({"type": "rtls", "f_iso": checker(0.2, 0.3)}, "f_iso.color0.value", (0.25, 0.35)),
    ({"type": "rpv"}, "rho_0.value", (0.2, 0.3)),
    ({"type": "rpv"}, "g.value", (-0.1, 0.1)),
    ({"type": "hapke"}, "w.value", (0.6, 0.7)),
    ({"type": "hapke"}, "b.value", (0.3, 0.4)),
    ({"type": "hapke", "B_0": 0.5}, "h.value", (0.1, 0.2)),
]


def _run(bsdf):
    """eval, pdf, eval_pdf and sample on a few lanes: the values as one array."""
    e = batch.evaluate(bsdf, WI, WO)
    s = batch.sample(bsdf, WI, U1, U2)
    return np.concatenate([e.value.ravel(), e.pdf, s.pdf, s.weight.ravel(), s.wo.ravel()])


def _change(bsdf, params, key, value):
    """Set ``key`` through mi.traverse, as a user does (a Python float), and evaluate:
    the values and the hashes of the kernels launched."""
    params[key] = value
    params.update()
    dr.kernel_history_clear()
    values = _run(bsdf)
    return values, {k["hash"] for k in dr.kernel_history() if "hash" in k}


@pytest.mark.parametrize("spec,key,values", CASES,
                         ids=[f"{s['type']}-{k}" for s, k, _ in CASES])
@pytest.mark.filterwarnings("ignore::mi_brdfs.errors.MiBrdfsWarning")
def test01_a_second_change_reuses_the_first_ones_kernels(variant_llvm_ad_rgb, spec, key,
                                                         values):
    bsdf = mi.load_dict(spec)
    params = mi.traverse(bsdf)
    before = _run(bsdf)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        first_values, first = _change(bsdf, params, key, values[0])
        second_values, second = _change(bsdf, params, key, values[1])
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, False)
    assert not np.allclose(first_values, before) and not np.allclose(second_values, first_values)
    assert first and second <= first, f"{len(second - first)} kernels compiled anew"
