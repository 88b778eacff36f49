"""
Triage of the audit's failures for ``principled``, ``principledthin``, ``pplastic`` and ``hair``.

Not covered here (our own χ² passes at the same angle, so they belong to the harness triage):
``principled`` "mitsuba chi2" (default resolution 101/4 on sharp or grazing lobes), ``hair``
"mitsuba chi2 θ=45°" (passes at res 201, ires 16 as shipped, seeds 0 and 1: resolution; it still
fails at 101/4 with the residual-lobe sampling fixed), ``pplastic`` "mitsuba chi2" (the harness's
BSDFAdapter raises on a Mueller-matrix weight in polarized variants).
"""

from __future__ import annotations

from ..triage import Finding

FINDINGS = [
    Finding(
        bsdf="principled", check=r"^(consistency|lobes)$", configs=r"", verdict="defect",
        summary=(
            "sample() reports component indices outside its component list: "
            "initialize_lobes() pushes only the lobes present (diffuse, [clearcoat], "
            "[spec_trans], main specular), but sample() writes fixed slots (specular 3, "
            "spec_trans 2, clearcoat 1, diffuse 0). Defaults: component_count() = 2, 46.7 % of "
            "samples report component 3; spec_trans=0.7: the transmission samples report 2, whose "
            "flags are GlossyReflection (76.6 % inconsistent). The audit counts 31k-98k such "
            "samples per configuration. The API numbers components 0..component_count()-1 "
            "(flags(i) asserts i < m_components.size(); sampled_component is 'the component "
            "index that was sampled'; dielectric, roughdielectric, mask and blendbsdf follow it), "
            "so this is not an over-reading by our check. Related: principled never consults "
            "ctx.component or ctx.type_mask (with component 0 selected, 47 % of the samples are "
            "still specular and eval is unchanged), and principled/principledthin append their "
            "lobes again at every parameters_changed() (component_count 2 -> 4 -> 6, "
            "3 -> 6 -> 9). Render impact: none in the shipped integrators (none reads "
            "sampled_component or sets ctx.component/type_mask). Issue text: "
            "validation/audit/upstream/principled_components.md."),
        reproducer="validation/audit/repro_principled_components.py",
        source=("src/bsdfs/principled.cpp, Principled::initialize_lobes lines 240-269 vs "
                "Principled::sample lines 423, 440, 463, 480 (fixed slots); no ctx.is_enabled in "
                "sample/eval/pdf; parameters_changed line 325 re-appends the lobes "
                "(principledthin.cpp line 257 likewise)")),
    Finding(
        bsdf="pplastic", check=r"^(consistency|lobes)$", configs=r"", verdict="defect",
        summary=(
            "pplastic declares ONE component (m_components = {m_flags}) but samples, evaluates "
            "and selects two: index 0 specular, 1 diffuse (ctx.is_enabled(GlossyReflection, 0) "
            "/ (DiffuseReflection, 1) in sample, eval and pdf). 33.1 % of the samples report "
            "sampled_component = 1 while component_count() = 1 (audit: 33,718). Consequence: "
            "blendbsdf routes ctx.component by its children's component_count(), so "
            "blendbsdf(pplastic, diffuse) with ctx.component = 1 evaluates the diffuse child "
            "(0.0637) instead of pplastic's diffuse lobe (0.1167). The same in RGB and polarized "
            "variants. Render impact: none in the shipped integrators. Same reproducer and issue "
            "as principled (validation/audit/upstream/principled_components.md)."),
        reproducer="validation/audit/repro_principled_components.py",
        source=("src/bsdfs/pplastic.cpp, PolarizedPlastic::PolarizedPlastic lines 209-210 (one "
                "component) vs sample lines 251-252, 278, 284, eval 299-300, pdf 443-444 (two)")),
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
        bsdf="principledthin", check=r"^(consistency|lobes)$", configs=r"", verdict="defect",
        summary=(
            "principledthin has principled's defect (the entry above): initialize_lobes() "
            "pushes only the lobes present (principledthin.cpp lines 195-215), sample() writes "
            "fixed slots (sampled_component = 3, 2, 0, 1 at lines 343, 377, 394, 402), and no "
            "method consults ctx.component or the type mask. The audit's lobe check shows it: "
            "with ctx.component = 1 or 2 selected, every sample at normal incidence reports "
            "component 0 with a type outside flags(c), and eval of all lobes differs from the "
            "sum over the lobes selected one by one by 67 %. The reproducer's part C shows the "
            "re-appended lobes of principledthin (component_count 3 -> 6 -> 9)."),
        reproducer="validation/audit/repro_principled_components.py",
        source=("src/bsdfs/principledthin.cpp, initialize_lobes lines 195-215 vs sample lines "
                "343, 377, 394, 402; no ctx.is_enabled anywhere")),
    Finding(
        bsdf="hair", check=r"chi2 θ=84|pdf integral", configs=r"", verdict="defect",
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
            "101/4 and 0.65/0.79 at 201/16. Impact: for the integral of f L with L = wo.y^2 "
            "(light along the fibre), sample() is -2.1 % (brown) and -13.8 % (blonde) off at the "
            "silhouette and -0.1/-0.7 % at h = 0, while the fixed sampler matches uniform "
            "sampling of eval() within noise. A render of 40 blonde bsplinecurve fibres (path "
            "tracer, 256 spp) is 0.09 % darker, against 0.01 % seed-to-seed. The furnace is "
            "unaffected. pbrt-v3's HairBSDF::Sample_f initialises sinThetaIp = sinThetaI. Issue "
            "text: validation/audit/upstream/hair_pmax_sampling.md; impact: "
            "validation/audit/impact_hair_pmax_sampling.py."),
        reproducer="validation/audit/repro_hair_pmax_sampling.py",
        source=("src/bsdfs/hair.cpp, Hair::sample lines 264-272 (loop j < P_MAX leaves "
                "sin/cos_theta_ip = 0 for p == P_MAX) and 287-288 (sin_theta_o); pdf side lines "
                "323-325 uses the untilted si.wi")),
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
