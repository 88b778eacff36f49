"""
He et al.'s BRDF in ``make bench``: the ``he`` plugin's render cost against a ``cooktorrance``
of the same aluminium and about the same roughness, for each reading and for series of several
lengths, beside what each length leaves of the converged series; and its sampler (the tabulated
density of the directional diffuse lobe) against cosine sampling, as the time to 1 % relative
RMSE in the white furnace and the showcase.
"""

from __future__ import annotations

import numpy as np

import mitsuba as mi

from ..campaign.core import SKIPPED, Context, Row, Section, md_table
from ..reference import he as reference
from ..scattering.he import READINGS
from ..scenes import load_scene
from ..timing import interleaved, median
from . import error_time
from .measured import time_ratio

#: The surface (westin reading, bbm's default σ0 = 0.18 µm, τ = 3 µm: α = 2σ0/τ = 0.12) and
#: the cooktorrance of about the same lobe that it is timed against.
HE = "he material=Al"
COOKTORRANCE = "cooktorrance material=Al alpha=0.12 shadowing=smith"
#: Targets: he's render time at most this many times cooktorrance's; its sampler faster to
#: 1 % than the cosine's.
TARGET_COST, TARGET_SAMPLING = 2.0, 1.0
#: The westin reading's series lengths timed besides its default (48).
TERMS = (16, 24, 32)


def truncation(terms: int) -> float:
    """The largest relative part of the converged series (float64) that its first ``terms``
    terms leave, over g ∈ (0, 18.5] (the westin reading's series; above, the asymptote) and
    c = v_xy²τ²k²/4 ∈ {0, 1, 10, 100}."""
    g = np.linspace(0.05, READINGS["westin"].rough_threshold, 371)
    worst = 0.0
    for c in (0.0, 1.0, 10.0, 100.0):
        cs = np.full_like(g, c)
        full = reference.series(g, cs)
        ok = full > 0
        cut = reference.series(g, cs, terms)
        worst = max(worst, float(np.max(np.abs(cut[ok] / full[ok] - 1.0))))
    return worst


def _costs(ctx: Context, s: Section) -> list:
    """Render time per sample of each form of he and of cooktorrance, every sphere of the
    showcase; rows (form, ns per sample, ratio, truncation)."""
    res, spp = ctx.n(128, 32), ctx.n(32, 4)
    forms = {"westin, 48 terms (default)": HE}
    if not ctx.quick:  # each form is a kernel to compile, the paper's for a minute
        forms.update({f"westin, {t} terms": f"{HE} terms={t}" for t in TERMS})
        forms.update({"paper, 128 centred terms": f"{HE} variant=paper",
                      "holzschuch, 10 terms": f"{HE} variant=holzschuch"})
    forms["cooktorrance"] = COOKTORRANCE
    ids = error_time.SCENES["showcase"]
    scenes = {k: load_scene("showcase", {"res": str(res)}, bsdfs={i: b for i in ids})
              for k, b in forms.items()}
    for sc in scenes.values():
        mi.render(sc, spp=spp)  # the JIT compilation, apart
    times = interleaved({k: (lambda sc=sc: mi.render(sc, spp=spp)) for k, sc in scenes.items()},
                        repeats=ctx.n(11, 2), warmup=0)
    base = median(times["cooktorrance"])
    rows = []
    for form, t in times.items():
        ratio = median(t) / base
        terms = {"westin, 48 terms (default)": 48}.get(form) or \
            next((n for n in TERMS if form == f"westin, {n} terms"), None)
        left = f"{truncation(terms):.1e}" if terms else "—"
        rows.append((form, f"{median(t) / (res * res * spp) * 1e9:.1f} ns", f"{ratio:.2f}×",
                     left))
        if form.startswith("westin, 48"):
            s.values["he vs cooktorrance, render time"] = f"{ratio:.2f}×"
            s.rows.append(Row("he vs cooktorrance (Al, σ0 = 0.18 µm, τ = 3 µm; α = 0.12)",
                              f"{ctx.variant} render time ratio", f"{ratio:.2f}×",
                              f"≤ {TARGET_COST:g}×", ratio <= TARGET_COST))
    return rows


def section(ctx: Context) -> Section:
    """The section; a quick run loads he and names the figures (:data:`SKIPPED`): every he
    kernel takes seconds to compile (tests/plugins/test_he_plugin.py renders he)."""
    s = Section("He et al.: he")
    if ctx.quick:
        s.values["he vs cooktorrance, render time"] = SKIPPED
        cost = [("westin, 48 terms (default)", "—", SKIPPED, "—")]
    else:
        cost = _costs(ctx, s)
    bsdf = mi.load_dict({"type": "he", "material": "Al"})
    cells = []
    for scene in ("furnace", "showcase"):
        if ctx.quick:
            s.values[f"he sampling vs cosine, time to 1 % ({scene})"] = SKIPPED
            cells += ["—"] * 3
            continue
        t_own, t_cos, ratio = time_ratio(ctx, scene, bsdf)
        shown = f"{ratio:.3g}×" if np.isfinite(ratio) else "— (too short to time)"
        s.values[f"he sampling vs cosine, time to 1 % ({scene})"] = shown
        cells += [error_time.seconds_text(t_own), error_time.seconds_text(t_cos),
                  f"**{shown}**"]
        if scene == "furnace":
            s.rows.append(Row("he (Al, σ0 = 0.18 µm, τ = 3 µm)", "time to 1 % rel. RMSE in "
                              "the furnace, cosine sampling / he's", shown,
                              f"> {TARGET_SAMPLING:g}×", bool(ratio > TARGET_SAMPLING)))
    s.markdown = "\n".join([
        f"Render cost: `{HE}` in each reading and with shorter series, against "
        f"`{COOKTORRANCE}` (about the same lobe: α = 2σ0/τ), every sphere of the showcase, "
        f"`{ctx.variant}`, medians of interleaved renders (target ≤ {TARGET_COST:g}×). "
        "\"Left\": the largest relative part of the converged float64 series that the "
        "westin reading's first terms leave for g ≤ 18.5 (above, it takes the asymptote), "
        "`benchmark.he.truncation`.", "",
        md_table(["form", "per sample", "vs cooktorrance", "left"], cost), "",
        f"Sampling: `{HE}` with its sampler (the tabulated density of the directional diffuse "
        "lobe; the delta's weight is below 10⁻⁷ on this surface) against the "
        "cosine-weighted hemisphere alone (`benchmark.measured.mi_brdfs_bench_cosine`), time "
        "to 1 % relative RMSE in the white furnace and the showcase (as for `merl`).", "",
        md_table(["furnace: he", "cosine", "cosine / he", "showcase: he", "cosine",
                  "cosine / he"], [cells])])
    return s
