#!/usr/bin/env python3
"""
Eradiate's reflectance plugins (src/bsdfs/*.cpp of its Mitsuba fork, ``eradiate-mitsuba`` on
PyPI) evaluated at fixed direction pairs and parameter sets: the tables
``validation/eradiate/<plugin>.json`` that tests/plugins/test_<plugin>_eradiate.py compare the
plugins of mi_brdfs against (:data:`PLUGINS`: ours, Eradiate's of the same meaning, the sets).

Runs only in a virtual environment holding ``eradiate-mitsuba``, never in the project's: the
fork is a Mitsuba of its own and cannot share a process with Mitsuba 3.9. It imports nothing
of mi_brdfs; the values go through the JSON file alone.

    make eradiate-values                       # creates .venv-eradiate/ and runs this
    .venv-eradiate/bin/python validation/eradiate/values.py [--plugin NAME] [--out PATH]

The pairs: a grid over θi, θo (nadir, 10°-75°, near grazing 85°-89°) and the relative azimuth
φ (0° and 180°: the principal plane; 45°, 90°, 135°), exact backscatter ωo = ωi (the hot
spot) at θ = 1°, 3°, …, 89° and three azimuths, and random pairs at random azimuths of both
directions. Every direction is rounded to float32 before anything evaluates it, so that the
fork's variants and the plugin under test see the same inputs. ``eval`` returns f·cosθo; it
is recorded per variant: scalar_rgb (float32, as Eradiate renders) and scalar_mono_double
(float64); non-finite values as the strings "nan", "inf", "-inf".
"""

from __future__ import annotations

import argparse
import json
import math
import random
import struct
from pathlib import Path

import drjit as dr
import mitsuba as mi

