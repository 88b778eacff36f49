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
:class:`~mi_brdfs.scattering.multiscatter.AlbedoTable` evaluates (piecewise linear in x = sqrt μ:
E_avg = 4∫E(x)x³dx, a cubic per segment, by Gauss-Legendre with 3 nodes per segment).
"""

from __future__ import annotations

import numpy as np

from .scattering.multiscatter import MU_GRAZING, alpha_nodes, average, mu_nodes  # noqa: F401

#: Nodes in μ (uniform in sqrt μ) and α (uniform in sqrt(α/α_max)); the largest α.
N_MU, N_ALPHA, ALPHA_MAX = 64, 128, 2.0

#: Samples per node: an n × n grid (512: within 7e-5 of 4096 × 4096 from μ = 0.016 up, and
#: within 1e-5 of GGX's exact visible-normal sampler at 1024 × 1024).
SAMPLES = 512

#: The dielectric's tables (``transmission``): nodes in μ, α (as above, up to ALPHA_MAX), and in
#: the relative index η, uniform in log η over [1/ETA_MAX, ETA_MAX] (an even count: η = 1 is
#: no interface and no node); samples per node.
N_MU_DIELECTRIC, N_ALPHA_DIELECTRIC, N_ETA, ETA_MAX = 32, 64, 32, 3.0
SAMPLES_DIELECTRIC = 256

#: The distributions and maskings tabulated, as the plugin names them.
KINDS = ("beckmann", "ggx")
SHADOWINGS = ("smith", "vcavity")


def eta_nodes(n_eta: int = N_ETA, eta_max: float = ETA_MAX) -> np.ndarray:
    """The relative indices of the dielectric's nodes: uniform in log η on [1/η_max, η_max]."""
    return np.exp(np.linspace(-np.log(eta_max), np.log(eta_max), n_eta))


def albedo_row(kind: str, shadowing: str, alpha: float, mus: np.ndarray,
               samples: int = SAMPLES, chunk: int = 1 << 22) -> np.ndarray:
    """E(μ) at roughness ``alpha`` for each of ``mus``, from the plugin's sample weights (F ≡ 1),
    in the current (JIT) variant; ``chunk`` lanes at a time."""
    import mitsuba as mi

    bsdf = mi.load_dict({"type": "cooktorrance", "distribution": kind, "shadowing": shadowing,
                         "fresnel": "none", "alpha": float(alpha), "sample_visible": False})
    return mean_weights(bsdf, mi.BSDFContext(), mus, samples, chunk)


def dielectric_row(kind: str, alpha: float, eta: float, mus: np.ndarray,
                   samples: int = SAMPLES_DIELECTRIC, chunk: int = 1 << 22) -> np.ndarray:
    """E_R+T(μ) of the rough dielectric (``transmission``) with relative index ``eta``, lit from
    above at each of ``mus``: the fraction of the light arriving along ωi that the single
    scattering reflects or refracts (importance transport), in the current (JIT) variant."""
    import mitsuba as mi

    bsdf = mi.load_dict({"type": "cooktorrance", "transmission": True, "distribution": kind,
                         "eta": float(eta), "alpha": float(alpha), "sample_visible": False})
    return mean_weights(bsdf, mi.BSDFContext(mi.TransportMode.Importance), mus, samples, chunk)


def mean_weights(bsdf, ctx, mus: np.ndarray, samples: int, chunk: int) -> np.ndarray:
    """The mean sample weight of ``bsdf`` (channel 0) at each incidence cosine of ``mus`` over
    a periodised ``samples`` × ``samples`` grid, ``chunk`` lanes at a time."""
    import drjit as dr
    import mitsuba as mi

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
        # the 1D sample picks among lobes (one lobe's D·cosθ sampler needs none; the
        # dielectric's reflection or refraction, with probability F, does): stratified too,
        # through Knuth's multiplicative hash of the cell (a permutation of 2¹⁶ strata)
        u1 = (mi.Float((cell * 40503) % 65536) + 0.5) / 65536.0
        _, weight = bsdf.sample(ctx, si, u1, u)
        w = dr.select(dr.isfinite(weight.x), weight.x * jacobian, 0.0)
        out.append(np.asarray(dr.block_sum(mi.Float64(w), per_node), np.float64) / per_node)
    return np.concatenate(out)


