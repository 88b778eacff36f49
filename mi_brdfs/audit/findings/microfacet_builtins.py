"""
Triage of Mitsuba's microfacet built-ins ``roughdielectric`` and ``roughconductor``.

The proofs are in ``validation/audit/``:

* ``repro_roughdielectric_widened_weight.py`` (exits 1 while the defect is present) and
  ``render_roughdielectric_widened_weight.py`` (its render impact);
* ``conditioning_microfacet_pdf.py``, which decomposes ``bs.pdf`` vs ``pdf(bs.wo)`` with a float64
  evaluation of the same pdf (Mitsuba's formulas, v3.9.1) into (a) the float32 arithmetic of
  ``sample()``, (b) that of ``pdf()``, and (c) the exact model's change between the direction that
  ``sample()`` meant (wo*, the float64 reflection/refraction about its float32 normal) and the
  float32 ``bs.wo`` it stored.

The "mitsuba chi2" failures of both plugins are triaged elsewhere: our own χ² passes at every
angle for every configuration of these plugins.
"""

from ..triage import Finding

_RD_SRC = ("src/bsdfs/roughdielectric.cpp (v3.9.1), RoughDielectric::sample: lines 261-271 "
           "(sample_distr = distr with alpha scaled by 1.2 - 0.2 sqrt|cos theta_i| when "
           "!m_sample_visible), 274-276 (m drawn from sample_distr), 349-353 (weight = "
           "G (wi.m) / (cos theta_i cos theta_m): D(m)/D'(m) missing); RoughDielectric::pdf "
           "lines 477-491 (widened, consistent with bs.pdf); introduced in commit fcb3786 (2018)")

_CONDITIONING = (
    "This is float32 conditioning, not a defect. At grazing incidence (cos θi ≈ 1e-3) the "
    "reflected wo is near grazing too, so wi + η·wo is short (≈ 2 cos θi). The half vector "
    "computed from the float32 bs.wo then moves with the ~1e-8 deviation of |wi| and |wo| from "
    "1, and D and the Jacobian follow it. "
    "validation/audit/conditioning_microfacet_pdf.py evaluates the same pdf in float64 at the "
    "same float32 directions. Each float32 value agrees with its float64 counterpart at its own "
    "inputs: (a) sample()'s arithmetic ≤ 4e-5 from outside and ≤ 6.3e-4 from inside; (b) "
    "pdf()'s ≤ 5.2e-5 and ≤ 3.2e-4. The whole mismatch is (c), the exact model's change "
    "between wo* (the direction "
    "sample() meant) and the float32 bs.wo. With wi, wo* and bs.wo renormalised in float64, the "
    "model's values agree to ≤ 1.6e-5 at the records' samples and ≤ 4e-4 over a stress set "
    "with cos θi down to 1e-4, where (c) reaches 94 %. The formulas are sensitive mainly to "
    "the lengths of the float32 vectors. Over seeds 0-9 every mismatch above "
    "1e-3 has cos θi ≤ 0.0071 (θi > 89.5°), and none exceeds 1.4 %. No render impact. "
    "What the check should do: a per-sample tolerance from the conditioning, measured with the "
    "BSDF itself. Perturb one coordinate of wi or wo at a time by an ABSOLUTE ±8·2⁻²⁴ (not "
    "relative to the coordinate, and without renormalising, because the lengths matter). That "
    "is 12 evaluations of eval_pdf per suspect sample. Take spread = max |Δ log pdf|, |Δ log "
    "eval/pdf| and tol = max(1e-3, 8·spread). Report how many samples were relaxed. The "
    "prototype /tmp/consistency_cond.py does this. On seeds 0-9 it passes every non-defective "
    "roughdielectric/roughconductor configuration, still flags the sample_visible=false weight "
    "defect (≈ 84 000 of 86 000 samples), and still flags an injected 0.5 % bs.pdf error in "
    "> 99 % of the samples. The check in the working tree (a relative 2⁻²² jitter, "
    "renormalised, factor 4) still false-rejects at seed 1: roughdielectric ggx αu=0.05 "
    "αv=0.3 gives 0.00103 > 0.001 with a measured conditioning of 7.7e-5, at wi = (−0.999, "
    "0.043, 0.004). The float64 decomposition gives (a) 8.5e-9, (b) 3.8e-7, (c) 1.03e-3 there.")

