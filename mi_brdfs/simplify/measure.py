"""
The measurements: an engine that renders the original and candidate scene texts at the seeds of
a seed set and times them interleaved with the original (:class:`_Engine`), the disk cache of
every measurement (:class:`_Cache`), and the statistics of a candidate from its difference
images (:func:`_statistics`: bias, its standard error and bounds, noise, variance ratio, FLIP;
see :mod:`mi_brdfs.simplify`).

The standard error of bias² is estimated per pixel and channel (for Gaussian noise of variance
σ² per seed, Var = 4b²σ²/k + 2σ⁴/k² + 2σ⁴/((k−1)k²)), times √3 because a pixel's three channels
come from the same paths. FLIP is evaluated on the box where the two images differ
(:func:`_flip_mean`).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from ..errors import MiBrdfsError, mitsuba_error_line
from ..scenes import used_defines

#: The most seeds rendered per scene while its bias is inconclusive (2, 4, 8, 16).
MAX_SEEDS = 16

#: Bump when what is measured or how changes: old cache entries are then ignored.
CACHE_VERSION = 2


def _key(*parts) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(part if isinstance(part, bytes) else json.dumps(part, sort_keys=True,
                                                                  default=str).encode())
        h.update(b"\0")
    return h.hexdigest()


class _Cache:
    """JSON records and .npz arrays in a folder; None: nothing stored."""

    def __init__(self, folder: Path | None):
        self.folder = folder
        if folder is not None:
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                raise MiBrdfsError(f"cannot create the cache folder {folder}: "
                                   f"{e.strerror or e}") from None

    def get(self, key: str):
        if self.folder is None:
            return None
        path = self.folder / f"{key[:32]}.json"
        try:
            return json.loads(path.read_text()) if path.is_file() else None
        except (OSError, ValueError):
            return None

    def put(self, key: str, record) -> None:
        if self.folder is None:
            return
        from ..imageio import atomic_path
        with atomic_path(self.folder / f"{key[:32]}.json", ".json") as tmp:
            Path(tmp).write_text(json.dumps(record, default=float))

    def get_arrays(self, key: str):
        if self.folder is None:
            return None
        path = self.folder / f"{key[:32]}.npz"
        try:
            with np.load(path) as f:
                return {k: f[k] for k in f.files}
        except (OSError, ValueError):
            return None

    def put_arrays(self, key: str, **arrays) -> None:
        if self.folder is None:
            return
        from ..imageio import atomic_path
        with atomic_path(self.folder / f"{key[:32]}.npz", ".npz") as tmp:
            np.savez_compressed(tmp, **arrays)


def default_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mi_brdfs" / "simplify"


class _Engine:
    """
    Renders the original and candidate scene texts at the seeds of a seed set, times them
    interleaved with the original, and caches every measurement (the difference images too, so
    that a rerun can add seeds).
    """

    def __init__(self, path: Path, data: bytes, defines: dict, spp: int, repeats: int,
                 timing_s: float, max_seeds: int, cache: _Cache, settings_key: str):
        import drjit as dr
        import mitsuba as mi

        self.path, self.data, self.defines = path, data, defines
        self.spp, self.repeats, self.timing_s = spp, repeats, timing_s
        self.max_seeds = max_seeds
        self.cache, self.settings_key = cache, settings_key
        self.jit = dr.is_jit_v(mi.Float)
        self._ref_scene = None
        self._refs: dict = {}       # seed set -> list of images
        self._ref_info = None
        self._ref_seconds: list = []  # seconds of the original's renders in this run
        self.renders = 0

    # -- loading and rendering ------------------------------------------------------------------

    def load(self, text: bytes):
        import mitsuba as mi

        if not self.jit:
            return None
        saved = mi.FileResolver(mi.file_resolver())
        mi.file_resolver().prepend(str(self.path.parent))
        try:
            return mi.load_string(text.decode("utf-8"), **used_defines(self.defines, text))
        except RuntimeError as e:
            raise MiBrdfsError(mitsuba_error_line(e)) from None
        finally:
            mi.set_file_resolver(saved)

    def _render(self, scene, text: bytes, seed: int, spp: int) -> tuple[np.ndarray, float]:
        """(image float64, seconds) of one render (the scene object, or in scalar variants
        the text through :func:`mi_brdfs.render.render`)."""
        self.renders += 1
        if self.jit:
            import mitsuba as mi

            from ..timing import timed
            try:
                seconds, image = timed(lambda: np.array(mi.render(scene, seed=seed, spp=spp)))
            except RuntimeError as e:
                raise MiBrdfsError(f"{self.path.name}: the render failed: "
                                   f"{mitsuba_error_line(e)}") from None
            return image.astype(np.float64), seconds
        from ..render import render

        folder = self.path.parent if os.access(self.path.parent, os.W_OK) else None
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.stem}.simplify.", suffix=".xml",
                                   dir=folder)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(text)
            # a fixed pass size: the same passes (seeds) for every scene
            result = render(tmp, spp=spp, seed=seed, defines=used_defines(self.defines, text),
                            pass_spp=max(1, spp // 4), progress=False)
        finally:
            os.unlink(tmp)
        return result.image.astype(np.float64), result.wall_time

    # -- the original ---------------------------------------------------------------------------

    def ref_scene(self):
        """The original scene, loaded and compiled (one untimed render)."""
        if self._ref_scene is None:
            self._ref_scene = self.load(self.data)
        return self._ref_scene

    def info(self) -> dict:
        """The original's timing spp (renders of about ``timing_s``) and mean value."""
        if self._ref_info is None:
            key = _key("reference info", self.settings_key)
            record = self.cache.get(key)
            if record is None:
                images = self.references("main", 2)
                if len(self._ref_seconds) < 2:  # the renders came from the cache: time one
                    if self.jit and self._ref_scene is None:
                        self._ref_scene = self.load(self.data)
                    for seed in (998, 999):  # the first may compile
                        seconds = self._render(self._ref_scene, self.data, seed, self.spp)[1]
                    self._ref_seconds.append(seconds)
                seconds = self._ref_seconds[-1]  # the second render: compiled
                per_spp = seconds / self.spp
                timing_spp = int(min(4 * self.spp, max(1, round(self.timing_s / per_spp))))
                record = {"timing_spp": timing_spp, "seconds_per_spp": per_spp,
                          "mean": float(np.mean(images[0] + images[1]) / 2)}
                self.cache.put(key, record)
            mean = record["mean"]
            if not mean > 0 or not math.isfinite(mean):
                raise MiBrdfsError(f"{self.path.name} renders black (mean {mean:g}): a relative "
                                   f"error has no meaning there")
            self._ref_info = record
        return self._ref_info

    def references(self, seedset: str, count: int) -> list:
        """The original's renders at the first ``count`` seeds of ``seedset``."""
        have = self._refs.get(seedset)
        key = _key("reference", self.settings_key, seedset)
        if have is None:
            arrays = self.cache.get_arrays(key) or {}
            have = [arrays[f"r{i}"].astype(np.float64) for i in range(len(arrays))]
        if len(have) < count:
            if self.jit and self._ref_scene is None:
                self._ref_scene = self.load(self.data)
            for i in range(len(have), count):
                image, seconds = self._render(self._ref_scene, self.data,
                                              _seed(seedset, i), self.spp)
                have.append(image)
                self._ref_seconds.append(seconds)
            self.cache.put_arrays(key, **{f"r{i}": im.astype(np.float32)
                                          for i, im in enumerate(have)})
        self._refs[seedset] = have
        return have[:count]

    # -- a candidate ----------------------------------------------------------------------------

    def measure(self, text: bytes, tolerance: float, seedset: str = "main") -> tuple[dict, bool]:
        """
        (measurements, cached) of a scene text against the original: renders at 2, 4, 8, ...
        seeds of ``seedset`` while its bias is inconclusive for ``tolerance`` (below it, yet
        its bound above), up to ``max_seeds``; then the timing. The difference images
        D = C − R of every seed are kept (compressed: 0 wherever the material does not show).
        """
        key = _key("candidate", self.settings_key, seedset, text)
        record, stored = self.cache.get(key), self.cache.get_arrays(key)
        cached = record is not None and stored is not None
        if not cached:
            record, stored = {}, {}
        diffs = [stored[f"d{i}"].astype(np.float64) for i in range(len(stored))]
        scene = None
        info = self.info()
        while True:
            if len(diffs) >= 2:
                record.update(_statistics(self.references(seedset, len(diffs)), diffs,
                                          self.spp, info["mean"]))
                if not _inconclusive(record, tolerance) or len(diffs) >= self.max_seeds:
                    break
            target = min(self.max_seeds, max(2, 2 * len(diffs)))
            if scene is None:
                scene = self.load(text)
            refs = self.references(seedset, target)
            for i in range(len(diffs), target):
                diffs.append(self._render(scene, text, _seed(seedset, i), self.spp)[0] - refs[i])
            cached = False
        if "cost_ratio" not in record:
            if scene is None:
                scene = self.load(text)
            record.update(self._timing(scene, text))
            cached = False
        if not cached:
            self.cache.put(key, record)
            self.cache.put_arrays(key, **{f"d{i}": d.astype(np.float32)
                                          for i, d in enumerate(diffs)})
        return record, cached

    def _timing(self, scene, text: bytes) -> dict:
        """Time ratios candidate/original of renders interleaved R C C R R C ...: their median,
        and its standard error from their spread (:func:`_median_se`)."""
        spp = self.info()["timing_spp"]
        ratios, ref_times = [], []
        ref_scene = self.ref_scene()
        if self.jit:  # untimed: a kernel of another spp may have to be compiled first
            self._render(scene, text, 999, spp)
            self._render(ref_scene, self.data, 999, spp)
        for i in range(self.repeats):
            order = ("ref", "cand") if i % 2 == 0 else ("cand", "ref")
            times = {}
            for who in order:
                times[who] = self._render(ref_scene if who == "ref" else scene,
                                          self.data if who == "ref" else text, 1000 + i, spp)[1]
            ratios.append(times["cand"] / times["ref"])
            ref_times.append(times["ref"])
        logs = np.log(np.asarray(ratios))
        return {"cost_ratio": float(np.exp(np.median(logs))), "cost_ratio_se": _median_se(logs),
                "ref_seconds_per_spp": float(np.median(ref_times)) / spp,
                "timing_ratios": [float(r) for r in ratios]}


