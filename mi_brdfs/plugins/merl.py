"""
Measured BRDFs in MERL's format (Matusik, Pfister, Brand & McMillan 2003) as a Mitsuba BSDF:
f interpolated between the bins' centres (or MERL's nearest bin), importance-sampled through the
half vector from a density tabulated per incident angle (:mod:`mi_brdfs.measured.warp`).
"""

from __future__ import annotations

import math

import drjit as dr
import mitsuba as mi
import numpy as np

from ..arrays import aligned as _aligned  # (tests place the table elsewhere through it)
from ..measured import data, lookup, warp
from . import lobes, properties

PLUGIN = "merl"

#: The tables of each file in this variant (this module runs once per variant), by the file's
#: path, modification time and size: every instance that names a file shares them, and a file
#: rewritten since is read again.
_tables: dict = {}


def _columns(rgb: np.ndarray) -> np.ndarray:
    """The bins' values as this variant reads them: RGB; luminance in monochrome variants;
    in spectral ones the coefficients of Jakob & Hanika's (2019) smooth spectrum of RGB/s and
    the scale s = 2·max(RGB), as Mitsuba stores unbounded RGB (its ``envmap`` and ``grid``),
    the coefficients computed by Mitsuba's own ``bitmap`` texture."""
    if mi.is_monochromatic:
        return (rgb @ np.array([0.212671, 0.715160, 0.072169], np.float32))[:, None]
    if not mi.is_spectral:
        return rgb
    scale = 2.0 * rgb.max(axis=1, keepdims=True)
    normalised = rgb / np.maximum(scale, 1e-8)
    bitmap = mi.Bitmap(np.ascontiguousarray(normalised.reshape(-1, 180, 3)),
                       mi.Bitmap.PixelFormat.RGB)
    texture = mi.load_dict({"type": "bitmap", "bitmap": bitmap, "raw": False,
                            "filter_type": "nearest"})
    coefficients = np.array(mi.traverse(texture)["data"]).reshape(-1, 3)
    return np.concatenate([coefficients, scale], axis=1).astype(np.float32)


#: The headroom of half precision: values are stored divided by a power of two that puts
#: the largest at most here (half precision's largest is 65504).
HALF_PEAK = 2.0 ** 15


def _stored(columns: np.ndarray) -> tuple[np.ndarray, float]:
    """(rows, unit): the bins' values as stored, ``rows · unit``. RGB and luminance in half
    precision, RGB padded to four channels (a row is one aligned 8-byte load, where a
    three-channel one is three): half the memory of float32, which an interpolated lookup in
    a table of 1.46 million bins is bound by (relative rounding ≤ 2⁻¹¹: 11 significant bits, well
    under the interpolation error); unit, a power of two, keeps the largest value in range.
    Spectral coefficients stay in float32: they are a polynomial's coefficients inside a
    sigmoid, whose rounding to half precision would move the spectra ten times more than the
    values' own (tests/plugins/test_merl.py::test07b_spectral_coefficients_in_float32)."""
    if mi.is_spectral:
        return columns, 1.0
    peak = float(columns.max())
    unit = 2.0 ** math.ceil(math.log2(peak / HALF_PEAK)) if peak > 0 else 1.0
    rows = np.zeros((len(columns), 4 if columns.shape[1] == 3 else 1), np.float16)
    rows[:, :columns.shape[1]] = columns / unit
    return rows, unit


class Table:
    """One measured file in this variant: the bins' values (:func:`_columns`, stored as
    :func:`_stored`, on a cache line: :func:`_aligned`) and the sampler of their density
    (:class:`mi_brdfs.measured.warp.Sampler`)."""

    def __init__(self, measured: data.Measured):
        columns = _columns(measured.rgb)
        self.channels = columns.shape[1]
        rows, self.unit = _stored(columns)
        rows = _aligned(rows)
        stored = dr.float16_array_t if rows.dtype == np.float16 else (lambda kind: kind)
        self.row = stored({1: mi.Float, 3: mi.Vector4f, 4: mi.Vector4f}[self.channels])
        # scalar variants call the methods with Python numbers: the rows stay in NumPy
        scalar = not dr.is_jit_v(mi.Float)
        self.buffer = rows if scalar else stored(mi.Float)(rows.ravel())
        self.sampler = warp.Sampler(measured.density, measured.thetas)
        self.unmeasured = measured.unmeasured

    def spectrum(self, index, si):
        """f in bin ``index`` (flat) as ``UnpolarizedSpectrum`` at ``si.wavelengths``."""
        row = warp.gather_row(self.row, self.buffer, index)  # one gather of the bin's row
        row = [row] if self.channels == 1 else [row[k] for k in range(self.channels)]
        c = [mi.Float(x) * self.unit for x in row]
        if mi.is_spectral:
            return mi.srgb_model_eval(mi.Vector3f(c[0], c[1], c[2]), si.wavelengths) * c[3]
        return mi.UnpolarizedSpectrum(c[0] if mi.is_monochromatic else mi.Color3f(*c))

    def f(self, si, wo, nearest: bool):
        """f at (ωi, ωo): trilinear between bin centres, or the nearest bin."""
        if nearest:
            return self.spectrum(lookup.nearest(si.wi, wo), si)
        total = None
        for index, w in lookup.corners(si.wi, wo):
            term = self.spectrum(index, si) * w
            total = term if total is None else total + term
        return total


