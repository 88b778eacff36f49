"""
``mi-brdfs tables``: the directional albedo E(μ, α) of ``cooktorrance``'s single-scattering
lobe with F ≡ 1, per distribution and masking, and its average E_avg(α), the tables of the
energy compensation (:mod:`mi_brdfs.scattering.multiscatter`, Kulla & Conty 2017).

Built from the plugin itself, deterministically: at each node (μ, α), E is the mean sample weight
f·cosθo/pdf of ``sample`` with ``sample_visible=false`` over a stratified n × n grid of its 2D
sample. That sampler draws microfacet normals from D·cosθ, whose density the plugin computes
exactly, so the mean weight converges to ∫ f cosθo dωo, the albedo of ``eval``. (Smith's
visible normals for Beckmann would not do: Mitsuba's sampler draws the exact distribution but
its pdf uses Walter's rational G1, so the mean weight departs from ∫ f cosθo by up to 3e-3.)
E_avg = 2∫E(μ)μ dμ is the exact integral of the interpolant that
:class:`~mi_brdfs.scattering.multiscatter.Table` evaluates (piecewise linear in x = sqrt μ:
E_avg = 4∫E(x)x³dx, a cubic per segment, by Gauss-Legendre with 3 nodes per segment).
"""

from __future__ import annotations

import numpy as np

#: Nodes in μ (uniform in sqrt μ) and α (uniform in sqrt(α/α_max)); the largest α.
N_MU, N_ALPHA, ALPHA_MAX = 64, 128, 2.0

#: The incidence cosine at which the node μ = 0 is computed (a lobe at μ = 0 exactly is
#: undefined: ωi lies in the surface); it stands for μ < 2.5e-4 (θ > 89.99°).
MU_GRAZING = 1e-4

#: Samples per node: an n × n grid (512: within 7e-5 of 4096 × 4096 from μ = 0.016 up, and
#: within 1e-5 of GGX's exact visible-normal sampler at 1024 × 1024).
SAMPLES = 512

#: The distributions and maskings tabulated, as the plugin names them.
KINDS = ("beckmann", "ggx")
SHADOWINGS = ("smith", "vcavity")

#: The clustering exponent p of the grid's first coordinate (see :func:`albedo_row`).
CLUSTER = 3


def mu_nodes(n_mu: int = N_MU) -> np.ndarray:
    """The incidence cosines of the nodes: x² on x uniform in [0, 1], the first MU_GRAZING."""
    mu = np.linspace(0.0, 1.0, n_mu) ** 2
    mu[0] = MU_GRAZING
    return mu


def alpha_nodes(n_alpha: int = N_ALPHA, alpha_max: float = ALPHA_MAX) -> np.ndarray:
    """The roughnesses of the nodes: α_max·y² on y uniform in [0, 1], the first (0) at the
    plugin's smallest α (:data:`~mi_brdfs.scattering.microfacet.ALPHA_MIN`)."""
    from .scattering.microfacet import ALPHA_MIN

    alpha = alpha_max * np.linspace(0.0, 1.0, n_alpha) ** 2
    alpha[0] = ALPHA_MIN
    return alpha


