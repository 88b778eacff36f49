"""
The measured conductors of Mitsuba's IOR data (``data/ior/<name>.eta.spd`` and ``.k.spd``), by
the names that Mitsuba's ``conductor`` and ``roughconductor`` take for ``material``, resolved as
Mitsuba resolves them in the current variant. Importable without a variant set.
"""

from __future__ import annotations

from pathlib import Path

import mitsuba as mi
import numpy as np

from ..errors import ParameterError


def conductor_names() -> list[str]:
    """
    The names ``material`` accepts: the conductors of Mitsuba's IOR data, found through the file
    resolver as Mitsuba finds their ``data/ior/<name>.eta.spd`` files for roughconductor.
    """
    folder = Path(str(mi.file_resolver().resolve("data/ior")))
    names = {p.name[: -len(".eta.spd")] for p in folder.glob("*.eta.spd")}
    return sorted(n for n in names if (folder / f"{n}.k.spd").is_file())


def material_ior(name, plugin: str = "cooktorrance"):
    """
    The (η, k) textures of a named conductor, taken from a ``roughconductor`` with that
    ``material``: the same data, resolved as Mitsuba resolves it in the current variant (an RGB
    colour in RGB variants, the measured spectra in spectral ones, luminance in mono).
    """
    names = conductor_names()
    if not isinstance(name, str) or name not in names:
        common = ", ".join(n for n in ("Ag", "Al", "Au", "Cr", "Cu", "Hg", "Ir", "Li", "Rh", "W")
                           if n in names)
        raise ParameterError(plugin, "material", name,
                             f"must name one of Mitsuba's {len(names)} measured conductors, e.g. "
                             f"{common} (all: mi_brdfs.plugins.materials.conductor_names())")
    found = {}

    class Collect(mi.TraversalCallback):
        def put(self, key, obj, flags):
            found[key] = obj

    mi.load_dict({"type": "roughconductor", "material": name}).traverse(Collect())
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
