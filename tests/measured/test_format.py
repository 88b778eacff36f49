"""
MERL's format (mi_brdfs.measured.merl) and the virtual gonioreflectometer
(mi_brdfs.measured.tabulate): the half/difference angles against closed forms, the bins as
MERL's reader computes them, the file's bytes read directly, one-line errors for bad files, and
tabulated BSDFs against their own evaluation.
"""

import numpy as np
import pytest

from helpers import cli_one_line_error, run
from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.measured import merl
from mi_brdfs.measured.tabulate import measure


def _unit(theta, phi):
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def test01_half_diff_closed_forms():
    """Mirror pair: θh = 0, θd = θi, φd = 0 (the difference vector is ωi). Normal incidence
    and ωo at θ: h halfway, θh = θd = θ/2, φd = π (ωi leans away from h). Rotating both
    directions about the normal changes φh alone."""
    a = 0.7
    mirror = np.array([-np.sin(a), 0.0, np.cos(a)])  # h exactly the normal, φh = atan2(0, 0)
    th, ph, td, pd = merl.half_diff(_unit(a, 0.0)[None], mirror[None])
    assert np.allclose([th[0], td[0], pd[0]], [0.0, a, 0.0], atol=1e-12)
    b = 1.1
    th, ph, td, pd = merl.half_diff(_unit(0.0, 0.0)[None], _unit(b, 0.0)[None])
    assert np.allclose([th[0], ph[0], td[0], abs(pd[0])], [b / 2, 0.0, b / 2, np.pi], atol=1e-12)
    rng = np.random.default_rng(1)
    wi = _unit(rng.random(50), 6 * rng.random(50)).T
    wo = _unit(rng.random(50), 6 * rng.random(50)).T
    rot = 0.9
    c, s = np.cos(rot), np.sin(rot)
    turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    before, after = merl.half_diff(wi, wo), merl.half_diff(wi @ turn.T, wo @ turn.T)
    for k in (0, 2, 3):
        assert np.allclose(before[k], after[k], atol=1e-9)
    assert np.allclose(np.angle(np.exp(1j * (after[1] - before[1]))), rot, atol=1e-9)


def test02_directions_invert_half_diff():
    rng = np.random.default_rng(2)
    n = 1000
    angles = (rng.random(n) * np.pi / 2, rng.uniform(-np.pi, np.pi, n),
              rng.random(n) * np.pi / 2, rng.uniform(-np.pi, np.pi, n))
    wi, wo = merl.directions(*angles)
    assert np.allclose(np.linalg.norm(wi, axis=1), 1) and np.allclose(np.linalg.norm(wo, axis=1), 1)
    back = merl.half_diff(wi, wo)
    for got, want in zip(back, angles):
        assert np.allclose(np.angle(np.exp(1j * (got - want))), 0.0, atol=1e-7)


def test03_bins_as_merl_reader():
    """θh by its square root, θd linearly, φd folded into [0, π), each clamped (values worked
    out by hand from the reader's formulas)."""
    half_pi = np.pi / 2
    i, j, k = merl.indices(np.array([0.0, half_pi * (10.5 / 90) ** 2, half_pi, -1e-9]),
                           np.array([0.0, np.pi / 4 + 1e-9, half_pi, 0.0]),
                           np.array([0.0, -half_pi + 1e-9, np.pi, -1e-9]))
    assert i.tolist() == [0, 10, 89, 0]
    assert j.tolist() == [0, 45, 89, 0]
    assert k.tolist() == [0, 90, 179, 179]
    # every bin centre falls in its own bin
    th, td, pd = merl.bin_centres()
    got = merl.indices(th, td, pd)
    want = np.indices(merl.RES)
    assert all(np.array_equal(g, w) for g, w in zip(got, want))


