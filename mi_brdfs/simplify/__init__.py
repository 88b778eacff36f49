"""
Simplify a scene's materials: for every BSDF, cheaper candidates that render the same image
within a tolerance, measured in the user's own scene, and the scene rewritten with the cheapest.

    from mi_brdfs.simplify import simplify
    result = simplify("scenes/showcase.xml", tolerance=0.01, output="simplified.xml")
    print(result.summary())

and ``mi-brdfs simplify SCENE.xml [--tolerance 0.01] [-o simplified.xml] [--report DIR]
[--quick] [--spp N] [-D name=value]``.

**Candidates** (:mod:`.candidates`). For each ``<bsdf>`` of the scene that is no wrapper (those
inside ``twosided``, ``blendbsdf``, ``mask``, ... are found too):

* switches of the plugins: ``cooktorrance`` with ``fresnel=schlick`` (Schlick 1994, "An
  Inexpensive BRDF Model for Physically-based Rendering", CGF 13(3)), the other ``distribution``
  (``beckmann``/``ggx``), the other ``sample_visible``, ``multiscatter=false`` (the energy
  compensation of Kulla & Conty 2017 left out: what it costs against what the scene shows of
  it); ``orennayar`` ``form=qualitative``;
* the weaker lobe of a two-lobe model left out (``phong``, ``ward``, ``cooktorrance`` with a
  diffuse base; weaker by directional albedo at 45°): a glossy-only model, or ``diffuse`` with
  the diffuse lobe's reflectance; ``ashikhmin``'s diffuse term where it is the weaker (its
  glossy lobe cannot be left out: F reaches 1 at grazing angles whatever Rs); ``lafortune``'s
  weakest term, its diffuse term or a lobe (weakest by the mean albedo at 15°, 45° and 75°, as
  an off-specular lobe reflects mostly towards grazing incidence and a retro-reflective one
  towards normal incidence);
* the built-in that computes the same model: ``lambert`` → ``diffuse``; reflecting
  ``cooktorrance`` → ``roughconductor`` (the same α, distribution, material or η/k: exact with
  ``shadowing=smith``, Smith's masking in place of the V-cavity's otherwise);
  ``cooktorrance transmission=true`` → ``roughdielectric``; and, a plugin computing the same,
  a normalized one-lobe ``lafortune`` whose lobe is Phong's mirror lobe (−Cx = −Cy = Cz) →
  ``phong`` (its normalized mirror lobe);
* cheaper models fitted with :func:`mi_brdfs.fit.fit`: ``diffuse`` (a fitted ``lambert``) for
  ``orennayar`` and for a ``phong``/``ward``/``ashikhmin``/``lafortune`` whose glossy lobes are
  the weaker, a Blinn-Phong ``phong`` for an isotropic ``cooktorrance``.

Built-ins (``diffuse``, ``roughconductor``, ...) get no candidates: they are listed as kept,
as are wrappers (their nested BSDFs, inline or by ``<ref>``, are listed apart), a material
whose ``type`` is a ``$default`` (a replacement measured for one plugin would be wrong for
another), and plugins of no package, each with its reason. Parameters may take any form
Mitsuba's XML allows (numbers, ``<rgb>``, ``<spectrum>``, textures, ``<ref>``s, ``$default``
values); a candidate that needs a value it cannot read (a lobe's albedo, a fit's target) is
left out, and said so. The materials of the files the scene ``<include>``s are simplified
too: such a file with a replaced material is written beside the output scene
(``OUTPUT-STEM.FILE``, every other byte kept), which includes it instead; a file included from
another folder that names files itself (whose relative names would resolve elsewhere) or by an
included file is left alone and named in the notes.

**What is measured, per candidate** (:mod:`.measure`). The scene is rendered with only that
material replaced (the rest of the XML byte for byte, :mod:`.scene`) at k seeds, as is the
original scene. With common random numbers (the same seed for both scenes: a JIT render draws
the same random numbers per pixel and sample, so paths that never meet the replaced material
are identical and their difference is exactly 0), the difference images D_s = C_s − R_s carry
only the material's effect and its own noise; with D̄ their mean and s² their sample variance
per pixel,

    bias² = mean(D̄² − s²/k) / mean(R̄)²,

an unbiased estimate of the squared relative RMSE between the converged candidate and the
converged original (s²/k estimates the variance of D̄; on common random numbers: Law & Kelton
2000, "Simulation Modeling and Analysis", 3rd ed., §11.2). Its standard error SE is estimated
from the same numbers, and the bounds are √(bias² ± 2·SE). k starts at 2 and doubles (4, 8,
16 = :data:`MAX_SEEDS`) while the bounds straddle the tolerance: the convergence is measured,
not assumed, and a candidate whose bound stays above the tolerance after 16 seeds is
"inconclusive", i.e. not accepted. The **noise** reported beside it is √mean(s²/k)/mean(R̄);
**FLIP** (Andersson et al. 2020, "FLIP: A Difference Evaluator for Alternating Images", HPG) is
the mean HDR-FLIP of R̄ against C̄, when ``flip-evaluator`` is installed.

The **variance** of a 1-spp image (relative to mean(R̄)²) is N times the per-pixel sample
variance of the k renders of N spp, its ratio to the original's measured at the same seeds.
The **cost per sample** is the time per spp of renders of the candidate interleaved with
renders of the original (R C C R R C ..., the median of the ratios, after a warm-up render that
holds the JIT compilation; see :mod:`mi_brdfs.timing`). As in
:mod:`mi_brdfs.benchmark.error_time`, the error of a render of t seconds is then
error² = bias² + V/t with V = variance × cost per spp, so the **time to reach the tolerance** τ
is

    T = V / (τ² − bias²)        (infinite when bias ≥ τ),

and the speed-up of a candidate is T(original)/T(candidate), with a standard error from the
repeat-to-repeat spread of the timing ratios (their sample standard deviation, from 3 repeats
or more: with fewer the error is unknown and no candidate counts as measurably faster) and of
the per-pixel variance differences.

**Choice** (:mod:`.choose`, :mod:`.pipeline`). The package's principle is to model only what
a scene requires, so by default (``objective="simplicity"``) a material is replaced by a
candidate with bias_hi ≤ τ that is **simpler** and **not measurably slower** (its speed-up not
below 1 by ``confidence`` standard errors, default 2); of several, the one with the least T.
Simpler, in this order: Mitsuba's built-in of the same model (compiled, no Python plugin), a
lobe fewer, a model of fewer lobes or parameters fitted to it, a feature left out (the energy
compensation, the exact Fresnel term for Schlick's, Oren-Nayar's full form); a switch that
swaps one feature for another (the distribution, the sampler) is not simpler
(:data:`.choose.SIMPLER_KINDS`, :data:`.choose.SIMPLER_SWITCHES`), and the report says which
reason made each choice. With ``objective="speed"`` only the candidate with the least T among
those whose speed-up exceeds 1 by ``confidence`` standard errors replaces the original. The
combined bias² is predicted as the sum of the chosen ones' (replacements whose bias² add up
beyond τ² are dropped, the largest first); then the **simplified scene** (each chosen
material's ``<bsdf>...</bsdf>`` text replaced, every other byte of the file kept) is measured
as one more candidate, at other seeds (101, 102, ...) and with its own timing: the
verification, with its measured bias and its predicted and measured speed-up, and whether the
two agree within 2 standard errors of their difference (the prediction's from its parts'
timing and variance errors), which the report says either way. Should its
bias_hi exceed τ, the replacement with the largest bias is dropped and the scene measured
again. The results, SIMPLIFY.md and the plot: :mod:`.report`.

**Cache.** Every measurement is stored (JSON; the original's renders and each candidate's
difference images D_s as compressed .npz, so that a rerun can add seeds), and every fit, under
a key of the scene file's content hash, the defines, the variant, the spp and timing settings,
and the candidate's text: in ``--report DIR/cache`` or ``~/.cache/mi_brdfs/simplify``
(``$XDG_CACHE_HOME``). The tolerance enters only the choice and the number of seeds, so a
rerun with another tolerance renders only where a bias's bounds straddle the new tolerance
and, where the choice changed, the simplified scene.

**Cost.** In ``llvm_ad_rgb`` a candidate costs one JIT compilation, 2 to 16 renders at N spp
and the timing renders, so the whole grows with the number of candidates and with the scene's
render time; ``--quick`` renders at a lower resolution with fewer spp, timing repeats and fit
steps, and a rerun from the cache renders little. Scalar variants render through
:func:`mi_brdfs.render.render` (processes for Python plugins), and are far slower; but there a
Python plugin costs several times its built-in, which JIT variants trace into the same kernel
at about the same cost.
"""

from .candidates import OURS, candidates_for
from .measure import CACHE_VERSION, MAX_SEEDS, default_cache_dir
from .pipeline import FIT_SIZES, QUICK_RES, REPEATS, SPP, TIMING_S, simplify
from .report import Candidate, MaterialResult, SimplifyResult, plot, write_report
from .scene import Material, element_text, scene_bsdfs, splice

__all__ = ["simplify", "SimplifyResult", "MaterialResult", "Candidate", "Material",
           "scene_bsdfs", "splice", "element_text", "candidates_for", "plot", "write_report"]
