"""The χ² check accepts correct samplers (ours and built-ins) and rejects a broken one."""

import pytest

from broken import register_broken
from mi_brdfs.checks import chi2_bsdf
from mi_brdfs.errors import MiBrdfsError


@pytest.mark.parametrize("bsdf", [{"type": "diffuse"}, {"type": "lambert", "reflectance": 0.9}],
                         ids=["diffuse", "lambert"])
def test01_accepts(variant_llvm_ad_rgb, bsdf):
    result = chi2_bsdf(bsdf, wi=[0.5, 0.2, 0.8])
    assert result.passed, result.message
    assert result.value >= 0.01


def test02_rejects_wrong_pdf(variant_llvm_ad_rgb):
    register_broken()
    result = chi2_bsdf({"type": "broken_pdf"})
    assert not result.passed
    assert result.value < 1e-6 and "rejected" in result.message


def test03_needs_jit(variant_scalar_rgb):
    with pytest.raises(MiBrdfsError, match="needs a JIT variant"):
        chi2_bsdf({"type": "lambert"})
