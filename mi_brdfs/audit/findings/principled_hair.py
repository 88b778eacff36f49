"""
Triage of the audit's failures for ``principled``, ``principledthin``, ``pplastic`` and ``hair``,
one mechanism per finding, each with its own reproducer:

* ``principled`` numbers its samples with fixed slots, not its lobe list
  (``repro_principled_component_slots.py``: the consistency records);
* ``principled`` and ``principledthin`` ignore ``ctx.component`` and ``ctx.type_mask``
  (``repro_principled_context.py``: the lobe records; principledthin numbers its samples right,
  with and without its transmission lobes);
* ``principledthin`` returns its pdf without its own mask of valid lanes: NaN at cosθi = 0 once
  its specular lobes exist (``repro_principledthin_pdf_mask.py``: positivity and stability);
* ``pplastic`` declares one component and uses two (``repro_pplastic_components.py``);
* ``hair`` samples its residual lobe in the fibre's normal plane (``repro_hair_pmax_sampling.py``:
  χ² at grazing incidence) and evaluates its longitudinal lobes with approximations of I0 that
  lose part of their mass (``repro_hair_fiber_pdf.py``: the pdf integral).

Related, with no audit record (no check updates parameters): ``principled`` and
``principledthin`` append their lobes again at every ``parameters_changed()``
(``repro_principled_lobes_growth.py``, in the issue text of the context finding).

Not covered here (our own χ² passes at the same angle, so they belong to the harness triage):
``principled`` "mitsuba chi2" (default resolution 101/4 on sharp or grazing lobes), ``hair``
"mitsuba chi2 θ=45°" (passes at res 201, ires 16 as shipped, seeds 0 and 1: resolution; it still
fails at 101/4 with the residual-lobe sampling fixed), ``pplastic`` "mitsuba chi2" (the harness's
BSDFAdapter raises on a Mueller-matrix weight in polarized variants).
"""

from __future__ import annotations

from ..triage import Finding

_UP = "validation/audit/upstream/"
_PR1951 = ("https://github.com/mitsuba-renderer/mitsuba3/pull/1951 ('Improvement pass over BSDFs "
           "(esp. principled, principledthin)'), merged after v3.9.1: its description lists 'The "
           "component indices reported by sample() were inconsistent with respect to the "
           "declared set of lobes' among the problems it fixes. Not verified in code: the newest "
           "stored snapshot of master (2026-08-08) predates the merge")