def build(kinds=KINDS, shadowings=SHADOWINGS, n_mu: int = N_MU, n_alpha: int = N_ALPHA,
          samples: int = SAMPLES, progress=None) -> dict[str, np.ndarray]:
    """The conductor's arrays of the table file: ``E_<kind>-<shadowing>`` (n_alpha, n_mu),
    ``E_avg_<kind>-<shadowing>`` (n_alpha,), ``alpha_max``, ``samples``."""
    mus, alphas = mu_nodes(n_mu), alpha_nodes(n_alpha, ALPHA_MAX)
    out = {"alpha_max": np.float64(ALPHA_MAX), "samples": np.int64(samples)}
    for kind in kinds:
        for shadowing in shadowings:
            rows = []
            for alpha in alphas:
                rows.append(albedo_row(kind, shadowing, alpha, mus, samples))
                _advance(progress, f"{kind}-{shadowing}")
            # as the plugin reads it; ≤ 1 (float32 rounding of D·cosθ's weights at μ → 0 must
            # not create energy)
            _store(out, f"E_{kind}-{shadowing}", f"E_avg_{kind}-{shadowing}", np.array(rows))
    return out


def build_dielectric(kinds=KINDS, n_mu: int = N_MU_DIELECTRIC,
                     n_alpha: int = N_ALPHA_DIELECTRIC, n_eta: int = N_ETA,
                     samples: int = SAMPLES_DIELECTRIC, progress=None) -> dict[str, np.ndarray]:
    """The dielectric's arrays of the table file (Smith masking, the only one it offers):
    ``ET_<kind>-smith`` (n_eta, n_alpha, n_mu), E_R+T lit from above at relative index η
    (lit from below at η it is the table at 1/η), ``ET_avg_<kind>-smith`` (n_eta, n_alpha),
    ``eta_max``, ``samples_dielectric``."""
    mus, alphas, etas = mu_nodes(n_mu), alpha_nodes(n_alpha, ALPHA_MAX), eta_nodes(n_eta)
    out = {"eta_max": np.float64(ETA_MAX), "samples_dielectric": np.int64(samples)}
    for kind in kinds:
        rows = []
        for eta in etas:
            for alpha in alphas:
                rows.append(dielectric_row(kind, alpha, eta, mus, samples))
                _advance(progress, f"{kind} dielectric")
        E = np.array(rows).reshape(n_eta, n_alpha, n_mu)
        _store(out, f"ET_{kind}-smith", f"ET_avg_{kind}-smith", E)
    return out


def _advance(progress, label: str) -> None:
    if progress is not None:
        progress.update(progress.done + 1, label)


def _store(out: dict, key: str, avg_key: str, E: np.ndarray) -> None:
    """E (clipped to ≤ 1: float32 rounding of the sample weights must not create energy) and
    E_avg of its last axis, as float32, the way the plugin reads them."""
    E = np.minimum(E, 1.0).astype(np.float32)
    out[key] = E
    shape = E.shape[:-1]
    out[avg_key] = average(E.reshape(-1, E.shape[-1]).astype(np.float64)) \
        .reshape(shape).astype(np.float32)


def write(path, arrays: dict) -> None:
    """The arrays as a compressed ``.npz`` at ``path``, written whole or not at all."""
    import os
    from pathlib import Path

    path = Path(path)
    tmp = path.with_name(path.name + ".part.npz")
    np.savez_compressed(tmp, **arrays)
    os.replace(tmp, path)
