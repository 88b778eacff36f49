"""
Every lecture model fitted to one material, as Ngan, Durand & Matusik (2005, "Experimental
Analysis of BRDF Models", EGSR) fit seven models to MERL's materials: ``mi-brdfs fit TARGET
--models all`` fits ``phong``, ``ward``, ``cooktorrance``, ``ashikhmin``, ``lafortune`` and
``he`` to TARGET (measured data or any BSDF) under one metric, scores every fit under every metric of
:data:`~mi_brdfs.fit.optimise.METRICS` on the same pairs, ranks the models per metric, and
draws the lobes in the plane of incidence at four incident angles (data and each fit) and a row
of spheres rendered with the target and each fit.

The models start from the lecture's reading of a material: Phong's halfway (Blinn-Phong) lobe
and Ward's balanced lobe over a Lambertian base, every continuous parameter free;
Cook-Torrance (V-cavity masking, exact Fresnel) with the target's metal for a
``roughconductor`` that names its material (α and the specular factor free) and, for any other target, as Cook & Torrance (1982,
"A Reflectance Model for Computer Graphics", ACM TOG 1(1)) render a plastic: a specular lobe
with the Fresnel term of a dielectric of free η (k = 0) over a Lambertian base of free albedo;
Ashikhmin & Shirley (2000) isotropic over its own diffuse term; Lafortune et al. (1997) one
lobe over a Lambertian term, starting as Phong's mirror lobe, C = (−1, −1, 1), with Cz, the
exponent, ρs and ρd free (with ``normalize`` the lobe depends on C/max|C| only); He et al.
(1991) as a dielectric of free η over its uniform diffuse term, σ0, τ (in log scale), the
specular factor (within [0, 1]) and the diffuse albedo free.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .optimise import METRICS, _target_values, objective_np
from .spec import spec_text

#: Model starts: a plugin with its start values, and the free parameters (None: all).
PHONG = ("phong lobe=halfway diffuse_reflectance=0.2 specular_reflectance=0.5", None)
WARD = ("ward diffuse_reflectance=0.2 specular_reflectance=0.5", None)
CT_METAL = ("cooktorrance material=Au", "alpha,specular_reflectance")
CT_PLASTIC = ("cooktorrance eta=1.5 k=0 diffuse_reflectance=0.5",
              "alpha,eta,specular_reflectance,diffuse_reflectance")
ASHIKHMIN = ("ashikhmin diffuse_reflectance=0.2 specular_reflectance=0.5", None)
LAFORTUNE = ("lafortune diffuse_reflectance=0.2 specular_reflectance_0=0.5",
             "cz_0,exponent_0,specular_reflectance_0,diffuse_reflectance")
HE = ("he sigma0=0.1 tau=3 eta=1.5 diffuse_reflectance=0.2",
      "sigma0,tau,eta,specular_reflectance,diffuse_reflectance")

#: The fitted models, in the order of the tables, with their colour and line in the figures.
STYLES = {"phong": ("C0", "--"), "ward": ("C1", "-."), "cooktorrance": ("C3", ":"),
          "ashikhmin": ("C2", "-"), "lafortune": ("C4", "--"), "he": ("C5", "-.")}
#: The five phenomenological lecture models (the validation campaign's fits compare these).
LECTURE = ("phong", "ward", "cooktorrance", "ashikhmin", "lafortune")

#: Incident angles of the lobe plots (degrees).
LOBE_THETAS = (0.0, 30.0, 60.0, 80.0)


def models_for(target) -> list:
    """(name, model start, free) of the six models for a target spec: Cook-Torrance as a metal
    of the target's material for a ``roughconductor`` that names one, else as a plastic."""
    material = _conductor_material(target)
    ct = (f"cooktorrance material={material}", CT_METAL[1]) if material else CT_PLASTIC
    return [("phong", *PHONG), ("ward", *WARD), ("cooktorrance", *ct),
            ("ashikhmin", *ASHIKHMIN), ("lafortune", *LAFORTUNE), ("he", *HE)]


def _conductor_material(target):
    """The ``material`` a ``roughconductor`` target names (a dict or ``'type key=value'``
    text), else None."""
    if isinstance(target, str) and not target.lstrip().startswith("<"):
        words = target.split()
        target = {"type": words[0] if words else "",
                  **dict(w.split("=", 1) for w in words[1:] if "=" in w)}
    if isinstance(target, dict) and target.get("type") == "roughconductor":
        return target.get("material")
    return None


