"""
Fits to measured data: a MERL file is a target like any BSDF (``fit X.binary``), compared at its
own bins with its own values, under each metric of the field (``--metric``): the pairs' solid
angle weights against a closed form, a known answer recovered from a tabulated BSDF with noise,
and the one-line errors.
"""

import json
import math

import numpy as np
import pytest

from helpers import cli_one_line_error
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.fit import METRICS, direction_pairs, fit
from mi_brdfs.fit.optimise import measured_pairs, metric_weights, objective_np
from mi_brdfs.measured import merl
from mi_brdfs.measured.tabulate import measure


@pytest.fixture(scope="module")
def ggx_file(tmp_path_factory):
    """roughconductor GGX α = 0.25 (gold) tabulated, with 3 % relative noise."""
    import mi_brdfs

    mi_brdfs.use_variant("llvm_ad_rgb")
    path = tmp_path_factory.mktemp("measured") / "ggx.binary"
    measure("roughconductor distribution=ggx alpha=0.25 material=Au", path, noise=(0.03, 0.0))
    return path


def test01_solid_angle_weights():
    """Over pairs with both directions above the surface, dωi dωo has total measure (2π)²
    and ∫∫ cosθi cosθo dωi dωo = π²: the weighted mean of cosθi·cosθo is 1/4 (2 % here, a
    Monte Carlo estimate). Unweighted (the pairs' own density) it is not; the weights of
    'bieron' add cosθo."""
    wi, wo = direction_pairs(400_000, seed=3)
    cos = wi[:, 2] * wo[:, 2]
    w = metric_weights("ngan", wi, wo)
    assert np.mean(w * cos) == pytest.approx(0.25, rel=0.02)
    assert abs(np.mean(cos) - 0.25) > 0.05
    b = metric_weights("bieron", wi, wo)
    assert np.allclose(b / b.mean(), w * wo[:, 2] / np.mean(w * wo[:, 2]))
    assert np.array_equal(metric_weights("cuberoot", wi, wo), np.ones(len(wi)))


def test02_measured_pairs_are_the_bins(ggx_file):
    """The pairs are bin centres (their half/difference angles fall on the centres) with the
    file's values, measured bins only, deterministic in the seed."""
    wi, wo, values = measured_pairs(ggx_file, 2000, seed=1)
    data = merl.read(ggx_file)
    theta_h, _, theta_d, phi_d = merl.half_diff(wi, wo)
    x, y, z = merl.coordinates(theta_h, theta_d, phi_d)
    assert np.allclose([x, y, z], np.round([x, y, z]), atol=1e-6)
    assert np.allclose(values / wo[:, 2:3], merl.lookup(data, wi, wo), rtol=1e-12)
    again = measured_pairs(ggx_file, 2000, seed=1)
    assert np.array_equal(again[0], wi) and len(wi) == 2000


@pytest.mark.parametrize("metric", list(METRICS))
def test03_alpha_recovered_from_noisy_data(ggx_file, metric):
    """A fit of cooktorrance (Smith, GGX, gold) from α = 0.08 to the tabulated, noisy
    roughconductor α = 0.25 recovers α within 2 % under every metric."""
    result = fit(str(ggx_file), "cooktorrance distribution=ggx shadowing=smith material=Au "
                 "alpha=0.08", "alpha", pairs=4096, steps=300, starts="given",
                 thetas_deg=(0.0, 60.0), metric=metric)
    assert result.parameters["alpha"] == pytest.approx(0.25, rel=0.02), metric
    assert result.metric == metric and not result.flags
    assert "measured target" in " ".join(result.notes)


def test04_zero_model_objective():
    """The objective of the zero model under each metric, in closed form for one pair."""
    wi, wo = np.array([[0.0, 0.0, 1.0]]), np.array([[0.6, 0.0, 0.8]])
    target = np.array([[0.8, 0.8, 0.8]])  # f·cosθo: f = 1
    assert objective_np("ngan", np.zeros((1, 3)), wi, wo, target) == pytest.approx(1.0)
    assert objective_np("low", np.zeros((1, 3)), wi, wo, target) == \
        pytest.approx(math.log(2.0) ** 2)
    assert objective_np("cuberoot", np.zeros((1, 3)), wi, wo, target) == \
        pytest.approx(((0.8 + 1e-6) ** (1 / 3) - 1e-2) ** 2, rel=1e-6)


def test05_errors(ggx_file):
    with pytest.raises(MiBrdfsError, match="metric = 'l1' is invalid: must be one of "
                                           "'cuberoot', 'ngan', 'low', 'bieron'"):
        fit(str(ggx_file), "cooktorrance", "alpha", metric="l1")
    cli_one_line_error(["fit", str(ggx_file), "--model", "ward", "--metric", "l1"],
                       "invalid choice: 'l1'")
    cli_one_line_error(["fit", "missing.binary", "--model", "ward"],
                       "missing.binary: cannot read the MERL file")


