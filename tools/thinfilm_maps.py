"""
Writes the thickness maps of scenes/thinfilm.xml (float32 EXR, one channel, nanometres):
``oil.exr``, an oil slick on water (smooth swirls between 100 and 900 nm), and ``bubble.exr``, a
soap film draining under gravity (thin at the top of the sphere's v, thick at the bottom, with
swirls). Deterministic: ``.venv/bin/python tools/thinfilm_maps.py`` rewrites the same files.
"""

from pathlib import Path

import numpy as np

import mi_brdfs  # noqa: F401  (chooses the libLLVM)
import mitsuba as mi

OUT = Path(__file__).resolve().parent.parent / "scenes" / "thinfilm"


def smooth_field(n: int, seed: int, blobs: int = 14) -> np.ndarray:
    """A smooth field in [0, 1]: Gaussian blobs of random sizes, swirled."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:n, 0:n] / n
    swirl = 0.08 * np.sin(2 * np.pi * (2 * y + x)) + 0.05 * np.cos(2 * np.pi * 3 * x)
    xs, ys = x + swirl, y - swirl
    field = np.zeros((n, n))
    for _ in range(blobs):
        cx, cy, r, w = rng.random(), rng.random(), 0.08 + 0.25 * rng.random(), rng.random()
        field += w * np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2) / (2 * r * r))
    field -= field.min()
    return field / field.max()


def main():
    mi.set_variant("scalar_rgb")
    OUT.mkdir(parents=True, exist_ok=True)
    n = 256
    oil = 100.0 + 800.0 * smooth_field(n, 1)
    v = (np.arange(n) / (n - 1))[:, None] * np.ones((1, n))
    bubble = 60.0 + 900.0 * v ** 1.5 + 120.0 * (smooth_field(n, 2) - 0.5)
    for name, data in (("oil", oil), ("bubble", np.clip(bubble, 20.0, None))):
        mi.Bitmap(data.astype(np.float32)[..., None]).write(str(OUT / f"{name}.exr"))
        print(f"{OUT / name}.exr: {data.min():.0f} to {data.max():.0f} nm")


if __name__ == "__main__":
    main()
