"""
Campaign section: how well do the lecture models describe Mitsuba's built-ins? ``phong``,
``ward``, ``cooktorrance``, ``ashikhmin`` and ``lafortune`` fitted (:func:`mi_brdfs.fit.fit`) to
``roughconductor`` (gold, α = 0.2), ``roughplastic`` (its defaults) and ``principled``
(roughness 0.4), with the residuals, the albedo errors, the models ranked per target, set
beside the ranking of Ngan, Durand & Matusik (2005, "Experimental Analysis of BRDF Models",
EGSR), and the lobes and albedo curves side by side.

The models start from the lecture's reading of each material (:mod:`mi_brdfs.fit.models`,
which ``mi-brdfs fit --models all`` shares): for the metal Cook-Torrance takes the target's gold,
since free η and k together made the fit diverge (NaN from every start); Lafortune et al.'s
(1997) three lobes (a second forward lobe and a retro-reflective one: ten free parameters) took
over a minute per fit of roughplastic and ended with two lobes at ρs = 1, the bound: one lobe.
"""

from __future__ import annotations

import numpy as np

from ..fit import ALBEDO_THETAS, fit, spec_text
from ..fit.models import LECTURE, STYLES, models_for
from ..plots import cube_root_lobe, lobe_values, pyplot, save_figure
from .core import Context, Row, Section, image, md_table

#: (label, target spec).
TARGETS = [
    ("roughconductor (Au, α = 0.2)", "roughconductor material=Au alpha=0.2"),
    ("roughplastic (defaults)", "roughplastic"),
    ("principled (roughness 0.4)", "principled roughness=0.4"),
]

#: Pairs with θi or θo at least this (degrees) are the grazing ones of :func:`grazing_residuals`.
GRAZING = 70.0

#: The sanity check of the method: Cook-Torrance with Smith's masking is roughconductor's model,
#: so the fit must find α = 0.2 and ks = 1 from a start elsewhere.
SANITY = ("cooktorrance material=Au shadowing=smith alpha=0.1 specular_reflectance=0.5",
          "alpha,specular_reflectance")

#: Incident angles of the lobe panels.
LOBE_THETAS = (30.0, 75.0)


def _sizes(ctx: Context) -> dict:
    if ctx.quick:
        return {"pairs": 1024, "steps": 40, "thetas_deg": (0.0, 60.0, 89.0)}
    return {"pairs": 16384, "steps": 800, "thetas_deg": ALBEDO_THETAS}


