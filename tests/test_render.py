"""The progressive render path: passes, accumulation, time budget, process arrangement."""

import mitsuba as mi
import numpy as np
import pytest

from mi_brdfs.errors import MiBrdfsError
from mi_brdfs.render import pass_seed, render, uses_python_plugins
from mi_brdfs.scenes import load_scene


def test01_pass_seeds_are_distinct_across_base_seeds():
    seeds = {pass_seed(s, i) for s in range(64) for i in range(512)}
    assert len(seeds) == 64 * 512
    assert pass_seed(0, 0) == 0 and pass_seed(1, 0) == 65536


def test02_passes_accumulate_to_the_mean_of_their_renders(variant_llvm_ad_rgb):
    """A 4-pass render equals the spp-weighted mean of the four single renders it made."""
    result = render("cbox", spp=16, pass_spp=4, defines={"res": "16"}, progress=False)
    assert (result.spp, result.passes, result.arrangement) == (16, 4, "jit")
    scene = load_scene("cbox", res=16)
    passes = [np.array(mi.render(scene, seed=pass_seed(0, i), spp=4)) for i in range(4)]
    np.testing.assert_allclose(result.image, np.mean(passes, axis=0), rtol=1e-6, atol=1e-7)
    assert np.isfinite(result.image).all()


def test03_uneven_last_pass(variant_llvm_ad_rgb):
    result = render("furnace", spp=10, pass_spp=4, defines={"res": "8"}, progress=False)
    assert (result.spp, result.passes) == (10, 3)
    assert abs(result.image.mean() - 1.0) < 0.02


def test04_time_budget_stops_early(variant_llvm_ad_rgb):
    # a first render compiles the pass's kernel: a cold compile on a busy machine (a second
    # before the budget is checked) is no pass started past the budget
    render("furnace", spp=1, pass_spp=1, defines={"res": "8"}, progress=False)
    result = render("furnace", time_budget=0.5, pass_spp=1, defines={"res": "8"}, progress=False)
    assert 1 <= result.spp and result.wall_time < 0.5 + 0.5  # no pass starts past the budget
    assert result.passes == result.spp


def test05_python_plugins_detected(variant_scalar_rgb):
    assert uses_python_plugins(load_scene("cbox", material="lambert", res=4))
    assert not uses_python_plugins(load_scene("cbox", material="diffuse", res=4))
    # nested in a built-in, and declared but unused
    nested = mi.load_string("""<scene version="3.0.0"><shape type="sphere">
        <bsdf type="twosided"><bsdf type="lambert"/></bsdf></shape></scene>""")
    unused = mi.load_string("""<scene version="3.0.0"><bsdf type="lambert" id="spare"/>
        <shape type="sphere"><bsdf type="diffuse"/></shape></scene>""")
    assert uses_python_plugins(nested) and not uses_python_plugins(unused)


def test06_scalar_processes_equal_one_thread(variant_scalar_rgb):
    """Spread over 2 worker processes, the scalar render gives the one-process image exactly."""
    defines = {"res": "8", "material": "lambert", "max_depth": "3"}
    one = render("cbox", spp=8, pass_spp=2, defines=defines, processes=1, progress=False)
    two = render("cbox", spp=8, pass_spp=2, defines=defines, processes=2, progress=False)
    assert one.arrangement == "1 thread"
    assert two.arrangement in ("2 processes × 1 thread", "1 thread")  # when it does not pay
    np.testing.assert_allclose(one.image, two.image, rtol=1e-6, atol=1e-7)


def test07_scalar_forced_into_processes(variant_scalar_rgb, monkeypatch):
    """With worker start-up made free, the pool path runs and matches the in-process image."""
    import mi_brdfs.render_pool as R
    monkeypatch.setattr(R, "WORKER_START_S", 0.0)
    defines = {"res": "8", "material": "lambert", "max_depth": "3"}
    two = render("cbox", spp=8, pass_spp=2, defines=defines, processes=2, progress=False)
    assert two.arrangement == "2 processes × 1 thread"
    one = render("cbox", spp=8, pass_spp=2, defines=defines, processes=1, progress=False)
    np.testing.assert_allclose(one.image, two.image, rtol=1e-6, atol=1e-7)


