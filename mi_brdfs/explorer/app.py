"""
The page of ``mi-brdfs explore`` (Panel on Bokeh: a Python web-visualisation library that
serves the same layout from a command and inside a Jupyter notebook, with no JavaScript
framework of ours). One :func:`build` per browser session: each has its own
:class:`Explorer` (its own :class:`~mi_brdfs.explorer.session.Session`), so two browsers
never share a BSDF's state.

The controls are generated from the BSDFs: a slider per number (over log₁₀ where its range
spans decades) or three per colour, a field to type a value in the parameter's units, a menu
per configuration switch. A value the plugin refuses is shown on the page in its own words,
and the BSDF keeps its last good value. The views (polar plot, albedo, 3-D lobe, (θh, θd)
slice, sampling density, spheres) are computed by the BSDFs' own ``eval``/``pdf``/``sample``;
a parameter change recomputes the views of that BSDF only, then the spheres' first pass; the
verdicts, the cost per sample and further passes of the spheres follow on a timer, so the
page answers between them.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import MiBrdfsError
from . import views
from .figures import COLOURS, Figures, hex_rgb, rgb_hex
from .session import Session

#: The albedo view's incident angles (degrees) and samples per angle.
ALBEDO_THETAS = tuple(float(t) for t in np.linspace(0.0, 85.0, 18))
ALBEDO_SAMPLES = 4096

#: The spheres' resolution, and the passes after which they stop refining.
SPHERE_RES = 64
SPHERE_PASSES = 16

#: The timer of the spheres' passes and the verdicts (milliseconds).
TICK_MS = 150

#: The fit button's effort: direction pairs and Adam steps (``mi-brdfs fit``'s are larger).
FIT_PAIRS, FIT_STEPS = 4096, 200


def _value(control, index, new):
    """The parameter's new value from a slider's: 10^x on a log slider, one channel set."""
    v = 10.0 ** new if control.log else float(new)
    if index is None:
        return v
    values = list(control.value)
    values[index] = v
    return tuple(values)


def _typed(text: str):
    """A typed value: a number, or three comma-separated numbers (a colour); else the text
    (which the session refuses in one line)."""
    parts = [p.strip() for p in str(text).strip("()[] ").split(",")]
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        return text
    return numbers[0] if len(numbers) == 1 else tuple(numbers)


def _angles(text: str) -> tuple:
    """Up to :data:`~mi_brdfs.explorer.figures.MORE_THETAS` incident angles in [0°, 90°)
    from a comma-separated text (empty: none); MiBrdfsError with one line otherwise."""
    from .figures import MORE_THETAS

    parts = [p.strip() for p in str(text).split(",") if p.strip()]
    try:
        angles = tuple(float(p) for p in parts)
    except ValueError:
        angles = None
    if angles is None or len(angles) > MORE_THETAS or \
            not all(0.0 <= a < 90.0 for a in angles):
        raise MiBrdfsError(f"explore: other θi = {text!r}: expected up to {MORE_THETAS} "
                           f"angles in degrees in [0, 90), comma-separated")
    return angles


def _on_loop(callback):
    """A widget's callback run on the server's event loop, with Bokeh's document lock (a
    typed field's change arrives without it, and writing to the plots' sources then fails);
    at once outside a server (a notebook, the tests)."""
    import panel as pn

    return lambda event: pn.state.execute(lambda: callback(event), schedule=True)


def _hex(rgb) -> str:
    """A linear RGB colour in [0, 1] as the sRGB ``#rrggbb`` a colour picker shows."""
    from ..imageio import to_srgb8

    return rgb_hex(to_srgb8(np.array([[rgb]], np.float32))[0, 0])


def _linear(hex_colour: str) -> tuple:
    """A picked ``#rrggbb`` (sRGB) as linear RGB."""
    from ..imageio import from_srgb8

    return tuple(float(v) for v in from_srgb8(hex_rgb(hex_colour)))


def _shown(value) -> str:
    if isinstance(value, tuple):
        return ", ".join(f"{v:.4g}" for v in value)
    return f"{value:.4g}"