def _main(args, monkeypatch, capsys) -> tuple:
    """``mi-brdfs args`` in this process (tests/cli runs the command line in subprocesses):
    (exit status, stdout, stderr)."""
    from mi_brdfs.cli import main

    monkeypatch.setenv("MI_BRDFS_NO_PROGRESS", "1")
    code = main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def test06_cli(ggx_file, tmp_path, monkeypatch, capsys):
    code, out, err = _main(["fit", str(ggx_file), "--model", "ward", "--metric", "low",
                            "--pairs", "1024", "--steps", "20", "-q",
                            "-o", str(tmp_path / "f.json")], monkeypatch, capsys)
    assert code == 0, err
    assert "metric: low" in out and "measured target: 1024 of its bins" in out
    assert json.loads((tmp_path / "f.json").read_text())["metric"] == "low"


def test07_ranking_table():
    """Each metric's column ranks the models by its own objective, lowest first."""
    from mi_brdfs.fit.models import ranking_table

    table = {"a": {"cuberoot": 3.0, "ngan": 1.0, "low": 2.0, "bieron": 1.0},
             "b": {"cuberoot": 1.0, "ngan": 2.0, "low": 1.0, "bieron": 3.0},
             "c": {"cuberoot": 2.0, "ngan": 3.0, "low": 3.0, "bieron": 2.0}}
    rows = {r[0]: r[1:] for r in ranking_table(table)}
    assert rows["a"] == ("3 (3)", "1 (1)", "2 (2)", "1 (1)")
    assert rows["b"] == ("1 (1)", "2 (2)", "1 (1)", "3 (3)")


def test08_models_all_cli(ggx_file, tmp_path, monkeypatch, capsys):
    """--models fits the lecture models named, scores each under every metric and writes the
    report, its JSON and the two figures; Cook-Torrance, the target's own model family, ranks
    first under every metric against Phong. Bad names are one line."""
    code, _, err = _main(["fit", str(ggx_file), "--models", "phong,cooktorrance", "--pairs",
                          "1024", "--steps", "40", "-q", "--out", str(tmp_path)],
                         monkeypatch, capsys)
    assert code == 0, err
    assert sorted(f.name for f in tmp_path.iterdir()) == ["lobes.png", "models.json",
                                                          "models.md", "spheres.png"]
    doc = json.loads((tmp_path / "models.json").read_text())
    scores = doc["scores"]
    assert set(scores) == {"phong", "cooktorrance"} and set(scores["phong"]) == set(METRICS)
    assert all(scores["cooktorrance"][m] < scores["phong"][m] for m in METRICS)
    assert "| cooktorrance | " in (tmp_path / "models.md").read_text()
    cli_one_line_error(["fit", str(ggx_file), "--models", "phong,torrance"],
                       "--models phong,torrance: torrance is not a lecture model")
    cli_one_line_error(["fit", str(ggx_file), "--models", "all", "--model", "ward"],
                       "not allowed with argument")


def test09_compare_published(tmp_path, monkeypatch, capsys):
    """Data tabulated from Ngan et al.'s published Ward fit of blue-acrylic: that preset
    scores (near) 0 on it under every metric, another material's does not; a model without an
    exact preset says why. The command takes the material's name from the file's."""
    from mi_brdfs import presets
    from mi_brdfs.fit.models import fit_models, published

    path = tmp_path / "blue-acrylic.binary"
    measure(presets.spec("ward", "ngan:blue-acrylic"), path, variant="llvm_ad_rgb")
    sizes = dict(pairs=1024, steps=30, figures=False)
    done = fit_models(str(path), ["ward", "ashikhmin"], "ngan", tmp_path, **sizes,
                      compare_published="blue-acrylic")
    theirs, why = done["published"]["ward"][0], done["published"]["ashikhmin"]
    assert all(theirs[m] < 1e-4 * max(done["scores"]["ward"][m], 1e-12) + 1e-9
               for m in METRICS), theirs
    assert why[0] is None and "no exact form in ashikhmin" in why[1]
    # another material's preset, scored on the same pairs as the fits (seed 0)
    other = published(str(path), ["ward"], "gold-metallic-paint", 1024, 0)["ward"][0]
    assert other["ngan"] > 100 * (theirs["ngan"] + 1e-12)
    code, out, err = _main(["fit", str(path), "--models", "ward", "--compare-published",
                            "--pairs", "1024", "--steps", "20", "-q",
                            "--out", str(tmp_path / "cli")], monkeypatch, capsys)
    assert code == 0, err
    assert "| ward | " in out and "published / ours" in out
    assert "blue-acrylic" in (tmp_path / "cli" / "models.md").read_text()
