"""
mi_brdfs.testing: every assertion passes a correct BSDF (returning the check's result) and
raises AssertionError with the check's one-line message on a broken one; the module
docstring's example runs as written.
"""

import re
import textwrap

import mitsuba as mi
import pytest

from broken import broken, register_broken, register_broken_gradients
from mi_brdfs import testing

GOOD = {"type": "lambert", "reflectance": 0.5}

#: assertion -> (arguments for a correct BSDF, arguments for a broken one)
CASES = {
    "assert_sampling_matches_pdf": ((GOOD,), (broken("pdf"),)),
    "assert_consistent": ((GOOD,), (broken("bspdf"),)),
    "assert_energy_conserving": ((GOOD,), (broken("eval"),)),
    "assert_albedo_matches_eval": ((GOOD,), (broken("weight"),)),
    "assert_reciprocal": ((GOOD,), (broken("reciprocal"),)),
    "assert_positive": ((GOOD,), (broken("negative"),)),
    "assert_stable": (([GOOD],), ([broken("nan")],)),
    "assert_furnace": ((GOOD,), (broken("eval"),)),  # emitter sampling sees eval()
    "assert_gradients": ((GOOD,), ({"type": "gradbroken", "defect": "eval_sign"},)),
}
#: Small sizes that still tell each pair apart by far: every defect is a factor or a sign
#: (uniform against cosine sampling, f ∝ cosθi, eval < 0 over half the sphere, NaN at the stress
#: directions, eval 3×), and the furnace predicts the broken Lambert from its sample weights,
#: which are exact (ρ), and the correct one from its float64 reference.
SMALL = {"assert_sampling_matches_pdf": {"sample_count": 100_000},
         "assert_energy_conserving": {"thetas_deg": (0.0, 60.0), "n": 4_000},
         "assert_albedo_matches_eval": {"thetas_deg": (0.0, 60.0), "n": 20_000},
         "assert_reciprocal": {"n": 2_000},
         "assert_positive": {"n": 2_000},
         "assert_stable": {"n_random": 200},
         "assert_furnace": {"spp": 16, "res": 16, "tol": 0.02, "n": 1_000},
         "assert_consistent": {"n": 2_000},
         "assert_gradients": {"n": 128}}


@pytest.mark.parametrize("name", list(CASES))
def test01_each_assertion_passes_good_and_fails_broken(variant_llvm_ad_rgb, name):
    register_broken()
    register_broken_gradients()
    assertion = getattr(testing, name)
    good, bad = CASES[name]
    kwargs = SMALL.get(name, {})
    result = assertion(*good, **kwargs)
    assert result.passed
    with pytest.raises(AssertionError) as info:
        assertion(*bad, **kwargs)
    assert "\n" not in str(info.value) and str(info.value) == str(info.value).strip()


def test02_every_public_assertion_is_covered():
    public = {n for n in dir(testing) if n.startswith("assert_")}
    covered = set(CASES) | {"assert_ndf_normalized", "assert_weak_furnace"}  # tests/checks/test_checks.py
    assert public == covered, public ^ covered


def test03_docstring_example_runs(variant_llvm_ad_rgb, monkeypatch):
    """The module docstring's example, with a correct BSDF as ``my_package.MyBSDF``, as
    written, with the albedo checks' default sample count lowered to 20 000 per angle (from
    10⁶: its statistics are the energy check's, test01 and tests/checks/)."""
    import sys
    import types

    from mi_brdfs.checks import albedo

    code = textwrap.dedent(re.search(r"::\n\n(.*?)\n\n[A-Z]", testing.__doc__, re.S).group(1))

    class MyBSDF(mi.BSDF):  # a Lambert of ρ = 0.5 that takes a 'roughness' it ignores
        def __init__(self, props):
            super().__init__(props)
            props.get("roughness", 0.0)
            self.m_flags = int(mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide)
            self.m_components = [self.m_flags]
            self.inner = mi.load_dict({"type": "diffuse"})

        def sample(self, ctx, si, sample1, sample2, active=True):
            return self.inner.sample(ctx, si, sample1, sample2, active)

        def eval(self, ctx, si, wo, active=True):
            return self.inner.eval(ctx, si, wo, active)

        def pdf(self, ctx, si, wo, active=True):
            return self.inner.pdf(ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.inner.eval_pdf(ctx, si, wo, active)

    monkeypatch.setitem(sys.modules, "my_package", types.SimpleNamespace(MyBSDF=MyBSDF))
    monkeypatch.setitem(albedo.DEFAULT_SAMPLES, True, 20_000)
    namespace = {}
    exec(compile(code, "testing-docstring", "exec"), namespace)  # noqa: S102
    namespace["test_my_bsdf"]()


def test07_defaults_judge_correct_bsdfs_as_the_battery(variant_llvm_ad_rgb):
    """The public assertions' defaults pass Mitsuba's own correct BSDFs where the battery
    does: χ² of a rough dielectric at the battery's resolution (Mitsuba's 101 × 4 rejects it:
    p = 0), the furnace of roughconductor at 2 samples per pixel (a fixed 0.005 took its noise
    for an error)."""
    rough = {"type": "roughdielectric", "alpha": 0.3}
    testing.assert_sampling_matches_pdf(rough, wi=[0.6, 0.0, 0.8], sample_count=200_000)
    testing.assert_furnace({"type": "roughconductor", "alpha": 0.5}, spp=2, res=16)