#: Fewest timing repeats from whose spread a standard error is estimated; with fewer, the
#: error is unknown (NaN) and no speed-up counts as significant.
MIN_REPEATS = 3


def _median_se(values: np.ndarray) -> float:
    """
    Standard error of the median of ``values`` (the logs of the per-repeat timing ratios):
    1.25 s/√n (the median's efficiency for normal errors), s the sample standard deviation of
    the repeats, i.e. their repeat-to-repeat spread; NaN under :data:`MIN_REPEATS` repeats.

    Not a robust σ such as the median absolute deviation: of three repeats, two that agree by
    chance make the MAD nearly 0 whatever the third says, and bars that small declared a
    replacement faster that a rerun found slower. A render slowed by another process widens
    these bars instead, which keeps the original: the safe side.
    """
    n = len(values)
    if n < MIN_REPEATS:
        return math.nan
    return 1.25 * float(np.std(values, ddof=1)) / math.sqrt(n)


def _seed(seedset: str, index: int) -> int:
    """The seed of render ``index`` of a seed set: 1, 2, ... ('main') or 101, ... ('verify')."""
    return {"main": 1, "verify": 101}[seedset] + index


def _inconclusive(stats: dict, tolerance: float) -> bool:
    return stats["bias_lo"] <= tolerance < stats["bias_hi"]


