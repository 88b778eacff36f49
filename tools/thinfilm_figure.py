"""
docs/thinfilm.png and the agreement docs/thinfilm.md quotes: scenes/thinfilm.xml rendered in
``scalar_spectral`` (left) and ``llvm_ad_rgb`` (right), side by side; then the same scene in
``llvm_ad_spectral`` and ``llvm_ad_rgb`` at many samples, and the difference of the two against
the difference of two RGB renders of independent seeds (the noise floor).

    .venv/bin/python tools/thinfilm_figure.py [--res 96] [--spp 16]   (make figures)
"""

import argparse
from pathlib import Path

import numpy as np

import mi_brdfs
import mitsuba as mi
from mi_brdfs.scenes import load_scene

DOCS = Path(__file__).resolve().parent.parent / "docs"


def render(variant: str, res: int, spp: int, seed: int = 0) -> np.ndarray:
    mi_brdfs.use_variant(variant)
    return np.array(mi.render(load_scene("thinfilm", {"res": str(res)}), spp=spp, seed=seed))


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
    parser.add_argument("--res", type=int, default=96)
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--check-spp", type=int, default=1024)
    args = parser.parse_args()
    left = render("scalar_spectral", args.res, args.spp)
    right = render("llvm_ad_rgb", args.res, args.spp * 16)
    gap = np.ones((args.res, 4, 3), np.float32)
    image = np.concatenate([left, gap, right], axis=1).astype(np.float32)
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8,
                             srgb_gamma=True).write(str(DOCS / "thinfilm.png"))
    print(f"wrote {DOCS / 'thinfilm.png'}")
    print(agreement(args.res, args.check_spp))


if __name__ == "__main__":
    main()