FINDINGS = [
    Finding(
        bsdf="principled", check=r"^consistency$", configs=r"", verdict="defect",
        summary=(
            "sample() reports fixed slot numbers in sampled_component (main specular 3, "
            "spec_trans 2, clearcoat 1, diffuse 0), while initialize_lobes() lists only the "
            "lobes the material has (diffuse, [clearcoat], [spec_trans], main specular). With "
            "the defaults (2 components) every specular sample reports 3, out of range (46 673 "
            "of 96 860 successful samples at wi = (0.6, 0, 0.8)); with spec_trans=0.7 and no "
            "clearcoat the transmission samples report 2, whose flags are the main specular's "
            "GlossyReflection (51 637), and the specular ones 3 (24 964). Mapping each slot to "
            "the index initialize_lobes() gives that lobe brings every count of the six "
            "configurations to 0 (repro_principled_component_slots.py), so the slot numbers "
            "alone explain the records. The API numbers components 0..component_count()-1 "
            "(flags(i) asserts i < m_components.size(); sampled_component is 'the component "
            "index that was sampled'; dielectric, roughdielectric, mask and blendbsdf follow "
            "it), so this is not an over-reading by our check. Only a configuration with both "
            "clearcoat and spec_trans (4 lobes) is numbered right. Render impact: none in the "
            "shipped integrators (none reads sampled_component)."),
        reproducer="validation/audit/repro_principled_component_slots.py",
        source=("src/bsdfs/principled.cpp, Principled::initialize_lobes lines 240-269 vs "
                "Principled::sample lines 423, 440, 463, 480 (fixed slots)"),
        issue=_UP + "principled_component_slots.md", fixed_upstream=_PR1951),
    Finding(
        bsdf="principled", check=r"^lobes$", configs=r"", verdict="defect",
        summary=(
            "principled never consults ctx.component or ctx.type_mask: sample(), eval() and "
            "pdf() return with ctx.component = c exactly what they return in the default "
            "context, for every c (repro_principled_context.py). That alone predicts the lobe "
            "check's numbers: the values of the lobes selected one by one add up to "
            "component_count() times the whole, a relative gap of (count-1)/count (0.50 with 2 "
            "lobes, 0.67 with 3, measured the same), and with ctx.component = c every sample of "
            "another lobe still comes, reporting its own component. The fixed slot numbers of "
            "the consistency finding change which index those samples report, not whether they "
            "come: principledthin, which numbers its samples right, fails the same way. Render "
            "impact: none in the shipped integrators (none sets ctx.component or type_mask)."),
        reproducer="validation/audit/repro_principled_context.py",
        source=("src/bsdfs/principled.cpp: no ctx.is_enabled in Principled::sample, eval, pdf "
                "or eval_pdf (compare plastic.cpp, roughplastic.cpp: ctx.is_enabled(flags, "
                "index) per lobe)"),
        issue=_UP + "principled_context.md"),
    Finding(
        bsdf="principledthin", check=r"^lobes$", configs=r"", verdict="defect",
        summary=(
            "principledthin ignores ctx.component and ctx.type_mask, as principled does (the "
            "entry above, same reproducer): with ctx.component = c, sample() and eval() return "
            "exactly their default-context results, so the lobes selected one by one add up "
            "to component_count() times the whole (gap 0.67 with 3 components, 0.75 with 4 "
            "when spec_trans > 0) and every sample of another lobe still comes. Its "
            "sampled_component numbering is right: its list (diffuse, diffuse transmission, "
            "[spec_trans], main specular) matches its slots 0-3 whenever the specular lobes "
            "are sampled, which happens only with spec_trans > 0; rechecked with spec_trans = "
            "0.6 and 0.4 (both grid configurations pass consistency, "
            "repro_principled_component_slots.py shows 0 inconsistent samples). Without "
            "spec_trans it declares a GlossyReflection component that is never sampled nor "
            "evaluated (a lobe of weight 0, not an error)."),
        reproducer="validation/audit/repro_principled_context.py",
        source=("src/bsdfs/principledthin.cpp: no ctx.is_enabled anywhere; initialize_lobes "
                "lines 193-219, sample slots at lines 343, 377, 394, 402"),
        issue=_UP + "principled_context.md"),
    Finding(
        bsdf="principledthin", check=r"^(positivity|stability)$", configs=r"spec_trans",
        verdict="defect",
        summary=(
            "With spec_trans > 0, pdf() is NaN at cosθi = 0 exactly (wi = (1, 0, 0); 2 of "
            "200 081 positivity pairs, 4 stability values), where eval() is 0. pdf() sets "
            "active &= cosθi != 0 but returns its result unmasked; its early 'return 0' tests "
            "dr::none_or<false>(active), which is false for a JIT array without looking at it, "
            "so in llvm and cuda variants even a call with that lane alone goes through. The "
            "specular lobes, present only with spec_trans > 0, add the GGX visible-normal pdf "
            "D G1 (wi·m)/cosθi, 0/0 there (the NaN's origin, shown directly). Applying the "
            "mask, as the early return intends, gives 0 at that lane and leaves the others "
            "unchanged (repro_principledthin_pdf_mask.py), so the missing mask alone explains "
            "the records; without spec_trans the same lane returns a nonzero pdf (no check "
            "flags it: principledthin declares transmission lobes). Found by the grid's new "
            "spec_trans configurations. Not a limit of the check: the plugin itself marks "
            "cosθi = 0 invalid, and eval() returns 0 there. roughplastic has the same missing "
            "final mask (its positivity finding). Render impact: none expected in the shipped "
            "integrators, which discard non-finite MIS weights (path.cpp's mis_weight), as "
            "for roughplastic."),
        reproducer="validation/audit/repro_principledthin_pdf_mask.py",
        source=("src/bsdfs/principledthin.cpp (v3.9.1), PrincipledThin::pdf lines 600-705: mask "
                "at 606, early return at 608-609 (dr::none_or<false>), specular lobes' "
                "spec_reflect_distr.pdf / spec_trans_distr.pdf at 688-692, result returned "
                "unmasked at 704"),
        issue=_UP + "principledthin_pdf_mask.md"),
    Finding(
        bsdf="pplastic", check=r"^(consistency|lobes)$", configs=r"", verdict="defect",
        summary=(
            "pplastic declares ONE component (m_components = {m_flags}) but samples, evaluates "
            "and selects two: index 0 specular, 1 diffuse (ctx.is_enabled(GlossyReflection, 0) "
            "/ (DiffuseReflection, 1) in sample, eval and pdf). 33 075 of 100 000 successful "
            "samples report sampled_component = 1 while component_count() = 1; against the two "
            "components the methods use, none is inconsistent "
            "(repro_pplastic_components.py), so the single declared component alone explains "
            "the record. Consequence: blendbsdf routes ctx.component by its children's "
            "component_count(), so blendbsdf(pplastic, diffuse) with ctx.component = 1 "
            "evaluates the diffuse child (0.0637) instead of pplastic's diffuse lobe (0.1167). "
            "Render impact: none in the shipped integrators."),
        reproducer="validation/audit/repro_pplastic_components.py",
        source=("src/bsdfs/pplastic.cpp, PolarizedPlastic::PolarizedPlastic lines 209-210 (one "
                "component) vs sample lines 251-252, 278, 284, eval 299-300, pdf 443-444 (two)"),
        issue=_UP + "pplastic_components.md"),
    Finding(
        bsdf="principled", check=r"^energy$", configs=r"roughness=0\.1", verdict="model-property",
        summary=(
            "E(89°) = 1.068 from sample() is the published model's. The Disney BRDF "
            "(Burley 2012, 'Physically-Based Shading at Disney', §5.3 diffuse with the Schlick "
            "'Fresnel shadow' and retro-reflection, §5.1/App. B specular D F G/(4 cos cos); "
            "Burley 2015, 'Extending the Disney BRDF to a BSDF with Integrated Subsurface "
            "Scattering', §3, the identical Lambert + retro-reflection split) ADDS the diffuse "
            "lobe to the specular one without a (1 - specular albedo) weight. At grazing "
            "incidence the specular albedo approaches the Fresnel reflectance (0.756 at 89° for "
            "eta = 1.5, GGX alpha = 0.01), while the diffuse Fresnel factor only halves the "
            "diffuse response (0.311). An independent float64 numpy implementation with "
            "deterministic quadrature gives E = 0.531, 0.574, 0.802, 0.967, 1.068 at "
            "0/60/80/85/89°, and Mitsuba's sample() gives 0.530, 0.575, 0.802, 0.966, "
            "1.068 ± 0.0004. Mitsuba's eval matches the model pointwise (median relative "
            "difference 5e-8). So Mitsuba implements the documented model faithfully; the model "
            "is not energy-conserving at grazing angles for smooth dielectrics. Script: "
            "validation/audit/model_principled_energy.py (exits 0: the model and Mitsuba agree)."),
        reproducer=None,
        source=("src/bsdfs/principled.cpp, Principled::eval lines 583-600 (specular) and "
                "642-679 (diffuse + retro, added without a 1 - F weight)")),
    Finding(
        bsdf="pplastic", check=r"^reciprocity$", configs=r"", verdict="check-limitation",
        summary=(
            "The max relative asymmetry of 0.060 at θ = 89.9° (cos 1.7e-3) is float32 "
            "conditioning in the polarized diffuse term. The model is reciprocal: Baek et al. "
            "2018, 'Simultaneous Acquisition of Polarimetric SVBRDF and Normals', §4, a "
            "microfacet specular plus a depolarized diffuse term rho/pi T(theta_i) T(theta_o) "
            "between two Fresnel transmissions, with T the same in both directions. pplastic "
            "does not declare NonSymmetric. Mitsuba's polarized eval computes the exit "
            "transmission Ti from the INTERNAL cosine of wi (mueller::specular_transmission("
            "|cos theta_t|, 1/eta)). Near grazing, T ~ k cos theta, and cos theta_t carries "
            "cos^2 theta only through a term that float32 rounding of cos theta_t (~0.74) "
            "perturbs by ~1e-7, giving a relative error ~eps32/cos^2 on one order only. Measured "
            "(validation/audit/conditioning_pplastic_reciprocity.py, 400k pairs): the error "
            "against a float64 evaluation of the model at the same float32 directions is at most "
            "2.97 x eps32 (1/cos_wi^2 + 1/cos_wo). Max asymmetry per bin of min cos: 8e-2 "
            "[1e-3, 3e-3), 1.2e-2 [3e-3, 1e-2), 1.1e-3 [1e-2, 3e-2), 1.2e-4 [3e-2, 0.1), "
            "8e-6 above 0.1. The specular component's asymmetry is at most 2.5e-4 at the "
            "grazing end. The RGB and spectral (unpolarized) variants are symmetric to 3e-8. "
            "Our check's fixed RTOL 1e-4 ignores conditioning. With a per-pair tolerance "
            "RTOL + C eps32/min(cos a, cos b)^2 it passes for seeds 0, 1 and 2 (max asym/tol = "
            "0.09 at C = 20, 0.42 at C = 4), while hair still fails 199,551 of 199,587 "
            "pairs."),
        reproducer=None,
        source=("src/bsdfs/pplastic.cpp, PolarizedPlastic::eval lines 364-402 (polarized "
                "diffuse: Ti from the refracted wi_hat_p at line 375-376)")),
    Finding(
        bsdf="hair", check=r"^chi2 θ=84", configs=r"", verdict="defect",
        summary=(
            "sample() draws the residual lobe (p >= P_MAX = 3) wrongly. sin_theta_ip and "
            "cos_theta_ip are initialised to 0 and set only for p < P_MAX, so every p = 3 "
            "sample gets sin_theta_o = 0 exactly: it lies in the fibre's normal plane "
            "(wo.y == 0; the fibre runs along local +y). pdf() and eval() spread that lobe "
            "over M_3(theta_i, theta_o). At the audit's grazing wi = (0.995, 0, 0.0995) (the "
            "fibre's silhouette, h ~ -1), 0.26 % of the samples land on wo.y == 0, while pdf() "
            "gives a 1e-6 band there a probability of 3e-6; for blonde hair the share is 3.7 %. "
            "Our χ² (res 201, ires 16) and Mitsuba's harness (res 101, ires 4) both reject with "
            "p = 0 for seeds 0 and 1. Redrawing only those samples as the fixed code would "
            "(same random numbers, untilted incident angle) makes both pass: p = 0.35/0.18 at "
            "101/4 and 0.65/0.79 at 201/16, so this cause alone explains the rejection; the "
            "pdf's missing mass (the pdf-integral finding) is still there when they pass. "
            "Impact: for the integral of f L with L = wo.y^2 "
            "(light along the fibre), sample() is -2.1 % (brown) and -13.8 % (blonde) off at the "
            "silhouette and -0.1/-0.7 % at h = 0, while the fixed sampler matches uniform "
            "sampling of eval() within noise. A render of 40 blonde bsplinecurve fibres (path "
            "tracer, 256 spp) is 0.09 % darker, against 0.01 % seed-to-seed. The furnace is "
            "unaffected. pbrt-v3's HairBSDF::Sample_f initialises sinThetaIp = sinThetaI. "
            "Impact script: validation/audit/impact_hair_pmax_sampling.py."),
        reproducer="validation/audit/repro_hair_pmax_sampling.py",
        source=("src/bsdfs/hair.cpp, Hair::sample lines 264-272 (loop j < P_MAX leaves "
                "sin/cos_theta_ip = 0 for p == P_MAX) and 287-288 (sin_theta_o); pdf side lines "
                "323-325 uses the untilted si.wi"),
        issue=_UP + "hair_pmax_sampling.md"),
    Finding(
        bsdf="hair", check=r"^pdf integral$", configs=r"", verdict="defect",
        summary=(
            "∫ pdf dω = 0.9971 at θ = 80° (0.9981 at 0° and 45°) while every sample succeeds: "
            "pdf() lacks part of its longitudinal lobes' mass. It evaluates d'Eon et al. 2011's "
            "M_p with warp::square_to_rough_fiber_pdf, whose detail::i0 sums 11 terms of the "
            "series of I0 (short by up to half a percent just below x = 12) and whose "
            "detail::log_i0 uses x + (log(1/(2πx)) + 1/(8x))/2 above 12, half of the asymptotic "
            "expansion's 1/(8x) term (pbrt-v3's LogI0 has the same expression). For the default "
            "roughness (κ = 11.8, 47.3, 2.95 for R, TT, TRT) a lobe integrates to 0.9965-1.0000 "
            "in Mitsuba and to the same digits in a float64 copy of the approximations, to "
            "1.000000 with numpy's exact I0. sample() draws each lobe with the exact inverse "
            "CDF, so its samples' density integrates to 1. Weighting each lobe's integral by "
            "the lobe probabilities of Hair::attenuation_pdf predicts the hair's ∫ pdf: 0.99815, "
            "0.99814 and 0.99709 at 0°, 45° and 80°, equal to the quadrature of Mitsuba's pdf() "
            "to the digits shown, and 1 with exact I0 (repro_hair_fiber_pdf.py), so the I0 "
            "approximations alone explain the record. Not the residual-lobe sampling defect: "
            "that moves samples, not the pdf's mass. Impact: eval() shares the approximation, "
            "so a sample's weight eval/pdf is nearly unaffected; BSDF-sampled estimates follow "
            "the exact lobes and light-sampled (eval-based) ones the approximated lobes, which "
            "differ by at most the lobes' missing mass (not measured in renders)."),
        reproducer="validation/audit/repro_hair_fiber_pdf.py",
        source=("include/mitsuba/core/warp.h (v3.9.1), detail::i0 lines 749-759 (11-term "
                "series), detail::log_i0 lines 761-766 (1/(16x) where the expansion has 1/(8x)), "
                "square_to_rough_fiber_pdf lines 771-793; src/bsdfs/hair.cpp "
                "Hair::longitudinal_scattering lines 704-708 and the exact longitudinal sampling "
                "in Hair::sample lines 275-280"),
        issue=_UP + "hair_fiber_pdf.md"),
    Finding(
        bsdf="hair", check=r"^reciprocity$", configs=r"", verdict="model-property",
        summary=(
            "hair declares NonSymmetric on its glossy component, and the model is non-reciprocal "
            "by construction. In Chiang et al. 2016, 'A Practical and Controllable Hair and Fur "
            "Model for Production Path Tracing' (CGF 35(2), §3-4, with d'Eon et al. 2011's M_p), "
            "the fibre offset h = sin(gamma_i), the attenuation A_p(theta_i, h) and the azimuthal "
            "lobe centres Phi_p = 2p gamma_t - 2 gamma_i + p pi all depend on the incident "
            "direction only, and the cuticle tilt is applied to theta_i only. An independent "
            "float64 numpy implementation (validation/audit/model_hair_reciprocity.py) matches "
            "Mitsuba's eval to a median of 1.8e-4 (99th percentile 4.7e-3, from Mitsuba's "
            "10-term I0 series and asymptotic log I0). At the audit's pair it gives f(a,b) = "
            "3.26e-8 and f(b,a) = 0.267 (Mitsuba: 3.26e-8 and 0.267), with a median asymmetry "
            "of 0.50 over random pairs. The current reciprocity check already passes it ('not "
            "expected to be reciprocal'); the record predates that change."),
        reproducer=None,
        source="src/bsdfs/hair.cpp, Hair::Hair lines 195-199 (NonSymmetric component)"),
]
