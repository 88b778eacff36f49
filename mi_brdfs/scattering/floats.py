"""
The terms of this package compiled for Python floats, for scalar variants.

The terms are written once, with drjit's elementwise functions, and serve every variant. In JIT
variants they are traced into the render kernel. In scalar variants Mitsuba calls a plugin once
per ray with Python floats, and there a call of a ``dr.`` function costs more than the
arithmetic it does. :func:`specialise` therefore recompiles a module's functions from their own
source, with these rewrites of the syntax tree and nothing else:

==============================  ==========================================================
``dr.select(c, a, b)``          ``(a if c else b)``
``dr.maximum(a, b)``            ``(a if a > b else b)``, each argument evaluated once
``dr.minimum(a, b)``            ``(a if a < b else b)``, each argument evaluated once
``dr.fma(a, b, c)``             ``a * b + c``
``dr.square(x)``                ``x * x``, ``x`` evaluated once
``dr.abs(x)``                   ``abs(x)``
``dr.sqrt(x)``, ``dr.rsqrt``,   the ``math`` function where it cannot raise (x > 0, no
``dr.rcp``, ``dr.exp``,         overflow), else drjit's own (NaN, ±inf, 0), ``x`` evaluated
``dr.log``                      once
``dr.pi``, ``dr.inv_pi``, ...   the constant's value
``mi.Vector3f``                 :class:`Vec3`: three floats whose ``.x`` costs a fifth of a
                                scalar ``mi.Vector3f``'s
``mi.<name>``                   the current variant's object, bound once
==============================  ==========================================================

A term that hands a direction to Mitsuba's own functions passes it through
``vector.mitsuba_vector``, which the compiled terms replace by :func:`to_mitsuba`; a plugin
converts its directions with :func:`to_mitsuba` where they leave the terms (``bs.wo``).

Every other name, call and operation is kept, in the same order. The compiled functions call
each other, and the compiled versions of the functions their module imports from other modules
of :mod:`mi_brdfs.scattering` (``microfacet`` uses ``vector.dot``), so a term that calls another
runs specialised throughout. ``tests/scattering/test_floats.py`` checks that every
compiled function returns what the original returns on the same floats.
"""

from __future__ import annotations
import __future__

import ast
import inspect
import itertools
import sys
from types import ModuleType, SimpleNamespace

import math

import drjit as dr
import mitsuba as mi

#: drjit's elementwise functions computed by ``math`` where ``math`` cannot raise, and by drjit
#: itself elsewhere (below or at 0, near overflow, NaN): (drjit name, expression template), where
#: ``{x}`` is the argument's first use and ``{y}`` every later one.
MATH = {
    "abs": "abs({x})",
    "sqrt": "(_math.sqrt({y}) if {x} >= 0.0 else _dr.sqrt({y}))",
    "rsqrt": "(1.0 / _math.sqrt({y}) if {x} > 0.0 else _dr.rsqrt({y}))",
    "rcp": "(1.0 / {y} if {x} != 0.0 else _dr.rcp({y}))",
    "exp": "(_math.exp({y}) if -700.0 < {x} < 700.0 else _dr.exp({y}))",
    "log": "(_math.log({y}) if {x} > 0.0 else _dr.log({y}))",
}

#: drjit constants inlined by value.
CONSTANTS = ("pi", "inv_pi", "two_pi", "inv_two_pi", "four_pi", "inv_four_pi", "sqrt_two",
             "inv_sqrt_two", "inf", "nan", "e")

_cache: dict = {}


class _Rewrite(ast.NodeTransformer):
    """The rewrites of the module docstring's table, on one module's syntax tree."""

    def __init__(self):
        self._names = (f"_f{i}" for i in itertools.count())
        self.mitsuba: set[str] = set()  # the mi.<name> that were bound

    @staticmethod
    def _dr(node, names) -> str | None:
        """The attribute name of ``dr.<name>`` when ``node`` is one of ``names``."""
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id == "dr" and node.attr in names):
            return node.attr
        return None

    def _once(self, expr):
        """(first use, later uses) of ``expr``: a name or constant as is, else a walrus."""
        if isinstance(expr, (ast.Name, ast.Constant)):
            return expr, expr
        name = next(self._names)
        return (ast.NamedExpr(target=ast.Name(name, ast.Store()), value=expr),
                ast.Name(name, ast.Load()))

    def visit_Attribute(self, node):
        name = self._dr(node, CONSTANTS)
        if name is not None:
            return ast.copy_location(ast.Constant(float(getattr(dr, name))), node)
        if isinstance(node.value, ast.Name) and node.value.id == "mi":
            # mi.<name> resolves per variant, at every call: bound once for this variant
            self.mitsuba.add(node.attr)
            return ast.copy_location(ast.Name(f"_mi_{node.attr}", ast.Load()), node)
        return self.generic_visit(node)

    def visit_Call(self, node):
        self.generic_visit(node)
        fn = self._dr(node.func, ("select", "maximum", "minimum", "fma", "square", *MATH))
        if fn is None or node.keywords:
            return node
        args = node.args
        if fn in MATH:
            if len(args) != 1:
                return node
            first, again = self._once(args[0])
            # the template, parsed with placeholders that are then swapped for the argument
            template = ast.parse(MATH[fn].format(x="_X_", y="_Y_"), mode="eval").body
            out = _Substitute({"_X_": first, "_Y_": again}).visit(template)
            return ast.copy_location(out, node)
        if fn == "select":
            out = ast.IfExp(test=args[0], body=args[1], orelse=args[2])
        elif fn in ("maximum", "minimum"):
            (a_first, a), (b_first, b) = self._once(args[0]), self._once(args[1])
            op = ast.Gt() if fn == "maximum" else ast.Lt()
            out = ast.IfExp(test=ast.Compare(a_first, [op], [b_first]), body=a, orelse=b)
        elif fn == "fma":
            out = ast.BinOp(ast.BinOp(args[0], ast.Mult(), args[1]), ast.Add(), args[2])
        else:  # square
            first, again = self._once(args[0])
            out = ast.BinOp(first, ast.Mult(), again)
        return ast.copy_location(out, node)


