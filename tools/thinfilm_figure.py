"""
docs/thinfilm.png and the agreement docs/thinfilm.md quotes: scenes/thinfilm.xml rendered in
``scalar_spectral`` (left) and ``llvm_ad_rgb`` (right), side by side; then the same scene in
``llvm_ad_spectral`` and ``llvm_ad_rgb`` at many samples, and the difference of the two against
the difference of two RGB renders of independent seeds (the noise floor).

    .venv/bin/python tools/thinfilm_figure.py [--res 128] [--spp 48] [--workers 2]
                                              (make figures)

``scalar_spectral`` runs the plugin's Python once per lane (about 0.45 ms a sample on one core,
a thousand times ``llvm_ad_rgb``'s): its samples are split over ``--workers`` processes of
independent seeds, averaged.
"""

import argparse
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np

import mi_brdfs
import mitsuba as mi
from mi_brdfs.scenes import load_scene

DOCS = Path(__file__).resolve().parent.parent / "docs"


def render(variant: str, res: int, spp: int, seed: int = 0) -> np.ndarray:
    mi_brdfs.use_variant(variant)
    return np.array(mi.render(load_scene("thinfilm", {"res": str(res)}), spp=spp, seed=seed))


def render_split(variant: str, res: int, spp: int, workers: int) -> np.ndarray:
    """The mean of ``workers`` renders of spp/workers samples each (seeds 0, 1, ...), each in
    a process of its own."""
    if workers <= 1:
        return render(variant, res, spp)
    counts = [spp // workers + (i < spp % workers) for i in range(workers)]
    with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as pool:
        images = list(pool.map(render, [variant] * workers, [res] * workers, counts,
                               range(workers)))
    return sum(n * image for n, image in zip(counts, images)) / spp


def agreement(res: int, spp: int) -> dict:
    """Mean |spectral − RGB| and |RGB − RGB'| (another seed) over the pixels, relative to the
    image's mean, and the image means per channel."""
    spectral = render("llvm_ad_spectral", res, spp, 1)
    rgb, rgb2 = render("llvm_ad_rgb", res, spp, 2), render("llvm_ad_rgb", res, spp, 3)
    scale = rgb.mean()
    return {"spectral vs rgb": float(np.abs(spectral - rgb).mean() / scale),
            "rgb vs rgb (noise)": float(np.abs(rgb2 - rgb).mean() / scale),
            "means spectral": spectral.reshape(-1, 3).mean(0).round(4).tolist(),
            "means rgb": rgb.reshape(-1, 3).mean(0).round(4).tolist()}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--res", type=int, default=128)
    parser.add_argument("--spp", type=int, default=48)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--check-spp", type=int, default=1024)
    args = parser.parse_args()
    left = render_split("scalar_spectral", args.res, args.spp, args.workers)
    right = render("llvm_ad_rgb", args.res, args.spp * 16)
    gap = np.ones((args.res, 4, 3), np.float32)
    image = np.concatenate([left, gap, right], axis=1).astype(np.float32)
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8,
                             srgb_gamma=True).write(str(DOCS / "thinfilm.png"))
    print(f"wrote {DOCS / 'thinfilm.png'}")
    print(agreement(args.res, args.check_spp))


if __name__ == "__main__":
    main()