def test08_bad_arguments(variant_scalar_rgb):
    with pytest.raises(MiBrdfsError, match="render.render: spp = 0 is invalid"):
        render("furnace", spp=0, progress=False)
    with pytest.raises(MiBrdfsError, match="render.render: pass_spp = 0 is invalid"):
        render("furnace", spp=4, pass_spp=0, progress=False)  # once looped forever
    with pytest.raises(MiBrdfsError, match="does not exist"):
        render("no_such_scene.xml", progress=False)
    with pytest.raises(MiBrdfsError, match="time budget must be a positive"):
        render("furnace", time_budget=-1, progress=False)


@pytest.mark.parametrize("processes", [1, 2])
def test09_time_budget_holds_with_processes(variant_scalar_rgb, processes):
    """No pass starts that would end after the budget, in the scalar arrangements too (helper
    processes included); the margin covers the machine's noise, not a late pass."""
    budget = 2.0
    result = render("cbox", time_budget=budget, processes=processes, progress=False,
                    defines={"res": "32", "material": "lambert"})
    assert result.spp >= 1 and result.wall_time <= 1.25 * budget, (result.arrangement,
                                                                    result.wall_time)


def test10_helpers_never_spawn_helpers(tmp_path):
    """
    A script without an ``if __name__ == "__main__"`` guard runs again in every spawned helper
    process; there ``_is_main_process`` is false, so a render in it does not start helpers of
    its own (which multiprocessing refuses while the helper starts: the pool would respawn the
    failing helper without end, and the render would hang).
    """
    import subprocess
    import sys
    script = tmp_path / "unguarded.py"
    script.write_text(
        "import multiprocessing as mp\n"
        "from mi_brdfs.render_pool import _is_main_process\n"
        "print('main' if _is_main_process() else 'helper', flush=True)\n"
        "if mp.current_process().name == 'MainProcess':  # the test's own guard: one child\n"
        "    with mp.get_context('spawn').Pool(1) as pool:\n"
        "        pool.apply(abs, (-1,))\n")
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path).stdout.split()
    assert sorted(out) == ["helper", "main"], out


def test11_guided_passes_shrink_at_the_end():
    """With workers sharing adaptive passes, the last passes shrink (at most 1/(2·workers) of
    what remains) so the processes finish together; every spp is issued exactly once."""
    from mi_brdfs.render import _Schedule
    plain, guided = _Schedule(40, 8, None), _Schedule(40, 8, None)
    guided.guided_workers = 2
    sizes = {}
    for name, schedule in (("plain", plain), ("guided", guided)):
        sizes[name] = []
        while (item := schedule.next()) is not None:
            sizes[name].append(item[1])
    assert sizes["plain"] == [8] * 5
    assert sum(sizes["guided"]) == 40 and sizes["guided"][:2] == [8, 8]
    assert sizes["guided"][-3:] == [1, 1, 1]  # 3 remaining: ceil(3/4) = 1 per pass


def test12_helpers_kept_for_the_next_render(variant_scalar_rgb, monkeypatch, tmp_path):
    """
    The helper processes stay for the next render of the variant; they load a scene again
    when its file was edited (a render of another scene times its first pass here first, then
    spreads where loading it there pays), and close_helpers ends them.
    """
    import mi_brdfs.render_pool as R
    monkeypatch.setattr(R, "WORKER_START_S", 0.0)
    monkeypatch.setattr(R, "WORKER_LOAD_S", 0.0)
    from mi_brdfs.scenes import scene_path
    scene, text = tmp_path / "box.xml", scene_path("cbox").read_text()
    scene.write_text(text)
    defines = {"res": "8", "material": "lambert", "max_depth": "3"}
    R.close_helpers()
    first = render(scene, spp=6, pass_spp=2, defines=defines, processes=2, progress=False)
    assert first.arrangement == "2 processes × 1 thread" and R._helpers_ready(1, mi.variant())
    pool = R._helpers[1]
    # the file edited: the white walls made dark
    scene.write_text(text.replace("0.885809, 0.698859, 0.666422", "0.1, 0.1, 0.1"))
    again = render(scene, spp=6, pass_spp=2, defines=defines, processes=2, progress=False)
    assert R._helpers[1] is pool, "the helpers were not kept"
    alone = render(scene, spp=6, pass_spp=2, defines=defines, processes=1, progress=False)
    assert alone.image.mean() < 0.8 * first.image.mean()  # the edit shows
    np.testing.assert_allclose(again.image, alone.image, rtol=1e-6, atol=1e-7)
    processes = list(pool._pool)
    R.close_helpers()
    assert R._helpers is None and not any(p.is_alive() for p in processes)