def albedo_row(kind: str, shadowing: str, alpha: float, mus: np.ndarray,
               samples: int = SAMPLES, chunk: int = 1 << 22) -> np.ndarray:
    """E(μ) at roughness ``alpha`` for each of ``mus``, from the plugin's sample weights (F ≡ 1),
    in the current (JIT) variant; ``chunk`` lanes at a time."""
    import drjit as dr
    import mitsuba as mi

    bsdf = mi.load_dict({"type": "cooktorrance", "distribution": kind, "shadowing": shadowing,
                         "fresnel": "none", "alpha": float(alpha), "sample_visible": False})
    per_node = samples * samples
    nodes = max(1, chunk // per_node)
    out = []
    for start in range(0, len(mus), nodes):
        mu_np = np.asarray(mus[start:start + nodes], np.float32)
        idx = dr.arange(mi.UInt32, len(mu_np) * per_node)
        node, cell = idx // per_node, idx % per_node
        mu = dr.gather(mi.Float, mi.Float(mu_np), node)
        si = dr.zeros(mi.SurfaceInteraction3f, dr.width(idx))
        si.wi = mi.Vector3f(dr.safe_sqrt(1.0 - mu * mu), 0.0, mu)
        # both coordinates through the periodising map u = t − sin(2πt)/(2π) (Sidi 1993),
        # du/dt = 1 − cos(2πt): nodes cluster at the edges of the square, where the samplers
        # put the tails of the slope distribution and the grazing directions
        tx = (mi.Float(cell // samples) + 0.5) / samples
        ty = (mi.Float(cell % samples) + 0.5) / samples
        sx, cx = dr.sincos(dr.two_pi * tx)
        sy, cy = dr.sincos(dr.two_pi * ty)
        u = mi.Point2f(tx - sx / dr.two_pi, ty - sy / dr.two_pi)
        jacobian = (1.0 - cx) * (1.0 - cy)
        # (the 1D sample picks among lobes, and the D·cosθ sampler of one lobe needs none)
        _, weight = bsdf.sample(mi.BSDFContext(), si, mi.Float(0.5), u)
        w = dr.select(dr.isfinite(weight.x), weight.x * jacobian, 0.0)
        out.append(np.asarray(dr.block_sum(mi.Float64(w), per_node), np.float64) / per_node)
    return np.concatenate(out)


def average(E: np.ndarray) -> np.ndarray:
    """
    E_avg = 2∫E(μ)μ dμ = 4∫E(x)x³dx of rows of E that are piecewise linear in x = sqrt μ on
    uniform nodes (exact: a cubic per segment, 3 Gauss-Legendre nodes each).
    """
    E = np.atleast_2d(E)
    n = E.shape[1]
    x, w = np.polynomial.legendre.leggauss(3)
    t, w = (x + 1.0) / 2.0, w / 2.0  # on [0, 1]
    h = 1.0 / (n - 1)
    total = np.zeros(E.shape[0])
    for tk, wk in zip(t, w):
        xs = (np.arange(n - 1) + tk) * h
        values = E[:, :-1] * (1.0 - tk) + E[:, 1:] * tk
        total += 4.0 * h * wk * (values * xs ** 3).sum(axis=1)
    return total


def build(kinds=KINDS, shadowings=SHADOWINGS, n_mu: int = N_MU, n_alpha: int = N_ALPHA,
          samples: int = SAMPLES, progress=None) -> dict[str, np.ndarray]:
    """The arrays of the table file: ``E_<kind>-<shadowing>`` (n_alpha, n_mu),
    ``E_avg_<kind>-<shadowing>`` (n_alpha,), ``alpha_max``, ``samples``."""
    mus, alphas = mu_nodes(n_mu), alpha_nodes(n_alpha)
    out = {"alpha_max": np.float64(ALPHA_MAX), "samples": np.int64(samples)}
    done = 0
    for kind in kinds:
        for shadowing in shadowings:
            rows = []
            for alpha in alphas:
                rows.append(albedo_row(kind, shadowing, alpha, mus, samples))
                done += 1
                if progress is not None:
                    progress.update(done, f"{kind}-{shadowing}")
            # as the plugin reads it; ≤ 1 (float32 rounding of D·cosθ's weights at μ → 0 must
            # not create energy)
            E = np.minimum(np.array(rows), 1.0).astype(np.float32)
            out[f"E_{kind}-{shadowing}"] = E
            out[f"E_avg_{kind}-{shadowing}"] = average(E.astype(np.float64)).astype(np.float32)
    return out


def write(path, arrays: dict) -> None:
    """The arrays as a compressed ``.npz`` at ``path``, written whole or not at all."""
    import os
    from pathlib import Path

    path = Path(path)
    tmp = path.with_name(path.name + ".part.npz")
    np.savez_compressed(tmp, **arrays)
    os.replace(tmp, path)
