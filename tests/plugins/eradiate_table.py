"""
What the comparisons of the Earth-observation plugins with Eradiate's share: the committed
tables validation/eradiate/<plugin>.json (``make eradiate-values``: Eradiate's plugins of
``eradiate-mitsuba``, evaluated in a virtual environment of their own, at fixed pairs and
parameter sets, in float32 and float64), the plugin's eval at the same pairs, and the rules:
where Eradiate's value is finite and non-negative the plugin's equals it within a tolerance
per pair; where it is negative (by more than the tolerance) the plugin's is 0 (a clamp);
where it is not finite the plugin's is finite. Each kind is counted. A plugin's own rule may
excuse pairs (``ocean``: exact backscatter, where Eradiate's value is 0/0).
"""

import json
import warnings
from pathlib import Path

import numpy as np
from helpers import CONDITIONING_FACTOR, reference_conditioning

from mi_brdfs.checks.batch import interaction, vectors
from mi_brdfs.errors import MiBrdfsWarning

FOLDER = Path(__file__).resolve().parents[2] / "validation" / "eradiate"
#: The unit roundoff of each of Eradiate's variants.
UNIT = {"scalar_rgb": 2.0 ** -24, "scalar_mono_double": 2.0 ** -53}


def load_table(plugin: str):
    """(kind (n,), wi (n, 3), wo (n, 3), {set name: params}, {(set, variant): values (n,)})
    of ``validation/eradiate/<plugin>.json``."""
    data = json.loads((FOLDER / f"{plugin}.json").read_text())
    rows = data["rows"]
    kind = np.array([r[0] for r in rows])
    wi, wo = (np.array([r[k] for r in rows], dtype=np.float64) for k in (1, 2))
    columns = {tuple(c.split()): np.array([float(r[i]) for r in rows])
               for i, c in enumerate(data["columns"]) if i >= 3}
    return kind, wi, wo, data["sets"], columns


def plugin_values(plugin: str, params: dict, wi, wo) -> np.ndarray:
    """Our plugin's eval at every pair: one array call (channel 0; the parameters are
    grey), its warnings at load silenced."""
    import mitsuba as mi

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MiBrdfsWarning)
        bsdf = mi.load_dict({"type": plugin, **params})
    value = bsdf.eval(mi.BSDFContext(), interaction(wi, len(wi)), vectors(wo))
    return np.array(value[0], dtype=np.float64)


def base_tolerance(rtol, f, wi, wo, theirs) -> np.ndarray:
    """The tolerance per pair that every comparison starts from: ``rtol`` (a number or one per
    pair) and the directions' conditioning of ``f(wi, wo)`` (the float64 model's f·cosθo, as
    in helpers.assert_matches_reference) relative to Eradiate's value, plus 10⁻⁶ of its
    largest finite value."""
    cond = reference_conditioning(f, wi, wo)
    return (rtol + CONDITIONING_FACTOR * cond) * np.abs(theirs) + \
        1e-6 * np.abs(theirs[np.isfinite(theirs)]).max()


def compare(ours, theirs, tol, wi, wo, what, excused=None) -> tuple[int, int, int]:
    """The rules of the module's docstring with ``tol`` (n,) the tolerance per pair; returns
    (agree, Eradiate negative, Eradiate not finite) counts. ``excused`` (n,) bool: pairs where
    the plugin's value may differ from Eradiate's (a rule of the plugin's own, checked by the
    caller); those that differ are not counted as agreeing. Raises AssertionError naming the
    first pair that breaks a rule."""
    finite = np.isfinite(theirs)
    tol = np.where(finite, tol, 0.0)
    differ = finite & ~(np.abs(ours - np.maximum(theirs, 0.0)) <= tol)
    excused = differ & (False if excused is None else excused)
    bad = (differ & ~excused) | ((theirs < -tol) & (ours != 0)) | ~np.isfinite(ours)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise AssertionError(
            f"{what}: {bad.sum()} pairs differ from Eradiate's, e.g. {ours[i]:.7g} against "
            f"{theirs[i]:.7g} at wi = {wi[i]}, wo = {wo[i]} (tolerance {tol[i]:.3g})")
    return (int((finite & (theirs >= 0) & ~excused).sum()), int((theirs < 0).sum()),
            int((~finite).sum()))


def counts_against_eradiate(plugin: str, table, compare_one) -> dict:
    """{(set, variant): counts} of ``compare_one(ours, theirs, params, variant, what)`` for every
    column of ``table`` (:func:`load_table`'s), our plugin evaluated once per parameter set,
    finite and non-negative at every pair."""
    _, wi, wo, sets, columns = table
    ours = {name: plugin_values(plugin, params, wi, wo) for name, params in sets.items()}
    for name, values in ours.items():
        assert np.all(values >= 0) and np.all(np.isfinite(values)), (plugin, name)
    return {(name, variant): compare_one(ours[name], theirs, sets[name], variant,
                                         f"{plugin} {name} against Eradiate's {variant}")
            for (name, variant), theirs in columns.items()}