def spheres(bsdfs, scene, light, kind: str = "directional"):
    """The spheres of ``bsdfs`` under a light of ``kind`` (:data:`~mi_brdfs.explorer.sphere.
    LIGHTS`) from ``light`` (θ, φ), or with ``scene`` = (a scene file, the id of its BSDF to
    replace) that scene's view under its own lights."""
    from .sphere import Spheres

    if scene is None:
        return Spheres(bsdfs, res=SPHERE_RES, light=kind, theta=light[0], phi=light[1])
    return Spheres.from_scene(scene[0], bsdfs, scene[1])


class Explorer:
    """What one page shows and does: the session, the figures, the widgets and the
    callbacks (``set_parameter``, ``set_switch``, ``set_view``, ``tick``, ``fit``) that the
    browser's events call (and tests and the latency benchmark call directly)."""

    def __init__(self, specs, theta_i: float = 30.0, scene=None):
        import panel as pn

        self.session = Session(specs)
        self.view = {"theta_i": theta_i, "log": False, "cosine": True, "light": (45.0, 30.0),
                     "more": (), "lobe": (25.0, -60.0), "light_kind": "directional"}
        self.figures = Figures([e.name for e in self.session.entries])
        self.spheres = spheres([e.bsdf for e in self.session.entries], scene,
                               self.view["light"])
        self.data = [dict() for _ in self.session.entries]
        self.stale = {"verdicts": set(range(len(self.data))), "cost": True}
        self.message = pn.pane.Alert("", alert_type="danger", visible=False,
                                     css_classes=["mb-alert"])
        #: what the plugins say of their values (their MiBrdfsWarnings), beside the message
        self.said = pn.pane.Alert("", alert_type="warning", visible=False,
                                  css_classes=["mb-warnings"])
        self.verdicts = pn.pane.Markdown("", css_classes=["mb-verdicts"])
        self.sphere_title = pn.pane.Markdown("")
        self.fit_result = pn.pane.Markdown("", css_classes=["mb-fit"])
        self.code = {kind: pn.pane.Markdown("", css_classes=[f"mb-{kind}"])
                     for kind in ("xml", "python")}
        self.raw = {kind: pn.widgets.TextInput(value="", visible=False)
                    for kind in ("xml", "python")}
        self.columns = [pn.Column(css_classes=["mb-controls"]) for _ in self.session.entries]
        #: (BSDF, parameter key) → (its sliders, [its field, its colour picker])
        self.sliders = {}
        #: nanoseconds per sample of each BSDF (None until the timer measures them)
        self.cost = None
        for i in range(len(self.session.entries)):
            self._controls(i)
            self._compute(i)
        self._draw()
        self._draw_code()
        self._draw_warnings()
        self._sphere_pass()

    # -- what a change does -------------------------------------------------------------
    def set_parameter(self, i: int, key: str, value) -> bool:
        """Set parameter ``key`` of BSDF ``i`` (through ``mi.traverse``) and redraw its views
        and the first pass of the spheres; a refused value is shown, nothing changes."""
        entry = self.session.entries[i]
        try:
            entry.set(key, value)
        except MiBrdfsError as e:
            return self._refuse(e)
        self.message.visible = False
        self._changed(i)
        self._sync_widgets(i, key)
        return True

    def set_switch(self, i: int, name: str, value) -> bool:
        """Set switch ``name`` of BSDF ``i``: the plugin is loaded anew (a switch selects
        code), its controls are made anew, the spheres hold the new object."""
        entry = self.session.entries[i]
        try:
            entry.switch(name, value)
        except MiBrdfsError as e:
            self._controls(i)  # the menu shows the value the BSDF keeps
            return self._refuse(e)
        self.message.visible = False
        self.spheres.replace(i, entry.bsdf)
        self.stale["cost"] = True
        self._controls(i)
        self._changed(i)
        return True

    def set_view(self, theta_i=None, log=None, cosine=None, light=None, more=None,
                 lobe=None, light_kind=None) -> bool:
        """Change what the views show (θi, log scale, f or f·cosθo, the light's direction and
        kind, the polar plot's other incident angles: a text of up to three angles in
        degrees, which is refused on the page where it is none; the 3-D lobe's view:
        elevation, azimuth)."""
        old = dict(self.view)
        if more is not None:
            try:
                more = _angles(more)
            except MiBrdfsError as e:
                return self._refuse(e)
            self.message.visible = False
        for key, value in (("theta_i", theta_i), ("log", log), ("cosine", cosine),
                           ("light", light), ("more", more), ("lobe", lobe),
                           ("light_kind", light_kind)):
            if value is not None:
                self.view[key] = value
        if self.view["light_kind"] != old["light_kind"] and self.spheres.light is not None:
            self.spheres = spheres([e.bsdf for e in self.session.entries], None,
                                   self.view["light"], self.view["light_kind"])
            self._sphere_pass()
        elif self.view["light"] != old["light"] and self.spheres.light is not None:
            self.spheres.set_light(*self.view["light"])
            self._sphere_pass()
        key = ("theta_i", "cosine", "more")
        if [self.view[k] for k in key] != [old[k] for k in key]:
            for i in range(len(self.data)):
                self._compute(i, incident_only=True)
            self.stale["verdicts"] = set(range(len(self.data)))
        self._draw()
        return True

    def _refuse(self, error: MiBrdfsError) -> bool:
        self.message.object, self.message.visible = str(error), True
        return False

    def _changed(self, i: int) -> None:
        """Redraw after a change of BSDF ``i``; :attr:`latency` says how long the 2-D plots
        and the spheres' first pass took (seconds; ``make bench`` reports them)."""
        clock = time.perf_counter()
        self._compute(i)
        self._draw()
        self._draw_code()
        self._draw_warnings()
        plots = time.perf_counter()
        self.stale["verdicts"].add(i)
        self._sphere_pass()
        self.latency = {"plots": plots - clock, "sphere": time.perf_counter() - plots}

    # -- computing and drawing ----------------------------------------------------------
    def _compute(self, i: int, incident_only: bool = False) -> None:
        """The views of BSDF ``i`` (those that depend on θi only, with ``incident_only``)."""
        bsdf, d, t = self.session.entries[i].bsdf, self.data[i], self.view["theta_i"]
        from ..plots import lobe_values

        d["polar"] = lobe_values(bsdf, t, 181, self.view["cosine"])
        d["polar_more"] = [lobe_values(bsdf, u, 181, self.view["cosine"])[1]
                           for u in self.view["more"]]
        d["lobe"] = views.lobe3d(bsdf, t)
        d["density"] = views.sampling_density(bsdf, t)
        if not incident_only:
            d["albedo"] = self.session.albedo(i, ALBEDO_THETAS, ALBEDO_SAMPLES)
            d["slice"] = views.slice_image(bsdf)

    def _draw(self) -> None:
        f = self.figures
        f.draw_polar(self.view["theta_i"], self.data[0]["polar"][0],
                     [d["polar"][1] for d in self.data], self.view["log"],
                     [d["polar_more"] for d in self.data])
        f.draw_albedo(ALBEDO_THETAS, [d["albedo"] for d in self.data])
        f.draw_slices([d["slice"] for d in self.data])
        f.draw_densities([d["density"] for d in self.data])
        f.draw_lobe([d["lobe"] for d in self.data], *self.view["lobe"])

    def _draw_code(self) -> None:
        entries = self.session.entries
        for kind, fence in (("xml", "xml"), ("python", "python")):
            texts = [e.xml() if kind == "xml" else e.python() for e in entries]
            self.raw[kind].value = "\n\n".join(texts)
            self.code[kind].object = "\n\n".join(
                f"**{e.name}**\n```{fence}\n{text}\n```" for e, text in zip(entries, texts))

    def _draw_warnings(self) -> None:
        lines = [f"**{i + 1}: {e.name}**: {said}"
                 for i, e in enumerate(self.session.entries) for said in e.warnings]
        self.said.object, self.said.visible = "\n\n".join(lines), bool(lines)

    def _sphere_pass(self) -> None:
        """Start the spheres anew and show their first pass."""
        self.spheres.reset()
        self.spheres.step()
        self._draw_spheres()

    def _draw_spheres(self) -> None:
        n = len(self.session.entries)
        self.figures.draw_spheres([self.spheres.image(i) for i in range(n)],
                                  [self.spheres.difference(i) for i in range(1, n)],
                                  [self.spheres.flip(i) for i in range(1, n)])
        self.sphere_title.object = f"**{'scene' if self.spheres.light is None else 'spheres'}**" \
            f" (Mitsuba's path tracer, progressive: {self.spheres.passes} passes of " \
            f"{self.spheres.spp} samples per pixel; below: the difference from 1, blue " \
            f"darker, red brighter, and FLIP)"

    def tick(self) -> None:
        """The timer's work, one piece at a time: a stale verdict, the cost per sample, else
        one more pass of the spheres (up to :data:`SPHERE_PASSES`)."""
        if self.stale["verdicts"]:
            i = min(self.stale["verdicts"])
            self.stale["verdicts"].discard(i)
            self.data[i]["verdicts"] = views.verdicts(self.session.entries[i].bsdf,
                                                      self.view["theta_i"])
            self._draw_verdicts()
        elif self.stale["cost"]:
            self.stale["cost"] = False
            self.cost = views.cost_per_sample([e.bsdf for e in self.session.entries])
            self._draw_verdicts()
        elif self.spheres.passes < SPHERE_PASSES:
            self.spheres.step()
            self._draw_spheres()

    def _draw_verdicts(self) -> None:
        rows = []
        cost = self.cost
        for i, (e, d) in enumerate(zip(self.session.entries, self.data)):
            head = f"**{i + 1}: {e.name}**"
            if cost:
                head += f" — cost per sample: {cost[i]:.0f} ns ({cost[i] / cost[0]:.2f}× the first)"
            items = [f"- {'–' if v.skipped else '✔' if v.ok else '✘'} {v.text}"
                     for v in d.get("verdicts", [])] or ["- (checking…)"]
            rows.append("\n".join([head, *items]))
        self.verdicts.object = "\n\n".join(rows)

    # -- the fit button -----------------------------------------------------------------
    def fit(self) -> bool:
        """Fit the second BSDF's parameters to the first (``mi_brdfs.fit.fit``, a short run)
        and put the fitted BSDF in its place; what the plugin or the fit refuses is shown."""
        from ..fit import fit

        if len(self.session.entries) < 2:
            return self._refuse(MiBrdfsError("fit: give a second BSDF to fit to the first"))
        target, model = self.session.entries[:2]
        spec = model.as_dict()
        if spec is None:
            return self._refuse(MiBrdfsError(f"fit: {model.name} was given as XML; give it "
                                             f"as 'type key=value' to fit it"))
        try:
            result = fit(target.bsdf, spec, pairs=FIT_PAIRS, steps=FIT_STEPS)
            model.replace(result.spec)
        except MiBrdfsError as e:
            return self._refuse(e)
        self.fit_result.object = f"**fit** (`mi_brdfs.fit.fit`, {FIT_STEPS} steps):\n\n" \
                                 f"```\n{result.summary()}\n```"
        self.spheres.replace(1, model.bsdf)
        self.stale["cost"] = True
        self._controls(1)
        self._changed(1)
        return True

    # -- widgets ------------------------------------------------------------------------
    def _controls(self, i: int) -> None:
        """(Re)make the widgets of BSDF ``i``: its switches' menus, its sliders and fields."""
        import panel as pn

        entry = self.session.entries[i]
        widgets = [pn.pane.Markdown(f"### <span style='color:{COLOURS[i]}'>■</span> "
                                    f"{i + 1}: {entry.name}")]
        for name, (value, options) in entry.switches.items():
            menu = pn.widgets.Select(label=name, options=[str(o).lower() if isinstance(o, bool)
                                                         else o for o in options],
                                     value=str(value).lower() if isinstance(value, bool)
                                     else value, width=140)
            menu.param.watch(_on_loop(lambda e, n=name, o=options: self.set_switch(
                i, n, {str(v).lower(): v for v in o}[e.new])), "value")
            widgets.append(menu)
        for control in entry.controls.values():
            widgets.append(self._control_row(pn, i, control))
        self.columns[i].objects = widgets

    def _control_row(self, pn, i: int, control):
        """The sliders of one control and its field (a value typed in its own units)."""
        sliders = []
        channels = [None] if control.channels == 1 else [0, 1, 2]
        for index in channels:
            value = control.value if index is None else control.value[index]
            lo, hi, v = control.lo, control.hi, value
            if control.log:
                lo, hi, v = math.log10(lo), math.log10(hi), math.log10(max(v, control.lo))
            label = control.label + (" (log₁₀)" if control.log else "") + \
                ("" if index is None else f" {'rgb'[index]}")
            slider = pn.widgets.FloatSlider(label=label, start=lo, end=hi, step=(hi - lo) / 200,
                                            value=min(max(v, lo), hi), format="0.000",
                                            width=220)
            slider.param.watch(_on_loop(lambda e, c=control, k=index: self.set_parameter(
                i, c.key, _value(c, k, e.new))), "value_throttled")
            sliders.append(slider)
        field = pn.widgets.TextInput(label=control.label, value=_shown(control.value),
                                     width=120, css_classes=["mb-field"])
        # (a value shown already is no change: the field follows the sliders too)
        field.param.watch(_on_loop(lambda e, c=control: e.new != _shown(c.value) and
                                   self.set_parameter(i, c.key, _typed(e.new))), "value")
        widgets = [field]
        if control.channels == 3 and control.hi <= 1.0:  # a reflectance: a colour too
            picker = pn.widgets.ColorPicker(label="colour", value=_hex(control.value),
                                            width=60)
            picker.param.watch(_on_loop(lambda e, c=control: e.new != _hex(c.value) and
                                        self.set_parameter(i, c.key, _linear(e.new))),
                               "value")
            widgets.append(picker)
        self.sliders[(i, control.key)] = (sliders, widgets)
        return pn.Row(pn.Column(*sliders, margin=0), *widgets)

    def _sync_widgets(self, i: int, key: str) -> None:
        """The field (and, for a typed value, the sliders) show the value now set."""
        sliders, (field, *picker) = self.sliders[(i, key)]
        control = self.session.entries[i].controls[key]
        values = [control.value] if control.channels == 1 else list(control.value)
        for slider, v in zip(sliders, values):
            v = math.log10(max(v, control.lo)) if control.log else v
            slider.value = min(max(v, slider.start), slider.end)
        field.value = _shown(control.value)
        for p in picker:
            p.value = _hex(control.value)


