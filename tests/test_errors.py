"""
mi_brdfs.errors: counts given to the public API are validated before any work, with one line
naming the function, the parameter and the value (a count of 0 once crashed Mitsuba with
SIGFPE, a pass of 0 spp looped forever).
"""

import pytest

from mi_brdfs import checks, compare, plots, render
from mi_brdfs.errors import CountError, ParameterError, counts

CALLS = [
    (render.render, ("furnace",), "spp"),
    (render.render, ("furnace",), "pass_spp"),
    (render.render, ("furnace",), "processes"),
    (checks.furnace_render, ("lambert",), "spp"),
    (checks.furnace_render, ("lambert",), "res"),
    (checks.check_furnace, ("lambert",), "res"),
    (checks.albedo_curve, ("lambert",), "n"),
    (checks.albedo_sampled, ("lambert", 0.0), "n"),
    (checks.check_energy, ("lambert",), "n"),
    (checks.check_consistency, ("lambert",), "n"),
    (checks.check_reciprocity, ("lambert",), "n"),
    (checks.check_positivity, ("lambert",), "n"),
    (checks.check_stability, (["lambert"],), "n_random"),
    (checks.check_equal, ("lambert", "diffuse"), "n"),
    (plots.slice_values, ("lambert",), "res"),
    (plots.lobe_values, ("lambert", 30.0), "n"),
    (compare.compare, ("furnace",), "spp"),
]


@pytest.mark.parametrize("fn,args,name", CALLS,
                         ids=[f"{f.__name__}-{n}" for f, _, n in CALLS])
@pytest.mark.parametrize("value", [0, -5, 2.5, True])
def test01_counts_are_checked_first(variant_scalar_rgb, fn, args, name, value):
    with pytest.raises(CountError) as info:
        fn(*args, **{name: value})
    text = str(info.value)
    assert f"{fn.__name__}: {name} = {value!r} is invalid: must be a whole number ≥ 1" in text
    assert "\n" not in text


def test02_the_decorator():
    @counts("n", "m")
    def f(a, n=None, m=1):
        return a + (n or 0) + m

    assert f(1, 2, m=3) == 6 and f(1) == 2
    with pytest.raises(CountError, match=r"test_errors.f: m = 0 is invalid"):
        f(1, m=0)
    assert issubclass(CountError, ValueError) and not issubclass(CountError, ParameterError)


def test_interrupt01_a_wrapped_ctrl_c_is_not_a_bad_input(variant_scalar_rgb):
    """A Python plugin's constructor interrupted by Ctrl-C reaches the caller as Mitsuba's
    RuntimeError with the text only; mitsuba_error_line raises it again as KeyboardInterrupt,
    so that no caller (simplify skips candidates that fail to load) takes it for a bad input,
    while another loader error stays one line."""
    import mitsuba as mi

    from mi_brdfs.bsdfspec import load_bsdf
    from mi_brdfs.errors import MiBrdfsError

    class Interrupted(mi.BSDF):
        def __init__(self, props):
            raise KeyboardInterrupt

    mi.register_bsdf("interrupted_on_load", Interrupted)
    with pytest.raises(KeyboardInterrupt):
        load_bsdf({"type": "interrupted_on_load"})
    with pytest.raises(MiBrdfsError, match="lambert"):
        load_bsdf({"type": "lambert", "reflectance": 2.0})
