"""Findings about the χ² harnesses themselves, for every BSDF."""

from ..triage import Finding

FINDINGS = [
    Finding(
        bsdf="*", check=r"^mitsuba chi2", configs="", verdict="check-limitation",
        when=lambda r: r["details"].get("ours_passed") is True,
        summary="Mitsuba's χ² harness (`mi.chi2.BSDFAdapter` with `ChiSquareTest`'s defaults: "
                "res = 101, ires = 4, 1 000 000 samples, no rotation) rejects the BSDF at this "
                "angle, while our χ² at the same angle passes with the resolution chosen from "
                "the lobe's sharpness (`chi2_settings`: res up to 401, ires up to 32, a sharp "
                "lobe near a pole rotated onto the equator, where the cells are finest). The "
                "harness integrates the pdf over each cell with ires² points: for a lobe "
                "narrower than a cell (α ≲ 0.1, or any lobe near a pole, where the cells are "
                "coarsest in θ) that integral is wrong (its 'PDF sum' departs from 1, e.g. 21.6 "
                "for roughdielectric GGX α = 0.05 at normal incidence), so the test compares "
                "the histogram with a mis-integrated pdf. Mitsuba's own tests raise the "
                "resolution for sharp lobes (test_rough_conductor.py of its src/bsdfs tests, "
                "v3.9.1: α = 0.05 with res = 140, ires = 32; anisotropic α = 0.05 with "
                "ires = 16)."),
]
