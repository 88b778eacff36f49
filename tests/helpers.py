"""Helpers shared by the tests: the library's batch layer, under the names the tests use."""

import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from mi_brdfs.checks.batch import evaluate
from mi_brdfs.checks.batch import random_directions as _random_directions
from mi_brdfs.checks.batch import sample as _sample


def random_directions(rng, n, lower=True):
    """n unit vectors, uniform on the sphere (``lower``) or the upper hemisphere, as (n, 3)."""
    return _random_directions(rng, n, sphere=lower)


def eval_pdf(bsdf, wi, wo, ctx=None, uv=None):
    """(f·cos (n, channels), pdf (n,), eval_pdf value, eval_pdf pdf) for pairs (wi, wo), at
    texture coordinates ``uv`` (one or (n, 2))."""
    e = evaluate(bsdf, wi, wo, ctx, uv)
    return e.value, e.pdf, e.eval_pdf_value, e.eval_pdf_pdf


def sample(bsdf, wi, s1, s2, ctx=None):
    """dict(wo (n,3), pdf, weight (n,channels), type, component) for samples (s1, s2) at wi."""
    s = _sample(bsdf, np.atleast_2d(wi), s1, s2, ctx)
    return dict(wo=s.wo, pdf=s.pdf, weight=s.weight, type=s.sampled_type,
                component=s.sampled_component)


def detailed_balance_error(bsdf, a, b, eta):
    """
    Across a refracting interface (η = 1 above the surface, ``eta`` below), importance
    transport: the largest |f(a→b)·η_a² − f(b→a)·η_b²| / (f(a→b)·η_a²) over the pairs (a, b)
    and the channels; pairs with a cosine below 0.05 or a value below 1e-3 are left out
    (float32 rounding there).
    """
    import mitsuba as mi

    ctx = mi.BSDFContext(mi.TransportMode.Importance)
    index2 = lambda v: np.where(v[:, 2] > 0, 1.0, eta ** 2)[:, None]  # noqa: E731
    lhs = eval_pdf(bsdf, a, b, ctx)[0] / np.abs(b[:, 2:3]) * index2(a)
    rhs = eval_pdf(bsdf, b, a, ctx)[0] / np.abs(a[:, 2:3]) * index2(b)
    keep = (np.minimum(np.abs(a[:, 2]), np.abs(b[:, 2])) > 0.05)[:, None] & (lhs > 1e-3)
    return np.max(np.abs(lhs - rhs)[keep] / lhs[keep])


def unbalance_the_shares(monkeypatch):
    """The dielectric compensation's refracted share from below without its 1/η²: detailed
    balance broken on purpose."""
    import drjit as dr

    from mi_brdfs.scattering import multiscatter

    shares = multiscatter.transmitted_shares
    monkeypatch.setattr(multiscatter, "transmitted_shares",
                        lambda t, eta, a, b: (shares(t, eta, a, b)[0],
                                              shares(t, eta, a, b)[1] * dr.square(eta)))


def closed_form(form, lobe, n):
    """E(0) of the specular lobe with ks = 1 (Lafortune & Willems 1994; Giesen 2009 for the
    halfway lobe)."""
    if form == "normalized":
        return 1.0
    if lobe == "mirror":
        return 2 * math.pi / (n + 2) if form == "lecture" else 2 * math.pi / (n + 1)
    if form == "lecture":
        return 8 * math.pi * (n + 2 ** (-n / 2)) / ((n + 2) * (n + 4))
    return 8 * math.pi * (1 - 2 ** (-(n + 2) / 2)) / (n + 2)


def eval_gradient(bsdf, key, value, step, wi, wo):
    """(d/dp by AD, central difference over ±``step``) of Σ eval over the pairs (wi, wo), where
    p is the parameter ``key`` of ``mi.traverse(bsdf)``, at ``value`` (an AD variant)."""
    import drjit as dr
    import mitsuba as mi

    from mi_brdfs.checks.batch import interaction, vectors

    params = mi.traverse(bsdf)
    si, w = interaction(wi, len(wi)), vectors(wo)

    def total(p, grad=False):
        params[key] = mi.Float(p)
        if grad:
            dr.enable_grad(params[key])
        params.update()
        return dr.sum(bsdf.eval(mi.BSDFContext(), si, w)[0])

    dr.backward(total(value, grad=True))
    grad = float(np.array(dr.grad(params[key]))[0])
    finite = (float(total(value + step)[0]) - float(total(value - step)[0])) / (2 * step)
    return grad, finite


#: The command line as a user runs it, in a subprocess.
CLI = [sys.executable, "-m", "mi_brdfs"]


def run(*args, env=None, cwd=None, timeout=120):
    """``mi-brdfs args`` in a subprocess (no progress bars): the CompletedProcess."""
    full_env = dict(os.environ, MI_BRDFS_NO_PROGRESS="1", **(env or {}))
    return subprocess.run(CLI + list(args), capture_output=True, text=True, env=full_env,
                          cwd=cwd, timeout=timeout)


def cli_one_line_error(args, message):
    """Run ``mi-brdfs args`` in-process: exit status 2 and one line ``mi-brdfs: error: ...``
    containing ``message``, no traceback; returns that line."""
    import sys
    from io import StringIO

    from mi_brdfs.cli import main

    err, saved = StringIO(), sys.stderr
    sys.stderr = err
    try:
        code = main(args)
    except SystemExit as e:  # argparse
        code = e.code
    finally:
        sys.stderr = saved
    text = err.getvalue()
    lines = [ln for ln in text.strip().splitlines() if ln]
    assert code == 2, (code, text)
    assert len(lines) == 1 and lines[0].startswith("mi-brdfs: error: "), text
    assert message in lines[0] and "Traceback" not in text, lines[0]
    return lines[0]


