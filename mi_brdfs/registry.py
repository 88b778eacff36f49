"""
Registration of the package's plugins with Mitsuba, in every variant.

``mi.BSDF`` is a different class in each variant, and ``mi.register_bsdf`` registers for the
*current* variant only. Each plugin module defines its class at module level on the current
variant's ``mi.BSDF``, as Mitsuba's own Python plugins do; :func:`register` executes the module
afresh once per variant (a new module object each time, so that the classes of earlier variants
keep their own module globals) and registers the class it defines. A Mitsuba variant callback
calls :func:`register` again after every later ``mi.set_variant``.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
import warnings

import drjit as dr
import mitsuba as mi

from . import _env
from .errors import MiBrdfsError, MiBrdfsWarning


def quiet_drjit_syntax() -> None:
    """
    Silence drjit's warning that @dr.syntax was called more than 1000 times, that alone.
    Mitsuba decorates the methods of its differentiable integrators with it each time a JIT
    variant is set (mitsuba/python/ad/integrators/prb.py and others: 7 per switch in 3.9.1), so
    a process that switches variants about 140 times (an audit, a test session) is told to move
    a decorator of its own out of a loop, though it decorates nothing. Called at import, and by
    the command line, whose caller may have reset the filters (pytest does per test).
    """
    warnings.filterwarnings("ignore", message=r"The AST-transforming decorator @drjit\.syntax "
                            r"was called more than 1000 times", category=RuntimeWarning)


quiet_drjit_syntax()

#: Plugin id -> (module, name of the plugin class it defines).
PLUGINS = {
    "lambert": ("mi_brdfs.plugins.lambert", "Lambert"),
    "phong": ("mi_brdfs.plugins.phong", "Phong"),
    "cooktorrance": ("mi_brdfs.plugins.cooktorrance", "CookTorrance"),
    "ward": ("mi_brdfs.plugins.ward", "Ward"),
    "orennayar": ("mi_brdfs.plugins.orennayar", "OrenNayar"),
    "ashikhmin": ("mi_brdfs.plugins.ashikhmin", "Ashikhmin"),
    "lafortune": ("mi_brdfs.plugins.lafortune", "Lafortune"),
    "merl": ("mi_brdfs.plugins.merl", "Merl"),
    "he": ("mi_brdfs.plugins.he", "He"),
    "rtls": ("mi_brdfs.plugins.rtls", "RTLS"),
    "rpv": ("mi_brdfs.plugins.rpv", "RPV"),
    "hapke": ("mi_brdfs.plugins.hapke", "Hapke"),
    "ocean": ("mi_brdfs.plugins.ocean", "Ocean"),
    "hk": ("mi_brdfs.plugins.hk", "HK"),
}

# variant -> {plugin id -> class}
_classes: dict[str, dict[str, type]] = {}


def builtin_plugin_names() -> set[str]:
    """Names of Mitsuba's own plugins (one shared library each), which we must never shadow."""
    folder = os.path.join(os.path.dirname(mi.__file__), "plugins")
    try:
        return {os.path.splitext(f)[0] for f in os.listdir(folder)}
    except OSError:  # pragma: no cover - every wheel has the folder
        return set()


#: Mitsuba's forks on the package index: their distribution installs the ``mitsuba`` package.
FORKS = ("eradiate-mitsuba",)


def mitsuba_build() -> tuple[str, str]:
    """The distribution that installed ``mitsuba`` and its version: ``("mitsuba", "3.9.1")``,
    or a fork's (:data:`FORKS`), e.g. ``("eradiate-mitsuba", "0.5.0")`` (Mitsuba 3.7.1 with
    Eradiate's plugins, https://github.com/eradiate/mitsuba3)."""
    from importlib import metadata

    for name in FORKS:
        try:
            return name, metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return "mitsuba", mi.__version__


def own_plugins(builtins: set, build: tuple) -> list[str]:
    """
    The ids of :data:`PLUGINS` to register with a Mitsuba whose own plugins are ``builtins``,
    installed by ``build`` (:func:`mitsuba_build`). Mitsuba's plugins are never shadowed: under
    Mitsuba itself an id of ours among them is a bug (RuntimeError); a fork's own plugin of
    that name (Eradiate's ``rtls``) is the one the fork's scenes mean, so ours is left out and
    a warning says so, once per process.
    """
    clash = [name for name in PLUGINS if name in builtins]
    if clash and build[0] == "mitsuba":
        raise RuntimeError(f"mi_brdfs: plugin id '{clash[0]}' shadows a Mitsuba built-in")
    if clash and build not in _warned:
        _warned.add(build)
        warnings.warn(f"mi_brdfs: {build[0]} {build[1]} ships its own {', '.join(clash)}: "
                      f"those are used, not mi_brdfs's", MiBrdfsWarning, stacklevel=3)
    return [name for name in PLUGINS if name not in builtins]