class Measured(lobes.TabulatedLobe):
    """The measured BRDF times ``scale``, one glossy component, one-sided."""

    def __init__(self, table: Table, scale, nearest: bool):
        self.table, self.scale, self.nearest = table, scale, nearest
        self.sampler = table.sampler

    def value(self, si, wo, active):
        scale = properties.clip_at(self.scale, si, active, 0.0, math.inf)
        return self.table.f(si, wo, self.nearest) * scale * wo.z

    def weight(self, ctx, si, active):
        return mi.Float(1.0)  # one lobe: the mixture never weighs it


def unmeasured_text(measured: data.Measured) -> str:
    """How many bins above the horizon are unmeasured: in every channel, and in some channels
    only, with how many of those each channel misses (its value is 0 there, the measured
    channels are used)."""
    u, total = measured.unmeasured, measured.rgb.shape[0]
    text = f"{u.every} of {total} bins unmeasured in every channel"
    if u.some:
        text += (f", {u.some} more in some channels only (red {u.red}, green {u.green}, "
                 f"blue {u.blue})")
    return text + "; an unmeasured value is evaluated as 0"


class Merl(mi.BSDF):
    r"""
    .. _bsdf-merl:

    Measured BRDF in MERL's format (:monosp:`merl`)
    -----------------------------------------------

    .. pluginparameters::

     * - filename
       - |string|
       - A MERL ``.binary`` file (Matusik et al. 2003; https://www.merl.com/brdf/), or one
         written by ``mi-brdfs measure``; resolved as Mitsuba resolves file names (Required)

     * - filter_type
       - |string|
       - ``trilinear``: f interpolated between the centres of the bins; ``nearest``: the bin
         the angles fall in, as MERL's own reader (Default: ``trilinear``)

     * - scale
       - |spectrum| or |texture|
       - A factor on f, finite and ≥ 0 (Default: 1)
       - |exposed|, |differentiable|

    A measured isotropic BRDF tabulated in Rusinkiewicz's (1998) half and difference angles
    over 90 × 90 × 180 bins (θh by its square root, θd, φd folded into [0, π)), after the
    conventions of MERL's reader (``mi_brdfs.measured.merl``). The value is

    .. math::

        \texttt{eval} = \text{scale} \cdot f(\theta_h, \theta_d, \phi_d) \cos\theta_o ,

    f interpolated trilinearly in the bins' coordinates (√θh, θd, φd; clamped to the first and
    last bins in θh and θd, periodic in φd), which keeps it reciprocal: swapping ωi and ωo
    turns φd by π. An unmeasured value (a negative entry) counts as 0, in its channel alone;
    the plugin warns how many bins are unmeasured in every channel and how many in some
    channels only, per channel. It is one-sided (0 for either direction below the surface) and has one glossy
    component, as Mitsuba's ``measured``.

    **Sampling.** ωo is drawn through the half vector from a density tabulated per incident
    angle (16 angles; a 64 × 32 grid over (√θh, φh − φi)) that is f·cosθo times the
    Jacobian of the map, bilinear in the grid and linear in θi, sampled in constant time
    (a θi node by its interpolation weight, a cell by Walker's 1977 alias method, the point
    in it by Mitsuba's ``square_to_bilinear``) with an exact pdf; a tenth
    of that density is the cosine-weighted hemisphere's carried into the grid (a defensive
    mixture, Hesterberg 1995), so the density is positive wherever f is.

    **Variants.** The data are RGB. RGB variants use them as they are, monochrome ones their
    luminance, spectral ones Mitsuba's smooth spectra of RGB (Jakob & Hanika 2019) of each bin,
    scaled as Mitsuba scales unbounded RGB (s = 2·max(RGB)) and interpolated as spectra.
    Polarized variants get a depolarizer: the data describe no polarization. RGB and
    monochrome variants store the bins in half precision (relative rounding ≤ 2⁻¹¹, far under
    the interpolation error; a power-of-two unit keeps the largest in range): the lookup is
    bound by memory, and the table starts on a cache line. Spectral ones keep their
    coefficients in float32.

    **Loading.** A file is read once per process while it is unchanged (about 35 MB: a few
    tenths of a second); every instance that names it shares its tables. A missing, short,
    truncated or non-MERL file is one error naming the file and what is wrong.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="merl">
                <string name="filename" value="gold-metallic-paint.binary"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'merl', 'filename': 'gold-metallic-paint.binary'}
    """

    def __init__(self, props):
        super().__init__(props)
        self.filename = properties.filename(props, PLUGIN, "filename", ".binary")
        self.filter_type = properties.choice(props, PLUGIN, "filter_type", "trilinear",
                                             ("trilinear", "nearest"))
        #: The factor on f.
        self.m_scale = properties.texture(props, PLUGIN, "scale", 1.0, 0.0, math.inf)
        measured = data.load(self.filename)
        if measured.stamp not in _tables:
            _tables[measured.stamp] = Table(measured)
        self.table = _tables[measured.stamp]
        if measured.unmeasured.every or measured.unmeasured.some:
            properties.warn(PLUGIN, f"{self.filename}: {unmeasured_text(measured)}")
        self.parameters_changed()

    def parameters_changed(self, keys=None):
        self.lobes = lobes.Mixture([Measured(self.table, self.m_scale,
                                             self.filter_type == "nearest")])
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)

    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def traverse(self, cb):
        cb.put("scale", self.m_scale, mi.ParamFlags.Differentiable)

    def to_string(self):
        return (f"Merl[\n  filename = \"{self.filename}\",\n  filter_type = "
                f"\"{self.filter_type}\",\n  scale = {properties.indent(self.m_scale)}\n]")
