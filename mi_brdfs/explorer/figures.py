"""
The explorer's plots as Bokeh figures with their data sources (:class:`Figures`): made once
per page, then only their sources' data change (Bokeh sends the new columns; nothing is laid
out again). What they show is computed elsewhere, by the BSDFs themselves
(:mod:`~mi_brdfs.explorer.session`, :mod:`~mi_brdfs.explorer.views`,
:mod:`~mi_brdfs.explorer.sphere`); here it is only drawn: curves overlaid one colour per BSDF,
images (the (θh, θd) slice, the sampling density, the spheres) side by side.
"""

from __future__ import annotations

import numpy as np

#: One colour per BSDF, in the order given (Bokeh's Category10).
COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")

#: The polar plot's curves at other incident angles than the slider's, at most.
MORE_THETAS = 3

#: Pixels of each small image on the page.
TILE = 170

#: The (θh, θd) slice's colour range: decades of f below its largest value.
SLICE_DECADES = 3.0

#: The sampling-density view's colour range: log₂ of density / (f·cosθo / E).
RATIO_RANGE = 3.0


def rgba(image: np.ndarray) -> np.ndarray:
    """An 8-bit (h, w, 3 or 4) image as Bokeh's ``image_rgba`` takes it: one uint32 per pixel,
    its rows from the bottom."""
    h, w = image.shape[:2]
    out = np.full((h, w, 4), 255, np.uint8)
    out[..., :image.shape[2]] = image[..., :4]
    return out[::-1].copy().view(np.uint32).reshape(h, w)


def _tile(title: str, width: int = TILE, height: int = TILE, x=(0, 1), y=(0, 1)):
    from bokeh.plotting import figure

    f = figure(title=title, width=width, height=height + 30, x_range=x, y_range=y,
               tools="", toolbar_location=None, min_border=2)
    f.axis.visible = False
    f.grid.visible = False
    f.title.text_font_size = "9pt"
    return f


def _screen(elevation_deg: float, azimuth_deg: float):
    """(towards the viewer, the screen's right, its up) of an orthographic view from
    ``elevation_deg`` above the surface's plane and ``azimuth_deg`` around its normal."""
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    return view, right, np.cross(view, right)


def projected(x, y, z, elevation_deg: float, azimuth_deg: float):
    """The quads of a surface given by grids ``x``, ``y``, ``z`` (as :func:`~mi_brdfs.
    explorer.views.lobe3d` gives them) seen from the direction at ``elevation_deg`` above the
    surface's plane and ``azimuth_deg`` around its normal (an orthographic view): each quad's
    four corners on the screen (xs, ys: (quads, 4)), its depth towards the viewer and its
    shade (0.3 + 0.7·|n·l|, a light above the viewer); quads of no area (where the lobe is
    0) left out."""
    view, right, up = _screen(elevation_deg, azimuth_deg)
    p = np.stack([x, y, z], axis=-1)
    corners = np.stack([p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]], axis=2).reshape(-1, 4, 3)
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    area = np.linalg.norm(normal, axis=1)
    keep = area > 1e-12 * max(float(area.max(initial=0.0)), 1e-30)
    corners, normal = corners[keep], normal[keep] / area[keep, None]
    light = view + 0.5 * up
    shade = 0.3 + 0.7 * np.abs(normal @ (light / np.linalg.norm(light)))
    return corners @ right, corners @ up, corners.mean(axis=1) @ view, shade


def hex_rgb(colour: str) -> np.ndarray:
    """``#rrggbb`` → its three 8-bit values."""
    return np.array([int(colour[k:k + 2], 16) for k in (1, 3, 5)])


def rgb_hex(rgb) -> str:
    """Three 8-bit values → ``#rrggbb``."""
    r, g, b = (int(v) for v in rgb)
    return f"#{r:02x}{g:02x}{b:02x}"


def _shaded(colour: str, shade: np.ndarray) -> list[str]:
    """``colour`` (#rrggbb) darkened by ``shade`` (0 to 1), as #rrggbb strings."""
    values = np.clip(np.round(shade[:, None] * hex_rgb(colour)), 0, 255)
    return [rgb_hex(v) for v in values]