def register() -> list[str]:
    """
    Register every plugin of the package in the current Mitsuba variant.

    Idempotent: a variant that is done already is left alone. Does nothing (and returns ``[]``)
    when no variant is set; the variant callback installed at import registers once one is.

    Returns → list[str]: the plugin ids now registered in the current variant.
    """
    variant = mi.variant()
    if variant is None:
        return []
    if variant not in _classes:
        classes = {}
        for name in own_plugins(builtin_plugin_names(), mitsuba_build()):
            module, class_name = PLUGINS[name]
            cls = getattr(_load_for_variant(module), class_name)
            mi.register_bsdf(name, _constructor(name, cls))
            classes[name] = cls
        _classes[variant] = classes
    return sorted(_classes[variant])


def _constructor(name: str, cls: type):
    """
    What Mitsuba calls to make plugin ``name``: the class, then the check that it read every
    property given (:func:`mi_brdfs.plugins.properties.check_all_read`), so that a misspelt
    parameter is one line naming the plugin, the parameter and the closest documented names,
    before Mitsuba's own check words it as an unreferenced property of an "unknown plugin".
    """
    from .plugins.properties import check_all_read

    def construct(props):
        bsdf = cls(props)
        check_all_read(props, name, cls.__doc__ or "")
        return bsdf

    return construct


def _load_for_variant(name: str):
    """
    Execute module ``name`` into a new module object for the current variant and make it the
    one ``import`` returns from now on (as re-importing a Mitsuba Python plugin does).
    """
    spec = importlib.util.find_spec(name)
    module = importlib.util.module_from_spec(spec)
    previous = sys.modules.get(name)
    sys.modules[name] = module  # a module may import itself (dataclasses, pickling)
    try:
        spec.loader.exec_module(module)
    except BaseException:
        if previous is not None:
            sys.modules[name] = previous
        else:
            del sys.modules[name]
        raise
    return module


def registered_variants() -> list[str]:
    """The variants in which :func:`register` has registered the plugins."""
    return sorted(_classes)


def plugin_class(name: str, variant: str | None = None) -> type:
    """The Python class of plugin ``name`` in ``variant`` (default: the current one)."""
    variant = variant or mi.variant()
    if variant not in _classes:
        raise MiBrdfsError(f"mi_brdfs: plugins are not registered in variant {variant!r}")
    return _classes[variant][name]


def llvm_usable() -> bool:
    """Whether drjit's LLVM backend is loaded with a libLLVM that works."""
    return bool(dr.has_backend(dr.JitBackend.LLVM)) and _env.loaded_llvm_problem() is None


def default_variant() -> str:
    """``llvm_ad_rgb`` where the LLVM backend works, else ``scalar_rgb``."""
    return "llvm_ad_rgb" if llvm_usable() else "scalar_rgb"


def usable_variants() -> list[str]:
    """The variants of this Mitsuba that can be set here: scalar ones, ``llvm_*`` where a
    working libLLVM is loaded, ``cuda_*`` where a CUDA device is."""
    ok = {"scalar_": True, "llvm_": llvm_usable(),
          "cuda_": bool(dr.has_backend(dr.JitBackend.CUDA))}
    return [v for v in mi.variants() if any(v.startswith(p) and u for p, u in ok.items())]


def _rgb(ad: bool) -> bool:
    """Whether the current variant is a plain RGB JIT one (with AD where ``ad``)."""
    return mi.variant() is not None and mi.is_rgb and not mi.is_polarized \
        and bool(dr.is_jit_v(mi.Float)) and (not ad or bool(dr.is_diff_v(mi.Float)))


