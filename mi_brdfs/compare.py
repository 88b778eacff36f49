"""
Side-by-side comparison of two renders: A | B | signed difference | FLIP error map, with the
numbers that tell a real difference from Monte Carlo noise.

Both renders use the same spp and seed. The *noise floor* is the same set of numbers between two
renders of A with different seeds: a difference between A and B of the size of the noise floor
is noise; one well above it is real. FLIP is NVIDIA's perceptual error metric (Andersson et al.
2020, the ``flip-evaluator`` package), evaluated in HDR mode on the linear images.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import MiBrdfsError, counts


@dataclass
class Metrics:
    """Differences between two images (the first is the reference)."""

    rmse: float
    rel_mse: float
    mean_flip: float | None
    max_abs: float

    def row(self) -> str:
        flip = f"{self.mean_flip:.4f}" if self.mean_flip is not None else "—"
        return f"RMSE {self.rmse:.3g}, relMSE {self.rel_mse:.3g}, mean FLIP {flip}"


def rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, np.float64) - b) ** 2)))


def rel_mse(reference: np.ndarray, test: np.ndarray, eps: float = 1e-2) -> float:
    """Relative MSE, mean of (test − ref)² / (ref² + ε), ε = 0.01 as in the denoising literature."""
    reference = np.asarray(reference, np.float64)
    return float(np.mean((np.asarray(test, np.float64) - reference) ** 2 / (reference ** 2 + eps)))


def _rgb(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image, np.float32)
    if image.ndim == 2:
        image = image[:, :, None]
    if image.shape[2] == 1:
        return np.repeat(image, 3, axis=2)
    return image[:, :, :3]


def flip_map(reference: np.ndarray, test: np.ndarray) -> tuple[np.ndarray, float] | None:
    """HDR-FLIP error map (H×W, in [0, 1]) and its mean; None without ``flip-evaluator``."""
    try:
        import flip_evaluator as flip
    except ImportError:
        return None
    ref = np.ascontiguousarray(np.maximum(np.nan_to_num(_rgb(reference)), 0))
    tst = np.ascontiguousarray(np.maximum(np.nan_to_num(_rgb(test)), 0))
    error, mean, _ = flip.evaluate(ref, tst, "HDR", applyMagma=False)
    return np.asarray(error, np.float32).reshape(ref.shape[:2]), float(mean)


def metrics(reference: np.ndarray, test: np.ndarray, with_flip: bool = True) -> Metrics:
    fl = flip_map(reference, test) if with_flip else None
    return Metrics(rmse(reference, test), rel_mse(reference, test),
                   fl[1] if fl else None,
                   float(np.max(np.abs(np.asarray(test, np.float64) - reference))))


@dataclass
class Comparison:
    """Two renders, their difference, and the noise floor of A."""

    a: np.ndarray
    b: np.ndarray
    a2: np.ndarray          # A again, with another seed
    labels: tuple
    spp: int
    seed: int
    variant: str
    ab: Metrics = None
    noise: Metrics = None
    flip: np.ndarray | None = None
    notes: list = field(default_factory=list)

    def ratios(self) -> dict:
        """Each metric of A vs B divided by the same metric of the noise floor."""
        pairs = {"RMSE": (self.ab.rmse, self.noise.rmse),
                 "relMSE": (self.ab.rel_mse, self.noise.rel_mse)}
        if self.ab.mean_flip is not None:
            pairs["FLIP"] = (self.ab.mean_flip, self.noise.mean_flip)
        return {k: a / b if b > 0 else (0.0 if a == 0 else float("inf"))
                for k, (a, b) in pairs.items()}

    def different(self, factor: float = 3.0) -> bool:
        """
        A real difference: some metric exceeds ``factor`` × its noise floor. All three are
        needed: RMSE is ruled by the brightest pixels' noise (a light), relative MSE and FLIP
        by the rest of the image.
        """
        return any(r > factor for r in self.ratios().values())

    def verdict(self, factor: float = 3.0) -> str:
        worst = max(self.ratios().items(), key=lambda kv: kv[1])
        word = "different" if self.different(factor) else "within noise"
        return f"{word} (largest ratio to the noise floor: {worst[0]} {worst[1]:.3g}×)"

    def summary(self) -> str:
        return (f"A = {self.labels[0]}, B = {self.labels[1]} ({self.variant}, {self.spp} spp, "
                f"seed {self.seed})\n  A vs B:         {self.ab.row()}\n"
                f"  noise floor:    {self.noise.row()}  (A, seed {self.seed} vs {self.seed + 1})\n"
                f"  verdict:        {self.verdict()}")


def _render(path, spp: int, seed: int, defines=None, bsdfs=None) -> np.ndarray:
    import mitsuba as mi

    from .render import pass_seed
    from .scenes import load_scene
    scene = load_scene(path, defines, bsdfs=bsdfs)
    image = np.array(mi.render(scene, spp=spp, seed=pass_seed(seed, 0)), dtype=np.float32)
    return image


@counts("spp")
def compare(a, b=None, swap: dict | None = None, spp: int = 64, seed: int = 0,
            defines: dict | None = None, labels=None, with_flip: bool = True,
            defines_b: dict | None = None, swap_a: dict | None = None) -> Comparison:
    """
    Render A and B in the current variant with the same spp and seed, plus A with seed + 1.

    Parameter ``a``, ``b``: scene files or bundled names. Without ``b``, B is A with ``swap``
    applied (``{id: BSDF}`` replaces the scene's ``<bsdf id=...>``: dict, XML or 'type k=v'),
    or with ``defines_b`` overriding some of ``defines`` (e.g. cbox's ``material``).
    ``swap_a`` swaps materials of A the same way (e.g. one scene, two BSDFs).
    """
    import mitsuba as mi

    from .bsdfspec import describe
    if b is None and not swap and not defines_b:
        raise MiBrdfsError("compare needs two scenes, or one scene and --swap ID=BSDF")
    img_a = _render(a, spp, seed, defines, bsdfs=swap_a)
    img_b = _render(b if b is not None else a, spp, seed, dict(defines or {}, **(defines_b or {})),
                    bsdfs=swap)
    img_a2 = _render(a, spp, seed + 1, defines, bsdfs=swap_a)
    if img_a.shape != img_b.shape:
        raise MiBrdfsError(f"the renders differ in size: {img_a.shape} vs {img_b.shape}")
    if labels is None:
        changes = [f"{k} = {describe(v)}" for k, v in (swap or {}).items()]
        changes += [f"{k}={v}" for k, v in (defines_b or {}).items()]
        labels = (Path(str(a)).stem, Path(str(b)).stem if b is not None else "; ".join(changes))
    result = Comparison(img_a, img_b, img_a2, labels, spp, seed, mi.variant())
    result.ab = metrics(img_a, img_b, with_flip)
    result.noise = metrics(img_a, img_a2, with_flip)
    fl = flip_map(img_a, img_b) if with_flip else None
    result.flip = fl[0] if fl else None
    for name, image in (("A", img_a), ("B", img_b)):
        bad = int((~np.isfinite(image)).sum())
        if bad:
            result.notes.append(f"{name} has {bad} non-finite pixel values")
    return result


def figure(result: Comparison, path, title: str | None = None) -> str:
    """A | B | signed difference (B − A) | FLIP map, one PNG; numbers in the caption."""
    from .imageio import to_srgb8
    from .plots import pyplot, save_figure

    plt = pyplot()
    panels = 4 if result.flip is not None else 3
    fig, axes = plt.subplots(1, panels, figsize=(3.3 * panels, 3.7))
    for ax, image, label in ((axes[0], result.a, f"A: {result.labels[0]}"),
                             (axes[1], result.b, f"B: {result.labels[1]}")):
        ax.imshow(to_srgb8(image))
        ax.set_title(label, fontsize=8)
    diff = np.mean(_rgb(result.b) - _rgb(result.a), axis=2)
    scale = float(np.nanpercentile(np.abs(diff), 99.5)) or 1e-6
    shown = axes[2].imshow(diff, cmap="RdBu_r", vmin=-scale, vmax=scale)
    axes[2].set_title("B − A (mean of channels)", fontsize=8)
    fig.colorbar(shown, ax=axes[2], fraction=0.046, pad=0.02)
    if result.flip is not None:
        shown = axes[3].imshow(result.flip, cmap="magma", vmin=0, vmax=1)
        axes[3].set_title(f"FLIP (mean {result.ab.mean_flip:.4f})", fontsize=8)
        fig.colorbar(shown, ax=axes[3], fraction=0.046, pad=0.02)
    for ax in axes:
        ax.set_xticks([])
        ax.set_yticks([])
    caption = (f"A vs B: {result.ab.row()}\nnoise floor (A, two seeds): {result.noise.row()}"
               f" — {result.verdict()}")
    fig.suptitle((title + "\n" if title else "") + caption, fontsize=8)
    return save_figure(fig, path)


def exr_paths(out: str | Path) -> dict:
    """{'A', 'B', 'diff': path}: the EXRs :func:`write_outputs` writes beside the figure
    ``out`` (``compare.png``: ``compare-A.exr``, ``compare-B.exr``, ``compare-diff.exr``)."""
    out = Path(out)
    return {suffix: out.with_name(f"{out.stem}-{suffix}.exr") for suffix in ("A", "B", "diff")}


def write_outputs(result: Comparison, out: str | Path) -> list[str]:
    """The figure ``out`` (PNG) plus A, B and B − A as float32 EXRs beside it
    (:func:`exr_paths`), each written atomically."""
    from ._version import __version__
    from .imageio import write_exr

    written = [figure(result, out)]
    meta = {"mi_brdfs.version": __version__, "compare.a": result.labels[0],
            "compare.b": result.labels[1], "render.spp": result.spp, "render.seed": result.seed,
            "render.variant": result.variant, "compare.rmse": f"{result.ab.rmse:.6g}",
            "compare.noise_rmse": f"{result.noise.rmse:.6g}"}
    images = {"A": result.a, "B": result.b, "diff": result.b - result.a}
    for suffix, path in exr_paths(out).items():
        write_exr(path, images[suffix], meta)
        written.append(str(path))
    return written


def parse_swaps(items) -> dict:
    """``['material=roughconductor alpha=0.3']`` → ``{'material': 'roughconductor alpha=0.3'}``."""
    swaps = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise MiBrdfsError(f"--swap expects ID=BSDF (e.g. material='roughconductor alpha=0.3'),"
                               f" got '{item}'")
        swaps[key.strip()] = value.strip()
    return swaps


__all__ = ["compare", "figure", "write_outputs", "exr_paths", "metrics", "rmse", "rel_mse",
           "flip_map", "Comparison", "Metrics", "parse_swaps"]
