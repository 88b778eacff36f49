"""
Triage of ``plastic`` and ``roughplastic``.

``roughplastic``: every failure (χ², Mitsuba's χ² harness, positivity, stability, in all three
configurations) comes from one defect of Mitsuba 3.9.1. ``RoughPlastic::pdf`` and
``RoughPlastic::eval_pdf`` compute the hemisphere mask ``active`` but return their pdf without
applying it. In JIT variants they therefore return (a) a nonzero density for ``wo`` below the
horizon and (b) NaN at ``cos θi = 0``. Reproducer:
``validation/audit/repro_roughplastic_pdf_mask.py``. Render impact:
``validation/audit/impact_roughplastic_pdf_mask.py``. Issue text:
``validation/audit/upstream/roughplastic_pdf_mask.md``.

Its gradients in ``alpha`` and ``eta`` miss the diffuse term's part: the tables of that term
are built from scalars taken from both (``validation/audit/repro_roughplastic_gradients.py``).

``plastic``: its only failures are Mitsuba's χ² harness on the default and nonlinear
configurations. They come from the Dirac lobe and are triaged elsewhere, so there is no entry
here. The harness's "PDF sum" equals the probability that the smooth lobe is selected (the
Fresnel-based selection probability, to the harness's precision). Our χ² passes on the smooth
lobe.
"""

from ..triage import Finding

_SOURCE = ("src/bsdfs/roughplastic.cpp (v3.9.1): RoughPlastic::pdf lines 381-423 (mask computed "
           "at 391; t_i gathered under that mask at 396-397; result returned unmasked at 422) and "
           "RoughPlastic::eval_pdf lines 425-502 (pdf returned unmasked at 501); compare "
           "roughconductor.cpp lines 426 and 517 and plastic.cpp line 322, which return "
           "dr::select(active, pdf, 0.f)")
_REPRO = "validation/audit/repro_roughplastic_pdf_mask.py"
_ISSUE = "validation/audit/upstream/roughplastic_pdf_mask.md"

