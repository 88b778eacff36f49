"""
The page of ``mi-brdfs explore`` (Panel on Bokeh: a Python web-visualisation library that
serves the same layout from a command and inside a Jupyter notebook, with no JavaScript of
ours). One :func:`build` per browser session: each has its own
:class:`~mi_brdfs.explorer.session.Session`, so two browsers never share a BSDF's state.

The controls are generated from the BSDFs (:func:`~mi_brdfs.explorer.session.controls`): a
slider per number (over log₁₀ of it where its range spans decades), three per colour; a value
the plugin refuses is shown on the page in its own words, and the BSDF keeps its last good
value. Views: the polar plot in the plane of incidence (f·cosθo, linear or log) and the albedo
E(θi) from ``sample()`` with its standard error band; the XML fragment of each BSDF as it is
now.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import MiBrdfsError
from .session import Session

#: One colour per BSDF, in the order given (Bokeh's Category10).
COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")

#: The albedo view's incident angles (degrees) and samples per angle.
ALBEDO_THETAS = tuple(float(t) for t in np.linspace(0.0, 85.0, 18))
ALBEDO_SAMPLES = 20_000


def _slider(pn, entry, control, on_change):
    """The slider(s) of one control: a number (log₁₀ where ``control.log``), or r, g, b."""
    def make(name, value, index):
        lo, hi, v = control.lo, control.hi, value
        if control.log:
            lo, hi, v = math.log10(lo), math.log10(hi), math.log10(max(v, control.lo))
        step = (hi - lo) / 200.0
        widget = pn.widgets.FloatSlider(label=name, start=lo, end=hi, value=min(max(v, lo), hi),
                                        step=step, format="0.000")
        widget.param.watch(lambda event: on_change(entry, control, index, event.new),
                           "value_throttled")
        return widget
    if control.channels == 1:
        name = f"{control.label} (log₁₀)" if control.log else control.label
        return [make(name, control.value, None)]
    return [make(f"{control.label} {c}", v, k) for k, (c, v) in
            enumerate(zip("rgb", control.value))]


def _value(control, index, new):
    """The parameter's new value from a slider's: 10^x on a log slider, one channel set."""
    v = 10.0 ** new if control.log else float(new)
    if index is None:
        return v
    values = list(control.value)
    values[index] = v
    return tuple(values)


def build(specs, theta_i: float = 30.0):
    """The page for ``specs`` (1 to 4 BSDFs, any form), in the current (JIT) variant."""
    import panel as pn
    from bokeh.models import ColumnDataSource
    from bokeh.plotting import figure

    session = Session(specs)
    state = {"theta_i": theta_i, "log": False}
    message = pn.pane.Alert("", alert_type="danger", visible=False)
    xml = pn.pane.Markdown("")
    polar_sources = [ColumnDataSource(dict(x=[], y=[])) for _ in session.entries]
    albedo_sources = [ColumnDataSource(dict(t=[], e=[], lo=[], hi=[])) for _ in session.entries]

    polar = figure(title="f·cosθo in the plane of incidence", width=460, height=300,
                   match_aspect=True, x_axis_label="", y_axis_label="")
    albedo = figure(title="albedo E(θi) from sample() (± 2 SE)", width=460, height=300,
                    x_axis_label="θi (degrees)", y_axis_label="E", y_range=(0.0, 1.1))
    for entry, src, asrc, colour in zip(session.entries, polar_sources, albedo_sources, COLOURS):
        polar.line("x", "y", source=src, color=colour, legend_label=entry.name, line_width=2)
        albedo.line("t", "e", source=asrc, color=colour, legend_label=entry.name, line_width=2)
        albedo.varea("t", "lo", "hi", source=asrc, color=colour, alpha=0.2)

    def redraw_polar():
        theta_o, curves = session.polar(state["theta_i"])
        t = np.radians(theta_o)
        for src, values in zip(polar_sources, curves):
            r = np.log1p(np.maximum(values, 0.0)) if state["log"] else values
            src.data = dict(x=r * np.sin(t), y=r * np.cos(t))

    def redraw_albedo():
        for src, (mean, err) in zip(albedo_sources,
                                    session.albedo(ALBEDO_THETAS, ALBEDO_SAMPLES)):
            src.data = dict(t=list(ALBEDO_THETAS), e=mean, lo=mean - 2 * err, hi=mean + 2 * err)

    def redraw_xml():
        xml.object = "\n\n".join(f"**{e.name}**\n```xml\n{e.xml()}\n```"
                                 for e in session.entries)

    def on_change(entry, control, index, new):
        try:
            entry.set(control.key, _value(control, index, new))
        except MiBrdfsError as e:
            message.object, message.visible = str(e), True
            return
        message.visible = False
        redraw_polar()
        redraw_albedo()
        redraw_xml()

    theta = pn.widgets.FloatSlider(label="θi (degrees)", start=0.0, end=89.0, value=theta_i,
                                   step=1.0)
    log = pn.widgets.Checkbox(label="log scale (log(1 + f·cosθo))")

    def on_view(event):
        state["theta_i"], state["log"] = theta.value, log.value
        redraw_polar()
    theta.param.watch(on_view, "value_throttled")
    log.param.watch(on_view, "value")

    redraw_polar()
    redraw_albedo()
    redraw_xml()
    columns = []
    for entry in session.entries:
        widgets = [w for c in entry.controls.values()
                   for w in _slider(pn, entry, c, on_change)]
        columns.append(pn.Column(pn.pane.Markdown(f"### {entry.name}"), *widgets))
    page = pn.Column(
        pn.pane.Markdown("# mi-brdfs explore"), message,
        pn.Row(*columns, pn.Column(theta, log)),
        pn.Row(pn.pane.Bokeh(polar), pn.pane.Bokeh(albedo)), xml)
    page.session = session  # what the page shows, for tests and notebooks
    return page