class Figures:
    """The Bokeh figures of a page for ``names`` (the BSDFs' names)."""

    def __init__(self, names: list[str]):
        from bokeh.models import ColumnDataSource, LinearColorMapper
        from bokeh.plotting import figure

        n = len(names)
        self.polar = figure(title="f·cosθo in the plane of incidence", width=460, height=320,
                            match_aspect=True)
        self.albedo = figure(title="albedo E(θi) from sample() (± 2 standard errors)",
                             width=460, height=320, x_axis_label="θi (degrees)",
                             y_axis_label="E", y_range=(0.0, 1.1))
        self.polar_src = [ColumnDataSource(dict(x=[], y=[])) for _ in range(n)]
        self.albedo_src = [ColumnDataSource(dict(t=[], e=[], lo=[], hi=[])) for _ in range(n)]
        for name, src, asrc, colour in zip(names, self.polar_src, self.albedo_src, COLOURS):
            self.polar.line("x", "y", source=src, color=colour, legend_label=name,
                            line_width=2)
            self.albedo.line("t", "e", source=asrc, color=colour, legend_label=name,
                             line_width=2)
            self.albedo.varea("t", "lo", "hi", source=asrc, color=colour, alpha=0.2)
        #: the curves at the other incident angles: per BSDF, :data:`MORE_THETAS` dashed ones
        self.polar_more = [[ColumnDataSource(dict(x=[], y=[])) for _ in range(MORE_THETAS)]
                           for _ in range(n)]
        for sources, colour in zip(self.polar_more, COLOURS):
            for k, src in enumerate(sources):
                self.polar.line("x", "y", source=src, color=colour, line_width=1.5,
                                line_dash=("dashed", "dotted", "dashdot")[k], alpha=0.8)
        self.incident = ColumnDataSource(dict(x=[], y=[]))
        self.polar.line("x", "y", source=self.incident, color="grey", line_dash="dashed")
        for f in (self.polar, self.albedo):
            f.legend.label_text_font_size = "8pt"
            f.legend.background_fill_alpha = 0.6
        self.lobe = figure(title="f·cosθo over the sphere of ωo (3-D lobe; ωi at φ = 0)",
                           width=420, height=380, match_aspect=True, tools="pan,wheel_zoom,reset",
                           toolbar_location="right")
        self.lobe.axis.visible = False
        self.lobe.grid.visible = False
        self.lobe_src = ColumnDataSource(dict(xs=[], ys=[], colour=[]))
        self.lobe.patches("xs", "ys", source=self.lobe_src, fill_color="colour",
                          line_color="colour", line_width=0.5,
                          fill_alpha=1.0 if n == 1 else 0.75)
        self.lobe_axes = ColumnDataSource(dict(xs=[], ys=[]))
        self.lobe.multi_line("xs", "ys", source=self.lobe_axes, color="grey", line_width=1)
        self.slice_map = LinearColorMapper(palette="Viridis256", low=-1.0, high=0.0,
                                           nan_color="white")
        self.density_map = LinearColorMapper(palette="RdBu11", low=-RATIO_RANGE,
                                             high=RATIO_RANGE, nan_color="white")
        #: the small images' titles: the plugin's name and its place (the colours say which)
        self.short = [f"{k + 1}: {name.split('(')[0]}" for k, name in enumerate(names)]
        self.slices = [self._image(name, self.slice_map) for name in self.short]
        self.densities = [self._image(name, self.density_map) for name in self.short]
        self.spheres = [self._rgba(name) for name in self.short]
        self.differences = [self._rgba(f"{name} − 1") for name in self.short[1:]]

    def _image(self, title, mapper):
        from bokeh.models import ColumnDataSource

        f = _tile(title)
        src = ColumnDataSource(dict(image=[np.zeros((2, 2))]))
        f.image("image", source=src, x=0, y=0, dw=1, dh=1, color_mapper=mapper)
        return f, src

    def _rgba(self, title):
        from bokeh.models import ColumnDataSource

        f = _tile(title)
        src = ColumnDataSource(dict(image=[np.zeros((2, 2), np.uint32)]))
        f.image_rgba("image", source=src, x=0, y=0, dw=1, dh=1)
        return f, src

    def draw_polar(self, theta_i_deg: float, theta_o_deg, curves, log: bool,
                   more=None) -> None:
        """Each BSDF's curve in polar form (radius: the value, or log(1 + value)), its curves
        at other incident angles (``more``: per BSDF, a list of curves) dashed, and the
        slider's incident direction in grey."""
        t = np.radians(theta_o_deg)
        top = 0.0
        for main, extra, values, others in zip(self.polar_src, self.polar_more, curves,
                                               more or [[] for _ in curves]):
            shown = [values, *others] + [None] * MORE_THETAS
            for src, v in zip([main, *extra], shown):
                if v is None:
                    src.data = dict(x=[], y=[])
                    continue
                r = np.log1p(np.maximum(v, 0.0)) if log else np.asarray(v)
                src.data = dict(x=r * np.sin(t), y=r * np.cos(t))
                top = max(top, float(np.nanmax(r, initial=0.0)))
        ti = np.radians(theta_i_deg)
        self.incident.data = dict(x=[0.0, -top * np.sin(ti)], y=[0.0, top * np.cos(ti)])

    def draw_lobe(self, surfaces, elevation_deg: float, azimuth_deg: float) -> None:
        """The lobes (:func:`~mi_brdfs.explorer.views.lobe3d`'s surfaces, one colour per
        BSDF, shaded) seen from (elevation, azimuth), their quads drawn far to near (the
        painter's order, all lobes together), with the surface's plane (a circle) and its
        normal in grey."""
        xs, ys, depth, colours = [], [], [], []
        size = 0.0
        for (x, y, z), colour in zip(surfaces, COLOURS):
            px, py, d, shade = projected(x, y, z, elevation_deg, azimuth_deg)
            xs.append(px), ys.append(py), depth.append(d)
            colours += _shaded(colour, shade)
            size = max(size, float(np.sqrt(np.max(x * x + y * y + z * z, initial=0.0))))
        xs, ys, depth = np.concatenate(xs), np.concatenate(ys), np.concatenate(depth)
        order = np.argsort(depth)
        self.lobe_src.data = dict(xs=list(xs[order]), ys=list(ys[order]),
                                  colour=[colours[k] for k in order])
        t = np.linspace(0.0, 2.0 * np.pi, 65)
        size = size or 1.0
        ring = size * np.stack([np.cos(t), np.sin(t), 0.0 * t], axis=-1)
        normal = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, size]])
        _, right, up = _screen(elevation_deg, azimuth_deg)
        self.lobe_axes.data = dict(xs=[list(ring @ right), list(normal @ right)],
                                   ys=[list(ring @ up), list(normal @ up)])

    def draw_albedo(self, thetas_deg, rows) -> None:
        """E(θi) of each BSDF with a band of ± 2 standard errors."""
        for src, (mean, err) in zip(self.albedo_src, rows):
            src.data = dict(t=list(thetas_deg), e=mean, lo=mean - 2 * err, hi=mean + 2 * err)

    def draw_slices(self, images) -> None:
        """The (θh, θd) images (rows θd, columns θh), as log₁₀ f on one colour scale over
        :data:`SLICE_DECADES` decades below the 99th percentile of the values (on a linear
        scale a peak leaves the rest dark), NaN (below the horizon) blank."""
        logs = [np.log10(np.maximum(np.asarray(i, np.float64), 1e-30)) for i in images]
        finite = np.concatenate([v[np.isfinite(v)] for v in logs])
        # the 99th percentile: a grazing corner's 1/(cosθi·cosθo) would darken the rest
        top = float(np.percentile(finite, 99.0)) if finite.size else 0.0
        self.slice_map.low, self.slice_map.high = top - SLICE_DECADES, top
        for (_, src), image in zip(self.slices, logs):
            src.data = dict(image=[image])

    def draw_densities(self, densities) -> None:
        """log₂ of the sampled density over f·cosθo/E per BSDF; its title gives the share of
        f·cosθo that importance sampling misses."""
        for (f, src), name, d in zip(self.densities, self.short, densities):
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.log2(d.histogram / d.target)
            ratio[~np.isfinite(ratio) | (d.target <= 0)] = np.nan
            src.data = dict(image=[np.clip(ratio, -RATIO_RANGE, RATIO_RANGE)])
            f.title.text = f"{name}: missed {100 * d.missed:.1f} %"

    def draw_spheres(self, images, differences, flips) -> None:
        """The spheres (8-bit sRGB), and each one's difference from the first with its mean
        FLIP."""
        for (f, src), image in zip(self.spheres, images):
            src.data = dict(image=[rgba(image)])
        for (f, src), name, image, value in zip(self.differences, self.short[1:], differences,
                                                flips):
            src.data = dict(image=[rgba(image)])
            f.title.text = f"{name.split(':')[0]} − 1: FLIP " + \
                ("—" if value is None else f"{value:.3f}")