FINDINGS = [
    Finding(
        bsdf="roughdielectric", check=r"^consistency$", configs=r"sample_visible=false",
        verdict="defect",
        summary=(
            "With sample_visible=false, sample() draws microfacet normals from a widened "
            "distribution D' (α × (1.2 − 0.2√|cos θi|), Walter et al. 2007, 'Microfacet Models "
            "for Refraction through Rough Surfaces', EGSR, §5.3). bs.pdf and pdf() use D' "
            "consistently. The weight uses the simplified G·(wi·m)/(cos θi cos θm), which "
            "assumes normals drawn from the unwidened D(m) cos θm, so the factor D(m)/D'(m) is "
            "missing. Record: weight vs eval/pdf is off by up to 0.92 (Beckmann, 84 221 of "
            "86 509 samples) and 0.30 (GGX, 79 523 of 82 482). At θi = 60° the median error is "
            "0.070 (Beckmann) and 0.053 (GGX). Multiplying the weight by D(m)/D'(m) "
            "(mi.MicrofacetDistribution.eval with and without scale_alpha) gives eval/pdf to a "
            "median 2.4e-7. The weight mismatch repeats on seeds 0-9 (≈ 84 000 and 79 000 "
            "samples). Mitsuba 0.6 used the general "
            "D·G·(wi·m)/(p_m cos θi), which is correct. The simplification came with commit "
            "fcb3786 (2018) and is still on master. Mitsuba's own tests run only χ², which never "
            "sees weights. The record's secondary 'bs.pdf vs pdf(bs.wo) 0.00101' at "
            "cos θi = 0.0012 is float32 conditioning (float64 decomposition: (a) 1.3e-6, "
            "(b) 5e-8, (c) 1.01e-3), not part of the defect. Issue text: "
            "validation/audit/upstream/roughdielectric_widened_weight.md."),
        reproducer="validation/audit/repro_roughdielectric_widened_weight.py",
        source=_RD_SRC, issue="validation/audit/upstream/roughdielectric_widened_weight.md"),
    Finding(
        bsdf="roughdielectric", check=r"^(energy|albedo)$", configs=r"sample_visible=false",
        verdict="defect",
        summary=(
            "The missing D(m)/D'(m) in sample()'s weight with sample_visible=false (see the "
            "consistency finding) biases every sampled albedo except at normal incidence, where "
            "the widening factor is 1. Importance transport, α = 0.3, 400 000 samples: "
            "Beckmann E(87°) = 1.083 ± 0.002 and E(89°) = 1.134 ± 0.003 (energy is created), "
            "against 0.965 and 0.972 with sample_visible=true. GGX gives 0.925/0.926 against "
            "0.829/0.809. With the factor restored, the same samples give 0.965, 0.972, 0.829 "
            "and 0.809. That matches the records: the energy check's 1.131 at 89° (Beckmann), "
            "and the albedo check's sample() 1.083 vs eval() quadrature 0.967 (Beckmann) and "
            "0.926 vs 0.829 (GGX) at 87°. Render impact "
            "(validation/audit/render_roughdielectric_widened_weight.py, path tracer, constant "
            "environment, 4 seeds × 256 spp): a rough glass pane seen at ≈ 87° incidence renders "
            "+5.6 % (Beckmann: 0.603 vs 0.571) and +5.4 % (GGX: 0.473 vs 0.448), ± 0.0003. The "
            "silhouette ring of a rough glass sphere (incidence 72-82°) is +1.3 % and +1.9 %. "
            "The centre is unchanged."),
        reproducer="validation/audit/repro_roughdielectric_widened_weight.py",
        source=_RD_SRC, issue="validation/audit/upstream/roughdielectric_widened_weight.md"),
    Finding(
        bsdf="roughdielectric", check=r"^consistency$",
        configs=r"^(beckmann|ggx) (α=0\.05|α=0\.3|αu=0\.05 αv=0\.3)$",
        verdict="check-limitation",
        summary=(
            "bs.pdf vs pdf(bs.wo) (and weight vs eval/pdf, the same sample) differ by 0.00422 "
            "(Beckmann α=0.05, 2 of 99 661 samples, wi = (0.157, −0.988, 0.0018): bs.pdf "
            "1724.64, pdf 1731.94). Over seeds 0-9 of the same check, the mismatch exceeds 1e-3 "
            "in 0-15 "
            "samples per configuration, reaching 0.0069 (Beckmann α=0.05), 0.0076 (Beckmann "
            "αu=0.05 αv=0.3), 0.0025 (GGX α=0.05) and 0.0015 (Beckmann α=0.3), always at "
            "cos θi ≤ 0.0071. "
            "For the record's worst sample, float64 gives bs.pdf vs p64(wo*) 1.9e-7, pdf(wo) vs "
            "p64(wo) 7.6e-8, and p64(wo*) vs p64(wo) 4.22e-3, i.e. all of the mismatch; with "
            "renormalised inputs the last is 1.5e-5. " + _CONDITIONING),
        reproducer=None,
        source=None),
    Finding(
        bsdf="roughconductor", check=r"^consistency$",
        configs=r"^(beckmann|ggx) α=0\.3 sample_visible=false$",
        verdict="check-limitation",
        summary=(
            "Two limitations of the check, no defect. "
            "(1) The 7 985 (Beckmann) / 11 416 (GGX) 'negative pdf' samples all have weight 0. "
            "The D·cos θm sampler draws back-facing normals (wi·m < 0). sample() then sets "
            "bs.pdf = D(m) cos θm / (4 wo·m) with wo·m = wi·m < 0 and masks the weight to 0 "
            "(roughconductor.cpp v3.9.1, lines 250, 259, 263-269). In 200 000 samples every "
            "negative bs.pdf is such a failed, back-facing sample (16 161 Beckmann, 22 951 GGX). "
            "Over seeds 0-9 of the check, no sample with weight > 0 has a negative, zero or NaN "
            "bs.pdf. The API "
            "leaves bs.pdf of a failed sample undefined, and the path integrator multiplies "
            "the throughput by the zero weight and stops the path (path.cpp lines 305, "
            "330-331). The check must judge finiteness and sign only where weight ≠ 0; the "
            "working tree already does. "
            "(2) 'bs.pdf vs pdf(bs.wo) 0.00166' (Beckmann, 2 of 83 826 samples, "
            "wi = (−0.829, 0.560, 0.0015); over seeds 0-9 up to 0.0071 for Beckmann and 0.0136 for "
            "GGX, always at cos θi ≤ 0.0059) is float32 conditioning. Float64 gives bs.pdf vs "
            "p64(wo*) 2.8e-6, pdf(wo) vs p64(wo) 3.3e-6, and p64(wo*) vs p64(wo) 1.66e-3; with "
            "renormalised inputs the last is 1.0e-5. " + _CONDITIONING),
        reproducer=None,
        source="src/bsdfs/roughconductor.cpp (v3.9.1), RoughConductor::sample lines 248-269 "
               "(bs.pdf /= 4 dot(wo, m) also for rejected back-facing m)"),
]