def test13_kept_helpers_start_at_once_on_the_same_scene(variant_scalar_rgb, monkeypatch):
    """A render of the scene the kept helpers rendered last hands them its first pass at once
    (two passes run side by side from the start); a render of another scene first times a
    pass here."""
    import mi_brdfs.render_pool as R
    monkeypatch.setattr(R, "WORKER_START_S", 0.0)
    monkeypatch.setattr(R, "WORKER_LOAD_S", 0.0)
    defines = {"res": "8", "material": "lambert", "max_depth": "3"}
    R.close_helpers()
    render("cbox", spp=4, pass_spp=1, defines=defines, processes=2, progress=False)
    handed = []
    original = R._render_with_helpers

    def spy(*args):
        handed.append(args[-1] is not None)  # (a first pass to run beside the helpers)
        return original(*args)

    monkeypatch.setattr(R, "_render_with_helpers", spy)
    render("cbox", spp=4, pass_spp=1, defines=defines, processes=2, progress=False)
    render("cbox", spp=4, pass_spp=1, defines=dict(defines, max_depth="4"), processes=2,
           progress=False)
    assert handed == [True, False]
    R.close_helpers()


def test_interrupted_during_the_first_pass_spreads_nothing(monkeypatch):
    """A Ctrl-C during the first pass of a scalar render (here with a time budget) leaves no
    pass timed: the decision to spread the render over processes is then 'no' (it was an
    IndexError on the missing timing), and render() goes on to raise KeyboardInterrupt,
    having nothing to keep."""
    from types import SimpleNamespace

    from mi_brdfs import render as render_module
    from mi_brdfs import render_pool

    monkeypatch.setattr(render_pool, "_helpers_ready", lambda *a: False)
    schedule = SimpleNamespace(pass_times=[], spp=100, issued=1, budget=10.0)
    passes = SimpleNamespace(schedule=schedule, variant="scalar_rgb", path="s.xml", defines={},
                             first=lambda: 0.0)
    assert render_module._spread(passes, True, 4) is None


def test_a_bsdf_of_an_included_file_is_swapped(variant_scalar_rgb, tmp_path):
    """load_scene(bsdfs=...) (compare --swap) finds an id in a file the scene <include>s: the
    sphere's material is the swapped one (it was 'the scene has no <bsdf id="metal">')."""
    (tmp_path / "materials.xml").write_text(
        '<scene version="3.0.0"><bsdf type="roughconductor" id="metal"/></scene>')
    (tmp_path / "main.xml").write_text(
        '<scene version="3.0.0"><integrator type="path"/><sensor type="perspective">'
        '<film type="hdrfilm"><integer name="width" value="4"/>'
        '<integer name="height" value="4"/></film></sensor><emitter type="constant"/>'
        '<include filename="materials.xml"/><shape type="sphere"><ref id="metal"/></shape>'
        '</scene>')
    scene = load_scene(tmp_path / "main.xml", bsdfs={"metal": {"type": "lambert"}})
    assert type(scene.shapes()[0].bsdf()).__name__ == "Lambert"
    with pytest.raises(MiBrdfsError, match='no <bsdf id="wood">'):
        load_scene(tmp_path / "main.xml", bsdfs={"wood": {"type": "lambert"}})


def test_a_define_only_the_swapped_bsdf_referenced(variant_scalar_rgb, tmp_path):
    """-D e=30 for the exponent of the material that compare --swap replaces: nothing
    references $e any more, which Mitsuba refuses ('declares no <default> for e'); the define
    is dropped, while one the scene does not declare is still refused."""
    (tmp_path / "main.xml").write_text(
        '<scene version="3.0.0"><default name="e" value="20"/><integrator type="path"/>'
        '<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>'
        '<integer name="height" value="4"/></film></sensor><emitter type="constant"/>'
        '<shape type="sphere"><bsdf type="phong" id="ball"><float name="exponent" '
        'value="$e"/></bsdf></shape></scene>')
    scene = load_scene(tmp_path / "main.xml", {"e": "30"}, bsdfs={"ball": "diffuse"})
    assert "SmoothDiffuse" in str(scene.shapes()[0].bsdf())
    with pytest.raises(MiBrdfsError, match="declares no <default> for f"):
        load_scene(tmp_path / "main.xml", {"f": "30"}, bsdfs={"ball": "diffuse"})