VARIANTS = ("scalar_rgb", "scalar_mono_double")
#: Eradiate's defaults; the weights of the plugin's docstring example; the same with crowns
#: of h/b = 1.5, b/r = 2; a surface whose volume kernel drives the BRF below 0 (f_vol > 7.2
#: f_iso, where K_vol reaches its least, -0.139).
RTLS = {
    "defaults": {},
    "example": {"f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.03},
    "crowns": {"f_iso": 0.2, "f_vol": 0.1, "f_geo": 0.03, "h": 3.0, "r": 1.0, "b": 2.0},
    "volume": {"f_iso": 0.01, "f_vol": 0.2, "f_geo": 0.0},
}
#: rpv's defaults (k = 0.1: the bowl, ρc = ρ0); its docstring's example (Eradiate's); a bowl
#: (k < 1) scattering forward with ρc apart from ρ0; a bell (k > 1) scattering backward.
RPV = {
    "defaults": {},
    "example": {"rho_0": 0.02, "k": 0.3, "g": -0.12},
    "bowl": {"rho_0": 0.1, "k": 0.6, "g": 0.2, "rho_c": 0.3},
    "bell": {"rho_0": 0.2, "k": 1.4, "g": -0.3, "rho_c": 0.05},
}
#: Each plugin of mi_brdfs: Eradiate's plugin of the same model and the parameter sets.
#: ocean_mishchenko's defaults; its docstring's example; a calm sea (U = 0: Cox & Munk's
#: σ² = 0.003, the narrowest glint); a storm of an absorbing index under another exterior.
OCEAN = {
    "defaults": {},
    "example": {"wind_speed": 10.0, "eta": 1.33, "k": 0.0, "ext_ior": 1.0},
    "calm": {"wind_speed": 0.0, "eta": 1.34},
    "storm": {"wind_speed": 30.0, "eta": 1.5, "k": 0.3, "ext_ior": 1.2},
}
#: hapke's defaults (B_0 = h = 0: Eradiate's NaN at g = 0); its docstring's example, a
#: lunar-like regolith; a smooth surface (θ̄ = 0) of forward-scattering grains; a bright one
#: (w = 0.99) with a broad opposition surge, whose directional albedo exceeds 1.
HAPKE = {
    "defaults": {},
    "example": {"w": 0.3, "b": 0.25, "c": 0.7, "theta": 20.0, "B_0": 1.0, "h": 0.06},
    "smooth": {"w": 0.6, "b": 0.4, "c": 0.3, "theta": 0.0, "B_0": 0.5, "h": 0.2},
    "bright": {"w": 0.99, "b": 0.3, "c": 0.9, "theta": 10.0, "B_0": 1.0, "h": 1.0},
}
PLUGINS = {
    "rtls": ("rtls", RTLS),
    "ocean": ("ocean_mishchenko", OCEAN),
    "rpv": ("rpv", RPV),
    "hapke": ("hapke", HAPKE),
}
THETA_I = (0, 10, 30, 45, 60, 75, 85, 87, 88, 89)
THETA_O = (0, 10, 30, 45, 60, 75, 85, 86, 87, 88, 89)
PHI = (0, 45, 90, 135, 180)
#: Exact backscatter (the hot spot, ωo = ωi): θ every 2° at three azimuths of ωi.
BACKSCATTER = range(1, 90, 2)
AZIMUTHS = (0, 30, 77)
N_RANDOM = 60
SEED = 46


def direction(theta_deg: float, phi_deg: float) -> list[float]:
    """The unit vector at zenith θ, azimuth φ (degrees), rounded to float32."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    w = (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))
    return [struct.unpack("f", struct.pack("f", x))[0] for x in w]


def pairs(specular: bool = False) -> tuple[list, list, list]:
    """(wi, wo, kind) of every pair: "grid", "backscatter" (ωo = ωi) and "random"; with
    ``specular`` also "specular" (ωo the mirror image of ωi: a glint's peak) at the
    backscatter's θ and azimuths."""
    wi, wo, kind = [], [], []
    for ti in THETA_I:
        for to in THETA_O:
            for phi in (PHI if to > 0 else (0,)):
                wi.append(direction(ti, 0.0))
                wo.append(direction(to, phi))
                kind.append("grid")
    for theta in BACKSCATTER:
        for azimuth in AZIMUTHS:
            wi.append(direction(theta, azimuth))
            wo.append(list(wi[-1]))
            kind.append("backscatter")
    rng = random.Random(SEED)
    for _ in range(N_RANDOM):
        ti, to = (math.degrees(math.acos(rng.random())) for _ in range(2))
        pi_, po = (rng.uniform(0.0, 360.0) for _ in range(2))
        wi.append(direction(ti, pi_))
        wo.append(direction(to, po))
        kind.append("random")
    for theta in BACKSCATTER if specular else ():
        for azimuth in AZIMUTHS:
            wi.append(direction(theta, azimuth))
            wo.append([-wi[-1][0], -wi[-1][1], wi[-1][2]])
            kind.append("specular")
    return wi, wo, kind


def encode(x: float):
    """A float as JSON keeps it: non-finite values as strings."""
    return x if math.isfinite(x) else str(x)


def evaluate(plugin: str, variant: str, params: dict, wi: list, wo: list) -> list:
    """eval (f·cosθo) of Eradiate's ``plugin`` at each pair, in ``variant`` (one channel: the
    parameters are the same in every channel)."""
    mi.set_variant(variant)
    bsdf = mi.load_dict({"type": plugin, **params})
    ctx, out = mi.BSDFContext(), []
    for a, b in zip(wi, wo):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        si.wi = mi.Vector3f(a)
        if mi.is_spectral:
            si.wavelengths = mi.Spectrum(550.0)
        f = bsdf.eval(ctx, si, mi.Vector3f(b))
        value = [float(f[k]) for k in range(len(f))]
        assert all(v == value[0] or (math.isnan(v) and math.isnan(value[0]))
                   for v in value), value
        out.append(encode(value[0]))
    return out


def table(name: str) -> dict:
    """The whole table of our plugin ``name``: the versions, Eradiate's plugin, the parameter
    sets, the columns and one row per pair (kind, wi, wo, then eval for each set in each
    variant)."""
    from importlib.metadata import version

    plugin, sets = PLUGINS[name]
    wi, wo, kind = pairs(specular=name == "ocean")
    columns = {f"{set_name} {v}": evaluate(plugin, v, params, wi, wo)
               for set_name, params in sets.items() for v in VARIANTS}
    return {
        "generator": f"validation/eradiate/values.py --plugin {name} (make eradiate-values)",
        "eradiate_plugin": plugin,
        "eradiate_mitsuba": version("eradiate-mitsuba"),
        "mitsuba": mi.__version__, "drjit": dr.__version__,
        "variants": list(VARIANTS), "sets": sets,
        "value": "eval: f cos(theta_o), one channel",
        "columns": ["kind", "wi", "wo", *columns],
        "rows": [[k, a, b, *(c[i] for c in columns.values())]
                 for i, (k, a, b) in enumerate(zip(kind, wi, wo))],
    }


def write(data: dict, path: Path) -> None:
    """The JSON file, one line per row (readable diffs when it is regenerated)."""
    head = {k: v for k, v in data.items() if k != "rows"}
    lines = [f" {json.dumps(k)}: {json.dumps(v, allow_nan=False)}," for k, v in head.items()]
    rows = ",\n  ".join(json.dumps(r, allow_nan=False) for r in data["rows"])
    path.write_text("{\n" + "\n".join(lines) + f'\n "rows": [\n  {rows}\n ]\n}}\n')


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plugin", choices=sorted(PLUGINS), action="append",
                        help="the plugin of mi_brdfs (repeatable; default: every one)")
    parser.add_argument("--out", type=Path, help="the table's file (one --plugin only; "
                        "default: validation/eradiate/<plugin>.json)")
    args = parser.parse_args(argv)
    names = args.plugin or sorted(PLUGINS)
    if args.out and len(names) > 1:
        parser.error("--out names the file of one --plugin")
    for name in names:
        _write_table(name, args.out or Path(__file__).resolve().parent / f"{name}.json")


def _write_table(name: str, out: Path) -> None:
    """Evaluate and write the table of ``name``, and say what it holds."""
    data = table(name)
    write(data, out)
    assert json.loads(out.read_text()) == json.loads(json.dumps(data))
    off = {c: sum(isinstance(r[i], str) or r[i] < 0 for r in data["rows"])
           for i, c in enumerate(data["columns"]) if i >= 3}
    print(f"{out}: {len(data['rows'])} pairs, eradiate-mitsuba "
          f"{data['eradiate_mitsuba']}; negative or non-finite values per column: {off}")


if __name__ == "__main__":
    main()
