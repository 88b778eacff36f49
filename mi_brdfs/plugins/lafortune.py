"""
Lafortune's reflectance model (Lafortune, Foo, Torrance & Greenberg 1997): a Lambertian term and
any number of generalized cosine lobes, each with its own coefficients Cx, Cy, Cz, exponent and
reflectance, reciprocal, importance-sampled lobe by lobe. The lobe terms live in
:mod:`mi_brdfs.scattering.lafortune`.
"""

from __future__ import annotations

import math
import re

import drjit as dr
import mitsuba as mi
import numpy as np

from ..errors import ParameterError
from ..scattering import lafortune as terms
from . import lobes, properties

PLUGIN = "lafortune"

GLOSSY_FLAGS = lobes.flag("GlossyReflection", "FrontSide")
ANISOTROPIC = lobes.flag("Anisotropic")
DIFFERENTIABLE = mi.ParamFlags.Differentiable

#: A lobe's properties: name -> default (Phong's mirror lobe, with the ``phong`` plugin's
#: exponent and reflectance).
LOBE_DEFAULTS = {"cx": -1.0, "cy": -1.0, "cz": 1.0, "exponent": 30.0,
                 "specular_reflectance": 0.2}
#: A lobe property's name: its kind, "_", its index (decimal, no leading zero).
INDEXED = re.compile(r"^(cx|cy|cz|exponent|specular_reflectance)_(0|[1-9][0-9]*)$")
LEADING_ZERO = re.compile(r"^(cx|cy|cz|exponent|specular_reflectance)_0[0-9]+$")
#: Largest |Cx|, |Cy|, |Cz| accepted: their products with direction components stay far
#: inside float32's range.
COEFFICIENT_MAX = 1e30

UNINDEXED_HINT = ("lafortune's lobe properties carry the lobe's index: cx_0, cy_0, cz_0, "
                  "exponent_0 and specular_reflectance_0 for the first lobe, *_1 for the next")


def lobe_count(props) -> int:
    """
    The number of lobes: one more than the largest index of a lobe property (at least one
    lobe, with every default). A lobe between 0 and it with no property of its own is a gap:
    an error, since the indices of an XML file are then likely mistyped.
    """
    for name in LOBE_DEFAULTS:
        properties.reject(props, PLUGIN, name, UNINDEXED_HINT)
    found = {}
    for key in props.keys():
        m = INDEXED.match(key)
        if m:
            found.setdefault(int(m.group(2)), key)
        elif LEADING_ZERO.match(key):
            raise ParameterError(PLUGIN, key, props[key], "a lobe's index is written without "
                                 "a leading zero (cx_1, not cx_01)")
    count = max(found) + 1 if found else 1
    missing = [i for i in range(count) if i not in found] if found else []
    if missing:
        key = found[min(i for i in found if i > missing[0])]
        raise ParameterError(PLUGIN, key, props[key],
                             f"lobe indices must run 0, 1, 2, … without a gap, and lobe "
                             f"{missing[0]} has no property (give one of its cx_{missing[0]}, "
                             f"exponent_{missing[0]}, …)")
    return count


def _coefficients(props, i: int) -> list[float]:
    """(Cx, Cy, Cz) of lobe ``i``: all three, finite, or none (Phong's mirror lobe)."""
    names = [f"c{axis}_{i}" for axis in "xyz"]
    given = [n for n in names if n in props]
    if 0 < len(given) < 3:
        missing = " and ".join(n for n in names if n not in props)
        raise ParameterError(PLUGIN, given[0], props[given[0]],
                             f"needs {missing} as well (a lobe gives all three coefficients, "
                             f"or none for Phong's mirror lobe −1, −1, 1)")
    return [properties.number(props, PLUGIN, n, LOBE_DEFAULTS[n[:2]], -COEFFICIENT_MAX,
                              COEFFICIENT_MAX) for n in names]


def _check_magnitude(i: int, coefficients, n: float) -> None:
    """The paper's form: cⁿ within float32's range (the lobe's peak, where the model itself
    would otherwise not be finite)."""
    c = max(abs(x) for x in coefficients)
    if c > 0 and n * math.log10(c) > math.log10(terms.MAGNITUDE_MAX):
        raise ParameterError(PLUGIN, f"exponent_{i}", n,
                             f"with max(|cx_{i}|, |cy_{i}|, |cz_{i}|) = {c:g} the lobe's peak "
                             f"cⁿ = 10^{n * math.log10(c):.4g} must be ≤ "
                             f"{terms.MAGNITUDE_MAX:g} (float32's range): lower the exponent "
                             f"or the coefficients, or set normalize = true")


