"""
Stability sweep: random and adversarial directions × a grid of parameters, counting NaN, Inf and
negative values in ``eval``, ``pdf``, ``sample()`` weights and ``bs.pdf``, with the worst inputs.

Adversarial directions are those where the algebra of BSDFs divides by zero or loses its
precision: exactly normal, grazing (cosθ = 0, ±1e-7, 1e-4), back-facing, V = −L, wi = wo, the
mirror direction itself and directions a hair away from it. Samples use extreme random numbers
(0, 1 − 2⁻²⁴, 0.5) as well as random ones.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from ..bsdfspec import describe, load_bsdf, loaded_once
from ..errors import MiBrdfsError, arguments, counts, nonempty_specs, valid_seed
from . import batch
from .result import CheckResult

ONE_MINUS = 1.0 - 2.0 ** -24


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def adversarial_incident() -> tuple[np.ndarray, list[str]]:
    """Incident directions that stress a BSDF, with a label each."""
    cases = {
        "normal": [0, 0, 1],
        "grazing cos=1e-4": [np.sqrt(1 - 1e-8), 0, 1e-4],
        "grazing cos=1e-7": [1, 0, 1e-7],
        "grazing cos=6e-17": [1, 0, np.cos(np.pi / 2)],  # what cos(90°) rounds to
        "tangent cos=0": [1, 0, 0],
        "below cos=-1e-7": [1, 0, -1e-7],
        "back-facing": [0.3, 0.2, -0.9],
        "oblique": [0.6, 0.3, 0.74],
        "near normal": [1e-4, 0, 1],
    }
    return _unit(list(cases.values())), list(cases)


def adversarial_pairs() -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(wi, wo) pairs that stress a BSDF, with a label each."""
    wis, names = adversarial_incident()
    pairs_wi, pairs_wo, labels = [], [], []
    for wi, name in zip(wis, names):
        mirror = np.array([-wi[0], -wi[1], wi[2]])
        for wo, what in ((wi, "wo = wi"), (-wi, "wo = -wi (V = -L)"), (mirror, "mirror"),
                         (_unit(mirror + [1e-6, 0, 0]), "mirror + 1e-6"),
                         (_unit(mirror + [0, 1e-3, 0]), "mirror + 1e-3"),
                         ([0, 0, 1], "wo normal"), ([1, 0, 0], "wo tangent"),
                         ([-1, 0, 1e-7], "wo grazing"), ([0, 0, -1], "wo below")):
            pairs_wi.append(wi)
            pairs_wo.append(_unit(wo))
            labels.append(f"wi {name}, {what}")
    return np.array(pairs_wi), np.array(pairs_wo), labels


@dataclass
class StabilityRow:
    """The counts for one parameter set."""

    spec: object
    counts: dict = field(default_factory=dict)   # quantity -> {"nan", "inf", "negative"}
    worst: list = field(default_factory=list)    # (quantity, label or inputs, value)
    rejected: str = ""                           # the plugin refused these parameters
    failed_nonfinite: int = 0                    # NaN/Inf bs.pdf of failed (weight 0) samples

    @property
    def bad(self) -> int:
        return sum(sum(c.values()) for c in self.counts.values())


class _Labels:
    """The label of each row: the stress cases' as given, a random row's made only when a
    failing row asks for it (formatting every random pair's took seconds per sweep)."""

    def __init__(self, fixed: list, text, *arrays):
        self.fixed, self.text, self.arrays = fixed, text, arrays

    def __getitem__(self, i: int) -> str:
        if i < len(self.fixed):
            return self.fixed[i]
        return self.text(*(np.round(a[i - len(self.fixed)], 4).tolist() for a in self.arrays))


def _count(name: str, values: np.ndarray, labels, row: StabilityRow, rows=None) -> None:
    """Count the NaN, Inf and negative rows of ``values``; the first three of each kind are
    kept with their labels (``labels[rows[i]]`` where ``values`` is a subset ``rows``)."""
    values = np.asarray(values, dtype=np.float64)
    values = values.reshape(len(values), -1) if values.size else values.reshape(0, 1)
    nan = np.isnan(values).any(axis=1)
    inf = np.isinf(values).any(axis=1)
    neg = (values < 0).any(axis=1)
    row.counts[name] = {"nan": int(nan.sum()), "inf": int(inf.sum()), "negative": int(neg.sum())}
    for mask, what in ((nan, "NaN"), (inf, "Inf"), (neg, "negative")):
        for i in np.flatnonzero(mask)[:3]:
            label = labels[int(rows[i]) if rows is not None else int(i)]
            row.worst.append((name, what, label, values[i].tolist()))