class _Substitute(ast.NodeTransformer):
    """Replace the placeholder names of a :data:`MATH` template by the argument's nodes (the
    first occurrence of ``_X_`` by its first use; a template evaluates ``_X_`` first)."""

    def __init__(self, nodes):
        self.nodes = nodes

    def visit_Name(self, node):
        return self.nodes.get(node.id, node)


class Vec3:
    """
    A direction of three Python floats with ``mi.Vector3f``'s ``x``, ``y``, ``z``: what the
    compiled terms build (an attribute read costs 11 ns against 50 ns for a scalar
    ``mi.Vector3f``, and the terms read dozens per call). Iterable, like ``mi.Vector3f``.
    """

    __slots__ = ("x", "y", "z")

    def __init__(self, x, y, z):
        self.x, self.y, self.z = x, y, z

    def __iter__(self):
        return iter((self.x, self.y, self.z))

    def __repr__(self):
        return f"Vec3({self.x!r}, {self.y!r}, {self.z!r})"


def to_vec3(v) -> Vec3:
    """A direction as a :class:`Vec3`: a ``mi.Vector3f``'s floats, or a list's or tuple's
    rounded as ``mi.Vector3f`` rounds them (as Mitsuba's BSDFs take them)."""
    if type(v) is Vec3:
        return v
    return Vec3(*(v if type(v) is mi.Vector3f else mi.Vector3f(v)))


def to_mitsuba(v):
    """A direction as the current variant's ``mi.Vector3f`` (a :class:`Vec3` is converted)."""
    return v if type(v) is not Vec3 else mi.Vector3f(v.x, v.y, v.z)


#: Functions of the terms that the compiled modules replace (by name).
OVERRIDES = {"mitsuba_vector": to_mitsuba}


def specialise(module: ModuleType) -> SimpleNamespace:
    """
    The functions of ``module`` compiled for Python floats (see the module docstring), as a
    namespace with the same names; its other public names are shared. Cached per module and
    variant.
    """
    key = (module.__name__, mi.variant())
    if key in _cache:
        return _cache[key]
    rewrite = _Rewrite()
    tree = rewrite.visit(ast.parse(inspect.getsource(module)))
    functions = [node for node in tree.body if isinstance(node, ast.FunctionDef)]
    code = compile(ast.fix_missing_locations(ast.Module(functions, [])),
                   f"<{module.__name__} for floats>", "exec",
                   flags=__future__.annotations.compiler_flag, dont_inherit=True)
    namespace = dict(vars(module))
    namespace.update({f"_mi_{name}": getattr(mi, name) for name in rewrite.mitsuba})
    namespace.update(_math=math, _dr=dr)
    if "Vector3f" in rewrite.mitsuba:
        namespace["_mi_Vector3f"] = Vec3
    for name, value in vars(module).items():  # terms imported from sibling modules
        home = getattr(value, "__module__", None) or ""
        if (inspect.isfunction(value) and home != module.__name__
                and home.startswith(__package__ + ".")):
            namespace[name] = getattr(specialise(sys.modules[home]), name)
    exec(code, namespace)  # noqa: S102 - the package's own source, rewritten above
    namespace.update({name: fn for name, fn in OVERRIDES.items() if name in namespace})
    result = SimpleNamespace(**{f.name: namespace[f.name] for f in functions})
    for name in dir(module):  # constants and other public names, shared
        if not name.startswith("__") and not hasattr(result, name):
            setattr(result, name, namespace.get(name, getattr(module, name)))
    _cache[key] = result
    return result
