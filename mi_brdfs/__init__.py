"""
mi_brdfs: the reflectance models of the classic rendering lectures as Mitsuba 3 plugins.

``import mi_brdfs`` registers the package's BSDF plugins (``lambert``, ...) with Mitsuba in the
current variant and, through a variant callback, in every variant set later, so that
``mi.load_dict({'type': 'lambert'})`` and ``<bsdf type="lambert">`` work everywhere::

    import mitsuba as mi
    mi.set_variant('llvm_ad_rgb')
    import mi_brdfs                     # or mi_brdfs.register() after any mi.set_variant()
    bsdf = mi.load_dict({'type': 'lambert', 'reflectance': 0.8})

Import mi_brdfs *before* mitsuba or drjit where you can: it then points drjit at a libLLVM that
works (see :mod:`mi_brdfs._env`).
"""

import sys as _sys

from ._version import __version__
from . import _env

_env.DRJIT_IMPORTED_FIRST = "drjit" in _sys.modules
if not _env.DRJIT_IMPORTED_FIRST:
    try:
        _env.check_libatomic()
    except ImportError as _e:
        if _env.running_cli():  # the command line answers user errors in one line
            print(f"mi-brdfs: error: {str(_e).removeprefix('mi_brdfs: ')}", file=_sys.stderr)
            raise SystemExit(2) from None
        raise
    if not _env.configure_llvm().ok:
        _env.import_drjit_quietly()

from . import scenes  # noqa: E402
from .errors import MiBrdfsError, MiBrdfsWarning, ParameterError  # noqa: E402
from .registry import (  # noqa: E402
    PLUGINS, default_variant, llvm_usable, plugin_class, register, registered_variants,
    use_variant,
)

__all__ = [
    "__version__", "PLUGINS", "register", "registered_variants", "plugin_class", "use_variant",
    "default_variant", "llvm_usable", "MiBrdfsError", "MiBrdfsWarning", "ParameterError", "scenes",
]

from .registry import _install as _install  # noqa: E402

_install()


def explore(*bsdfs, variant=None, scene=None, scene_bsdf=None):
    """The interactive explorer of 1 to 4 BSDFs as a Panel layout, for Jupyter notebooks
    (:func:`mi_brdfs.explorer.explore`; needs ``pip install 'mi-brdfs[explore]'``)."""
    from .explorer import explore as _explore

    return _explore(*bsdfs, variant=variant, scene=scene, scene_bsdf=scene_bsdf)