def _pair(pn, x, what: str, names, ranges, values, event: str = "value_throttled"):
    """Two sliders (degrees) that set the view's ``what`` (a pair) together."""
    sliders = [pn.widgets.FloatSlider(label=f"{what.replace('_', ' ')} {n} (degrees)",
                                      start=lo, end=hi, value=v, step=1.0, width=210)
               for n, (lo, hi), v in zip(names, ranges, values)]
    for s in sliders:
        s.param.watch(_on_loop(lambda e: x.set_view(**{what: tuple(w.value for w in sliders)})),
                      event)
    return sliders


def _view_widgets(pn, x) -> list:
    """The widgets of what the views show: θi and the other θi, log scale, f or f·cosθo, the
    light (where the spheres have one: not a scene file's), the fit button (two BSDFs)."""
    from .sphere import LIGHTS

    theta = pn.widgets.FloatSlider(label="θi (degrees)", start=0.0, end=89.0,
                                   value=x.view["theta_i"], step=1.0, width=210)
    theta.param.watch(_on_loop(lambda e: x.set_view(theta_i=e.new)), "value_throttled")
    more = pn.widgets.TextInput(label="other θi (degrees, dashed)", placeholder="e.g. 0, 60",
                                width=210, css_classes=["mb-more-thetas"])
    more.param.watch(_on_loop(lambda e: x.set_view(more=e.new)), "value")
    log = pn.widgets.Checkbox(label="log scale (log(1 + value))")
    log.param.watch(_on_loop(lambda e: x.set_view(log=e.new)), "value")
    cosine = pn.widgets.Checkbox(label="times cosθo", value=True)
    cosine.param.watch(_on_loop(lambda e: x.set_view(cosine=e.new)), "value")
    out = [theta, more, log, cosine]
    if x.spheres.light is not None:
        kind = pn.widgets.Select(label="light", options=list(LIGHTS), value="directional",
                                 width=140)
        kind.param.watch(_on_loop(lambda e: x.set_view(light_kind=e.new)), "value")
        out += [kind, *_pair(pn, x, "light", "θφ", ((0.0, 180.0), (-180.0, 180.0)),
                             x.view["light"])]
    if len(x.session.entries) > 1:
        button = pn.widgets.Button(label="fit the second BSDF to the first", color="primary")
        button.on_click(_on_loop(lambda e: x.fit()))
        out.append(button)
    return out


