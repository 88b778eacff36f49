"""
``mi-brdfs explore`` and :func:`explore`: an interactive BRDF explorer driven by the plugins
themselves (:mod:`~mi_brdfs.explorer.session` computes what the page shows,
:mod:`~mi_brdfs.explorer.app` lays it out with Panel, :mod:`~mi_brdfs.explorer.server` serves
it). Needs the ``explore`` extra: ``pip install 'mi-brdfs[explore]'``.
"""

from __future__ import annotations


def explore(*bsdfs, variant: str | None = None):
    """
    The explorer of 1 to 4 BSDFs (any form: dict, XML fragment or file, 'type key=value',
    a MERL file, a preset) as a Panel layout: shown inline as the last expression of a
    Jupyter cell (after ``panel.extension()``), or served with ``.show()``. Loads them in
    ``variant`` (default: llvm_ad_rgb where LLVM works).
    """
    from ..bsdfspec import parse_cli
    from ..errors import MiBrdfsError
    from ..registry import use_variant
    from .app import build

    variant = use_variant(variant)
    if not variant.startswith(("llvm", "cuda")):
        raise MiBrdfsError(f"explore needs a JIT variant (llvm_*, cuda_*), not {variant}")
    specs = [s for b in bsdfs for s in (parse_cli([b]) if isinstance(b, str) and
                                          not b.lstrip().startswith("<") else [b])]
    return build(specs)
