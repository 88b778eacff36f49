"""
Plots of BSDFs in the manner of Disney's BRDF Explorer, with matplotlib (``pip install
mi-brdfs[plots]``): the polar lobe in the plane of incidence, the directional albedo over the
incident angle, and the (θh, θd) image slice; and the principal-plane plot of Earth
observation (the BRF against the view zenith, :mod:`mi_brdfs.earth`). Each takes several
BSDFs, to compare them.
"""

from __future__ import annotations

import math
import os

import numpy as np

from .bsdfspec import describe, load_bsdf
from .checks import batch
from .errors import MiBrdfsError, counts


def pyplot():
    """matplotlib's pyplot with the file-only Agg backend, or one line saying how to install it."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise MiBrdfsError("plots need matplotlib: pip install 'mi-brdfs[plots]'") from None
    return plt


def save_figure(fig, path) -> str:
    """Write ``fig`` to ``path`` (format from the extension) atomically, close it, return the
    path."""
    from .imageio import atomic_path

    path = os.fspath(path)
    with atomic_path(path, os.path.splitext(path)[1] or ".png") as tmp:
        fig.savefig(tmp, dpi=120, bbox_inches="tight")
    pyplot().close(fig)
    return path


def _luminance(value: np.ndarray) -> np.ndarray:
    """One number per row: the mean of the channels (a BSDF's grey-level response)."""
    return value.mean(axis=1)


@counts("n")
def lobe_values(spec, theta_i_deg: float, n: int = 721, cosine: bool = True):
    """
    The BSDF in the plane of incidence: θo from −90° (the side of ``wi``) to +90° (the mirror
    side), and eval = f·cosθo (``cosine``) or f.
    """
    bsdf = load_bsdf(spec)
    theta_o = np.linspace(-90.0, 90.0, n)
    t = np.radians(theta_o)
    wo = np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=1)
    wi = batch.direction(math.radians(-theta_i_deg))  # wi on the negative-x side
    value = _luminance(batch.evaluate(bsdf, wi, wo).value)
    if not cosine:
        value = np.where(wo[:, 2] > 1e-6, value / np.maximum(wo[:, 2], 1e-6), 0.0)
    return theta_o, value


def cube_root_lobe(ax, curves, title: str) -> None:
    """A polar half-plane of (f·cosθo)^(1/3) curves in the plane of incidence, as the fit plots
    draw them: ``curves`` are (θo in degrees, values, matplotlib style, keyword arguments)."""
    for theta_o, value, style, kw in curves:
        ax.plot(np.radians(theta_o), np.cbrt(np.maximum(value, 0.0)), style, **kw)
    ax.set_theta_zero_location("N")
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    ax.set_yticklabels([])
    ax.tick_params(axis="x", labelsize=7)
    ax.set_title(title, fontsize=9)