def test04_file_bytes_and_round_trip(tmp_path):
    """The header and the stored values read directly from the bytes: channel c of bin
    (i, j, k) at 3 + ... (red, green, blue blocks), divided by MERL's scales; unmeasured -1.
    A writer with a channel's scale wrong, or the θd and φd axes transposed, fails here."""
    rng = np.random.default_rng(3)
    values = rng.random((3,) + merl.RES)
    values[:, 5, 6, 7] = np.nan
    path = tmp_path / "x.binary"
    merl.write(path, values)
    data = path.read_bytes()
    assert len(data) == merl.SIZE
    assert np.frombuffer(data[:12], "<i4").tolist() == [90, 90, 180]
    raw = np.frombuffer(data[12:], "<f8")
    block = 90 * 90 * 180
    for c, scale in enumerate((1 / 1500, 1.15 / 1500, 1.66 / 1500)):
        index = c * block + 12 * 180 * 90 + 34 * 180 + 56  # θh 12, θd 34, φd 56
        assert raw[index] == pytest.approx(values[c, 12, 34, 56] / scale, rel=1e-15)
        assert raw[c * block + 5 * 180 * 90 + 6 * 180 + 7] == -1.0
    back = merl.read(path)
    assert np.array_equal(np.isnan(back), np.isnan(values))
    assert np.allclose(back[~np.isnan(back)], values[~np.isnan(values)], rtol=1e-15)


@pytest.mark.parametrize("content,message", [
    (None, "cannot read the MERL file"),
    (b"\x01\x02", "2 bytes, too short for a MERL file"),
    (np.array([90, 90, 360], "<i4").tobytes() + b"\0" * 64, "dimensions (90, 90, 360), not "
                                                             "MERL's (90, 90, 180)"),
    (np.array([90, 90, 180], "<i4").tobytes() + b"\0" * 64, "76 bytes where a MERL file has "
                                                            "34992012"),
    ("nan", "1 values are NaN or beyond float32's range"),
    ("huge", "1 values are NaN or beyond float32's range"),
])
def test05_bad_files_are_one_line(tmp_path, content, message):
    path = tmp_path / "bad.binary"
    if isinstance(content, str):  # a complete file, one value NaN or 1e300
        raw = np.zeros(3 * 90 * 90 * 180)
        raw[1234] = np.nan if content == "nan" else 1e300
        content = np.array([90, 90, 180], "<i4").tobytes() + raw.astype("<f8").tobytes()
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(MiBrdfsError, match="bad.binary: ") as e:
        merl.read(path)
    assert message in str(e.value) and "\n" not in str(e.value)


def test06_measure_diffuse_closed_form(variant_llvm_ad_rgb):
    """A diffuse reflector measures ρ/π in every bin above the horizon, NaN exactly where
    either direction is below it."""
    values = measure({"type": "diffuse", "reflectance": {"type": "rgb",
                                                         "value": [0.2, 0.5, 0.8]}})
    wi, wo = merl.bin_directions()
    below = ((wi[:, 2] <= 0) | (wo[:, 2] <= 0)).reshape(merl.RES)
    assert np.array_equal(np.isnan(values[0]), below)
    for c, rho in enumerate((0.2, 0.5, 0.8)):
        assert np.allclose(values[c][~below], rho / np.pi, rtol=1e-5)


def test07_lookup_of_a_tabulated_bsdf(variant_llvm_ad_rgb):
    """roughconductor tabulated, then looked up at each bin's centre turned by a random φh
    (an isotropic BSDF does not see it): MERL's nearest-bin lookup returns the BSDF's own
    f = eval/cosθo there, to float32 rounding. A lookup or tabulation with its axes crossed,
    or φd unfolded, fails here."""
    from mi_brdfs.checks.batch import evaluate

    spec = {"type": "roughconductor", "alpha": 0.3, "material": "Au"}
    values = measure(spec)
    theta_h, theta_d, phi_d = (a.ravel() for a in merl.bin_centres())
    rng = np.random.default_rng(4)
    pick = rng.choice(len(theta_h), 5000, replace=False)
    wi, wo = merl.directions(theta_h[pick], rng.uniform(-np.pi, np.pi, 5000), theta_d[pick],
                             phi_d[pick])
    keep = (wi[:, 2] > 1e-3) & (wo[:, 2] > 1e-3)
    wi, wo = wi[keep], wo[keep]
    direct = evaluate(spec, wi, wo).value / wo[:, 2:3]
    looked = merl.lookup(values, wi, wo)
    assert np.allclose(looked, direct, rtol=2e-3, atol=1e-6)
    swapped = merl.lookup(values, wo, wi)  # reciprocal: the same bin
    assert np.allclose(swapped, looked, rtol=1e-12)