class Glossy(lobes.Lobe):
    """
    One generalized cosine lobe, ρs·K·rⁿ·cosⁿβ·cosθo, β the angle to its principal direction
    d = C∘ωi/r (``constants``: its :class:`~mi_brdfs.scattering.lafortune.Lobe`), sampled by
    cosⁿβ about d.
    """

    kind = "GlossyReflection"

    def __init__(self, specular, constants, component: int, flags: int):
        self.specular, self.constants = specular, constants
        self.component, self.flags = component, flags

    def eval_pdf(self, ctx, si, wo, active):
        active = active & (si.wi.z > 0) & (wo.z > 0)  # one-sided, like `diffuse`
        # ρs·K·rⁿ·cosⁿβ·cosθo, and the density of the cosⁿ lobe about its principal direction
        f, pdf = terms.lobe_value(wo, *terms.axis(si.wi, self.constants), self.constants)
        value = properties.clip_at(self.specular, si, active) * (f * wo.z)
        return dr.select(active, value, 0.0), dr.select(active, pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        d, _ = terms.axis(si.wi, self.constants)
        return terms.sample(d, sample2, self.constants.inv_n1), True

    def weight(self, ctx, si, active):
        """mean(ρs)·K·rⁿ·2π/(n+2): the lobe's albedo were d the normal; it follows ωi."""
        return dr.mean(properties.clip_at(self.specular, si, active)) * \
            self.constants.albedo_scale * terms.axis(si.wi, self.constants)[1]


class Lafortune(mi.BSDF):
    r"""
    .. _bsdf-lafortune:

    Lafortune's generalized cosine lobes (:monosp:`lafortune`)
    ----------------------------------------------------------

    .. pluginparameters::

     * - diffuse_reflectance
       - |spectrum| or |texture|
       - Diffuse albedo ρd, finite and within [0, 1] (Default: 0.5)
       - |exposed|, |differentiable|

     * - specular_reflectance_0, specular_reflectance_i
       - |spectrum| or |texture|
       - Reflectance ρs of lobe 0, lobe i; finite and within [0, 1] (Default: 0.2)
       - |exposed|, |differentiable|

     * - cx_0, cy_0, cz_0, cx_i, cy_i, cz_i
       - |float|
       - Coefficients C of lobe 0, lobe i: any sign, finite; all three or none
         (Default: −1, −1, 1, Phong's mirror lobe)
       - |exposed| (JIT variants), |differentiable|

     * - exponent_0, exponent_i
       - |float|
       - Exponent n of lobe 0, lobe i, finite and within [0, 1e30] (Default: 30)
       - |exposed| (JIT variants), |differentiable|

     * - normalize
       - |bool|
       - ``true``: each lobe is scaled so that ρs is its largest albedo, as Phong's modified
         lobe; ``false``: the paper's form, where C carries the lobe's magnitude
         (Default: ``true``)
       -

     * - preset
       - |string|
       - A published fit that fills every parameter the scene does not give (explicit ones
         win): ``ngan:<material>``, Ngan et al. 2005's one-lobe Lafortune fit to a MERL
         material (lobe 0, ``normalize`` true); docs/presets.md lists the materials and the
         conversion (Default: none)
       -

    The lobes are numbered 0, 1, 2, … (decimal, no leading zero: ``cx_01`` is an error); their
    count is one more than the largest index given (one lobe, lobe 0, when none is given).
    Every lobe up to it needs at least one property of its own: a gap (``cx_1``, ``cy_1``,
    ``cz_1`` with nothing for lobe 0) is an error, as its indices are likely mistyped. Any
    other property of a lobe left out takes its default. With u = ωi, v = ωo in the local frame (z the normal), for each lobe
    gᵢ = Cx,i ux vx + Cy,i uy vy + Cz,i uz vz and :math:`c_i = \max(|C_{x,i}|, |C_{y,i}|,
    |C_{z,i}|)`:

    .. math::

        f = \frac{\rho_d}{\pi} + \sum_i \rho_{s,i}\,K_i \max\!\left(0, \frac{g_i}{c_i}\right)^{n_i},
        \qquad K_i = \frac{n_i+2}{2\pi}\ (\texttt{normalize}) \ \text{or}\ c_i^{\,n_i}

    so that ``normalize`` = false is the paper's f = ρs·max(0, g)ⁿ. A lobe whose g is ≤ 0
    contributes 0 (for n = 0 too); ``eval`` returns f·cosθo, one-sided. g is symmetric in u
    and v, so every configuration is reciprocal. The paper's special cases: Cx = Cy = −Cz is
    Phong's mirror lobe (with ``normalize``, exactly the ``phong`` plugin's ``normalized``
    mirror lobe, Lafortune & Willems 1994; without, with C = (−1, −1, 1), its ``lecture``
    form), Cx = Cy > 0 reflects back towards the light (retro-reflection), and
    :math:`|C_z| < -C_x = -C_y` moves the lobe's peak towards grazing angles (off-specular
    reflection).
    Cx ≠ Cy is anisotropic. With ``normalize`` no lobe reflects more than its ρs at any angle
    (the albedo of a cosⁿ lobe is largest about the normal; a lobe with :math:`|C_z| =
    c` reaches ρs there, at normal incidence), so the model conserves energy if
    ρd + Σ ρs,i ≤ 1; a warning names that bound where it
    exceeds 1 (for ``normalize`` = false: ρd + Σ ρs,i·cᵢⁿ·2π/(nᵢ+2)), values kept.

    **Sampling.** For given ωi, lobe i is cosⁿ of the angle to its principal direction
    d = C∘ωi/‖C∘ωi‖, which ``sample()`` draws with density (n+1)/(2π)·cosⁿβ (Phong's
    sampler about d), or it draws the cosine-weighted hemisphere for the diffuse term. It picks
    among them in proportion to mean(ρd) and, per lobe, mean(ρs)·K·(‖C∘ωi‖/c)ⁿ·2π/(n+2) (the
    lobe's albedo were d the normal: its weight follows ωi; the means over channels at the hit
    point); ``pdf()`` and ``bs.pdf`` are
    the mixture density over all lobes, and samples below the horizon have weight 0.

    A lobe whose reflectance is the constant 0 is left out entirely (flags, components,
    sampling, cost, ``mi.traverse``), and so is a zero diffuse term; the components are the
    diffuse term, then the lobes left in, in order (``ctx.component`` picks one). So a
    component's index is not its lobe's: with the diffuse term, lobe i is component i + 1,
    less one for each lobe before it that is left out. Parameter names keep the lobe's index. Float32: the lobe is evaluated as
    Phong's, exp(n·log1p(−(1 − cos β))) with 1 − cos β free of cancellation, and no NaN, Inf
    or negative value is returned anywhere from n = 0 to 1e30, for C = 0 and at grazing
    angles.

    **Polarized variants.** The model describes no polarization: ``eval`` and the sample
    weights are depolarizers (the Mueller matrix with the value in its first element alone), as
    Mitsuba's ``diffuse`` returns them.

    .. tabs::
        .. code-tab:: xml

            <bsdf type="lafortune">
                <rgb name="diffuse_reflectance" value="0.3, 0.2, 0.1"/>
                <float name="cx_0" value="-1"/>
                <float name="cy_0" value="-1"/>
                <float name="cz_0" value="0.6"/>
                <float name="exponent_0" value="20"/>
                <float name="specular_reflectance_0" value="0.4"/>
                <float name="cx_1" value="1"/>
                <float name="cy_1" value="1"/>
                <float name="cz_1" value="1"/>
                <float name="exponent_1" value="5"/>
                <float name="specular_reflectance_1" value="0.2"/>
            </bsdf>

        .. code-tab:: python

            {'type': 'lafortune', 'diffuse_reflectance': {'type': 'rgb', 'value': [0.3, 0.2, 0.1]},
             'cx_0': -1.0, 'cy_0': -1.0, 'cz_0': 0.6, 'exponent_0': 20.0,
             'specular_reflectance_0': 0.4,
             'cx_1': 1.0, 'cy_1': 1.0, 'cz_1': 1.0, 'exponent_1': 5.0,
             'specular_reflectance_1': 0.2}
    """

    def __init__(self, props):
        super().__init__(props)
        properties.preset(props, PLUGIN)  # a preset's parameters, where the scene gives none
        #: ``true``: Phong's normalisation per lobe; ``false``: the paper's form
        self.m_normalize = properties.boolean(props, PLUGIN, "normalize", True)
        self.m_diffuse_reflectance = properties.reflectance(props, PLUGIN,
                                                            "diffuse_reflectance", 0.5)
        #: Per lobe: Cx, Cy, Cz and n (Float: updatable in JIT variants), and ρs.
        self.m_cx, self.m_cy, self.m_cz, self.m_exponent = [], [], [], []
        self.m_specular_reflectance, anisotropic = [], []
        for i in range(lobe_count(props)):
            cx, cy, cz = _coefficients(props, i)
            n = properties.number(props, PLUGIN, f"exponent_{i}", LOBE_DEFAULTS["exponent"],
                                  0.0, terms.EXPONENT_MAX)
            if not self.m_normalize:
                _check_magnitude(i, (cx, cy, cz), n)
            anisotropic.append(cx != cy)
            for values, x in zip((self.m_cx, self.m_cy, self.m_cz, self.m_exponent),
                                 (cx, cy, cz, n)):
                values.append(mi.Float(x))
            self.m_specular_reflectance.append(properties.reflectance(
                props, PLUGIN, f"specular_reflectance_{i}", LOBE_DEFAULTS["specular_reflectance"]))
        # Terms in component order, the diffuse one first; one whose reflectance is the
        # constant 0 is left out
        self._has_diffuse = not properties.is_zero(self.m_diffuse_reflectance)
        self._present = [not properties.is_zero(rho) for rho in self.m_specular_reflectance]
        self._flags = [GLOSSY_FLAGS | (ANISOTROPIC if a else 0) for a in anisotropic]
        self.parameters_changed()
        self.m_components, self.m_flags = lobes.components(self.lobes.lobes)
        self._warn_energy(props)

    def _warn_energy(self, props):
        """Warn (values kept) where ρd + Σ ρs,i·K·2π/(n+2), the bound of the albedo, exceeds
        1 in some channel (one value stands for every channel)."""
        total = properties.upper_bound(props, "diffuse_reflectance", self.m_diffuse_reflectance)
        for i, rho in enumerate(self.m_specular_reflectance):
            bound = properties.upper_bound(props, f"specular_reflectance_{i}", rho)
            if total is None or bound is None:
                return  # a bound that cannot be known at load: nothing to say
            scale = float(np.asarray(self._lobes[i].albedo_scale).ravel()[0])
            total = np.add(total, np.multiply(bound, scale))
        total = float(np.max(total))
        if total > 1.0 + 1e-6:  # not for rounding: an <rgb> 0.8 is stored as 0.800000012
            properties.warn(PLUGIN, f"ρd + Σ ρs,i·Kᵢ·2π/(nᵢ+2), the bound of the albedo, "
                                    f"reaches {total:g} > 1: the BSDF may reflect more light "
                                    f"than it receives; values kept")

    # the lobes and the diffuse term, each with its sampler, mixed by their albedos
    sample, eval, pdf, eval_pdf = lobes.sample, lobes.eval, lobes.pdf, lobes.eval_pdf
    eval_diffuse_reflectance = lobes.eval_diffuse_reflectance

    def parameters_changed(self, keys=()):
        """Each lobe's constants (opaque: a changed parameter updates the kernel's inputs
        instead of recompiling it), and the terms; sampling takes the lobes first."""
        self._lobes = [terms.Lobe(*params, self.m_normalize) for params in
                       zip(self.m_cx, self.m_cy, self.m_cz, self.m_exponent)]
        dr.make_opaque(*[v for lobe in self._lobes for v in lobe.arrays()])
        present = [i for i, p in enumerate(self._present) if p]
        glossy = [Glossy(self.m_specular_reflectance[i], self._lobes[i], component,
                         self._flags[i])
                  for component, i in enumerate(present, start=int(self._has_diffuse))]
        diffuse = [lobes.Diffuse(self.m_diffuse_reflectance)] if self._has_diffuse else []
        self.lobes = lobes.Mixture(glossy + diffuse)

    def traverse(self, cb):
        # Only the parameters of terms that exist: the lobe structure is fixed at load time.
        if self._has_diffuse:
            cb.put("diffuse_reflectance", self.m_diffuse_reflectance, DIFFERENTIABLE)
        for i, present in enumerate(self._present):
            if not present:
                continue
            cb.put(f"specular_reflectance_{i}", self.m_specular_reflectance[i], DIFFERENTIABLE)
            if dr.is_jit_v(mi.Float):  # a Python float cannot be updated in scalar variants
                for name in ("cx", "cy", "cz", "exponent"):
                    cb.put(f"{name}_{i}", getattr(self, f"m_{name}")[i], DIFFERENTIABLE)

    def to_string(self):
        text = [f"Lafortune[\n  normalize = {str(self.m_normalize).lower()},\n"
                f"  diffuse_reflectance = {properties.indent(self.m_diffuse_reflectance)},\n"]
        for i in range(len(self._lobes)):
            text.append(f"  lobe {i} = [cx = {self.m_cx[i]}, cy = {self.m_cy[i]}, "
                        f"cz = {self.m_cz[i]}, exponent = {self.m_exponent[i]},\n"
                        f"    specular_reflectance = "
                        f"{properties.indent(self.m_specular_reflectance[i], 4)}],\n")
        return "".join(text).rstrip(",\n") + "\n]"