FINDINGS = [
    Finding(
        bsdf="roughplastic", check=r"chi2|pdf integral", configs="", verdict="defect",
        summary=(
            "Our χ² and Mitsuba's harness reject or refuse roughplastic. GGX α=0.5 at all three "
            "angles: 'PDF integrates to a value greater than 1.0: 1.178' at θi=0° and 1.151 at "
            "45°, and p=0 at 84.26°. Beckmann α=0.1 (default) at 84.26°: PDF sum 1.017 in ours "
            "and 1.241 in Mitsuba's. Beckmann α=0.3 nonlinear at 45° and 84.26°. The cause is "
            "that RoughPlastic::pdf() returns a nonzero density for wo below the horizon. It "
            "computes active = cosθi>0 && cosθo>0 but never applies it to the result, and the "
            "early 'return 0' only fires when no lane is active (scalar variants). Worse, t_i "
            "is gathered under that mask: it reads 0 below the horizon, so prob_specular "
            "becomes 1 there. So below the horizon pdf() returns the whole visible-normal "
            "density D·G1/(4cosθi), not weighted by the lobe's selection probability. For GGX "
            "α=0.5 at normal incidence, ∫pdf = 1.178, split 0.978 above the horizon and 0.200 "
            "below. The fraction of samples with weight>0 is 0.978. The specular selection "
            "probability is 0.110, and 20% of specular samples fail below the horizon, so "
            "failed samples account for only 0.022 of probability there, against the 0.200 "
            "that pdf() reports. Above the horizon pdf() matches sample(). The diffuse term, "
            "the m_external_transmittance table, the specular selection weight and the "
            "nonlinear switch (which only changes eval()) are consistent between sample() and "
            "pdf(). Proof that the mask is the whole story: our adapter with pdf() masked to "
            "cosθo>0 passes every configuration at every angle for seeds 0-3 (p 0.12-0.96). "
            "So does Mitsuba's harness at its default resolution where it failed: GGX α=0.5 at "
            "0°, 45° and 84.26°, and Beckmann α=0.3 at 45° (seeds 0-2). The sample_visible="
            "false branch has the same bug: GGX α=0.5 PDF sum 1.178 at 0°; masked, it passes at "
            "all three angles. Not a check limitation. The excess is 20% of probability, far "
            "beyond float32 conditioning, and pdf() is deterministic, so no seed changes it. "
            "The BSDF has no Dirac lobe, no polarization, no geometry or uv dependence, and "
            "pdf() ignores the transport mode. The same pdf() returns 0 in scalar_rgb, and "
            "roughconductor returns 0 at the same directions. Mitsuba's own "
            "test02_chi2_rough configuration is rejected at wi=45° (PDF sum 1.0045); its tests "
            "only run at normal incidence. Render impact: none in the shipped integrators, "
            "because the excess density only meets eval()=0 and mis_weight discards non-finite "
            "weights. A path-traced GGX α=0.5 plane, built-in vs masked pdf with the same "
            "seed, differs by <= 5.1e-7, no more than the built-in's own run-to-run 5.1e-7 (mean "
            "0.183318 for both) "
            "(impact_roughplastic_pdf_mask.py). It matters to code that uses pdf() directly and "
            "to χ² tests. Remaining check issue: after the fix, Mitsuba's harness at its "
            "default res=101/ires=4 still rejects the α=0.1 lobe at 84.26° (PDF sum 1.054, "
            "under-resolved). At res 301/ires 32, which our check chooses, it passes, p "
            "0.65-0.96."),
        reproducer=_REPRO, source=_SOURCE, issue=_ISSUE),
    Finding(
        bsdf="roughplastic", check=r"^(positivity|stability)$", configs="", verdict="defect",
        summary=(
            "All three configurations fail positivity (9 non-finite of 200081) and stability "
            "(18 bad values). All of them are pdf() and eval_pdf().pdf = NaN at the 9 stress "
            "pairs with wi=(1,0,0), cosθi=0 exactly. The cause is the same missing final "
            "dr::select(active, result, 0) as in the χ² finding: the lane is inactive "
            "(cosθi>0 is false) but still computes D·G1/(4·cosθi) = 0/0. It is not a "
            "domain limitation of the check. The BSDF's own code treats cosθi<=0 explicitly "
            "and means to return 0. scalar_rgb roughplastic returns 0 there. In llvm_ad_rgb, "
            "roughconductor, plastic, diffuse, roughdielectric and principled all return pdf=0 "
            "at these pairs, and roughplastic's eval() is 0 there too. Mitsuba's path tracer "
            "does hand the BSDF cosθi=0 exactly: with shading normals perpendicular to the "
            "rays (a quad with vertex normals (1,0,0) seen by an orthographic camera along -z), "
            "si.wi = (0,1,0) and eval_pdf returns (0, NaN). The same case also shows the "
            "render impact is none: 0 NaN pixels, because the NaN pdf only meets eval()=0 and "
            "path's mis_weight replaces non-finite weights by 0 (path.cpp lines 359-364). "
            "sample() masks its weight, so failed samples at cosθi<=0 carry bs.pdf=NaN, which "
            "the contract allows. The same fix removes the NaN. The reproducer's part [C] "
            "exits 1 on it."),
        reproducer=_REPRO, source=_SOURCE, issue=_ISSUE),
    Finding(
        bsdf="roughplastic", check=r"gradients", configs="", verdict="defect",
        summary=(
            "The derivatives in alpha and eta, both marked differentiable by traverse(), miss "
            "the diffuse term's dependence on them in every configuration: eval, pdf and the "
            "sample weights disagree with central differences by 2 to 600 times the check's "
            "tolerance (pdf in eta reads as detached). parameters_changed() builds the diffuse "
            "term's Fresnel transmittance tables, m_external_transmittance and "
            "m_internal_reflectance, from dr::slice(m_eta) and dr::slice(m_alpha): scalars "
            "without a derivative. The reproducer gives, for GGX alpha=0.5 at one pair where "
            "the diffuse term dominates, d eval/d alpha -0.0117 by AD against -0.0684 by "
            "differences, d eval/d eta -0.0461 against -0.0250. Not a check limitation: the "
            "same check passes on roughconductor, roughdielectric, plastic and principled, "
            "and on the package's plugins with their own tables (cooktorrance's compensation, "
            "whose table lookups carry their slope in eta)."),
        reproducer="validation/audit/repro_roughplastic_gradients.py",
        source=("src/bsdfs/roughplastic.cpp (v3.9.1): traverse lines 210-211 mark alpha and "
                "eta differentiable; parameters_changed line 235 takes dr::slice of both for "
                "the tables gathered at lines 275, 354-356 and 396"),
        issue="validation/audit/upstream/roughplastic_gradients.md"),
]
