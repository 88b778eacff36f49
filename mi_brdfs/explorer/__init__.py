"""
``mi-brdfs explore`` and :func:`explore`: an interactive BRDF explorer driven by the plugins
themselves (:mod:`~mi_brdfs.explorer.session` computes what the page shows,
:mod:`~mi_brdfs.explorer.app` lays it out with Panel, :mod:`~mi_brdfs.explorer.server` serves
it). Needs the ``explore`` extra: ``pip install 'mi-brdfs[explore]'``.
"""

from __future__ import annotations


def jit_variant(variant: str | None) -> str:
    """Set ``variant`` (None: llvm_ad_rgb where LLVM works) and return it; MiBrdfsError with
    one line where it is not a JIT variant (the explorer traces its views' kernels once)."""
    from ..errors import MiBrdfsError
    from ..registry import use_variant

    variant = use_variant(variant)
    if not variant.startswith(("llvm", "cuda")):
        raise MiBrdfsError(f"explore needs a JIT variant (llvm_*, cuda_*), not {variant}")
    return variant


def explore(*bsdfs, variant: str | None = None, scene=None, scene_bsdf: str | None = None):
    """
    The explorer of 1 to 4 BSDFs (any form: dict, XML fragment or file, 'type key=value',
    a MERL file, a preset) as a Panel layout: shown inline as the last expression of a
    Jupyter cell (after ``panel.extension()``), or served with ``.show()``. Loads them in
    ``variant`` (default: llvm_ad_rgb where LLVM works). ``scene``: a scene file (or a
    bundled scene's name) rendered instead of the sphere, each BSDF in place of its
    ``<bsdf id=scene_bsdf>``.
    """
    from .app import build

    jit_variant(variant)
    return build(list(bsdfs), scene=_scene(scene, scene_bsdf))


def _scene(scene, scene_bsdf):
    """(scene, id) where a scene is given; MiBrdfsError with one line where only one of the
    two is."""
    from ..errors import MiBrdfsError

    if (scene is None) != (scene_bsdf is None):
        raise MiBrdfsError("explore: a scene needs the id of the BSDF to replace in it "
                           "(--scene FILE --scene-bsdf ID), and an id its scene")
    return None if scene is None else (str(scene), scene_bsdf)
