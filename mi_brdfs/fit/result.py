"""
What a fit found (:class:`FitResult`: its summary and JSON document) and its outputs: the JSON
file and the plot of target against fit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .spec import command_line, spec_text

#: Incident angles (degrees) of the albedo comparison: dense towards grazing.
ALBEDO_THETAS = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 75.0, 80.0, 84.26, 87.0, 89.0)


@dataclass
class FitResult:
    """What :func:`~mi_brdfs.fit.fit` found; ``parameters``: the free ones as written back
    (float, [r, g, b]); ``flags``: what makes the fit useless or unphysical, one line each
    (:mod:`~mi_brdfs.fit.flags`; empty when nothing does)."""

    target: object
    model: dict
    spec: dict
    parameters: dict
    residual: float
    residual_projected: float
    albedo_error: float
    albedo_theta: float
    loss: float
    start: str
    starts: dict
    thetas_deg: np.ndarray
    albedo_target: np.ndarray
    albedo_fit: np.ndarray
    pairs: int
    steps: int
    seed: int
    variant: str
    seconds: float
    metric: str = "cuberoot"
    notes: list = field(default_factory=list)
    flags: list = field(default_factory=list)

    def command_line(self) -> str:
        """The fitted BSDF as a command-line spec (``plugin key=value ...``)."""
        return command_line(self.spec)

    def xml(self) -> str:
        """The fitted BSDF as an XML ``<bsdf>`` element."""
        from ..bsdfspec import to_xml

        return to_xml(self.spec)

    def to_json(self) -> dict:
        """The JSON document of ``mi-brdfs fit -o``."""
        return {"target": spec_text(self.target), "model": spec_text(self.model),
                "parameters": self.parameters, "residual": self.residual,
                "albedo_error": self.albedo_error, "residual_projected": self.residual_projected,
                "fitted": self.command_line(),
                "xml": self.xml(), "objective": self.loss, "start": self.start,
                "variant": self.variant, "pairs": self.pairs, "steps": self.steps,
                "seed": self.seed, "metric": self.metric, "flags": list(self.flags)}

    def summary(self) -> str:
        """The printed report: fitted values, residual, albedo error, command line and XML."""
        width = max(len(n) for n in self.parameters)
        lines = [f"fit of {spec_text(self.model)} to {spec_text(self.target)} "
                 f"({self.pairs} direction pairs, {self.steps} steps, start: {self.start}, "
                 f"metric: {self.metric}, {self.seconds:.1f} s)"]
        lines += [f"  {name:<{width}} = {_show(value)}"
                  for name, value in self.parameters.items()]
        lines.append(f"residual      ‖f_fit − f_target‖/‖f_target‖ = {self.residual:.4g} "
                     f"(f·cosθo over the pairs; of f·cosθi·cosθo: "
                     f"{self.residual_projected:.4g})")
        lines.append(f"albedo error  max |ΔE(θ)| = {self.albedo_error:.4g} "
                     f"(at θ = {self.albedo_theta:g}°)")
        if len(self.starts) > 1:
            lines.append("starts        " + ", ".join(f"{label}: objective {loss:.4g}"
                                                      for label, loss in self.starts.items()))
        lines += [f"note: {n}" for n in self.notes]
        lines += [f"WARNING: {f}" for f in self.flags]
        lines.append(f"fitted BSDF   {self.command_line()}")
        lines.append(self.xml())
        return "\n".join(lines)


def _show(value) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(f"{v:.6g}" for v in value) + "]"
    return f"{value:.6g}"


def _figures(target_bsdf, fitted: dict, wi, wo, target_values, thetas: np.ndarray) -> dict:
    """
    The reported figures (fields of :class:`FitResult`), from the fitted spec as written
    (rounded), loaded afresh: the residuals over the pairs and the albedo comparison.
    """
    from ..bsdfspec import load_bsdf
    from ..checks import batch
    from ..checks.albedo import albedo_quadrature

    fitted_bsdf = load_bsdf(fitted)
    fit_values = batch.evaluate(fitted_bsdf, wi, wo).value
    residual = float(np.linalg.norm(fit_values - target_values) / np.linalg.norm(target_values))
    cos_i = wi[:, 2:3]
    residual_projected = float(np.linalg.norm((fit_values - target_values) * cos_i)
                               / np.linalg.norm(target_values * cos_i))
    e_target = np.array([albedo_quadrature(target_bsdf, t) for t in np.radians(thetas)])
    e_fit = np.array([albedo_quadrature(fitted_bsdf, t) for t in np.radians(thetas)])
    e_target = np.broadcast_to(e_target, e_fit.shape) if e_target.shape[1] == 1 else e_target
    diff = np.abs(e_fit - e_target)
    worst = np.unravel_index(int(np.argmax(diff)), diff.shape)
    return dict(residual=residual, residual_projected=residual_projected,
                albedo_error=float(diff[worst]), albedo_theta=float(thetas[worst[0]]),
                thetas_deg=thetas, albedo_target=e_target, albedo_fit=e_fit)


# -------------------------------------------------------------------------------------------------
# Output
# -------------------------------------------------------------------------------------------------


def write_json(result: FitResult, path) -> str:
    """Write :meth:`FitResult.to_json` to ``path`` atomically; return the path."""
    import json
    import os

    from ..imageio import atomic_path

    from ..errors import ParameterError

    path = os.fspath(path)
    if not path.lower().endswith(".json"):
        raise ParameterError("fit.write_json", "path", path, "must end in .json")
    with atomic_path(path, ".json") as tmp, open(tmp, "w") as f:
        json.dump(result.to_json(), f, indent=1)
        f.write("\n")
    return path


def plot_fit(result: FitResult, path, thetas_deg=(0.0, 30.0, 60.0, 80.0)) -> str:
    """
    Target against fit: f·cosθo in the plane of incidence at ``thetas_deg`` (polar, radius
    (f·cosθo)^(1/3), the fit's compression) and the directional albedo E(θ) (mean of channels).
    """
    from ..bsdfspec import describe
    from ..plots import cube_root_lobe, lobe_values, pyplot, save_figure

    plt = pyplot()
    k = len(thetas_deg)
    fig = plt.figure(figsize=(3.6 * k + 4.8, 4.2))
    for j, theta_i in enumerate(thetas_deg):
        ax = fig.add_subplot(1, k + 1, j + 1, projection="polar")
        cube_root_lobe(ax, [(*lobe_values(spec, theta_i), style, dict(lw=1.4, label=label))
                            for spec, label, style in ((result.target, "target", "-"),
                                                       (result.spec, "fit", "--"))],
                       f"θi = {theta_i:g}°")
    ax.legend(loc="lower right", fontsize=7)
    ax = fig.add_subplot(1, k + 1, k + 1)
    ax.plot(result.thetas_deg, result.albedo_target.mean(axis=1), "-o", ms=3, label="target")
    ax.plot(result.thetas_deg, result.albedo_fit.mean(axis=1), "--s", ms=3, label="fit")
    ax.set_xlabel("incident angle θ (degrees)")
    ax.set_ylabel("albedo E(θ)")
    ax.set_xlim(0, 90)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.subplots_adjust(wspace=0.45)
    fig.suptitle(f"fit {describe(result.spec)}\nto {describe(result.target)}: residual "
                 f"{result.residual:.3g}, max |ΔE(θ)| {result.albedo_error:.3g}; lobes: "
                 f"(f·cosθo)^(1/3) in the plane of incidence", fontsize=9)
    return save_figure(fig, path)