@loaded_once()
@counts("n_random")
@arguments(seed=valid_seed)
def sweep_one(spec, n_random: int | None = None, seed: int = 0) -> StabilityRow:
    """Every stress direction and ``n_random`` random pairs/samples for one parameter set."""
    row = StabilityRow(spec)
    try:
        bsdf = load_bsdf(spec)
    except MiBrdfsError as e:
        row.rejected = str(e)
        return row
    n_random = n_random or (20_000 if batch.is_jit() else 200)
    rng = np.random.default_rng(seed)
    wi, wo, labels = adversarial_pairs()
    rwi = batch.random_directions(rng, n_random)
    rwo = batch.random_directions(rng, n_random)
    wi, wo = np.concatenate([wi, rwi]), np.concatenate([wo, rwo])
    labels = _Labels(labels, lambda a, b: f"random wi {a}, wo {b}", rwi, rwo)
    e = batch.evaluate(bsdf, wi, wo)
    _count("eval", e.value, labels, row)
    _count("pdf", e.pdf, labels, row)
    _count("eval_pdf", np.concatenate([e.eval_pdf_value, e.eval_pdf_pdf[:, None]], axis=1),
           labels, row)

    inc, names = adversarial_incident()
    u = [0.0, 0.5, ONE_MINUS]
    grid = list(itertools.product(range(len(inc)), u, u, u))
    swi = np.concatenate([inc[[g[0] for g in grid]], rwi])
    s1 = np.concatenate([[g[1] for g in grid], rng.random(n_random)])
    s2 = np.concatenate([[[g[2], g[3]] for g in grid], rng.random((n_random, 2))])
    slabels = _Labels([f"sample at wi {names[g[0]]}, u = ({g[1]:g}, {g[2]:g}, {g[3]:g})"
                       for g in grid], lambda a: f"sample at random wi {a}", rwi)
    s = batch.sample(bsdf, swi, s1, s2)
    _count("weight", s.weight, slabels, row)
    # A sample with weight 0 has failed: integrators discard it, and its other fields are
    # undefined (Mitsuba's roughconductor returns bs.pdf = NaN at exactly tangent incidence).
    produced = np.any(s.weight != 0, axis=1)
    idx = np.flatnonzero(produced)
    _count("bs.pdf", s.pdf[idx], slabels, row, rows=idx)
    row.failed_nonfinite = int((~produced & ~np.isfinite(s.pdf)).sum())
    norm_err = np.abs(np.linalg.norm(s.wo, axis=1) - 1)
    bad_wo = produced & ~(norm_err < 1e-3)
    row.counts["bs.wo"] = {"nan": int((produced & np.isnan(s.wo).any(axis=1)).sum()), "inf": 0,
                           "negative": 0, "not unit": int(bad_wo.sum())}
    for i in np.flatnonzero(bad_wo)[:3]:
        row.worst.append(("bs.wo", "not a unit vector", slabels[i], s.wo[i].tolist()))
    return row


def parameter_grid(base: dict, **axes) -> list[dict]:
    """Every combination: ``parameter_grid({'type': 'phong'}, exponent=[0, 1e6], ...)``."""
    names = list(axes)
    return [dict(base, **dict(zip(names, values)))
            for values in itertools.product(*(axes[k] for k in names))]


@loaded_once()
@counts("n_random")
@arguments(specs=nonempty_specs, seed=valid_seed)
def check_stability(specs, n_random: int | None = None, seed: int = 0) -> CheckResult:
    """
    The sweep over ``specs`` (one spec or a list, e.g. from :func:`parameter_grid`): passes when
    no eval, pdf, weight or bs.pdf is NaN, Inf or negative, and every sampled direction is a
    unit vector. Parameter sets the plugin rejects (with its one-line error) are listed, not
    failed.
    """
    specs = specs if isinstance(specs, list) else [specs]
    rows = [sweep_one(s, n_random, seed) for s in specs]
    bad = sum(r.bad for r in rows)
    rejected = [r for r in rows if r.rejected]
    tested = len(rows) - len(rejected)
    label = describe(specs[0]) + (f" and {len(specs) - 1} more parameter sets" if len(specs) > 1
                                  else "")
    if bad == 0:
        msg = (f"stability: {label}: no NaN, Inf or negative value in eval, pdf, eval_pdf, "
               f"weights and bs.pdf over {tested} parameter set(s) × stress and random directions")
    else:
        first = next(r for r in rows if r.bad)
        q, what, where, value = first.worst[0]
        msg = (f"stability: {label}: {bad} bad values; first: {what} {q} for "
               f"{describe(first.spec)} at {where} (value {value})")
    if rejected:
        msg += f"; {len(rejected)} parameter set(s) rejected by the plugin"
    harmless = sum(r.failed_nonfinite for r in rows)
    if harmless:
        msg += f"; {harmless} failed samples (weight 0) carry a non-finite bs.pdf (harmless)"
    return CheckResult("stability", bad == 0, float(bad), 0, msg, details={"rows": rows})