def test08_cli(variant_llvm_ad_rgb, tmp_path, monkeypatch):
    """mi-brdfs measure writes the file; bad input is one line and writes nothing."""
    monkeypatch.chdir(tmp_path)
    p = run("measure", "diffuse reflectance=0.5", "-o", "d.binary")
    assert p.returncode == 0, p.stderr
    assert "wrote" in p.stdout and "1096216 of 1458000 bins measured" in p.stdout
    assert np.nanmax(np.abs(merl.read(tmp_path / "d.binary") - 0.5 / np.pi)) < 1e-6
    p = run("measure", "diffuse reflectance=0.5", "--noise", "0.02", "-o", "n.binary")
    assert p.returncode == 0, p.stderr
    spread = np.nanstd(merl.read(tmp_path / "n.binary") / (0.5 / np.pi))
    assert 0.018 < spread < 0.022
    (tmp_path / "n.binary").unlink()
    for args, message in [
        (["measure", "diffuse", "-o", "d.txt"], "'d.txt' must end in .binary"),
        (["measure", "diffuse", "lambert", "-o", "e.binary"], "2 BSDFs given; give one"),
        (["measure", "diffuse", "--variant", "scalar_rgb", "-o", "e.binary"],
         "measure needs an RGB JIT variant"),
        (["measure", "diffuse", "-o", "/nonexistent/e.binary"], "does not exist"),
        (["measure", "diffuse", "--noise", "0.1,-1", "-o", "e.binary"],
         "'0.1,-1' is not REL or REL,ABS"),
    ]:
        cli_one_line_error(args, message)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.binary"]


def _at_coordinates(x, y, z):
    """A direction pair at continuous bin coordinates (x, y, z) (φh = 0)."""
    theta_h = ((np.asarray(x) + 0.5) / 90) ** 2 * np.pi / 2
    theta_d = (np.asarray(y) + 0.5) / 90 * np.pi / 2
    phi_d = (np.asarray(z) + 0.5) / 180 * np.pi
    return merl.directions(theta_h, 0.0, theta_d, phi_d)


def test09_interpolation_closed_forms():
    """Trilinear between bin centres: data linear in the bin coordinates come back exactly
    between the centres (and clamped beyond the first and last); a single bin k = 0 of φd is
    seen half at z = −½ and z = 179.5, its neighbours across the fold (f(φd) = f(φd + π)); the
    result is reciprocal. An interpolation with an axis misplaced, or φd clamped instead of
    periodic, fails here."""
    i, j, k = np.indices(merl.RES, dtype=np.float64)
    linear = np.stack([1.0 + 0.01 * i + 0.02 * j,
                       2.0 + 0.03 * i, 0.5 + 0.004 * j])
    rng = np.random.default_rng(5)
    x, y, z = rng.uniform(0, 89, 400), rng.uniform(0, 80, 400), rng.uniform(0, 179, 400)
    wi, wo = _at_coordinates(x, y, z)
    keep = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    want = np.stack([1 + 0.01 * x + 0.02 * y, 2 + 0.03 * x, 0.5 + 0.004 * y], axis=1)
    got = merl.interpolate(linear, wi, wo)
    assert np.allclose(got[keep], want[keep], rtol=1e-9)
    assert np.allclose(merl.interpolate(linear, wo, wi)[keep], got[keep], rtol=1e-12)
    below = merl.interpolate(linear, *_at_coordinates(np.array([-0.4]), np.array([10.0]),
                                                       np.array([5.0])))
    assert np.allclose(below, [[1.2, 2.0, 0.54]], rtol=1e-9)  # x clamped to the first bin
    hat = np.zeros((3,) + merl.RES)
    hat[:, 30, 20, 0] = 1.0
    for z, expected in ((0.0, 1.0), (-0.5, 0.5), (179.5, 0.5), (179.0, 0.0), (0.25, 0.75)):
        pair = _at_coordinates(np.array([30.0]), np.array([20.0]), np.array([z]))
        assert merl.interpolate(hat, *pair)[0, 0] == pytest.approx(expected, abs=1e-9), z


