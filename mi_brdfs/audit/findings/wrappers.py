"""
Triage of the wrappers: ``blendbsdf``, ``mask``, ``bumpmap``, ``normalmap``, ``twosided``, ``null``.

Defects of Mitsuba 3.9.1, one mechanism each (each with a reproducer in ``validation/audit/``
that exits 1 while the defect is present, and an issue text with its prior art in
``validation/audit/upstream/``):

* ``blendbsdf`` reports ``bs.sampled_component`` of its second BSDF without the offset its own
  component list and its ``ctx.component`` handling use (``repro_blendbsdf_sampled_component``).
* ``blendbsdf`` turns a failed nested sample into a NaN weight, because it reads the undefined
  ``bs.pdf``/``bs.wo`` of that sample (``repro_blendbsdf_nan_weight``). No shipped integrator is
  affected (``impact_blendbsdf_nan_weight.py``).
* ``blendbsdf`` weights the samples of a Dirac lobe blended with a smooth BSDF too low, as if
  their discrete probability were a density of the mixture (``repro_blendbsdf_delta_weight``,
  ``render_blendbsdf_delta_weight.py``); the lobe check's additivity of sampled albedos sees it.
* ``mask`` inverts a context restricted to one of its parts: nested-only returns only Null
  pass-through samples, Null-only returns none (``repro_mask_context``).
* ``twosided`` reports a back-side sample with the nested BSDF's component index
  (``repro_twosided_back_component``), and maps ``ctx.component`` to the back BSDF wrongly
  (``repro_twosided_back_selection``); the audit's own ``sides`` check
  (:mod:`mi_brdfs.audit.sides`) and the consistency check, which draws back-facing ``wi`` for
  a BSDF that declares ``BackSide``, see it.

Check limitations: the test interaction had no surface tangents (``bumpmap``), float32 rounding
at grazing angles (``normalmap`` on roughconductor), and Mitsuba's χ² harness, which either
counts Dirac/Null samples that ``pdf()`` cannot see or uses too coarse a pdf integration at
grazing angles. Model property: ``normalmap`` is not reciprocal (shading normals,
``validation/audit/model_normalmap_reciprocity.py``).
"""

from ..triage import Finding

_BLEND = "src/bsdfs/blendbsdf.cpp (v3.9.1)"
_MASK = "src/bsdfs/mask.cpp (v3.9.1)"
_TWOSIDED = "src/bsdfs/twosided.cpp (v3.9.1)"
_UP = "validation/audit/upstream/"