def chosen(names: str) -> list:
    """The models of ``--models``: ``all`` or comma-separated names of :data:`STYLES` (each
    once); one line for a name that is none, or for none at all (``--models ''``)."""
    from ..errors import MiBrdfsError

    allowed = f"give 'all' or names among {', '.join(STYLES)}, comma-separated"
    picked = list(STYLES) if names.strip() == "all" else \
        list(dict.fromkeys(n.strip() for n in names.split(",") if n.strip()))
    if not picked:
        raise MiBrdfsError(f"--models {names!r} names no model: {allowed}")
    unknown = [n for n in picked if n not in STYLES]
    if unknown:
        raise MiBrdfsError(f"--models {names}: {', '.join(unknown)} is not a lecture model; "
                           f"{allowed}")
    return picked


def score(target, fitted, pairs: int, seed: int) -> dict:
    """{metric: objective} of the fitted spec ``fitted`` at the pairs a fit to ``target`` with
    ``pairs`` and ``seed`` uses (the same pairs for every model)."""
    from ..bsdfspec import load_bsdf
    from ..checks import batch

    wi, wo, values = _target_values(target, load_bsdf(target), pairs, seed, [])
    e = np.broadcast_to(batch.evaluate(load_bsdf(fitted), wi, wo).value, values.shape)
    return {m: objective_np(m, e, wi, wo, values) for m in METRICS}


def fit_one(target, name: str, metric: str, pairs: int = 16384, steps: int = 800,
            seed: int = 0, progress: bool = False):
    """(FitResult, {metric: objective}): lecture model ``name`` fitted to ``target`` under
    ``metric`` from its start (:func:`models_for`), and scored under every metric."""
    from . import fit

    (model, free), = [(m, f) for n, m, f in models_for(target) if n == name]
    result = fit(target, model, free, pairs=pairs, steps=steps, seed=seed, metric=metric,
                 progress=progress)
    return result, score(target, result.spec, pairs, seed)


def published(target, names: list, material: str, pairs: int, seed: int) -> dict:
    """{model: ({metric: objective}, spec) or (None, why)}: Ngan et al.'s (2005) published fit
    of ``material`` for each model (the ``ngan:`` presets, :mod:`mi_brdfs.presets`), scored on
    the pairs of the fits to ``target``; why, where a model has no exact preset."""
    from .. import presets
    from ..errors import MiBrdfsError

    out = {}
    for name in names:
        try:
            spec = presets.spec(name, f"{presets.SOURCE}:{material}")
        except MiBrdfsError as e:
            out[name] = (None, str(e).split(" is invalid: ", 1)[-1])
            continue
        out[name] = (score(target, spec, pairs, seed), spec)
    return out


def published_table(table: dict, theirs: dict, metric: str) -> list:
    """Rows (model, ours, Ngan's published, ratio) under ``metric``."""
    rows = []
    for name, ours in table.items():
        scores_, spec = theirs.get(name, (None, "not compared"))
        if scores_ is None:  # the whole reason is in models.json
            rows.append((name, f"{ours[metric]:.4g}", "—", spec.split(":")[0].split(", ")[0]))
        else:
            rows.append((name, f"{ours[metric]:.4g}", f"{scores_[metric]:.4g}",
                         f"{scores_[metric] / ours[metric]:.3g}×"))
    return rows


def ranking_table(table: dict) -> list:
    """Rows (model, then per metric 'objective (rank)'), ranked by each metric's column."""
    ranks = {m: {name: i + 1 for i, name in enumerate(sorted(table, key=lambda n: table[n][m]))}
             for m in METRICS}
    return [(name, *[f"{table[name][m]:.4g} ({ranks[m][name]})" for m in METRICS])
            for name in table]


def plot_lobes(target, results: dict, path) -> str:
    """(f·cosθo)^(1/3) in the plane of incidence at :data:`LOBE_THETAS`, target and fits."""
    from ..plots import cube_root_lobe, lobe_values, pyplot, save_figure

    plt = pyplot()
    fig = plt.figure(figsize=(3.4 * len(LOBE_THETAS), 3.6))
    for j, theta in enumerate(LOBE_THETAS):
        ax = fig.add_subplot(1, len(LOBE_THETAS), j + 1, projection="polar")
        curves = [(*lobe_values(target, theta), "k-", dict(lw=1.8, label="target"))]
        curves += [(*lobe_values(r.spec, theta), STYLES[n][1],
                    dict(color=STYLES[n][0], lw=1.3, label=n)) for n, r in results.items()]
        cube_root_lobe(ax, curves, f"θi = {theta:g}°")
        if j == 0:
            ax.legend(loc="lower left", fontsize=7)
    fig.suptitle(f"{spec_text(target)}: lobes as (f·cosθo)^(1/3) in the plane of incidence",
                 fontsize=9)
    return save_figure(fig, path)