def test10_noise_model():
    """f·(1 + r·ε₁) + a·ε₂ clipped at 0: the relative spread of the noisy values is r where
    the additive term is negligible, the additive spread a where f = 0 (half the draws clip
    to 0); a seed repeats, another differs; NaN stays NaN; no noise returns the values."""
    from mi_brdfs.measured.tabulate import add_noise

    values = np.full((3,) + merl.RES, 2.0)
    values[:, :, :, :90] = 0.0
    values[:, 0] = np.nan
    noisy = add_noise(values, 0.05, 1e-3, seed=7)
    rel = (noisy[:, 1:, :, 90:] - 2.0) / 2.0
    assert abs(rel.std() - 0.05) < 0.001 and abs(rel.mean()) < 0.001
    floor = noisy[:, 1:, :, :90]
    assert abs(np.mean(floor == 0.0) - 0.5) < 0.01
    assert abs(np.sqrt(np.mean(floor ** 2) * 2) - 1e-3) < 5e-5
    assert np.isnan(noisy[:, 0]).all() and not np.isnan(noisy[:, 1:]).any()
    assert np.array_equal(add_noise(values, 0.05, 1e-3, seed=7), noisy, equal_nan=True)
    assert not np.array_equal(add_noise(values, 0.05, 1e-3, seed=8), noisy, equal_nan=True)
    assert add_noise(values) is values
    with pytest.raises(MiBrdfsError, match="relative noise must be finite and ≥ 0, not -0.1"):
        add_noise(values, -0.1)


#: BSDFs no MERL table describes, and what measure's one line says of each.
UNMEASURABLE = [
    ("conductor", "conductor has no diffuse or glossy reflection"),
    ("dielectric", "dielectric has no diffuse or glossy reflection"),
    ({"type": "lambert", "reflectance": {"type": "checkerboard"}},
     "has a parameter that varies over the surface, reflectance (Checkerboard)"),
    ({"type": "twosided", "bsdf": {"type": "roughconductor", "alpha": {
        "type": "mesh_attribute", "name": "vertex_color"}}},
     "varies over the surface, brdf_0.alpha (MeshAttribute); MERL's format holds one BRDF"),
    ("diffuse reflectance=0", "is 0 at every bin above the horizon"),
    ("roughdielectric specular_reflectance=0", "is 0 at every bin above the horizon"),
]


@pytest.mark.parametrize("spec,message", UNMEASURABLE)
def test11_what_no_table_holds_is_refused_before_writing(variant_llvm_ad_rgb, tmp_path, spec,
                                                          message):
    """A delta BSDF once wrote a 35 MB file of zeros, and a textured one a table of the
    texture at one point, both with exit 0: each is one line now, and nothing is written."""
    path = tmp_path / "m.binary"
    with pytest.raises(MiBrdfsError) as info:
        measure(spec, path)
    assert message in str(info.value) and "\n" not in str(info.value)
    assert not path.exists()


def test12_measure_hands_the_callers_variant_back(variant_scalar_rgb, tmp_path, monkeypatch):
    """measure() from scalar_rgb measures in llvm_ad_rgb and sets scalar_rgb again (it once
    left llvm_ad_rgb set, and the caller's next mi.render of a scene it had loaded failed
    with a bare AssertionError), also when it raises; the CLI refuses a delta BSDF too."""
    import mitsuba as mi

    from conftest import LLVM_OK

    if not LLVM_OK:
        pytest.skip("no working libLLVM")
    film = {"type": "hdrfilm", "width": 8, "height": 8}
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path"},
                          "sensor": {"type": "perspective", "film": film},
                          "emitter": {"type": "constant"}, "shape": {"type": "sphere"}})
    values = measure("diffuse reflectance=0.5")
    assert mi.variant() == "scalar_rgb"
    assert np.nanmax(values) == pytest.approx(0.5 / np.pi, rel=1e-5)
    with pytest.raises(MiBrdfsError):
        measure("conductor")
    assert mi.variant() == "scalar_rgb"
    assert np.all(np.isfinite(np.array(mi.render(scene, spp=1))))
    monkeypatch.chdir(tmp_path)
    cli_one_line_error(["measure", "conductor", "-o", "c.binary"],
                       "conductor has no diffuse or glossy reflection")
    assert list(tmp_path.iterdir()) == []


def test13_what_the_table_leaves_out_is_said(variant_llvm_ad_rgb):
    """plastic's delta coating and roughdielectric's transmission have no place in a BRDF
    table: their diffuse or glossy reflection is tabulated, and a warning says what is not
    (it was left out without a word)."""
    from mi_brdfs.errors import MiBrdfsWarning

    for spec, what in (("plastic", "also has a delta reflection"),
                       ("roughdielectric alpha=0.3", "also has transmission")):
        with pytest.warns(MiBrdfsWarning, match=f"measure: .* {what}, which the table of its "
                                                f"BRDF leaves out"):
            values = measure(spec)
        assert np.nanmax(values) > 0