#: The absolute step of :func:`reference_conditioning`, the one the checks use
#: (:data:`mi_brdfs.checks.consistency.STEP`): float32 directions, and every direction a float32
#: computation derives from them (a half vector, a refracted ray), carry absolute errors of a few
#: units of the last place at 1.
def _step():
    from mi_brdfs.checks.consistency import STEP
    return STEP


def reference_conditioning(f, wi, wo):
    """
    How much the float64 function ``f(wi, wo)`` (values (n,) or (n, channels)) moves, relative
    to itself, when one coordinate of ``wi`` or ``wo`` moves by the float32 step
    :func:`_step` (12 evaluations; the largest change per pair). A float32 evaluation of the
    same model can differ from ``f`` by that much through the rounding of its directions alone,
    whichever CPU compiled it (drjit compiles for the host: the last bits differ between CPUs).
    """
    def rows(x):
        x = np.asarray(x, dtype=np.float64)
        return x.reshape(len(x), -1)

    base = rows(f(wi, wo))
    scale = np.maximum(np.abs(base), np.finfo(np.float64).tiny)
    spread = np.zeros(len(wi))
    for which in range(2):
        for axis in range(3):
            for sign in (-1.0, 1.0):
                a, b = np.array(wi, dtype=np.float64), np.array(wo, dtype=np.float64)
                (a if which == 0 else b)[:, axis] += sign * _step()
                change = np.abs(rows(f(a, b)) - base) / scale
                spread = np.fmax(spread, np.nan_to_num(change, nan=0.0).max(axis=1))
    return spread


#: A difference within this many times the conditioning (:func:`reference_conditioning`) is
#: rounding; the checks use the same factor
#: (:data:`mi_brdfs.checks.consistency.CONDITIONING_FACTOR`).
CONDITIONING_FACTOR = 8.0


def assert_matches_reference(value, f, wi, wo, rtol, what=""):
    """
    A float32 evaluation ``value`` (n,) or (n, channels) of a model against its float64
    reference ``f(wi, wo)``: per pair, |value − f| ≤ (rtol + 8·conditioning)·|f| + atol, where
    the conditioning is :func:`reference_conditioning` and atol is 1e-6 of the largest |f|
    (float32 keeps about 7 digits of the largest value a sum or a lobe is made of). No floor
    cuts through the data: the tolerance grows smoothly with |f|. Returns the largest ratio of
    difference to tolerance.
    """
    def rows(x):
        x = np.asarray(x, dtype=np.float64)
        return x.reshape(len(x), -1)

    a, b = rows(value), rows(f(wi, wo))
    cond = reference_conditioning(f, wi, wo)[:, None]
    tol = (rtol + CONDITIONING_FACTOR * cond) * np.abs(b) + 1e-6 * np.abs(b).max()
    ratio = np.abs(a - b) / tol
    i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    assert ratio[i] <= 1.0, (
        f"{what}: {a[i]:.6g} against the float64 reference {b[i]:.6g} at wi = {wi[i[0]]}, "
        f"wo = {wo[i[0]]}: difference {abs(a[i] - b[i]):.3g} > tolerance {tol[i]:.3g} "
        f"(rtol {rtol:g}, conditioning {cond[i[0], 0]:.3g})")
    return float(ratio[i])


#: Where the tests keep the MERL files they write (regenerated when missing; the name carries
#: the generator's version, so a changed generator never reads an old file).
MERL_DIR = Path(tempfile.gettempdir()) / f"mi_brdfs-tests-{os.getuid()}"


def glossy_brdf(wi, wo, rho_d=(0.3, 0.2, 0.1), rho_s=0.5, alpha=0.1):
    """A closed-form isotropic BRDF (n, 3) in float64: a coloured Lambertian term and a grey
    Beckmann lobe of the half vector with Kelemen & Szirmay-Kalos's (2001) approximation of
    the geometry term, ρs·D(θh)/(4 (ωi·h)²)."""
    wi, wo = np.asarray(wi, np.float64), np.asarray(wo, np.float64)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_h, cos_d = h[..., 2], np.sum(wi * h, axis=-1)
    tan2 = (1.0 - cos_h ** 2) / cos_h ** 2
    d = np.exp(-tan2 / alpha ** 2) / (np.pi * alpha ** 2 * cos_h ** 4)
    return np.asarray(rho_d) / np.pi + (rho_s * d / (4.0 * cos_d ** 2))[..., None]


def merl_file(name="glossy"):
    """A MERL file the tests share: ``glossy`` (:func:`glossy_brdf` at every bin's centre,
    unmeasured below the horizon, as ``mi-brdfs measure`` writes them)."""
    from mi_brdfs.measured import merl

    path = MERL_DIR / f"{name}-v1.binary"
    if not path.exists():
        MERL_DIR.mkdir(parents=True, exist_ok=True)
        wi, wo = merl.bin_directions()
        f = glossy_brdf(wi, wo)
        f[(wi[:, 2] <= 0) | (wo[:, 2] <= 0)] = np.nan
        merl.write(path, np.moveaxis(f.reshape(merl.RES + (3,)), -1, 0))
    return path


def spec(name):
    """The spec of plugin ``name`` with its defaults: ``merl`` needs a file."""
    return {"type": name, "filename": str(merl_file())} if name == "merl" else {"type": name}