def _flip_mean(reference: np.ndarray, test: np.ndarray, mean: float) -> float | None:
    """
    Mean HDR-FLIP of ``test`` against ``reference``, evaluated on the bounding box of the
    pixels that differ by more than 10⁻³ of the image mean, padded by 32 pixels (FLIP's
    filters are a few pixels wide), and counted as 0 elsewhere: the images of a candidate
    differ where its material is seen, and FLIP is costly per pixel.
    """
    from ..compare import flip_map

    differs = np.any(np.abs(test - reference) > 1e-3 * mean, axis=-1)
    if not differs.any():
        return 0.0
    rows, cols = np.flatnonzero(differs.any(axis=1)), np.flatnonzero(differs.any(axis=0))
    pad = 32
    r0, r1 = max(0, rows[0] - pad), min(differs.shape[0], rows[-1] + pad + 1)
    c0, c1 = max(0, cols[0] - pad), min(differs.shape[1], cols[-1] + pad + 1)
    fl = flip_map(reference[r0:r1, c0:c1], test[r0:r1, c0:c1])
    if fl is None:
        return None
    return float(fl[1] * (r1 - r0) * (c1 - c0) / differs.size)


def _statistics(refs: list, diffs: list, spp: int, mean: float) -> dict:
    """
    Bias, its standard error and bounds, noise, variance ratio and FLIP of a candidate from
    the original's renders R_s and the differences D_s = C_s − R_s at k seeds.
    """
    k = len(diffs)
    d = np.stack(diffs)
    r = np.stack(refs[:k])
    c = r + d
    dbar = d.mean(axis=0)
    s2 = d.var(axis=0, ddof=1)  # sample variance of D per pixel and channel
    var_dbar = s2 / k
    b2_pixels = dbar * dbar - var_dbar
    n = dbar.size
    b2 = float(np.mean(b2_pixels))
    # Var of D̄² − s²/k per pixel for Gaussian noise of variance σ² per seed:
    # 4b²σ²/k + 2σ⁴/k² + 2σ⁴/((k−1)k²), with σ⁴ ≈ s⁴(k−1)/(k+1); ×3: a pixel's channels
    sigma4 = s2 * s2 * (k - 1) / (k + 1)
    var = 4 * np.maximum(b2_pixels, 0.0) * var_dbar + sigma4 * (2 / k ** 2 + 2 / ((k - 1) * k ** 2))
    se = float(math.sqrt(3.0 * np.sum(var)) / n)
    var_r, var_c = r.var(axis=0, ddof=1), c.var(axis=0, ddof=1)
    vr = float(np.mean(var_r))
    var_ratio = float(np.mean(var_c) / vr) if vr > 0 else math.nan
    var_se = float(math.sqrt(3.0) * np.std(var_c - var_r) / math.sqrt(n) / vr / var_ratio) \
        if vr > 0 and var_ratio > 0 else math.nan
    m2 = mean * mean
    return {"b2": b2 / m2, "b2_se": se / m2, "seeds": k,
            "bias": math.sqrt(max(b2, 0.0) / m2),
            "bias_hi": math.sqrt(max(b2 + 2 * se, 0.0) / m2),
            "bias_lo": math.sqrt(max(b2 - 2 * se, 0.0) / m2),
            "noise": float(math.sqrt(np.mean(var_dbar)) / mean),
            "variance_ratio": var_ratio, "variance_ratio_se": var_se,
            "variance_1spp_ref": vr * spp / m2,
            "flip": _flip_mean(r.mean(axis=0), c.mean(axis=0), mean),
            "nonfinite": int((~np.isfinite(d)).sum())}


def _original_numbers(results, engine) -> dict:
    """
    The original's cost per spp (the median over every timing render of it) and the relative
    variance of its 1-spp image (from its renders at every seed rendered).
    """
    per_spp = [c.measured["ref_seconds_per_spp"] for r in results for c in r.candidates[1:]
               if c.ok]
    if not per_spp:
        per_spp = [engine.info()["seconds_per_spp"]]
    refs = engine.references("main", max(2, len(engine._refs.get("main", []))))
    var = float(np.mean(np.stack(refs).var(axis=0, ddof=1))) * engine.spp \
        / engine.info()["mean"] ** 2
    return {"ref_seconds_per_spp": float(np.median(per_spp)), "variance_1spp_ref": var,
            "seeds": len(refs)}