def figure(ctx: Context, fits: dict) -> str:
    """One row per target: (f·cosθo)^(1/3) in the plane of incidence at two incident angles,
    and E(θ), the target and the five fits."""
    plt = pyplot()
    rows = len(TARGETS)
    fig = plt.figure(figsize=(13.0, 3.7 * rows))
    styles = STYLES
    for i, (label, target) in enumerate(TARGETS):
        results = fits[label]
        for j, theta in enumerate(LOBE_THETAS):
            ax = fig.add_subplot(rows, 3, 3 * i + j + 1, projection="polar")
            curves = [(*lobe_values(target, theta), "k-", dict(lw=1.8, label="target"))]
            curves += [(*lobe_values(result.spec, theta), styles[name][1],
                        dict(color=styles[name][0], lw=1.4, label=name))
                       for name, result in results.items()]
            cube_root_lobe(ax, curves, f"{label}: θi = {theta:g}°")
            if j == 0:
                ax.legend(loc="lower left", fontsize=7)
        ax = fig.add_subplot(rows, 3, 3 * i + 3)
        first = next(iter(results.values()))
        ax.plot(first.thetas_deg, first.albedo_target.mean(axis=1), "k-o", ms=3, lw=1.8,
                label="target")
        for name, result in results.items():
            color, ls = styles[name]
            ax.plot(result.thetas_deg, result.albedo_fit.mean(axis=1), ls, marker="s", ms=3,
                    color=color, label=f"{name} (max |ΔE| {result.albedo_error:.3f})")
        ax.set_xlim(0, 90)
        ax.set_xlabel("incident angle θ (degrees)", fontsize=8)
        ax.set_ylabel("albedo E(θ), mean of RGB", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        ax.set_title(f"{label}: directional albedo", fontsize=9)
    fig.suptitle("Lecture models fitted to Mitsuba's built-ins: lobes as (f·cosθo)^(1/3) in the "
                 "plane of incidence, and E(θ)", fontsize=10)
    fig.subplots_adjust(hspace=0.45, wspace=0.3)
    return save_figure(fig, ctx.figure("fits_builtins.png"))


def _fit_all(ctx: Context, sizes: dict, s: Section) -> tuple[dict, list]:
    """({target label: {model: FitResult}}, the table's rows): every model fitted to every
    target; their residuals and albedo errors in ``s.values``."""
    fits, table = {}, []
    for label, target in TARGETS:
        fits[label] = {}
        for name, model, free in [m for m in models_for(target) if m[0] in LECTURE]:
            result = fit(target, model, free, **sizes)
            fits[label][name] = result
            table.append((label, f"`{spec_text(result.model)}`", free or "all",
                          f"`{result.command_line()}`", f"{result.residual:.3g}",
                          f"{result.residual_projected:.3g}",
                          f"{result.albedo_error:.3f} (θ = {result.albedo_theta:g}°)",
                          f"{result.seconds:.1f}"))
            s.values[f"fit {name} to {target}: residual"] = f"{result.residual_projected:.3g}"
            s.values[f"fit {name} to {target}: albedo error"] = f"{result.albedo_error:.3f}"
    return fits, table


def grazing_residuals(target: str, results: dict, pairs: int) -> dict:
    """
    {model: ‖f_fit − f_target‖/‖f_target‖ of f·cosθi·cosθo over the grazing pairs}: the fit's
    own direction pairs (seed 0) with θi or θo ≥ :data:`GRAZING`, for each fitted spec of
    ``results`` ({model: FitResult}); pairs where the target is not finite are left out.
    """
    from ..bsdfspec import load_bsdf
    from ..checks import batch
    from ..fit import direction_pairs

    wi, wo = direction_pairs(pairs, 0)
    cos = np.cos(np.radians(GRAZING))
    keep = (wi[:, 2] <= cos) | (wo[:, 2] <= cos)
    wi, wo = wi[keep], wo[keep]

    def projected(spec):
        value = batch.evaluate(load_bsdf(spec), wi, wo).value
        return np.broadcast_to(value, (len(wi), 3)) * wi[:, 2:3]

    ref = projected(target)
    finite = np.all(np.isfinite(ref), axis=1)
    norm = np.linalg.norm(ref[finite])
    return {name: float(np.linalg.norm((projected(r.spec) - ref)[finite]) / norm)
            for name, r in results.items()}


def ranking(values: dict) -> list:
    """The models of ``values`` ({model: error}), least error first."""
    return sorted(values, key=values.get)


def _ranked(errors: dict, digits: str) -> str:
    """"target: a (e) < b (e) < ...; ..." of {target label: {model: error}}."""
    return "; ".join(f"{label}: " + " < ".join(f"{n} ({e[n]:{digits}})" for n in ranking(e))
                     for label, e in errors.items())


def _claims(ctx: Context, s: Section, fits: dict) -> None:
    """The judged rows: Cook-Torrance follows the albedo best, no model the coated one (a
    quick run's fits are too short to judge them: 40 steps)."""
    names = ", ".join(LECTURE)
    for label, _ in TARGETS:
        errors = {name: r.albedo_error for name, r in fits[label].items()}
        best = min(errors, key=errors.get)
        s.rows.append(Row(f"fits: {label}", f"cooktorrance has the least max |ΔE(θ)| of "
                          f"{names}", ", ".join(f"{n} {e:.3f}" for n, e in errors.items()),
                          "least: cooktorrance", best == "cooktorrance", judged=not ctx.quick))
    plastic = fits[TARGETS[1][0]]
    worst = min(r.albedo_error for r in plastic.values())
    s.rows.append(Row("fits: roughplastic (defaults)", "no lecture model follows the coated "
                      "albedo: every max |ΔE(θ)| ≥ 0.1", f"smallest {worst:.3f}", "≥ 0.1",
                      worst >= 0.1, judged=not ctx.quick))


def _sanity(ctx: Context, s: Section, sizes: dict) -> float:
    """The method itself: the model of the target, from elsewhere, must land on it; its α."""
    sanity = fit(TARGETS[0][1], SANITY[0], SANITY[1], **sizes)
    alpha = float(sanity.parameters["alpha"])
    ks = np.atleast_1d(np.asarray(sanity.parameters["specular_reflectance"], dtype=float))
    ok = abs(alpha / 0.2 - 1) <= 0.01 and np.all(np.abs(ks - 1) <= 0.01) and \
        sanity.residual <= 1e-3
    s.rows.append(Row("fits: method", "cooktorrance (Smith, Au) fitted to roughconductor (Au, "
                      "α = 0.2) from α = 0.1, ks = 0.5", f"α = {alpha:.4f}, ks = "
                      f"{', '.join(f'{k:.4f}' for k in ks)}, residual {sanity.residual:.2g}",
                      "α, ks within 1 %, residual ≤ 1e-3", bool(ok), judged=not ctx.quick))
    return alpha


def section(ctx: Context) -> Section:
    s = Section("How well do the lecture models describe Mitsuba's built-ins")
    sizes = _sizes(ctx)
    fits, table = _fit_all(ctx, sizes, s)
    _claims(ctx, s, fits)
    alpha = _sanity(ctx, s, sizes)
    residuals = {label: {n: r.residual_projected for n, r in fits[label].items()}
                 for label, _ in TARGETS}
    grazing = {label: grazing_residuals(target, fits[label], sizes["pairs"])
               for label, target in TARGETS}
    albedo = {label: {n: r.albedo_error for n, r in fits[label].items()} for label, _ in TARGETS}
    for label, target in TARGETS:
        s.values[f"ranked by residual: {target}"] = " < ".join(ranking(residuals[label]))
        for name, value in grazing[label].items():
            s.values[f"fit {name} to {target}: grazing residual"] = f"{value:.3g}"
    fig = figure(ctx, fits)
    s.markdown = "\n".join([
        _method_text(sizes), "",
        md_table(["target", "model (start)", "free", "fitted", "residual f·cosθo",
                  "residual f·cosθi·cosθo", "max |ΔE(θ)|", "fit (s)"], table), "",
        "Ranked by the residual of f·cosθi·cosθo, the quantity fitted: "
        + _ranked(residuals, ".3g") + ".", "",
        f"Ranked by that residual over the grazing pairs alone (θi or θo ≥ {GRAZING:g}°): "
        + _ranked(grazing, ".3g") + ".", "",
        "Ranked by the albedo error: " + _ranked(albedo, ".3f") + ".", "",
        ngan_comparison(residuals, grazing), "",
        _albedo_text(fits, alpha), "",
        image(ctx, fig, "lecture models fitted to Mitsuba's built-ins: lobes and albedo")])
    return s


def _method_text(sizes: dict) -> str:
    return (
        "Each lecture model is fitted to each built-in with `mi_brdfs.fit.fit` (its "
        "f·cosθo matched by Adam over "
        f"{sizes['pairs']} direction pairs in Rusinkiewicz's half/difference angles, "
        f"{sizes['steps']} steps, under the cube root of f·cosθi·cosθo, after Ngan et al. 2005 "
        "and Forés et al. 2012; see the module's docstring). Phong is the halfway "
        "(Blinn-Phong) lobe and Ward the balanced form, each over a Lambertian base with every "
        "parameter free; Cook-Torrance keeps the gold of the metal (α and the specular factor "
        "free) and models the plastics as Cook & Torrance (1982) do: the Fresnel term of a "
        "dielectric of free η over a Lambertian base. Ashikhmin-Shirley (2000) is isotropic "
        "over its own diffuse term, every parameter free (the exponent, Rs and Rd). Lafortune "
        "(1997) is one lobe over a Lambertian term, from Phong's mirror lobe C = (−1, −1, 1), "
        "with Cz free beside the exponent, ρs and ρd (the normalized lobe depends on C/max|C| "
        "only, so Cx = Cy = −1 stay; |Cz| < 1 leans the lobe towards grazing angles). The "
        "**residual** is ‖f_fit − f_target‖/‖f_target‖ of f·cosθo over the pairs (ruled by "
        "the largest values: grazing pairs, where the V-cavity and the Smith masking differ "
        "most), then the same of f·cosθi·cosθo, the quantity fitted; the **albedo error** is "
        "max over θ and RGB of |E_fit(θ) − E_target(θ)| by quadrature.")


#: The models Ngan, Durand & Matusik (2005) found with the lowest errors (He et al.'s model,
#: with them, is not fitted here), and two they found worse.
NGAN_BEST, NGAN_WORSE = ("ashikhmin", "cooktorrance"), ("ward", "phong")


def _where(agree: list, differ: list) -> str:
    """"agrees on A (...), B (...); not on C (...)" (or "on every target", "on none")."""
    if not differ:
        return "agrees on every target: " + "; ".join(agree)
    if not agree:
        return "agrees on none: " + "; ".join(differ)
    return "agrees on " + "; ".join(agree) + "; not on " + "; ".join(differ)


def _ranks(rank: dict, names) -> str:
    return ", ".join(f"{n} {rank[n]}" for n in names)


def ngan_comparison(residuals: dict, grazing: dict) -> str:
    """
    What of Ngan et al.'s (2005) ranking the fits here agree with, per target, from the
    residuals ({target label: {model: residual of f·cosθi·cosθo}}) and their grazing part.
    """
    best, worse, above, share = ([], []), ([], []), ([], []), ([], [])
    for label, errors in residuals.items():
        order = ranking(errors)
        rank = {n: order.index(n) + 1 for n in order}
        top = set(order[:2]) == set(NGAN_BEST)
        best[0 if top else 1].append(
            f"{label} (ranks of {len(order)}: {_ranks(rank, NGAN_BEST)}"
            + (")" if top else f"; {order[0]} and {order[1]} first)"))
        behind = min(rank[n] for n in NGAN_WORSE) > max(rank[n] for n in NGAN_BEST)
        worse[0 if behind else 1].append(f"{label} ({_ranks(rank, NGAN_WORSE)})")
        g = grazing[label]
        above[0 if g["lafortune"] > max(g[n] for n in NGAN_BEST) else 1].append(
            f"{label} ({', '.join(f'{n} {g[n]:.3g}' for n in ('lafortune', *NGAN_BEST))})")
        ratio = {n: g[n] / errors[n] for n in ("lafortune", *NGAN_BEST)}
        share[0 if ratio["lafortune"] > max(ratio[n] for n in NGAN_BEST) else 1].append(
            f"{label} ({', '.join(f'{n} {ratio[n]:.2f}×' for n in ratio)})")
    return "\n".join([
        "Ngan, Durand & Matusik (2005, \"Experimental Analysis of BRDF Models\", EGSR) fitted "
        "models to the measured materials of the MERL database under an L2 metric of the "
        "cosine-weighted BRDF and found Ashikhmin-Shirley and Cook-Torrance (with He et al.'s "
        "model, not fitted here) with the lowest errors, Ward and Blinn-Phong worse, and "
        "Lafortune's lobe worse at grazing angles. The fits above, by the residual of "
        "f·cosθi·cosθo:", "",
        f"* Ashikhmin-Shirley and Cook-Torrance the two best: {_where(*best)}.",
        f"* Ward and Blinn-Phong behind both of them: {_where(*worse)}.",
        "* Lafortune worse than those two over the grazing pairs (θi or θo ≥ "
        f"{GRAZING:g}°): {_where(*above)}.",
        "* Lafortune worse at grazing angles than elsewhere, more so than those two (its "
        "residual over the grazing pairs divided by that over all pairs, against theirs): "
        f"{_where(*share)}.", "",
        "The targets are not Ngan et al.'s: they are microfacet models, not measurements "
        "(roughconductor is Cook-Torrance's own model with Smith's masking, a head start for "
        "Cook-Torrance), without the measurement noise, retro-reflection or subsurface "
        "scattering of real materials, and the metric here is the cube root of f·cosθi·cosθo, "
        "not their L2 of the cosine-weighted BRDF."])


def _albedo_text(fits: dict, alpha: float) -> str:
    """Why the albedo curves part, with the fitted values they rest on."""
    falls = []
    for label, results in fits.items():
        r = results["ashikhmin"]
        falls.append(f"{label}: E({r.thetas_deg[-1]:g}°) = {r.albedo_fit[-1].mean():.3f} "
                     f"against {r.albedo_target[-1].mean():.3f}")
    cz = ", ".join(f"{label}: {results['lafortune'].parameters['cz_0']:.3g}"
                   for label, results in fits.items())
    return (
        "Cook-Torrance and Ashikhmin-Shirley (Schlick's) have a Fresnel term, Lafortune's "
        f"lobe can lean towards grazing angles (fitted Cz: {cz}), Phong and Ward have "
        "neither, so they cannot follow the targets' albedo rising towards grazing incidence. "
        "Ashikhmin-Shirley's albedo falls there, Fresnel term and all: its lobe is a density "
        "of half vectors, and what it reflects below the horizon is lost (its fitted albedo "
        "at the largest angle, mean "
        f"of RGB: {'; '.join(falls)}). None of the five couples its diffuse base to the "
        "interface above it as roughplastic and principled do (they weigh the base by the "
        "light the coating transmits, 1 − F; Ashikhmin-Shirley's diffuse term has a fixed "
        "form of it), which is where even Cook-Torrance's fit of the plastics parts from the "
        "target. The fit of Cook-Torrance with Smith's masking, roughconductor's own model, "
        f"lands on its α and ks from a start elsewhere (α = {alpha:.4f}): the differences "
        "above are the models', not the fit's.")


__all__ = ["section", "TARGETS", "models_for", "ranking", "grazing_residuals", "ngan_comparison"]
