"""
The report's section on ``cooktorrance``'s energy compensation (Kulla & Conty 2017) against
the random walk of Heitz et al. (2016), in quick mode: its rows, named values and figures; and
its white-furnace rows reject the plugin with its albedo tables scaled by 0.98. The full grids
run in ``mi-brdfs validate --only multiscatter``.
"""

import re

from mi_brdfs import campaign
from mi_brdfs.campaign import multiscatter
from mi_brdfs.campaign import multiscatter_dielectric as dielectric
from mi_brdfs.campaign.core import Context, Section
from mi_brdfs.scattering import multiscatter as tables

FIGURES = ("multiscatter_furnace.png", "multiscatter_lobes.png",
           "multiscatter_furnace_render.png", "multiscatter_dielectric_render.png")


def _rows(section, plugin_part: str, check_part: str) -> list:
    return [r for r in section.rows if plugin_part in r.plugin and check_part in r.check]


def test01_quick_section_rows_values_and_figures(variant_llvm_ad_rgb, tmp_path):
    ctx = Context(tmp_path, quick=True)
    s = multiscatter.section(ctx)
    assert s.title == "Energy compensation: cooktorrance multiscatter"
    # the white furnace, per distribution and α: closed form, sample(), eval = closed form
    for kind in ("ggx", "beckmann"):
        closed = _rows(s, f"{kind} smith", "float64 closed form")
        sampled = _rows(s, f"{kind} smith", "mean sample() weight")
        assert len(closed) == len(sampled) == 2
        assert all(r.passed for r in sampled), [r.result for r in sampled]
        assert all(r.passed for r in _rows(s, f"{kind} smith", "eval integrated"))
        # both reach the target in closed form (the tables hold ∫ f cosθo, from D·cosθ
        # sampling)
        for r in closed:
            value = float(re.search(r"= ([\d.e+-]+)", r.result).group(1))
            assert r.judged and r.passed and value < 2e-3, r.result
        assert all(r.passed for r in _rows(s, f"{kind} vcavity", ""))
    # measured rows: the walk, anisotropy (flagged), lobes, gold
    for plugin, check in (("ggx", "random walk order 1"), ("beckmann", "every order"),
                          ("anisotropic", "equivalent α"), ("ggx", "relative L1"),
                          ("beckmann", "relative L1"), ("gold", "random walk total")):
        assert len(_rows(s, plugin, check)) >= 1, (plugin, check)
    assert all("above 0.01" in r.result for r in _rows(s, "anisotropic", ""))
    # the render: compensated sphere at 1, the single-scattering one = roughconductor
    render = _rows(s, "(ggx smith, α = 1)", "white furnace render")
    assert len(render) == 3 and all(r.passed for r in render), [r.result for r in render]
    # the dielectric: the furnace from both sides, the walk's total, the η sweep, the render
    for kind in ("ggx", "beckmann"):
        rows = _rows(s, f"transmission multiscatter {kind}", "white furnace in importance")
        assert len(rows) == 2 and all(r.passed for r in rows), [r.result for r in rows]
        assert _rows(s, f"transmission multiscatter {kind}", "random walk")[0].passed
    assert len(_rows(s, "transmission multiscatter", "reflected share")) == 2
    assert _rows(s, "transmission multiscatter", "over η")[0].passed
    assert _rows(s, "transmission multiscatter (ggx", "every path")[0].passed
    assert not [r for r in s.rows if not r.ok]
    for key in ("multiscatter: worst ggx smith closed form", "multiscatter: lobe L1 beckmann",
                "multiscatter: gold worst relative", "multiscatter: render cooktorrance "
                "multiscatter", "multiscatter dielectric: worst ggx",
                "multiscatter dielectric: render"):
        assert key in s.values
    for name in FIGURES:
        assert (tmp_path / "figures" / name).stat().st_size > 1000, name
        assert f"(figures/{name})" in s.markdown
    names = [f.__module__.rsplit(".", 1)[-1] for f in campaign.sections()]
    assert names[names.index("transmission") + 1] == "multiscatter"


def test02_tables_scaled_by_098_fail_the_furnace(variant_llvm_ad_rgb, tmp_path, monkeypatch):
    """The plugin reading E and E_avg scaled by 0.98 gains 0.02·E(μi): its sample() and eval
    rows fail; the closed form reads the shipped file, not the plugin, and still passes."""
    shipped = tables.load_tables()
    scaled = {"E": {k: 0.98 * v for k, v in shipped["E"].items()},
              "E_avg": {k: 0.98 * v for k, v in shipped["E_avg"].items()},
              "alpha_max": shipped["alpha_max"]}
    monkeypatch.setattr(tables, "load_tables", lambda *args: scaled)
    ctx = Context(tmp_path, quick=True)
    grid = multiscatter.furnace_grid(ctx, kinds=("ggx",), alphas=(1.0,), thetas=(60.0,),
                                     walk=False)
    s = Section("broken")
    multiscatter.furnace_rows(grid, s)
    assert not _rows(s, "ggx smith", "mean sample() weight")[0].passed
    assert not _rows(s, "ggx smith", "eval integrated")[0].passed
    assert _rows(s, "ggx smith", "float64 closed form")[0].passed


def test03_dielectric_tables_scaled_by_098_fail_the_furnace(variant_llvm_ad_rgb, tmp_path,
                                                            monkeypatch):
    """The dielectric's tables scaled by 0.98 in the plugin: its sample() rows fail, the
    closed form (the reference reads the file) passes."""
    shipped = tables.dielectric_arrays
    monkeypatch.setattr(tables, "dielectric_arrays", lambda kind, eta: tuple(
        (0.98 * E, 0.98 * E_avg) for E, E_avg in shipped(kind, eta)))
    ctx = Context(tmp_path, quick=True)
    s = Section("broken")
    dielectric.furnace_rows(dielectric.furnace_grid(ctx, multiscatter.sampled), s)
    assert not any(r.passed for r in _rows(s, "transmission multiscatter", "mean sample()"))
    assert all(r.passed for r in _rows(s, "transmission multiscatter", "closed form"))