def plot_lobe(specs, path, thetas_deg=(0.0, 30.0, 60.0, 80.0), log: bool = False,
              cosine: bool = True) -> str:
    """Polar plots of the lobes, one panel per incident angle, every BSDF in each panel."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(thetas_deg), subplot_kw={"projection": "polar"},
                             figsize=(3.6 * len(thetas_deg), 3.9))
    axes = np.atleast_1d(axes)
    for ax, theta_i in zip(axes, thetas_deg):
        for spec in specs:
            theta_o, value = lobe_values(spec, theta_i, cosine=cosine)
            r = np.log10(np.maximum(value, 1e-4)) + 4 if log else value
            ax.plot(np.radians(theta_o), r, label=describe(spec), lw=1.4)
        ax.set_theta_zero_location("N")
        ax.set_thetamin(-90)
        ax.set_thetamax(90)
        top = ax.get_ylim()[1]
        ax.annotate("", xy=(0, 0), xytext=(math.radians(-theta_i), top * 0.95),
                    arrowprops=dict(arrowstyle="->", color="0.4"))
        if log:  # rings at every decade, 1e-3 ... 10
            ax.set_yticks([t for t in (1, 2, 3, 4, 5, 6) if t <= top])
            ax.set_title(f"θi = {theta_i:g}°", fontsize=10)
        else:
            ax.set_yticks([top / 4, top / 2, 3 * top / 4, top])
            ax.set_title(f"θi = {theta_i:g}° (outer ring {top:.3g})", fontsize=10)
        ax.set_yticklabels([])
        ax.tick_params(axis="x", labelsize=7)
    what = "f·cosθo" if cosine else "f"
    scale = ", log radius: one ring per decade from 1e-3" if log else ""
    fig.suptitle(f"{what} in the plane of incidence (arrow: towards the light){scale}",
                 fontsize=10)
    axes[-1].legend(loc="upper left", bbox_to_anchor=(1.05, 1.0), fontsize=8)
    return save_figure(fig, path)


@counts("n")
def plot_albedo(specs, path, thetas_deg=None, n: int | None = None, curves=None) -> str:
    """Directional albedo E(θ) of each BSDF: sample() mean ± 2σ, eval() quadrature, reference."""
    from .checks.albedo import albedo_curve

    plt = pyplot()
    thetas = thetas_deg if thetas_deg is not None else \
        np.degrees(np.arccos(np.linspace(1.0, 0.02, 25)))
    curves = curves or [albedo_curve(spec, thetas, n=n, progress=True) for spec in specs]
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for curve in curves:
        y, err = curve.sampled.mean(axis=1), curve.sampled_err.mean(axis=1)
        line, = ax.plot(curve.theta_deg, y, "-", lw=1.5, label=f"{describe(curve.spec)}: sample()")
        ax.fill_between(curve.theta_deg, y - 2 * err, y + 2 * err, color=line.get_color(),
                        alpha=0.25, lw=0)
        if curve.quadrature is not None:
            q = np.where(curve.quadrature_resolved, curve.quadrature.mean(axis=1), np.nan)
            ax.plot(curve.theta_deg, q, "o", ms=3, color=line.get_color(),
                    label="    eval() quadrature")
        if curve.reference is not None:
            ax.plot(curve.theta_deg, curve.reference.mean(axis=1), "--", color="k", lw=0.8,
                    label="    float64 reference")
    ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel("incident angle θ (degrees)")
    ax.set_ylabel("directional albedo E(θ)")
    ax.set_xlim(0, 90)
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


def slice_directions(res: int, phi_d_deg: float = 90.0):
    """
    (wi, wo) for the (θh, θd) slice at azimuth φd (Rusinkiewicz coordinates, φh = 0): θh along
    x, θd along y, both over [0°, 90°), as (res², 3) arrays.
    """
    t = (np.arange(res) + 0.5) / res * (math.pi / 2)
    th, td = np.meshgrid(t, t, indexing="xy")  # rows: θd, columns: θh
    pd = math.radians(phi_d_deg)
    d = np.stack([np.sin(td) * math.cos(pd), np.sin(td) * math.sin(pd), np.cos(td)], axis=-1)
    # rotate the difference vector from the half-vector frame by θh about y
    c, s = np.cos(th), np.sin(th)
    wi = np.stack([c * d[..., 0] + s * d[..., 2], d[..., 1], -s * d[..., 0] + c * d[..., 2]], -1)
    h = np.stack([s, np.zeros_like(s), c], axis=-1)
    wo = 2 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    return wi.reshape(-1, 3), wo.reshape(-1, 3)


@counts("res")
def slice_values(spec, res: int = 128, phi_d_deg: float = 90.0) -> np.ndarray:
    """f (without the cosine) on the (θh, θd) slice, (res, res), θd along rows."""
    bsdf = load_bsdf(spec)
    wi, wo = slice_directions(res, phi_d_deg)
    value = _luminance(batch.evaluate(bsdf, wi, wo).value)
    f = np.where(wo[:, 2] > 1e-6, value / np.maximum(wo[:, 2], 1e-6), 0.0)
    return f.reshape(res, res)


@counts("res")
def plot_slice(specs, path, res: int = 128, phi_d_deg: float = 90.0) -> str:
    """The (θh, θd) image slice of each BSDF side by side, as in BRDF Explorer (log colour)."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(specs), figsize=(3.4 * len(specs) + 0.8, 3.4))
    axes = np.atleast_1d(axes)
    images = [slice_values(spec, res, phi_d_deg) for spec in specs]
    positive = [im[im > 0] for im in images if (im > 0).any()]
    vmax = max((p.max() for p in positive), default=1.0)
    vmin = max(min((np.percentile(p, 1) for p in positive), default=1e-3), vmax * 1e-6)
    from matplotlib.colors import LogNorm
    for ax, spec, im in zip(axes, specs, images):
        shown = ax.imshow(np.maximum(im, vmin), origin="lower", extent=(0, 90, 0, 90),
                          norm=LogNorm(vmin=vmin, vmax=vmax), cmap="inferno")
        ax.set_title(describe(spec), fontsize=9)
        ax.set_xlabel("θh (degrees)")
    axes[0].set_ylabel("θd (degrees)")
    fig.colorbar(shown, ax=list(axes), shrink=0.85, label="f (1/sr)")
    fig.suptitle(f"BRDF slice at φd = {phi_d_deg:g}°", fontsize=10)
    return save_figure(fig, path)


def plot_principal_plane(specs, path, thetas_deg=None) -> str:
    """The BRF = π·f in the principal plane (:func:`mi_brdfs.earth.principal_plane`), one
    panel per sun zenith, every BSDF in each: backward (the sun's side, the hot spot) right
    of the zenith, forward (the specular side) left."""
    from .earth import SUN_ZENITHS, principal_plane

    plt = pyplot()
    suns = tuple(thetas_deg) if thetas_deg else SUN_ZENITHS
    planes = [principal_plane(spec, suns) for spec in specs]
    fig, axes = plt.subplots(1, len(suns), figsize=(4.2 * len(suns), 3.6),
                             squeeze=False)
    for k, (ax, sun) in enumerate(zip(axes[0], suns)):
        for plane in planes:
            ax.plot(plane.view_zenith_deg, _luminance(plane.brf[k]), lw=1.4,
                    label=describe(plane.spec))
        ax.axvline(sun, color="0.6", lw=0.8, ls=":")  # the hot spot
        ax.axhline(1.0, color="0.8", lw=0.8, ls="--")  # a white Lambertian surface
        ax.set_xlim(-90, 90)
        ax.set_xticks(range(-90, 91, 30))
        ax.set_title(f"sun zenith θi = {sun:g}° (dotted: the hot spot)", fontsize=9)
        ax.set_xlabel("view zenith θo (degrees): < 0 forward, > 0 backward", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("BRF = π·f (1: white Lambertian)")
    axes[0, -1].legend(loc="upper left", bbox_to_anchor=(1.03, 1.0), fontsize=8)
    fig.suptitle("BRF in the principal plane (forward: the specular side; backward: the "
                 "sun's side)", fontsize=10)
    return save_figure(fig, path)
