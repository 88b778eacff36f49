"""
Triage of the BSDF plugins Eradiate adds to its Mitsuba fork, ``eradiate-mitsuba`` 0.5.0
(Mitsuba 3.7.1; sources: https://github.com/eradiate/mitsuba3 at tag v0.5.0,
src/eradiate_plugins/bsdfs/). Every entry has ``build="eradiate-mitsuba"``: it covers the
fork's plugins only (``rtls`` is also the name of one of the package's). Each reproducer in
``validation/audit/eradiate/`` runs with the fork's Python alone and exits 1 while what it
shows is there.
"""

from ..triage import Finding

_DIR = "validation/audit/eradiate/"
_SRC = "eradiate/mitsuba3 v0.5.0, src/eradiate_plugins/bsdfs/"
_BUILD = "eradiate-mitsuba"


FINDINGS = [
    Finding(
        bsdf="rtls", check=r"^(consistency|positivity|stability)$", configs="",
        verdict="model-property", build=_BUILD,
        summary=(
            "rtls returns negative values and negative sample weights, with its defaults "
            "(f_iso 0.209741, f_vol 0.081384, f_geo 0.004140) and more so with f_geo = 0.05: "
            "eval = -0.000659 at normal incidence towards grazing backwards (f cosθo at θo = "
            "90°; f = -0.306 at θo = 89.9°), and 521 negative sample weights in the default "
            "configuration (-0.0319 at θi = 89.55°; 29 % of the weights at θi = 89.5°). The "
            "kernel-driven model f = (f_iso + f_vol K_vol + f_geo K_geo)/π is a linear fit "
            "(Lucht, Schaaf & Strahler 2000, eqs. 37-41) whose Li-Sparse-Reciprocal kernel "
            "K_geo is negative and grows like -secθ towards grazing; nothing bounds the sum "
            "below. The same formula in float64, written from the paper, gives the same values "
            "at the same pairs (f = 0.0643694, 0.0621168, 0.0334684, -0.305905 at θo = 80°, "
            "85°, 89°, 89.9°, to all digits printed): a property of the model, which Eradiate "
            "implements as published (sample() weights eval/pdf with the cosine pdf, so a "
            "negative f is a negative weight)."),
        reproducer=_DIR + "repro_rtls_negative.py",
        source=_SRC + "rtls.cpp lines 241-242 (the linear combination of the kernels), "
                      "line 110 (sample's weight)"),
    Finding(
        bsdf="rtls", check=r"^reciprocity$", configs="", verdict="check-limitation",
        build=_BUILD,
        summary=(
            "With f_iso = 0.1, f_vol = 0.05, f_geo = 0.05 the reciprocity check's worst pair, "
            "a = (θ 84.0°, φ -176.6°), b = (θ 27.2°, φ 177.5°), has f(a,b) = -1.897e-7 and "
            "f(b,a) = -2.040e-7: a sum of terms of order 0.1 that cancels to 2e-7, so float32 "
            "rounding of the terms (ε₃₂ · 0.1 ≈ 1e-8) is 7 % of the result. The model is "
            "reciprocal (both kernels are symmetric in θi, θo and depend on the azimuths "
            "through cos φ only). The finer check (validation/audit/eradiate/"
            "conditioning_rtls_reciprocity.py, 200 000 random pairs, exits 0): every pair's "
            "|f(a,b) - f(b,a)| is within 16 ε₃₂ (|f_iso| + |f_vol K_vol| + |f_geo K_geo|)/π "
            "(at most 0.85 of it), and the float64 model is symmetric to 0 at every pair; the "
            "check's relative tolerance does not allow for a value that cancels to near "
            "zero."),
    ),
    Finding(
        bsdf="rpv", check=r"^energy$", configs="", verdict="model-property", build=_BUILD,
        summary=(
            "rpv with its defaults (rho_0 = 0.1, k = 0.1, g = 0) reflects E = 21.15 ± 0.21 "
            "at θi = 89° in the white furnace (the reproducer: 20.95 ± 0.13 from sample()'s "
            "weights, 20.80 ± 0.15 from the float64 formula of Rahman, Pinty & Verstraete "
            "1993, eq. 3, both with 2·10⁶ samples). The Minnaert factor (cosθi cosθo (cosθi + "
            "cosθo))^(k-1) grows without bound towards grazing incidence for k < 1: the "
            "model creates energy there, as published. k = 1.2 passes every check; k = 0.8 "
            "passes the energy check at the audited angles."),
        reproducer=_DIR + "repro_rpv_energy.py",
        source=_SRC + "rpv.cpp lines 160-161 (the Minnaert factor)"),
    Finding(
        bsdf="rpv", check=r"^(positivity|stability)$", configs="", verdict="defect",
        build=_BUILD,
        summary=(
            "rpv returns Inf at grazing backscatter (wi = wo at cosθ = 6.1e-17) for k = 0.1 "
            "and k = 0.8: the Minnaert factor's base cosθi cosθo (cosθi + cosθo) = 4.6e-49 "
            "underflows to 0 in float32, and pow(0, k - 1 < 0) is Inf. The float64 value of "
            "eval = f cosθo there is finite: 1.7e-8 for k = 0.8, 1.2e26 for k = 0.1 (the "
            "latter is the model's divergence, the energy finding above). Inf where the model "
            "is finite is the implementation's; of little consequence off the horizon "
            "(cosθ = 1e-4 gives finite values), but a path that reaches it carries Inf."),
        reproducer=_DIR + "repro_rpv_grazing_inf.py",
        source=_SRC + "rpv.cpp lines 160-161: dr::pow(cos_theta_i * cos_theta_o * "
                      "(cos_theta_i + cos_theta_o), k - 1.f)",
        issue=_DIR + "upstream/rpv_grazing_inf.md"),
    Finding(
        bsdf="hapke", check=r"^(positivity|stability)$", configs=r"^default",
        verdict="defect", build=_BUILD,
        summary=(
            "hapke with its defaults (w 0.5, b 0.2, c 0.5, θ 30°, B_0 = 0, h = 0) returns NaN "
            "at normal incidence looking straight back (wo = wi = +z, the opposition peak "
            "itself; 14 non-finite of 200 081 pairs, with the grazing ones below): eval_B "
            "returns B_0 / (1 + 1/h · tan(g/2)), and with the default h = 0 at the phase "
            "angle g = 0 that is 0 / (1 + Inf · 0) = NaN. Any h = 0 does it at g = 0 (B_0 = 0 "
            "should make the term vanish); h = 0.05 gives 0.0337213 there. A single literal "
            "lane in llvm_ad_rgb happens to come out finite (LLVM folds the constant); a "
            "batch, and scalar_rgb, give NaN."),
        reproducer=_DIR + "repro_hapke_opposition_nan.py",
        source=_SRC + "hapke.cpp line 261 (eval_B: B_0 / (1.f + 1.f / h * dr::tan(g / 2))) "
                      "with the default h = 0 of line 78",
        issue=_DIR + "upstream/hapke_opposition_nan.md"),
    Finding(
        bsdf="hapke", check=r"^(positivity|stability)$", configs="", verdict="defect",
        build=_BUILD,
        summary=(
            "hapke returns NaN at grazing incidence with grazing exitance forwards (wi at "
            "cosθ = 6.1e-17, wo its mirror image, relative azimuth π), in every configuration "
            "audited (3 non-finite of 200 081 pairs with B_0 = 0.5, h = 0.2): eval_mu divides "
            "cosφ · E2_e + sin²(φ/2) · E2_i by 2 - E1_e - (φ/π) E1_i, and at e = i = 90° "
            "E1 and E2 round to 1 in float32, so at φ = π both are 0: 0/0. At cosθ = 1e-4 "
            "the same pair gives 2.3e-9. Of little consequence off the horizon."),
        reproducer=_DIR + "repro_hapke_grazing_nan.py",
        source=_SRC + "hapke.cpp lines 181-185 (eval_mu)",
        issue=_DIR + "upstream/hapke_grazing_nan.md"),
*[Finding(
        bsdf=name, check=r"^(positivity|stability)$", configs="", verdict="defect",
        build=_BUILD,
        summary=(
            f"{name} returns Inf (NaN in the checks' batches) at normal incidence for views "
            "within about 1e-4 rad of the normal: the centre of the sun glint seen from "
            "above. Exactly at wo = wi = +z and at 1e-3 rad the values are finite (0.0557 for "
            "ocean_mishchenko at 5 m/s), as the models are. ocean_mishchenko, ocean_grasp and "
            "maignan (which has no microfacet term) are Inf at exactly the same offsets, and "
            "what they share is the Fresnel Mueller matrix of Mishchenko & Travis (1997), "
            "fresnel_sunglint_polarized, the only term that depends on the plane of wi and wo "
            "(undefined as they meet): it rebuilds both directions from their azimuths and "
            "scales by 1/|wi × wo|⁴ behind an exact-equality guard against collinear "
            "directions."),
        reproducer=_DIR + "repro_ocean_mishchenko_normal.py",
        source="eradiate/mitsuba3 v0.5.0, include/mitsuba/eradiate/oceanprops.h lines 457-555 "
               "(fresnel_sunglint_polarized; coeff = 1 / norm2 at 521-525), called from "
               f"src/eradiate_plugins/bsdfs/{call}",
        issue=_DIR + "upstream/ocean_mishchenko_normal.md")
      for name, call in (("ocean_mishchenko", "ocean_mishchenko.cpp eval (lines 235-262)"),
                         ("ocean_grasp", "ocean_grasp.cpp line 223"),
                         ("maignan", "maignan.cpp line 166"))],
    Finding(
        bsdf="maignan", check=r"^(consistency|albedo|reciprocity)$", configs="",
        verdict="defect", build=_BUILD,
        summary=(
            "maignan leaves out the cosine foreshortening: eval() returns C·F, the BRDF f "
            "itself, where BSDF::eval returns f·cosθo, and sample() returns the same C·F as "
            "its weight where the weight is f·cosθo/pdf. Hence eval is symmetric in wi and "
            "wo (eval(a→b)/eval(b→a) = 1.0000 where a reciprocal f·cosθo gives cosθb/cosθa = "
            "5.19), the reciprocity check's f = eval/cosθo is off by 1/cosθo (its ratio "
            "0.1923 = cosθa/cosθb = 0.1925 at a = (θ 78.9°), b = (θ 1.2°)), every sample "
            "weight equals eval instead of eval/pdf (weight/(eval/pdf) = 0.2213 at θi = 45°: "
            "consistency fails in 100 000 of 100 000 samples), and sample()'s albedo (0.024 "
            "at 89° with C = 5, ndvi = 0.6) is not eval()'s quadrature (0.332). The model "
            "(Maignan et al. 2009, eq. 21) is a reciprocal BRDF."),
        reproducer=_DIR + "repro_maignan_cosine.py",
        source=_SRC + "maignan.cpp line 214 (eval returns C * F & active) and line 197 "
                      "(sample returns C * F as the weight)",
        issue=_DIR + "upstream/maignan_cosine.md"),
    Finding(
        bsdf="bilambertian", check=r"^lobes$", configs="", verdict="defect", build=_BUILD,
        summary=(
            "bilambertian's sample() ignores the lobe the context selects: with "
            "ctx.component = 0 (diffuse reflection) 22 040 of 100 000 samples report its "
            "transmission lobe, with ctx.component = 1 77 577 report its reflection "
            "(reflectance 0.7, transmittance 0.2, normal incidence): the lobe is chosen from "
            "sample1 in proportion r/(r + t) as for the default context, and the flags "
            "has_reflect/has_transmit it computes from the context only stop it when both are "
            "off. So the sum of the lobes one by one is twice the whole (2.00000 vs 1.00000 "
            "with the defaults)."),
        reproducer=_DIR + "repro_bilambertian_component.py",
        source=_SRC + "bilambertian.cpp lines 64-65 (has_reflect, has_transmit) and 90-91 "
                      "(the lobe chosen from sample1 alone)",
        issue=_DIR + "upstream/bilambertian_component.md"),
    Finding(
        bsdf="ocean_legacy", check=r"^(positivity|stability)$", configs="", verdict="defect",
        build=_BUILD,
        summary=(
            "ocean_legacy returns NaN at grazing incidence with grazing exitance (wi at "
            "cosθ = 6.1e-17; wo = wi at 0.1 m/s, wo near the mirror image at 5 m/s: 1 of "
            "200 081 pairs each), in its glint component (ctx.component = 1; the diffuse one "
            "is finite there, and every value is finite at cosθo = 1e-3). The half vector is "
            "then horizontal: Beckmann's D(m) is 0 and the Gram-Charlier correction of Cox & "
            "Munk, whose slopes m.x/(σ m.z) reach 1e16, overflows float32 in its quartic "
            "terms: 0 · Inf = NaN, the likely cause. Of little consequence off the horizon."),
        reproducer=_DIR + "repro_ocean_legacy_grazing_nan.py",
        source=_SRC + "ocean_legacy.cpp lines 424-427 (eval_glint: D *= "
                      "cox_munk_gram_charlier_coef(...)); include/mitsuba/eradiate/"
                      "oceanprops.h from line 641 (the slopes xn, xe and their quartic terms)",
        issue=_DIR + "upstream/ocean_legacy_grazing_nan.md"),
    Finding(
        bsdf="ocean_legacy", check=r"^reciprocity$", configs="", verdict="model-property",
        build=_BUILD,
        summary=(
            "ocean_legacy is not reciprocal (42 % at a = (θ 82.3°, φ 0.9°), b = (θ 64.6°, "
            "φ -91.1°) with the default wind; 50 % at 5 m/s) and does not declare "
            "NonSymmetric. The asymmetry is all in its diffuse component (ctx.component = 0: "
            "whitecaps, coverage 9e-10 at 0.1 m/s, and the underlight); the glint is 0 at that "
            "pair. The 6S ocean model's underlight (Vermote et al. 1997) weights the water's "
            "reflectance by the transmittance of the sun's direction into the water and of the "
            "view's out of it, two different functions (tabulated downwelling and upwelling), "
            "so the model is not reciprocal; the plugin's flags do not say so."),
        reproducer=_DIR + "repro_ocean_legacy_reciprocity.py",
        source=_SRC + "ocean_legacy.cpp lines 489-490 (eval_underlight: t_d from the "
                      "downwelling table at wi, t_u from the upwelling table at wo)"),
    Finding(
        bsdf="selectbsdf", check=r"^crash$", configs="", verdict="defect", build=_BUILD,
        summary=(
            "The worker dies in the gradients check (the battery's last, not its first): "
            "dr.forward through selectbsdf's eval aborts the process with Dr.Jit's fatal "
            "'jit_var(rN): unknown variable!'. Once a selectbsdf is loaded, forward mode "
            "aborts in any call through a BSDF pointer, another BSDF's too, and a prb render "
            "of a scene holding a selectbsdf differentiated with dr.forward; primal "
            "evaluation, dr.backward and JitFlag.SymbolicCalls = False work. selectbsdf "
            "gathers a nested BSDF pointer and calls it from inside its own methods: a "
            "symbolic call over the BSDF registry, which traces every registered BSDF, the "
            "selectbsdf itself among them, so BSDF::eval is traced within a call of "
            "BSDF::eval, and the forward-mode replay of that call aborts. Dr.Jit's own: a "
            "pure-Python model (validation/audit/eradiate/drjit_nested_call_forward.py, a "
            "dr.dispatch whose callable dispatches the same function one level deeper) "
            "aborts the same way under Dr.Jit 1.2.0 (this build) and 1.5.0 (Mitsuba 3.9.1, "
            "which has no selectbsdf: the 3.9 audit does not cover it), and works when the "
            "inner call runs another function. Not our check: forward-mode derivatives are "
            "part of the API (prb's render_forward)."),
        reproducer=_DIR + "repro_selectbsdf_forward_ad.py",
        source=_SRC + "selectbsdf.cpp lines 95-97, 104-106, 113-115, 124-126 (a nested "
                      "BSDFPtr gathered and called); Dr.Jit v1.2.0 (the fork's ext/drjit) "
                      "src/extra/call.cpp lines 302-310 (every registered instance traced), "
                      "616 and 704 (CallOp::forward re-running each callable), 283-285 with "
                      "Dr.Jit-Core src/api.cpp 187-189 (the recursion limit)",
        issue=_DIR + "upstream/selectbsdf_forward_ad.md"),
    Finding(
        bsdf="ocean_grasp", check=r"^(energy|albedo)$", configs=r"wind 5 m/s",
        verdict="defect", build=_BUILD,
        when=lambda r: ("sample() nan" in r["message"] if r["check"] == "albedo"
                        else isinstance(r["value"], float) and r["value"] <= 1.0),
        summary=(
            "One sample() weight of 10⁶ at θi = 15° is NaN (wind 5 m/s), so the sampled "
            "albedo there is NaN: the albedo record, and the energy record, which fails on the "
            "non-finite estimate although every finite E(θ) is below 1 (its message names the "
            "largest finite one, 0.414 at 89°). The sample's wo = (3.6e-5, -7.8e-5, "
            "1.0000001) has a float32 length just above 1 (reflect() of the facet normal), "
            "and eval is NaN at any such direction: at wo = (0, 0, 1.0000001) eval is NaN, at "
            "(0, 0, 1) it is 0.0326 (wi at 15°). The Smith term lambda(v, σ) takes "
            "sqrt(1 - v.z²) unclamped: the square root of a negative number. Of little "
            "consequence in a render (a NaN sample in about 10⁶), but a NaN where the model is "
            "finite is the implementation's."),
        reproducer=_DIR + "repro_ocean_grasp_glint_nan.py",
        source=_SRC + "ocean_grasp.cpp lines 241-249 (lambda: dr::sqrt(1.f - v.z() * "
                      "v.z())), 226 and 230 (G and the glint), 322 (sample's reflect)",
        issue=_DIR + "upstream/ocean_grasp_glint_nan.md"),
    Finding(
        bsdf="ocean_grasp", check=r"^lobes$", configs="", verdict="defect", build=_BUILD,
        summary=(
            "With ctx.component = 1 (the glint) sample() still returns whitecap samples "
            "(component 0, DiffuseReflection) in the proportion of the whitecap coverage: "
            "184 of 200 000 at normal incidence with wind 5 m/s (the reproducer: 877 of 10⁶; "
            "Monahan's coverage 2.95e-6 · U^3.52 = 8.5e-4 there; 9e-10 at the default 0.1 "
            "m/s, where it is not seen). sample() draws foam from sample1 alone before it "
            "looks at the context, whose has_diffuse only sets the split between the water's "
            "two lobes; pdf() adds the foam's density whatever the context too, while eval() "
            "leaves the whitecaps out unless the context enables them."),
        reproducer=_DIR + "repro_ocean_grasp_component.py",
        source=_SRC + "ocean_grasp.cpp lines 296-313 (foam drawn from sample1 alone), "
                      "265-266 and 288-293 (the context's flags), 467-482 and 496 (pdf), 376 "
                      "(eval); include/mitsuba/eradiate/oceanprops.h lines 330-336 (coverage)",
        issue=_DIR + "upstream/ocean_grasp_component.md"),
    Finding(
        bsdf="blendbsdf", check=r"^lobes$", configs=r"textured", verdict="defect",
        build=_BUILD,
        summary=(
            "Under Mitsuba 3.7.1 the textured-weight record (diffuse + conductor, weight 0.8 "
            "at the check's uv) fails on the component offset alone: with ctx.component = 1 "
            "(the conductor's lobe) every sample reports sampled_component 0; the albedos of "
            "the lobes one by one add up to the whole (0.100 + 0.800 = 0.900, all lobes "
            "0.901). sample() shifts ctx.component down for the second BSDF and returns its "
            "BSDFSample3f without shifting sampled_component back up, as in 3.9.1. The "
            "Dirac-weight defect that Mitsuba 3.9.1's audit gives this record "
            "(validation/audit/repro_blendbsdf_delta_weight.py, exit 0 here) is not in "
            "this build: 3.7.1's sample() returns each nested BSDF's own weight, not the "
            "mixture's (3.9.1 gives 0.871 for the whole with the same reproducer)."),
        reproducer=_DIR + "repro_blendbsdf_component_offset.py",
        source="eradiate/mitsuba3 v0.5.0 (Mitsuba 3.7.1), src/bsdfs/blendbsdf.cpp lines "
               "116-125 (ctx.component offset on the way in, line 120; the nested sample "
               "returned unchanged) and 134-146 (each nested sample and weight copied as is)",
        issue="validation/audit/upstream/blendbsdf_sampled_component.md"),
]