FINDINGS = [
    Finding(
        bsdf="blendbsdf", check=r"^lobes$", configs=r"textured", verdict="defect",
        summary=(
            "blendbsdf of diffuse and a smooth conductor (a Dirac lobe) with weight 0.2: the "
            "albedo from sample() with every lobe enabled, 0.871 at normal incidence, falls short "
            "of the sum of the lobes selected one by one, 0.900 (0.8·ρ_diffuse + 0.2·1): "
            "sample() weights the Dirac sample as if its pdf of 1 were a density in the mixture "
            "(validation/audit/repro_blendbsdf_delta_weight.py; a rendered sphere comes out 3.3 % "
            "too dark at its centre, validation/audit/render_blendbsdf_delta_weight.py). The "
            "same record also shows the component offset defect below: with ctx.component = 1 "
            "every sample reports component 0."),
        reproducer="validation/audit/repro_blendbsdf_delta_weight.py",
        source="src/bsdfs/blendbsdf.cpp, BlendBSDF::sample (the MIS weight of the mixture, "
               "lines 134-156)",
        issue=_UP + "blendbsdf_delta_weight.md"),
    Finding(
        bsdf="blendbsdf", check=r"^lobes$", configs=r"roughconductor", verdict="defect",
        summary=(
            "With ctx.component = 1 (the first lobe of the second BSDF, as blendbsdf numbers "
            "its components: a's, then b's) every sample reports sampled_component 0: "
            "blendbsdf shifts ctx.component down for b on the way in but does not shift b's "
            "sampled_component back up (the consistency entry below; "
            "validation/audit/repro_blendbsdf_sampled_component.py)."),
        reproducer="validation/audit/repro_blendbsdf_sampled_component.py",
        source="src/bsdfs/blendbsdf.cpp, BlendBSDF::sample lines 146-155",
        issue=_UP + "blendbsdf_sampled_component.md"),
    # ------------------------------------------------------------------ blendbsdf
    Finding(
        bsdf="blendbsdf", check=r"^consistency$", configs="", verdict="defect",
        summary=(
            "sampled_type/sampled_component inconsistent: 29 410 of 100 000 samples (diffuse + "
            "roughconductor, weight 0.3) and 79 709 (diffuse + conductor, textured weight 0.8 at "
            "uv (0.5, 0.5)) are 'not in flags(component)'. These are exactly the successful "
            "samples of the second BSDF: 29.6% and 79.7% of the samples, for weights 0.3 and "
            "0.8. BlendBSDF numbers its components as bsdf_0's followed by bsdf_1's "
            "(constructor). It reads ctx.component that way in sample/eval/pdf/eval_pdf: an index "
            "≥ component_count(bsdf_0) selects bsdf_1, offset down. But sample() copies bsdf_1's "
            "BSDFSample3f unchanged, so a GlossyReflection (or DeltaReflection) sample of bsdf_1 "
            "reports component 0, which is the blend's DiffuseReflection lobe. Feeding it back as "
            "ctx.component evaluates the wrong lobe: 0.109 (diffuse) instead of 0.369. None of "
            "the check's limits applies. The sampled fields are integers and no rounding is "
            "involved. These are successful samples, not failed ones with undefined fields. "
            "Delta samples are legitimately typed Delta, and the failure is the index, not the "
            "type. Geometry and polarization play no part, and the result is the same for every "
            "seed and every wi. Impact: no shipped integrator reads sampled_component (v3.9.1), "
            "so renders are unaffected. It misleads user code that re-evaluates or tags the "
            "sampled lobe. twosided has the same missing offset on its back side (its 'sides' "
            "finding). Fix: bs1.sampled_component += component_count(bsdf_0). Reported for "
            "Mitsuba 2 in 2020 (https://github.com/mitsuba-renderer/mitsuba2/issues/151, "
            "open)."),
        reproducer="validation/audit/repro_blendbsdf_sampled_component.py",
        source=(f"{_BLEND}: constructor lines 94-97 (m_components = bsdf_0's then bsdf_1's); "
                "BlendBSDF::sample lines 116-121 (ctx.component offset on the way in) and "
                "146-155 (bs1 copied into bs without the offset); same offset in eval 167-172, "
                "pdf 185-190, eval_pdf 205-209"),
        issue=_UP + "blendbsdf_sampled_component.md"),
    Finding(
        bsdf="blendbsdf", check=r"^stability$", configs=r"roughconductor", verdict="defect",
        summary=(
            "5220 bad values: 1305 sample() weights are NaN, and with them bs.pdf and bs.wo. "
            "They occur at wi tangent (cosθi = 0) and back-facing wi (9 of 27 grid points each), "
            "and at 1302 of 20 000 random wi on the sphere, all with cosθi between -1 and "
            "-0.56, "
            "whenever sample1 ≤ weight 0.3 selects the roughconductor. The roughconductor's "
            "sample fails there: it returns weight 0 and leaves bs.wo and bs.pdf as NaN, which "
            "the API allows for a failed sample. BlendBSDF::sample then uses those undefined "
            "fields. pdf_weighted = w·bs1.pdf + (1-w)·pdf0(bs1.wo) is NaN. result_weighted = "
            "(w·result1·bs1.pdf + (1-w)·eval0)·select(pdf_weighted > 0, rcp, 0) = (0·NaN)·0 = "
            "NaN. So the blend turns a failed sample (weight 0) into a NaN weight, where diffuse "
            "and roughconductor alone both return weight 0. Not a check limit: the NaN is the "
            "weight itself, the one field the API defines for a failed sample, not an undefined "
            "one. The result is the same for any seed, does not depend on float32 conditioning "
            "(it is 0·NaN), and needs no geometry. It needs a vectorized call in which some "
            "lanes succeed; when every lane fails, roughconductor returns early with zeros, and "
            "scalar variants do that always. Render impact: none in the shipped integrators. "
            "path, volpath, direct, prb and ptracer renders of a one-sided blendbsdf plane seen "
            "from behind have 0 NaN pixels, because the path ends when throughput_max != 0 is "
            "false for NaN (an ordered compare). The prb gradient with respect to the weight is "
            "finite, and 0 for the back-facing view. Any code that accumulates sample weights "
            "gets NaN (validation/audit/impact_blendbsdf_nan_weight.py). Fix: combine only "
            "nested samples whose weight is nonzero."),
        reproducer="validation/audit/repro_blendbsdf_nan_weight.py",
        source=(f"{_BLEND}: BlendBSDF::sample lines 146-156 (bs1.pdf and bs1.wo of a failed "
                "nested sample used in pdf_weighted and result_weighted, lines 149-152) and "
                "134-144 (the same for bsdf_0); roughconductor.cpp lines 234-266 leave bs.pdf "
                "and bs.wo unmasked for inactive lanes, which the API allows"),
        issue=_UP + "blendbsdf_nan_weight.md"),
    Finding(
        bsdf="blendbsdf", check=r"^mitsuba chi2", configs=r"textured", verdict="check-limitation",
        summary=(
            "Mitsuba's χ² harness: 'Histogram sum = 1.000000, PDF sum = 0.200003', χ² ≈ 4e9, at "
            "all three angles. At uv (0.5, 0.5) the checkerboard weight is 0.8, so 80% of "
            "samples come from the conductor's Dirac lobe, whose pdf() is 0 by convention. "
            "mi.chi2.BSDFAdapter histograms every sample with the default context, while pdf() "
            "integrates only the diffuse part, 1 - w = 0.2. The harness does not apply to a BSDF "
            "with a Dirac lobe (the audit's _harness_applies now skips it). The finer check "
            "passes: the default context, with samples whose sampled_type is Delta given weight "
            "0 in the adapter, against pdf() at res 101, ires 16. Histogram sum 0.1998 vs PDF "
            "sum 0.2000, p = 0.316 (seed 0) and 0.023 (seed 1), at every angle. Our own χ² (on "
            "the non-delta lobes) passes too, p = 0.317.")),
    Finding(
        bsdf="blendbsdf", check=r"^mitsuba chi2 θ=84", configs=r"roughconductor",
        verdict="check-limitation",
        summary=(
            "Mitsuba's χ² harness at θi = 84.26° (diffuse + roughconductor α = 0.2, weight 0.3) "
            "gives p = 0.0021 at its defaults, res 101 and ires 4. Other seeds give p = 0.0018 "
            "and 0.079. With ires = 16 it passes, p = 0.22 and 0.19 (seeds 0 and 1), and with "
            "res 201, ires 16, p = 0.97. Our χ² passes at the same angle, p = 0.77. The grazing "
            "glossy lobe is narrow in θ next to the horizon, and 4×4 points per cell do not "
            "integrate its pdf accurately. This is a resolution limit of the harness, the same "
            "one the generic harness finding describes.")),
    # ------------------------------------------------------------------ twosided
    Finding(
        bsdf="twosided", check=r"^(sides|consistency)$", configs="", verdict="defect",
        summary=(
            "A sample on the back side reports the component index of the nested BSDF, not "
            "twosided's index of that lobe. twosided lists the front BSDF's n0 lobes "
            "(FrontSide) followed by the back BSDF's (BackSide; the same BSDF again when only "
            "one is nested), so back lobe c is component n0 + c; sample() hands the nested "
            "sample back unchanged on the back side, in the one-BSDF branch and in the "
            "two-BSDF branch, which shifts ctx.component down by n0 on the way in but not "
            "sampled_component up on the way out (blendbsdf's missing offset, in a wrapper "
            "that splits by side). At back-facing wi every successful sample reports "
            "component 0: a FrontSide lobe, and for diffuse + roughconductor one whose flags "
            "(DiffuseReflection) lack the sampled GlossyReflection. Adding n0 to the component "
            "of the back-side samples brings every count to 0 for the three configurations "
            "(repro_twosided_back_component.py), so the missing offset alone explains the "
            "records. Not a limit of the check: the API's sampled_component is 'the component "
            "index that was sampled' and twosided's own flags(c) say which side c belongs to; "
            "the fields are integers of successful samples, the same for every seed. The "
            "audit's 'sides' check sees it, and so does the battery's consistency check, "
            "which draws every other wi below the surface for a BSDF that declares BackSide "
            "(it reports the samples whose sampled_component's flags lack the sampled type: "
            "with two different BSDFs). Render impact: none in the shipped integrators (none "
            "reads sampled_component)."),
        reproducer="validation/audit/repro_twosided_back_component.py",
        source=(f"{_TWOSIDED}: constructor lines 89-100 (front lobes, then back lobes); "
                "TwoSidedBRDF::sample lines 124-127 (one BSDF: the nested sample unchanged) "
                "and 136-144 (two BSDFs: ctx.component -= n0 at 137-138, result copied at "
                "141-143 without sampled_component += n0)"),
        issue=_UP + "twosided_back_component.md"),
    Finding(
        bsdf="twosided", check=r"^sides selection$", configs="", verdict="defect",
        summary=(
            "Selecting a lobe with ctx.component at a back-facing wi samples and evaluates the "
            "wrong side, because twosided maps ctx.component to the back BSDF wrongly: with one "
            "nested BSDF it passes ctx.component on unchanged, so a front lobe c < n0 samples "
            "the back side and the back lobes n0 + c sample and evaluate nothing; with two it "
            "subtracts n0 in unsigned arithmetic, so the last front lobe (n0 - 1) becomes "
            "(uint32_t) -1, 'every component', the whole back BSDF. A correct mapping enables "
            "back lobe c - n0 for c >= n0 and nothing otherwise. twosided's results at "
            "back-facing wi equal, for every ctx.component, those of the nested BSDF called "
            "with the component the code passes on, and differ from those with the correct "
            "one exactly where the records fail (repro_twosided_back_selection.py: "
            "diffuse + roughconductor, ctx.component = 0: 0.977 of the samples succeed where "
            "none should; diffuse alone: ctx.component = 0 gives all, 1 none, where the "
            "reverse is right). One mapping in both branches, one fix. Render impact: none in "
            "the shipped integrators (none sets ctx.component)."),
        reproducer="validation/audit/repro_twosided_back_selection.py",
        source=(f"{_TWOSIDED}: one BSDF, ctx passed unchanged in sample lines 124-127, eval "
                "159-162, pdf 194-197, eval_pdf 232-235; two BSDFs, 'ctx.component -= "
                "(uint32_t) m_brdf[0]->component_count()' without a range check in sample "
                "137-138, eval 171-172, pdf 206-207, eval_pdf 244-245"),
        issue=_UP + "twosided_back_selection.md"),
    Finding(
        bsdf="twosided", check=r"^mitsuba chi2 θ=84", configs=r"roughconductor",
        verdict="check-limitation",
        summary=(
            "Mitsuba's χ² harness at θi = 84.26° rejects twosided(roughconductor Beckmann "
            "α = 0.3) with p = 3.7416736375917026e-12. That is bit for bit the p-value of the "
            "bare 'roughconductor beckmann α=0.3 Au' record: for cosθi > 0, twosided hands the "
            "same random numbers to the same sampler and returns the same directions. The "
            "failure belongs to roughconductor at grazing incidence, not to the wrapper. It is "
            "the harness's resolution. At res 101, ires 4, seeds 0-2 give p = 3.7e-12, 1.0e-14 "
            "and 0. With ires = 16 the test passes, p = 0.93 and 0.37 (seeds 0 and 1), and with "
            "res 201, ires 16, p = 0.67. Our χ² passes at the same angle, p = 0.67. Mitsuba's "
            "own tests raise ires for such lobes.")),
    # ------------------------------------------------------------------ mask
    Finding(
        bsdf="mask", check=r"^(chi2|lobes)", configs="", verdict="defect",
        summary=(
            "Our χ² (non-delta lobes, i.e. ctx.type_mask = the flags without Null) could not run "
            "at any angle: 'expected frequency 0', histogram all in one cell. mask.sample() "
            "ignores the Null lobe being excluded and returns *only* Null pass-through samples: "
            "wo = -wi, weight 1, sampled_type Null. The reason is that sample() overrides "
            "opacity = sample_transmission ? 1 : 0 when only one part is enabled, and that is "
            "inverted. Nested-only sets opacity 0 and never samples the nested BSDF; Null-only "
            "(ctx.component = 1) sets opacity 1 and returns no sample at all. pdf() takes the "
            "intended reading: nested-only gives the nested pdf, sampled with probability 1. "
            "Measured at θi = 17.5°, opacity 0.4 on diffuse 0.5. Nested-only context: 1.000 "
            "Null-typed samples, mean weight 1.000, where no Null sample and mean = ∫eval = "
            "0.200 are expected. ctx.component = 0 gives the same. ctx.component = 1 gives 0.000 "
            "Null samples and mean 0, where 1.000 and 0.600 are expected. The default context is "
            "right (0.600 Null, mean 0.7999). Not our adapter's fault: restricting type_mask is "
            "the documented way to select lobes, and other BSDFs (plastic, roughplastic, "
            "principled) honour it: none of their samples falls outside the mask. "
            "Deterministic for any seed. Not a geometry, precision or polarization effect. The "
            "sample() code path is the same in every transport mode. "
            "Render impact: none in the shipped integrators, which all sample mask in the "
            "default context (no integrator in v3.9.1 restricts type_mask or component). It "
            "breaks any caller that samples selected lobes. Finer check, for the default "
            "context that renderers use: the adapter drops Dirac/Null-typed samples by "
            "sampled_type (weight 0) and keeps the default context. It passes at all three "
            "angles, histogram sum 0.3998 vs PDF sum 0.4000, p = 0.625 and 0.262 (seeds 0 and "
            "1)."),
        reproducer="validation/audit/repro_mask_context.py",
        source=(f"{_MASK}: MaskBSDF::sample lines 128-166 (opacity override inverted at lines "
                "139-140; nested branch 157-164 then never taken for nested-only and always for "
                "Null-only); compare MaskBSDF::pdf lines 177-193 (nested-only: nested pdf, "
                "i.e. selection probability 1)"),
        issue=_UP + "mask_context.md"),
    Finding(
        bsdf="mask", check=r"^albedo$", configs="", verdict="defect",
        summary=(
            "Albedo: 'sample() 1.00000 vs quadrature of eval() 0.20000' at every angle. The "
            "check already compares only the non-delta lobes: it samples with type_mask = the "
            "flags without Delta, which removes Null. That context hits the same defect as the "
            "χ². In it, mask.sample() returns only Null pass-through samples (weight 1), while "
            "eval() in the same context correctly returns opacity·nested = 0.4·0.5. With a "
            "correct sample() the two estimates agree: in the default context the samples not "
            "typed Null have mean weight 0.2002, against a quadrature of 0.2000. The sampled "
            "albedos add up in a correct BSDF (E(default) = E(Dirac ctx) + E(non-Dirac ctx): "
            "plastic 0.5199 = 0.0387 + 0.4812). mask breaks that: 0.7998 vs 0.5996 + 1.0000."),
        reproducer="validation/audit/repro_mask_context.py",
        source=f"{_MASK}: MaskBSDF::sample lines 139-140 (inverted opacity override)",
        issue=_UP + "mask_context.md"),
    Finding(
        bsdf="mask", check=r"^mitsuba chi2", configs="", verdict="check-limitation",
        summary=(
            "Mitsuba's χ² harness: 'Histogram sum = 1.000000, PDF sum = 0.400005' at every "
            "angle. The harness histograms all samples in the default context, including the "
            "60% that are Null pass-through (wo = -wi). pdf() integrates only the nested lobe: "
            "opacity 0.4, which is the PDF sum. The harness does not apply to a BSDF with a "
            "Dirac or Null lobe (the audit's _harness_applies now skips it). With a corrected "
            "adapter (default context, Null/Delta-typed samples weighted 0) the test passes at "
            "res 101, ires 16: histogram sum 0.3998 vs 0.4000, p = 0.625 and 0.262 (seeds 0 and "
            "1). Mitsuba's default context is correct for mask; its restricted contexts are the "
            "defect triaged under our chi2 entry.")),
    # ------------------------------------------------------------------ bumpmap
    Finding(
        bsdf="bumpmap", check=r"^chi2 θ=84", configs=r"flip_invalid_normals=false",
        verdict="check-limitation",
        summary=(
            "χ² at θi = 84.26° has nothing to test: 'no sample succeeded (every weight is 0)'. "
            "At the check's uv the height map tilts the shading normal so that this wi lies "
            "behind it; flip_invalid_normals=false is the switch that leaves such a wi "
            "unflipped, so the nested roughconductor sees a back-facing wi and the BSDF is 0 "
            "there. Sampler and pdf agree on that: at this wi the quadrature of eval() and of "
            "pdf() over the sphere are both 0, and 0 of 100 000 samples succeed, while with "
            "flip_invalid_normals=true (the other bumpmap configuration) 0.98 of the samples "
            "succeed and ∫ pdf = 0.983. At 0° and 45° the configuration passes χ²; its "
            "success fractions there equal ∫ pdf (0.710 vs 0.710, 0.242 vs 0.244). The check "
            "rightly refuses to pass vacuously; there is no density to compare.")),
    Finding(
        bsdf="bumpmap", check=r"^(consistency|chi2|stability)", configs="",
        verdict="check-limitation",
        summary=(
            "Consistency ('bs.pdf vs pdf 1, weight = 2.3e-41, wo = (0,0,0)'), χ² at 45° and "
            "84.26° ('samples outside the domain') and stability ('not a unit vector bs.wo', "
            "20 243 bad values) all failed because the harness's SurfaceInteraction had no "
            "tangents. batch.interaction built it with dr.zeros, so dp_du = dp_dv = 0. "
            "BumpMap::frame computes the perturbed tangents dp_du' = dp_du + n·(∂h/∂u - "
            "n·dp_du) and dp_dv' likewise. With zero tangents both are multiples of n, their "
            "cross product is 0, and the normal normalize(0) is NaN. result.s = "
            "normalize(dp_du - n(n·dp_du)) is NaN too. Every sample is then garbage or fails, "
            "and several records 'passed' only vacuously: χ² at 0°, energy and albedo "
            "7e-40, reciprocity. Proof: with si.dp_du = (1,0,0), si.dp_dv = (0,1,0), si.n = "
            "(0,0,1), si.sh_frame = Frame(n) (whose s is (1,0,0)) and si.uv = (0.5,0.5) "
            "(height-map slope there 0.81 after scale 0.5, a 39° tilt), all of these pass. "
            "Consistency: 82 357 weighted samples, max relative error 3.9e-4. χ²: p = 0.53, "
            "0.39, 0.32 at 0°, 45°, 84.26°. Stability: no bad value. Energy: max E = 0.980. "
            "Albedo: sample() and the quadrature agree. Putting the zero tangents back "
            "reproduces the failures. The harness must set: dp_du and dp_dv nonzero with "
            "cross(dp_du, dp_dv) ∥ n and dp_du ∥ sh_frame.s, because BumpMap builds its "
            "tangent from dp_du and an anisotropic nested lobe would otherwise turn; n and "
            "sh_frame consistent (sh_frame = Frame(n) gives s = dp_du = (1,0,0) for n = z); uv "
            "at the texture point; wi in local coordinates. With these, a bumpmap over a "
            "constant height map equals its nested BSDF exactly (eval and pdf differ by 0 for "
            "an anisotropic roughconductor). dn_du and dn_dv are not read by bumpmap or "
            "normalmap, so zero is fine. batch.interaction now sets all of these. Mitsuba's "
            "BSDFAdapter sets only wi and uv (not n, sh_frame or tangents), so it cannot test "
            "the frame wrappers either. With proper geometry, bumpmap's reciprocity fails as "
            "expected, like normalmap's (shading normals).")),
    # ------------------------------------------------------------------ normalmap
    Finding(
        bsdf="normalmap", check=r"^reciprocity$", configs="", verdict="model-property",
        summary=(
            "Asymmetry up to 1, in 95.8% of pairs (diffuse) and 32.4% (roughconductor). The "
            "worst pair: f(a,b) = 0, f(b,a) = 0.0387. A normal map replaces the shading frame, "
            "and the normal-mapped BSDF is not reciprocal by construction: Veach 1997, 'Robust "
            "Monte Carlo Methods for Light Transport Simulation', §5.3, non-symmetry due to "
            "shading normals. validation/audit/model_normalmap_reciprocity.py implements "
            "NormalMap::eval independently in float64. Its ingredients: the map's normal "
            "(tilt 26.1° at uv 0.5), mirrored when wi is behind it (flip_invalid_normals); "
            "the nested Lambert or Walter et al. 2007 Beckmann BSDF in that frame; the "
            "one-sided mask cosθo·cosθo' > 0; and the shadowing of ωo only from Conty Estevez, "
            "Lecocq & Stein 2019 (Ray Tracing Gems ch. 12). It shows four things. (1) The model "
            "reproduces Mitsuba's eval in both orders for all pairs, to within 1.5e-4 relative "
            "(float32). (2) The nested BSDFs are reciprocal in the shading frame, to 3.5e-16. "
            "(3) Wherever both orders use the same frame and neither is masked (150 104 pairs "
            "diffuse, 22 411 roughconductor), f(a,b)/f(b,a) equals Veach's shading-normal "
            "factor [cosθ'_b/cosθ_b·S(b)] / [cosθ'_a/cosθ_a·S(a)]. The factor itself ranges "
            "from 3e-5 to 6e4; the agreement has median relative error 9e-8 and is within "
            "3.6e-6 everywhere the shading-frame cosines exceed 0.01, and within 1.2e-3 at the "
            "horizon (float32). (4) All other asymmetric pairs (41 215 and 6 805) have the "
            "frame flipped in one order only, because the frame depends on ωi. The "
            "asymmetry is therefore exactly the model's, and the check should report it as "
            "expected (its expected_asymmetry now does, for NormalMap and BumpMap)."),
        reproducer="validation/audit/model_normalmap_reciprocity.py",
        source=("src/bsdfs/normalmap.cpp (v3.9.1): NormalMap::eval lines 159-176, "
                "NormalMap::frame lines 220-240 (flip_invalid_normals 223-227); "
                "src/bsdfs/normalmap_helpers.h eval_shadow_terminator")),
    Finding(
        bsdf="normalmap", check=r"^consistency$", configs=r"roughconductor",
        verdict="check-limitation",
        summary=(
            "'weight vs eval/pdf: relative error 0.00114 > 0.001' in 1 of 89 673 samples: wi = "
            "(-0.597, -0.787, 0.156), wo = (0.624, 0.702, 0.343), weight 4.17794e-4 vs eval/pdf "
            "4.18272e-4. In the normal-mapped frame this wo is at the horizon: cosθo' = "
            "2.95e-5, and tanθ·α ≈ 8000 for αu = 0.05, αv = 0.3, so the Smith G1 there is "
            "≈ a, proportional to cosθo'. sample() computes the weight from the sampled "
            "direction before rotating it to the world frame. eval() and pdf() rotate the "
            "stored float32 wo back. One float32 ulp of wo's world components (~6e-8) moves "
            "cosθo' by ~2e-3 relative. A float64 implementation (G1(wo', m)·shadowing term, "
            "F = 1) at the same float32 directions gives 4.18371e-4: eval/pdf is 2.4e-4 from "
            "it, the weight 1.4e-3, and the float32 conditioning (1 ulp of wo) is 9.1e-4. The "
            "gap is therefore rounding of an ill-conditioned direction, not a disagreement "
            "between sample() and eval()/pdf(). Other seeds (1-3) stay below 2e-4. The "
            "conditioning-aware tolerance now in check_consistency (4 × the relative spread "
            "under float32 jitter of wi and wo) accepts it: 'max relative error 0.0011 (1 "
            "within the float32 conditioning of their directions)'.")),
    # ------------------------------------------------------------------ null
    Finding(
        bsdf="null", check=r"^mitsuba chi2", configs="", verdict="check-limitation",
        summary=(
            "Mitsuba's χ² harness cannot run: 'Histogram sum = 0.000001, PDF sum = 0.000000, "
            "d.o.f = 2^64-1' at every angle. null has only a Null lobe, pdf() = 0 everywhere by "
            "convention and wo = -wi, so there is no density to test. Its sample() also "
            "returns width-1 constants (wo = -si.wi with a constant wi), so BSDFAdapter's "
            "histogram sees one sample out of 10^6. Our χ² reports 'not applicable (only Dirac "
            "delta lobes)', and the audit's _harness_applies now skips Dirac/Null BSDFs. What "
            "can be checked passes: consistency, energy = 1, and eval_null_transmission = 1.")),
]