def use_rgb_jit(who: str, variant: str | None = None, ad: bool = False) -> str:
    """
    Set the variant of an entry point that works in an RGB JIT variant (``measure``: MERL's
    format holds RGB; ``fit``: Adam needs automatic differentiation, ``ad``) and return it:
    ``variant`` where given, else the current variant where it is such a variant, else
    ``llvm_ad_rgb`` (``cuda_ad_rgb`` from another ``cuda_*`` variant). The entry point hands
    the caller's variant back on return (:func:`mi_brdfs.variants.keeps_variant`).

    Raises MiBrdfsError (one line naming ``who``) for a ``variant`` that is no such variant,
    or where the one it would switch to cannot run here (no working libLLVM).
    """
    kind = "an RGB variant with automatic differentiation" if ad else "an RGB JIT variant"
    if variant is None and _rgb(ad):
        return mi.variant()
    if variant is None:
        current = mi.variant() or ""
        variant = "cuda_ad_rgb" if current.startswith("cuda_") else "llvm_ad_rgb"
        try:
            return use_variant(variant, fallback=False)
        except MiBrdfsError as e:
            raise MiBrdfsError(f"{who} needs {kind} (llvm_ad_rgb or cuda_ad_rgb), and switching "
                               f"from {current or 'no variant'} failed: {e}") from None
    use_variant(variant, fallback=False)
    if not _rgb(ad):
        lacks = "no AD" if ad and not dr.is_diff_v(mi.Float) else \
            "no JIT" if not dr.is_jit_v(mi.Float) else "no plain RGB"
        raise MiBrdfsError(f"{who} needs {kind} (llvm_ad_rgb or cuda_ad_rgb); {variant} has "
                           f"{lacks}")
    return variant


def use_variant(variant: str | None = None, fallback: bool = True) -> str:
    """
    Set a Mitsuba variant and register the plugins in it.

    Parameter ``variant`` (str | None): the variant; ``None`` means :func:`default_variant`.

    Parameter ``fallback`` (bool): when an ``llvm_*`` variant is asked for but no working libLLVM
    is there, warn in one line and use the scalar counterpart instead of failing.

    Returns → str: the variant now set. Raises MiBrdfsError (one line) for a variant this
    Mitsuba lacks or this machine cannot run (a ``cuda_*`` one without a CUDA device: the line
    names the variants that are usable here).
    """
    if variant is None:
        variant = default_variant()
        if variant == "scalar_rgb" and not llvm_usable():
            _warn_no_llvm("llvm_ad_rgb", variant)
    available = mi.variants()
    if variant not in available:
        raise MiBrdfsError(f"unknown variant '{variant}'; this Mitsuba has: {', '.join(available)}")
    if variant.startswith("llvm_") and not llvm_usable():
        if not fallback:
            raise MiBrdfsError(f"variant '{variant}' is unusable: {_llvm_problem()}")
        scalar = variant.replace("llvm_ad_", "scalar_")
        scalar = scalar if scalar in available else "scalar_rgb"
        _warn_no_llvm(variant, scalar)
        variant = scalar
    if variant.startswith("cuda_") and not dr.has_backend(dr.JitBackend.CUDA):
        raise MiBrdfsError(f"variant '{variant}' needs a CUDA device, and this machine has none "
                           f"(no NVIDIA GPU or driver); usable here: "
                           f"{', '.join(usable_variants())}")
    try:
        mi.set_variant(variant)
    except (ImportError, RuntimeError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise MiBrdfsError(f"variant '{variant}' is unusable here: {first}") from None
    register()
    return variant


def _llvm_problem() -> str:
    return (_env.loaded_llvm_problem() or _env.find_llvm().message
            or f"drjit's LLVM backend is off; fix: {_env.LLVM_FIX}")


_warned: set = set()


def _warn_no_llvm(wanted: str, instead: str) -> None:
    """Say once per process, in one line, why an LLVM variant is not used and how to fix it."""
    if (wanted, instead) not in _warned:
        _warned.add((wanted, instead))
        warnings.warn(f"{_llvm_problem()}; using {instead} instead of {wanted}", MiBrdfsWarning,
                      stacklevel=3)


def _on_variant_change(old, new) -> None:
    try:
        register()
    except Exception as e:  # a callback must not break mi.set_variant itself
        warnings.warn(f"mi_brdfs: registering the plugins in {new} failed: {e}", MiBrdfsWarning)


_installed = False


def _install() -> None:
    """Register in the current variant now and after every later ``mi.set_variant``."""
    global _installed
    if _installed:
        return
    _installed = True
    mi.detail.add_variant_callback(_on_variant_change)
    if _env.DRJIT_IMPORTED_FIRST and mi.variant() and mi.variant().startswith("llvm_"):
        problem = _env.loaded_llvm_problem()
        if problem:
            warnings.warn(problem, MiBrdfsWarning, stacklevel=3)
    register()