def sphere_row(target, results: dict, path, spp: int = 64, res: int = 128) -> str:
    """The target and each fit on the sphere of ``scenes/material.xml``, side by side."""
    import mitsuba as mi

    from ..imageio import to_srgb8
    from ..plots import pyplot, save_figure
    from ..scenes import load_scene

    panels = [("target", target)] + [(n, r.spec) for n, r in results.items()]
    plt = pyplot()
    fig, axes = plt.subplots(1, len(panels), figsize=(2.2 * len(panels), 2.5), squeeze=False)
    for ax, (label, spec) in zip(axes[0], panels):
        scene = load_scene("material", {"res": str(res)}, bsdfs={"material": spec})
        ax.imshow(to_srgb8(np.array(mi.render(scene, spp=spp, seed=0))))
        ax.set_title(label, fontsize=9)
        ax.axis("off")
    fig.tight_layout()
    return save_figure(fig, path)


def write_report(target, results: dict, table: dict, metric: str, out: Path,
                 figures: dict, theirs: dict | None = None, material: str = "") -> list:
    """models.md and models.json in ``out`` (with ``theirs``, Ngan's published fits of
    ``material`` beside ours); returns the paths written."""
    from ..markdown import md_table
    from ..imageio import atomic_path

    lines = [f"# Lecture models fitted to {spec_text(target)}", "",
             f"Each model fitted under the `{metric}` metric ({METRICS[metric]}), then scored "
             "under every metric on the same pairs (objective, and rank among the models):", "",
             md_table(["model", *METRICS], ranking_table(table)), "",
             md_table(["model", "fitted", "residual of f·cosθi·cosθo", "albedo error"],
                      [(n, f"`{r.command_line()}`", f"{r.residual_projected:.3g}",
                        f"{r.albedo_error:.3f} (θ = {r.albedo_theta:g}°)")
                       for n, r in results.items()]), ""]
    if theirs is not None:
        lines += [f"Ngan et al.'s (2005) published fits of `{material}` (the `ngan:` presets), "
                  f"scored on the same pairs under `{metric}`, beside ours (their objective "
                  "over ours; where a model has no exact preset, why):", "",
                  md_table(["model", "ours", "published", "published / ours"],
                           published_table(table, theirs, metric)), ""]
    lines += [f"![{k}]({Path(v).name})" for k, v in figures.items()]
    written = []
    for name, text in (("models.md", "\n".join(lines) + "\n"),
                       ("models.json", json.dumps({
                           "target": spec_text(target), "metric": metric,
                           "scores": table, "fits": {n: r.to_json() for n, r in
                                                     results.items()},
                           "published": {n: {"material": material, "scores": v[0],
                                             "spec" if v[0] else "why": v[1]}
                                         for n, v in (theirs or {}).items()}},
                          indent=2, default=str))):
        with atomic_path(out / name, Path(name).suffix) as tmp:
            Path(tmp).write_text(text)
        written.append(str(out / name))
    return written


def fit_models(target, names: list, metric: str, out, *, pairs: int = 16384, steps: int = 800,
               seed: int = 0, figures: bool = True, progress: bool = False,
               compare_published: str | None = None) -> dict:
    """
    Fit the lecture models ``names`` to ``target`` under ``metric``, score them under every
    metric, and write ``models.md``, ``models.json`` (and with ``figures`` ``lobes.png`` and
    ``spheres.png``) in the folder ``out``; with ``compare_published`` (a MERL material's name)
    Ngan et al.'s published fits of it are scored beside. Returns {'results', 'scores',
    'published', 'written'}.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    results, table = {}, {}
    for name in [n for n in STYLES if n in names]:
        results[name], table[name] = fit_one(target, name, metric, pairs, steps, seed, progress)
    theirs = None if compare_published is None else \
        published(target, list(results), compare_published, pairs, seed)
    drawn = {}
    if figures:
        drawn = {"lobes": plot_lobes(target, results, out / "lobes.png"),
                 "spheres": sphere_row(target, results, out / "spheres.png")}
    written = write_report(target, results, table, metric, out, drawn, theirs,
                           compare_published or "") + list(drawn.values())
    return {"results": results, "scores": table, "published": theirs, "written": written}


__all__ = ["LOBE_THETAS", "STYLES", "chosen", "fit_models", "fit_one", "models_for",
           "published", "published_table", "ranking_table", "score"]
