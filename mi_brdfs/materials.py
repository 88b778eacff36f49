"""
The measured conductors of Mitsuba's IOR data (``data/ior/<name>.eta.spd`` and ``.k.spd``), by
the names that Mitsuba's ``conductor`` and ``roughconductor`` take for ``material``, resolved as
Mitsuba resolves them in the current variant. Importable without a variant set.
"""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi
import numpy as np

from .errors import ParameterError


def conductor_names() -> list[str]:
    """
    The names ``material`` accepts: the conductors of Mitsuba's IOR data, found through the file
    resolver as Mitsuba finds their ``data/ior/<name>.eta.spd`` files for roughconductor.
    """
    folder = Path(str(mi.file_resolver().resolve("data/ior")))
    names = {p.name[: -len(".eta.spd")] for p in folder.glob("*.eta.spd")}
    return sorted(n for n in names if (folder / f"{n}.k.spd").is_file())


def _instantiate(plugin_type: str, **values):
    """A Mitsuba plugin made directly by its plugin manager, not through the scene parser: the
    plugins call this from their constructors, which Mitsuba may run on its parser's worker
    threads while a scene loads, where a nested ``mi.load_dict`` is a re-entrant parse (in two
    full test runs the showcase failed to load there, intermittently, with
    ``basic_string::_M_create``; not reproduced in isolation)."""
    props = mi.Properties(plugin_type)
    for key, value in values.items():
        props[key] = value
    return mi.PluginManager.instance().create_object(props)


def material_ior(name, plugin: str = "cooktorrance"):
    """
    The (η, k) textures of a named conductor, taken from a ``roughconductor`` with that
    ``material``: the same data, resolved as Mitsuba resolves it in the current variant (an RGB
    colour in RGB variants, the measured spectra in spectral ones, luminance in mono). ``none``
    is ``roughconductor``'s perfect conductor, η = 0, k = 1: F ≡ 1 at every angle.
    """
    names = conductor_names()
    if not isinstance(name, str) or (name not in names and name != "none"):
        common = ", ".join(n for n in ("Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ir", "Li", "Rh", "W")
                           if n in names)
        raise ParameterError(plugin, "material", name,
                             f"must name one of Mitsuba's {len(names)} measured conductors, e.g. "
                             f"{common} (all: mi_brdfs.materials.conductor_names()), or none "
                             f"(a perfect conductor)")
    found = {}

    class Collect(mi.TraversalCallback):
        def put(self, key, obj, flags):
            found[key] = obj

    _instantiate("roughconductor", material=name).traverse(Collect())
    return found["eta"], found["k"]


def conductor_ior(name: str, si=None):
    """
    (η, k) of a named conductor as float64 arrays, one value per channel of the current
    variant, the values ``cooktorrance`` and ``roughconductor`` use: RGB variants 3, mono 1,
    spectral ones the measured data at the wavelengths of ``si`` (give one there: a default
    ``mi.SurfaceInteraction3f()`` has wavelengths 0, outside the data, where η = k = 0).
    """
    eta, k = material_ior(name)
    si = si if si is not None else mi.SurfaceInteraction3f()
    return tuple(np.array(mi.unpolarized_spectrum(t.eval(si)), dtype=np.float64).ravel()
                 for t in (eta, k))


#: The dielectrics Mitsuba's ``dielectric`` and ``roughdielectric`` name for ``int_ior`` and
#: ``ext_ior`` (Mitsuba's ``ior.h``: values from Hecht, "Optics", at about 589 nm); their
#: values are read from Mitsuba itself by :func:`dielectric_ior`.
DIELECTRIC_NAMES = ("vacuum", "helium", "hydrogen", "air", "carbon dioxide", "water", "acetone",
                    "ethanol", "carbon tetrachloride", "glycerol", "benzene", "silicone oil",
                    "bromine", "water ice", "fused quartz", "pyrex", "acrylic glass",
                    "polypropylene", "bk7", "sodium chloride", "amber", "pet", "diamond")

_dielectric_cache: dict = {}


def dielectric_ior(value, plugin: str = "cooktorrance", name: str = "int_ior") -> float:
    """
    An index of refraction given as ``dielectric`` takes ``int_ior``/``ext_ior``: a positive
    number, or the name of one of :data:`DIELECTRIC_NAMES` (case-insensitive), whose value is
    the one Mitsuba's own dielectrics use (read from a ``dielectric`` with that ``int_ior``).
    """
    if isinstance(value, str):
        try:  # a number written as a string, as XML's <string> gives it
            value = float(value)
        except ValueError:
            pass
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = float(value)
        if not (value > 0 and value < float("inf")):
            raise ParameterError(plugin, name, value, "must be a finite number > 0, or the name "
                                                      "of a dielectric (e.g. bk7, water, air)")
        return value
    key = value.lower() if isinstance(value, str) else None
    if key not in DIELECTRIC_NAMES:
        raise ParameterError(plugin, name, value,
                             "must be a number > 0 or one of Mitsuba's named dielectrics: "
                             + ", ".join(DIELECTRIC_NAMES))
    if key not in _dielectric_cache:
        # The value as Mitsuba stores it: the relative index of a smooth dielectric against
        # vacuum is the bs.eta of a ray it refracts at normal incidence (not mi.traverse, which
        # must not run while a scene file is being parsed).
        smooth = _instantiate("dielectric", int_ior=key, ext_ior=1.0)
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(0.0, 0.0, 1.0)
        bs, _ = smooth.sample(mi.BSDFContext(), si, 0.999999, mi.Point2f(0.5, 0.5))
        _dielectric_cache[key] = float(np.asarray(bs.eta).ravel()[0])
    return _dielectric_cache[key]