def _code(pn, x) -> list:
    """The XML and the Python of the BSDFs, each with its copy button."""
    out = []
    for kind in ("xml", "python"):
        copy = pn.widgets.Button(label=f"copy {kind.upper() if kind == 'xml' else 'Python'}")
        copy.js_on_click(args={"source": x.raw[kind]},
                         code="navigator.clipboard.writeText(source.value)")
        out.append(pn.Column(copy, x.raw[kind], x.code[kind]))
    return out


def build(specs, theta_i: float = 30.0, scene=None):
    """The page for ``specs`` (1 to 4 BSDFs, any form), in the current (JIT) variant; its
    :class:`Explorer` is ``page.explorer``; ``scene``: (a scene file, the id of the BSDF that
    each BSDF replaces in it) rendered instead of the sphere."""
    import panel as pn

    x = Explorer(specs, theta_i, scene)
    f = x.figures
    # turning the lobe computes nothing: it follows the slider as it moves
    turn = _pair(pn, x, "lobe", ("elevation", "azimuth"), ((-90.0, 90.0), (-180.0, 180.0)),
                 x.view["lobe"], "value")
    page = pn.Column(
        pn.pane.Markdown("# mi-brdfs explore"), x.message, x.said,
        pn.Row(*x.columns, pn.Column(pn.pane.Markdown("### views"), *_view_widgets(pn, x))),
        pn.Row(pn.Column(pn.pane.Bokeh(f.polar), css_classes=["mb-polar"]),
               pn.Column(pn.pane.Bokeh(f.albedo), css_classes=["mb-albedo"]),
               pn.Column(pn.pane.Bokeh(f.lobe), pn.Row(*turn), css_classes=["mb-lobe3d"])),
        pn.Column(pn.pane.Markdown("**(θh, θd) slice, φd = 90°**: log₁₀ f (θh →, θd ↑)"),
                  pn.Row(*[pn.pane.Bokeh(g) for g, _ in f.slices]), css_classes=["mb-slice"]),
        pn.Column(pn.pane.Markdown("**sampled density / (f·cosθo / E)**, log₂ over (φo →, "
                                   "cosθo ↑) (blue: oversampled, red: missed)"),
                  pn.Row(*[pn.pane.Bokeh(g) for g, _ in f.densities]),
                  css_classes=["mb-density"]),
        x.sphere_title,
        pn.Column(pn.Row(*[pn.pane.Bokeh(g) for g, _ in f.spheres]),
                  pn.Row(*[pn.pane.Bokeh(g) for g, _ in f.differences]),
                  css_classes=["mb-sphere"]),
        pn.Row(x.verdicts, x.fit_result),
        pn.Row(*_code(pn, x)))
    page.explorer = x
    page.session = x.session

    def start():
        timer = pn.state.add_periodic_callback(x.tick, period=TICK_MS)
        pn.state.on_session_destroyed(lambda context: timer.stop())
    pn.state.onload(start)
    return page
