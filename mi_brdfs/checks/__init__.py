"""
The validation library: checks that work on any Mitsuba BSDF (the package's, Mitsuba's built-ins
or a user's own Python plugin), given as a ``load_dict`` dict, an XML fragment, a command-line
string ``'roughconductor alpha=0.3'`` or a loaded ``mi.BSDF``. Each check returns a
:class:`CheckResult`; pytest (:mod:`mi_brdfs.testing`), the command line (``mi-brdfs check``,
``furnace``, ``plot``) and the validation campaign all call the same functions.

=========================  ========================================================================
check                      what it establishes
=========================  ========================================================================
``chi2_bsdf``              ``sample()`` draws directions with the density ``pdf()`` reports (JIT)
``check_consistency``      weight = eval/pdf, bs.pdf = pdf(bs.wo), eval_pdf = (eval, pdf), flags
``check_energy``           directional albedo E(θ) ≤ 1 at every incident angle
``check_albedo_agreement`` E(θ) from ``sample()`` = E(θ) from ``eval()`` (reference or quadrature)
``check_lobes``            ctx.component selects one lobe; the lobes add up to the whole (eval, E)
``check_pdf_integral``     ∫ pdf dω over the sphere = the fraction of samples that succeed
``check_reciprocity``      f(a, b) = f(b, a), and where it fails most
``check_positivity``       eval ≥ 0, pdf ≥ 0 everywhere on the sphere
``check_stability``        no NaN/Inf/negative at stress directions × parameter extremes
``check_furnace``          the white furnace render equals what E(θ) predicts, no NaN pixel
``check_gradients``        AD derivatives of eval, pdf, weights = finite differences (AD variants)
``check_equal``            two BSDFs agree pointwise (eval, pdf, sample): a plugin = a built-in
``check_ndf``              ∫ D cosθ dω = 1 (microfacet terms)
``check_weak_furnace``     Heitz's weak white furnace = 1 (microfacet D and G1)
=========================  ========================================================================
"""

from .albedo import (
                     AlbedoCurve,
                     albedo_curve,
                     albedo_eval,
                     albedo_quadrature,
                     albedo_sampled,
                     check_albedo_agreement,
                     check_energy,
)
from .battery import format_table, run_battery
from .consistency import check_consistency
from .furnace import FurnaceRender, check_furnace, furnace_render
from .gradients import Gradient, check_gradients, gradient_rows
from .lobes import check_lobes, check_pdf_integral
from .microfacet import (
                     check_ndf,
                     check_weak_furnace,
                     mitsuba_terms,
                     ndf_normalization,
                     package_terms,
                     weak_white_furnace,
)
from .pointwise import check_equal
from .precision import eval_precision
from .reciprocity import check_positivity, check_reciprocity, reciprocity
from .result import CheckResult
from .sampling import chi2_bsdf
from .stability import check_stability, parameter_grid, sweep_one

__all__ = [
    "CheckResult", "chi2_bsdf", "check_consistency", "check_energy", "check_albedo_agreement",
    "albedo_curve", "albedo_sampled", "albedo_eval", "albedo_quadrature", "AlbedoCurve",
    "check_reciprocity", "check_positivity", "reciprocity", "check_stability", "parameter_grid",
    "sweep_one", "check_furnace", "furnace_render", "FurnaceRender", "check_ndf",
    "check_gradients", "gradient_rows", "Gradient",
    "check_weak_furnace", "ndf_normalization", "weak_white_furnace", "mitsuba_terms",
    "package_terms",
    "run_battery", "format_table", "check_equal", "eval_precision", "check_lobes",
    "check_pdf_integral",
]
