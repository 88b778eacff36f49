"""
The terms of this package, and the methods of its plugins, compiled for Python floats, for
scalar variants.

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
``NAME`` (a module constant)    its value, where NAME is an upper-case module-level int or
                                float that the function does not bind itself
``f(a, b)``                     the expression ``f`` returns, with ``a``, ``b`` put in for
                                its parameters, where ``f`` is a term whose body is one
                                ``return`` of an expression of its parameters alone and each
                                argument is a name, a constant or an attribute of a name
                                (reads without side effects: :func:`_inlinable`)
==============================  ==========================================================

:func:`specialise_class` compiles a plugin class's methods the same way, and also rewrites
the calls of its variant tools (:func:`mi_brdfs.plugins._common.variant_tools`, ``V``), as
they are defined in scalar variants:

==============================  ==========================================================
``V.select(c, a, b)``           ``(a if c else type(a)(b))``, ``a`` evaluated once
``V.choose(c, f, g)``           ``(f() if c else g())``; the body of a ``lambda:`` in place
``V.none(x)``                   ``(not x)``
``V.depolarize(x)``             ``x`` (not in polarized variants)
==============================  ==========================================================

Beyond expressions, the body of a term (or of a plugin's own method) with a single exit, one
``return`` at its end, is taken in where it is called as a statement of its own, ``x = f(...)``
or ``return f(...)``: its parameters bound to the arguments (an argument that cannot change
before the body reads it is put in directly), its names renamed apart, the globals of another
module's term bound under names of their own (:meth:`_Rewrite._body_of`). A direction that a
function only reads by component, or hands to Mitsuba, is then kept as three local floats
(:func:`_unbox`); one also handed on whole has its components read into locals once
(:func:`_scalarise`). :func:`configure` compiles an instance's ``eval_pdf`` and ``sample`` once
more, for its configuration: its switches, and which optional parts are None, put in as
constants and every test they decide folded away (:func:`_fold`), after :data:`PROMOTE_AFTER`
calls.

A term that hands a direction to Mitsuba's own functions passes it through
``vector.mitsuba_vector``, which the compiled terms replace by :func:`to_mitsuba`, and reads
one back through ``vector.terms_vector`` (:func:`read_vector`); a plugin converts its
directions with :func:`to_mitsuba` where they leave the terms (``bs.wo``).

Every other name, call and operation is kept, in the same order. The compiled functions call
each other, and the compiled versions of the functions their module imports from other modules
of :mod:`mi_brdfs.scattering` (``microfacet`` uses ``vector.dot``), so a term that calls another
runs specialised throughout. ``tests/scattering/test_floats.py`` checks that every compiled
function returns what the original returns on the same floats, and that the compiled and
configured plugin class returns bit for bit what its generic methods return.
"""

from __future__ import annotations
import __future__

import ast
import inspect
import itertools
import sys
import threading
import types
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


def _copy(node):
    """A copy of a syntax tree (``copy.deepcopy`` does the same, five times slower)."""
    if isinstance(node, ast.AST):
        new = node.__class__.__new__(node.__class__)
        for field in node._fields:
            setattr(new, field, _copy(getattr(node, field, None)))
        for attribute in node._attributes:
            if hasattr(node, attribute):
                setattr(new, attribute, getattr(node, attribute))
        return new
    if isinstance(node, list):
        return [_copy(item) for item in node]
    return node


class _Rewrite(ast.NodeTransformer):
    """The rewrites of the module docstring's table, on one module's syntax tree."""

    def __init__(self, constants=None, inline=None, tools=None, bodies=None):
        self._names = (f"_f{i}" for i in itertools.count())
        self.mitsuba: set[str] = set()  # the mi.<name> that were bound
        #: module constants put in by value: name -> int or float
        self.constants = {} if constants is None else constants
        #: inlinable terms: name, or (namespace name, name) -> (parameters, expression); the
        #: caller's dict itself (specialise adds each term as it is compiled)
        self.inline = {} if inline is None else inline
        #: the variant tools' name whose calls are rewritten (specialise_class), or None
        self.tools = tools
        #: terms whose bodies a statement ``x = f(...)`` or ``return f(...)`` takes in: name, or
        #: (namespace name, name) -> (FunctionDef, the globals it runs in, or None for this
        #: module's own); the caller's dict itself
        self.bodies = {} if bodies is None else bodies
        #: the globals the compiled code needs for the bodies it took in: name -> value
        self.injected: dict = {}
        self._bound: list = []  # the names each enclosing function binds (_Lazy)

    def visit_FunctionDef(self, node):
        self._bound.append(_Lazy(node))
        try:
            return self.generic_visit(node)
        finally:
            self._bound.pop()

    def _comprehension(self, node):
        """Comprehensions are kept as they are: a rewrite may bring in an assignment
        expression, which Python forbids in a comprehension's iterable."""
        return node

    visit_ListComp = visit_SetComp = visit_DictComp = visit_GeneratorExp = _comprehension

    def visit_Name(self, node):
        if (isinstance(node.ctx, ast.Load) and node.id in self.constants
                and not any(node.id in bound for bound in self._bound)):
            return ast.copy_location(ast.Constant(self.constants[node.id]), node)
        return node

    def _key(self, func):
        """The key of :attr:`inline` and :attr:`bodies` a callee ``f`` or ``ns.f`` has, or None
        (a name the function binds itself)."""
        if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            key, name = (func.value.id, func.attr), func.value.id
            if name == "self":  # (a method's own first parameter: specialise_class)
                return key
        elif isinstance(func, ast.Name):
            key = name = func.id
        else:
            return None
        return None if any(name in bound for bound in self._bound) else key

    def _inlined(self, node):
        """The callee's expression with the arguments put in, or None."""
        key = self._key(node.func)
        target = self.inline.get(key) if key is not None else None
        if target is None or node.keywords or len(node.args) != len(target[0]) or \
                not all(_simple(a) for a in node.args):
            return None
        params, expr = target
        names = {}  # the callee's walrus temporaries, renamed to this function's own
        for sub in ast.walk(expr):
            if isinstance(sub, ast.NamedExpr):
                names[sub.target.id] = next(self._names)
        out = _Substitute(dict(zip(params, node.args)), names).visit(_copy(expr))
        return ast.copy_location(out, node)

    def visit_Assign(self, node):
        node = self.generic_visit(node)
        taken = self._body_of(node.value) if len(node.targets) == 1 else None
        if taken is None:
            return node
        statements, result = taken
        return statements + [ast.copy_location(ast.Assign(node.targets, result), node)]

    def visit_Return(self, node):
        node = self.generic_visit(node)
        taken = self._body_of(node.value) if node.value is not None else None
        if taken is None:
            return node
        statements, result = taken
        return statements + [ast.copy_location(ast.Return(result), node)]

    def _body_of(self, call):
        """
        (statements, expression) that do what ``call`` does, for a term of :attr:`bodies`
        (:func:`_body`): its parameters bound to the arguments (a simple argument of a
        parameter the body never assigns put in directly), its statements, and the
        expression it returns; every name it binds renamed to a name of its own, the globals
        of another module's term bound in :attr:`injected`. None for other calls.
        """
        if not isinstance(call, ast.Call) or any(isinstance(a, ast.Starred) for a in call.args) \
                or any(k.arg is None for k in call.keywords):
            return None
        key = self._key(call.func)
        entry = self.bodies.get(key) if key is not None else None
        if entry is None:
            return None
        fn, home = entry
        params, defaults = [p.arg for p in fn.args.args], fn.args.defaults
        args = list(call.args)
        if type(key) is tuple and key[0] == "self":  # a method: self is its first argument
            args.insert(0, ast.Name("self", ast.Load()))
        # each parameter's argument: positional, by keyword, or the default
        defaults = dict(zip(params[len(params) - len(defaults):], defaults))
        keywords = {k.arg: k.value for k in call.keywords}
        if len(args) > len(params) or set(keywords) - set(params[len(args):]):
            return None
        for p in params[len(args):]:
            if p not in keywords and p not in defaults:
                return None
            args.append(keywords[p] if p in keywords else _copy(defaults[p]))
        body = _docless(fn.body)
        nodes = [n for stmt in body for n in ast.walk(stmt)]
        stored = {n.id for n in nodes
                  if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
        globals_read = {n.id for n in nodes if isinstance(n, ast.Name)} - stored - set(params)
        if home is None and any(name in bound for name in globals_read for bound in self._bound):
            return None  # (this module's globals: a name the caller binds would hide one)
        tag = next(_unique)
        rename = {n: f"_i{tag}_{n}" for n in stored | set(params)}
        # an argument is put in directly where its value cannot change before the body reads
        # it: a name or constant (the body's own names are renamed), or an attribute where
        # the body neither stores an attribute nor calls anything
        changes = any(isinstance(n, ast.Call) or (isinstance(n, ast.Attribute) and
                                                 not isinstance(n.ctx, ast.Load)) for n in nodes)
        put = {p: a for p, a in zip(params, args) if p not in stored and _simple(a)
               and (not changes or not isinstance(a, ast.Attribute))}
        statements = [ast.Assign([ast.Name(rename[p], ast.Store())], a)
                      for p, a in zip(params, args) if p not in put]
        aliases = {}
        if home is not None:  # another module's term: its globals, bound here
            for name in sorted(globals_read):
                if name in home:
                    aliases[name] = f"_g{next(_unique)}"
                    self.injected[aliases[name]] = home[name]
        out = _Substitute(put, {**rename, **aliases})
        statements += [out.visit(_copy(stmt)) for stmt in body[:-1]]
        result = out.visit(_copy(body[-1].value))
        for stmt in statements:
            ast.copy_location(stmt, call)
        return statements, result

    def _tools_call(self, node):
        """A call of the variant tools rewritten (the module docstring's second table), or
        None."""
        func = node.func
        if not (self.tools and isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name)
                and func.value.id == self.tools) or node.keywords:
            return None
        args, name = node.args, func.attr
        if name == "select" and len(args) == 3:
            c, a, b = args
            if _simple(a):
                first, again = a, _copy(a)
            else:  # a in each branch, evaluated in the one taken
                t = next(self._names)
                first = ast.NamedExpr(ast.Name(t, ast.Store()), a)
                again = ast.NamedExpr(ast.Name(t, ast.Store()), _copy(a))
            other = ast.Call(ast.Call(ast.Name("type", ast.Load()), [again], []), [b], [])
            return ast.IfExp(test=c, body=first, orelse=other)
        if name == "choose" and len(args) == 3:
            def call(f):
                if isinstance(f, ast.Lambda) and not (f.args.args or f.args.vararg or
                                                      f.args.kwonlyargs or f.args.kwarg):
                    return f.body
                return ast.Call(f, [], [])
            return ast.IfExp(test=args[0], body=call(args[1]), orelse=call(args[2]))
        if name == "none" and len(args) == 1:
            return ast.UnaryOp(ast.Not(), args[0])
        if name == "depolarize" and len(args) == 1 and not mi.is_polarized:
            return args[0]
        return None

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
        out = self._tools_call(node)
        if out is None:
            out = self._inlined(node)
        if out is not None:
            return ast.copy_location(out, node)
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
    """Replace names by nodes (copies of them): the placeholders of a :data:`MATH` template
    (the first occurrence of ``_X_`` by its first use; a template evaluates ``_X_`` first), or
    an inlined term's parameters by its arguments; ``rename`` renames walrus temporaries."""

    def __init__(self, nodes, rename=None):
        self.nodes, self.rename = nodes, rename or {}

    def visit_Name(self, node):
        if node.id in self.nodes:
            return _copy(self.nodes[node.id])
        if node.id in self.rename:
            return ast.copy_location(ast.Name(self.rename[node.id], node.ctx), node)
        return node


def _simple(node) -> bool:
    """A name, a (negated) constant, or an attribute of a name (``wi.z``, ``self.m_alpha``):
    evaluated again where an inlined term uses its parameter twice, at no cost but the read."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return isinstance(node.operand, ast.Constant)
    while isinstance(node, ast.Attribute):
        node = node.value
    return isinstance(node, (ast.Name, ast.Constant))


def _bound_names(fn) -> set[str]:
    """The names a function binds: its parameters and every name it stores, with those of
    the functions and lambdas nested in it (their parameters of every kind), ``except ... as``
    and ``import ... as``."""
    names = set()
    for sub in ast.walk(fn):
        if isinstance(sub, ast.Name) and isinstance(sub.ctx, (ast.Store, ast.Del)):
            names.add(sub.id)
        elif isinstance(sub, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            a = sub.args
            names |= {p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)}
            names |= {p.arg for p in (a.vararg, a.kwarg) if p is not None}
            if sub is not fn and not isinstance(sub, ast.Lambda):
                names.add(sub.name)
        elif isinstance(sub, ast.ExceptHandler) and sub.name:
            names.add(sub.name)
        elif isinstance(sub, (ast.Import, ast.ImportFrom)):
            names |= {(alias.asname or alias.name).split(".")[0] for alias in sub.names}
    return names


class _Lazy:
    """:func:`_bound_names` of a function, computed when first asked (most visits never ask)."""

    def __init__(self, fn):
        self.fn, self.names = fn, None

    def __contains__(self, name) -> bool:
        if self.names is None:
            self.names = _bound_names(self.fn)
        return name in self.names


#: Numbers for the names that inlined bodies bind, unique across every compiled function.
_unique = itertools.count()


def _docless(body: list) -> list:
    """A function body without its docstring."""
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        return body[1:]
    return body


#: Statements and expressions a term whose body is taken in must not hold: new scopes,
#: control flow that leaves it, names of other scopes.
_NOT_IN_BODIES = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef, ast.Global,
                  ast.Nonlocal, ast.Yield, ast.YieldFrom, ast.Await, ast.Try, ast.With,
                  ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp, ast.Import,
                  ast.ImportFrom, ast.Delete, ast.Return, ast.Break, ast.Continue)


def _plain(fn: ast.FunctionDef) -> bool:
    """Whether ``fn`` has no decorator, only positional parameters and constant defaults, and
    ends in a ``return`` of a value (after a docstring): what inlining and taking in need."""
    a, body = fn.args, _docless(fn.body)
    return not (fn.decorator_list or a.posonlyargs or a.vararg or a.kwonlyargs or a.kwarg
                or not all(isinstance(d, ast.Constant) for d in a.defaults) or not body
                or not isinstance(body[-1], ast.Return) or body[-1].value is None)


def _body(fn: ast.FunctionDef) -> bool:
    """Whether callers may take in the body of ``fn`` (:meth:`_Rewrite._body_of`): a
    :func:`_plain` function with nothing of :data:`_NOT_IN_BODIES` before its ``return``
    nor in its value."""
    if not _plain(fn):
        return False
    body = _docless(fn.body)
    return not any(isinstance(n, _NOT_IN_BODIES) for stmt in body[:-1] for n in ast.walk(stmt)) \
        and not any(isinstance(n, _NOT_IN_BODIES) for n in ast.walk(body[-1].value))


#: Expression nodes an inlined term may hold (no lambda, comprehension or call of anything
#: but the names below).
_PURE = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.BoolOp, ast.Compare, ast.IfExp,
         ast.NamedExpr, ast.Attribute, ast.Name, ast.Constant, ast.Call, ast.operator,
         ast.unaryop, ast.boolop, ast.cmpop, ast.expr_context)
#: The free names an inlined term may use besides its parameters.
_FREE = {"abs", "_math", "_dr"}


def _inlinable(fn: ast.FunctionDef):
    """(parameters, expression) of a rewritten term whose body is one ``return`` of an
    expression of its parameters alone (after a docstring), else None."""
    body = _docless(fn.body)
    if not _plain(fn) or len(body) != 1 or fn.args.defaults:
        return None
    expr, params = body[0].value, [p.arg for p in fn.args.args]
    temps = {n.target.id for n in ast.walk(expr) if isinstance(n, ast.NamedExpr)}
    for sub in ast.walk(expr):
        if not isinstance(sub, _PURE):
            return None
        if isinstance(sub, ast.Name) and sub.id not in params and sub.id not in temps \
                and sub.id not in _FREE:
            return None
    return params, expr


def _constants(namespace: dict) -> dict:
    """The upper-case module-level ints, floats and strings of a module's ``namespace`` (not
    bools)."""
    return {name: value for name, value in namespace.items()
            if type(value) in (int, float, str) and name.lstrip("_")[:1].isupper()
            and name.lstrip("_").upper() == name.lstrip("_")}


class Vec3:
    """
    A direction of three Python floats with ``mi.Vector3f``'s ``x``, ``y``, ``z``: what the
    compiled terms build (an attribute read costs 11 ns against 50 ns for a scalar
    ``mi.Vector3f``, and the terms read dozens per call). Iterable, like ``mi.Vector3f``.
    """

    __slots__ = ("x", "y", "z", "source")

    def __init__(self, x, y, z):
        self.x, self.y, self.z = x, y, z
        #: the ``mi.Vector3f`` these floats were read from (:func:`to_mitsuba` returns it),
        #: or None
        self.source = None

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
    """A direction as the current variant's ``mi.Vector3f`` (a :class:`Vec3` is converted, or
    gives back the vector it was read from)."""
    if type(v) is not Vec3:
        return v
    return v.source if v.source is not None else mi.Vector3f(v.x, v.y, v.z)


_new = object.__new__


def read_vector(v) -> Vec3:
    """A direction from one of Mitsuba's functions (a ``mi.Vector3f`` or ``mi.Normal3f``) as
    a :class:`Vec3` of its floats, read once: what ``vector.terms_vector`` becomes."""
    d = _new(Vec3)
    d.x, d.y, d.z = v
    d.source = None
    return d


#: Functions of the terms that the compiled modules replace (by name).
OVERRIDES = {"mitsuba_vector": to_mitsuba, "terms_vector": read_vector}


def specialise(module: ModuleType) -> SimpleNamespace:
    """
    The functions of ``module`` compiled for Python floats (see the module docstring), as a
    namespace with the same names; its other public names are shared. Cached per module and
    variant. The namespace's ``_inline`` and ``_bodies`` hold the terms that callers may
    inline and whose bodies they may take in (:func:`compiled_source` gives its source).
    """
    key = (module.__name__, mi.variant())
    if key in _cache:
        return _cache[key]
    namespace = dict(vars(module))
    # what this module's functions may inline (expressions) and take in (bodies): siblings'
    # terms, then its own
    inline, bodies = {}, {}
    for name, value in vars(module).items():  # terms imported from sibling modules
        home = getattr(value, "__module__", None) or ""
        if (inspect.isfunction(value) and home != module.__name__
                and home.startswith(__package__ + ".")):
            sibling = specialise(sys.modules[home])
            namespace[name] = getattr(sibling, value.__name__)
            if name not in OVERRIDES:
                if value.__name__ in sibling._inline:
                    inline[name] = sibling._inline[value.__name__]
                if value.__name__ in sibling._bodies:
                    bodies[name] = sibling._bodies[value.__name__]
    rewrite = _Rewrite(_constants(vars(module)), inline, bodies=bodies)
    functions, own, own_bodies = [], {}, {}
    for node in ast.parse(inspect.getsource(module)).body:
        if isinstance(node, ast.FunctionDef):  # in order: a term inlines those before it
            node = rewrite.visit(node)
            functions.append(node)
            if node.name in OVERRIDES:
                continue
            target = _inlinable(node)
            if target is not None:
                inline[node.name] = own[node.name] = target
            elif _body(node):
                bodies[node.name] = (node, None)  # (this module's globals)
                own_bodies[node.name] = node
    kinds = _kinds({**namespace, **{n: f for n, f in OVERRIDES.items() if n in namespace},
                    **_helpers(rewrite), **rewrite.injected})
    functions = [_scalarise(_unbox(node, kinds, None)) for node in functions]
    code = compile(ast.fix_missing_locations(ast.Module(functions, [])),
                   f"<{module.__name__} for floats>", "exec",
                   flags=__future__.annotations.compiler_flag, dont_inherit=True)
    namespace.update(_helpers(rewrite))
    namespace.update(rewrite.injected)
    exec(code, namespace)  # noqa: S102 - the package's own source, rewritten above
    namespace.update({name: fn for name, fn in OVERRIDES.items() if name in namespace})
    result = SimpleNamespace(**{f.name: namespace[f.name] for f in functions})
    for name in dir(module):  # constants and other public names, shared
        if not name.startswith("__") and not hasattr(result, name):
            setattr(result, name, namespace.get(name, getattr(module, name)))
    result._inline, result._compiled = own, ast.Module(functions, [])
    result._bodies = {name: (node, namespace) for name, node in own_bodies.items()}
    _cache[key] = result
    return result


#: The attributes :func:`_scalarise` reads into local names.
_COMPONENTS = ("x", "y", "z")


def _component_local(node: ast.Attribute, names) -> ast.Name | None:
    """The read ``v.x`` (``.y``, ``.z``) of a name ``v`` in ``names`` as the local ``v__x``."""
    if (isinstance(node.value, ast.Name) and node.value.id in names
            and node.attr in _COMPONENTS and isinstance(node.ctx, ast.Load)):
        return ast.copy_location(ast.Name(f"{node.value.id}__{node.attr}", ast.Load()), node)
    return None


class _Census:
    """What :func:`_unbox` and :func:`_scalarise` need to know of a function, in one walk:
    how often each name is stored, the values of its plain assignments, the names read as
    ``v.x``, ``v.y``, ``v.z`` (and how often), those stored as components, the names that
    nested scopes use, those stored in loops, and its parameters."""

    def __init__(self, fn):
        self.stores: dict[str, int] = {}
        self.assigned: dict[str, list] = {}
        self.reads: dict[str, dict[str, int]] = {}
        self.component_names: set[int] = set()  # ids of the Name nodes of v.x, v.y, v.z
        self.written: set[str] = set()
        self.nested: set[str] = set()
        self.loads: list = []  # every Name node read
        self.calls: list = []
        self.loops: list = []
        for node in ast.walk(fn):
            kind = type(node)
            if kind is ast.Name:
                if isinstance(node.ctx, ast.Load):
                    self.loads.append(node)
                else:
                    self.stores[node.id] = self.stores.get(node.id, 0) + 1
            elif kind is ast.Attribute:
                if isinstance(node.value, ast.Name) and node.attr in _COMPONENTS:
                    if isinstance(node.ctx, ast.Load):
                        counts = self.reads.setdefault(node.value.id, {})
                        counts[node.attr] = counts.get(node.attr, 0) + 1
                        self.component_names.add(id(node.value))
                    else:
                        self.written.add(node.value.id)
            elif kind is ast.Assign:
                if len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
                    self.assigned.setdefault(node.targets[0].id, []).append(node.value)
            elif kind is ast.Call:
                self.calls.append(node)
            elif kind in (ast.For, ast.While):
                self.loops.append(node)
            elif kind in (ast.FunctionDef, ast.Lambda) and node is not fn:
                self.nested |= {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
        a = fn.args
        self.params = {p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)}
        #: the names stored inside a loop
        self.looped = {n.id for loop in self.loops for n in ast.walk(loop)
                       if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}


def _scalarise(fn: ast.FunctionDef) -> ast.FunctionDef:
    """
    Read the components of a direction into local names once: for a local name ``v`` that
    ``fn`` assigns exactly once, in a plain ``v = ...`` outside any loop, never in a nested
    scope, and whose ``v.x``, ``v.y``, ``v.z`` it reads at least four times in all (and never
    stores), ``v__x, v__y, ... = v.x, v.y, ...`` follows the assignment and the reads become
    the names (an attribute read of a :class:`Vec3` costs about five times a local's). The
    value is the same: the terms never change a vector once it is made.
    """
    c = _Census(fn)
    chosen = {name: sorted(counts) for name, counts in c.reads.items()
              if sum(counts.values()) >= 4 and c.stores.get(name) == 1
              and name not in c.params | c.nested | c.written | c.looped}
    if not chosen:
        return fn

    class Insert(ast.NodeTransformer):
        def _block(self, statements):
            out = []
            for stmt in statements:
                stmt = self.visit(stmt)
                out.extend(stmt if isinstance(stmt, list) else [stmt])
                if (isinstance(stmt, ast.Assign) and len(stmt.targets) == 1
                        and isinstance(stmt.targets[0], ast.Name)
                        and stmt.targets[0].id in chosen):
                    name = stmt.targets[0].id
                    attrs = chosen[name]
                    out.append(ast.copy_location(ast.Assign(
                        [ast.Tuple([ast.Name(f"{name}__{a}", ast.Store()) for a in attrs],
                                   ast.Store())],
                        ast.Tuple([ast.Attribute(ast.Name(name, ast.Load()), a, ast.Load())
                                   for a in attrs], ast.Load())), stmt))
                    done.add(name)
            return out

        def generic_visit(self, node):
            for field in ("body", "orelse", "finalbody"):
                if isinstance(getattr(node, field, None), list) and \
                        all(isinstance(s, ast.stmt) for s in getattr(node, field)):
                    setattr(node, field, self._block(getattr(node, field)))
            for field, value in ast.iter_fields(node):
                if field in ("body", "orelse", "finalbody"):
                    continue
                if isinstance(value, ast.AST):
                    setattr(node, field, Reads().visit(value))
                elif isinstance(value, list):
                    setattr(node, field, [Reads().visit(v) if isinstance(v, ast.AST) else v
                                          for v in value])
            return node

    class Reads(ast.NodeTransformer):
        def visit_Attribute(self, node):
            return _component_local(node, done) or self.generic_visit(node)

    done: set[str] = set()
    fn.body = Insert()._block(fn.body)
    return fn


def _unbox(fn: ast.FunctionDef, kinds: dict, tools: str | None) -> ast.FunctionDef:
    """
    Keep a direction as three local names instead of a :class:`Vec3`, where ``fn`` only reads
    its components or hands it to Mitsuba: for a local name ``v`` (never in a nested scope)
    that every assignment gives a constructor of :class:`Vec3`, :func:`read_vector`, the
    variant tools' ``direction`` or another such name, and that is otherwise only read as
    ``v.x``, ``v.y``, ``v.z`` or passed alone to :func:`to_mitsuba` (or the tools'
    ``to_mitsuba``), each assignment becomes ``v__x, v__y, v__z = ...`` (the constructor's
    arguments, the other name's, or the floats of the direction: a ``mi.Vector3f``'s directly,
    anything else through ``direction``), the reads the names, and ``to_mitsuba(v)`` a
    ``mi.Vector3f`` of them. ``kinds`` names the globals that are
    :class:`Vec3` ('new'), :func:`read_vector` ('read') and :func:`to_mitsuba` ('out').
    """
    def kind(func) -> str | None:
        """What a callee is: 'new', 'read', 'direction', 'out' or None."""
        if isinstance(func, ast.Name):
            return kinds.get(func.id)
        if (tools and isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name)
                and func.value.id == tools):
            return {"direction": "direction", "to_mitsuba": "out"}.get(func.attr)
        return None

    def handed(call) -> ast.Name | None:
        """The name ``v`` of a call ``to_mitsuba(v)``, else None."""
        if (isinstance(call, ast.Call) and kind(call.func) == "out" and len(call.args) == 1
                and not call.keywords and isinstance(call.args[0], ast.Name)):
            return call.args[0]
        return None

    def made(value) -> str | None:
        if not isinstance(value, ast.Call) or value.keywords or \
                any(isinstance(a, ast.Starred) for a in value.args):
            return None
        k = kind(value.func)
        wanted = {"new": 3, "read": 1, "direction": 1}
        return k if k in wanted and len(value.args) == wanted[k] else None

    c = _Census(fn)
    uses = set(c.component_names)  # ids of the Name nodes read as v.x, ... or to_mitsuba(v)
    uses |= {id(handed(call)) for call in c.calls if handed(call) is not None}
    assigned = c.assigned
    # every store of a chosen name is 'v = <a maker>' or 'v = w' of another chosen name w
    chosen = {name for name, values in assigned.items()
              if len(values) == c.stores.get(name) and name not in c.params | c.nested
              and all(made(v) or isinstance(v, ast.Name) for v in values)}
    # names loaded otherwise (w in a copy 'v = w' into a candidate v is judged below, with v)
    copies = {id(v) for name in chosen for v in assigned[name] if isinstance(v, ast.Name)}
    bare = {name.id for name in c.loads if id(name) not in uses | copies}
    while True:  # a copy of a name that is not chosen is no maker: drop until none is left
        keep = {name for name in chosen if name not in bare and all(
            made(v) or v.id in chosen for v in assigned[name])}
        bare |= {v.id for name in chosen - keep for v in assigned[name]
                 if isinstance(v, ast.Name)}
        if keep == chosen:
            break
        chosen = keep
    if not chosen:
        return fn

    def parts(name, ctx):
        return [ast.Name(f"{name}__{a}", ctx()) for a in _COMPONENTS]

    class Unbox(ast.NodeTransformer):
        def visit_Assign(self, node):
            self.generic_visit(node)
            if not (len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                    and node.targets[0].id in chosen):
                return node
            name, value = node.targets[0].id, node.value
            how = made(value)
            if isinstance(value, ast.Name):  # a copy of another chosen name
                out = ast.Tuple(parts(value.id, ast.Load), ast.Load())
            elif how == "new":
                out = ast.Tuple(value.args, ast.Load())
            elif how == "read":  # a Mitsuba vector or normal: its floats, read once
                out = value.args[0]
            else:  # a mi.Vector3f's floats directly; anything else through direction()
                arg = value.args[0]
                if isinstance(arg, ast.Name):
                    first, again = arg, ast.Name(arg.id, ast.Load())
                else:
                    t = f"_u{next(_unique)}"
                    first = ast.NamedExpr(ast.Name(t, ast.Store()), arg)
                    again = ast.Name(t, ast.Load())
                out = ast.IfExp(
                    test=ast.Compare(ast.Call(ast.Name("type", ast.Load()), [first], []),
                                     [ast.Is()], [ast.Name("_mi_vector_class", ast.Load())]),
                    body=_copy(again),
                    orelse=ast.Call(value.func, [_copy(again)], []))
            target = ast.Tuple(parts(name, ast.Store), ast.Store())
            return ast.copy_location(ast.Assign([target], out), node)

        def visit_Call(self, node):
            name = handed(node)
            if name is not None and name.id in chosen:
                return ast.copy_location(ast.Call(ast.Name("_mi_vector_class", ast.Load()),
                                                  parts(name.id, ast.Load), []), node)
            return self.generic_visit(node)

        def visit_Attribute(self, node):
            return _component_local(node, chosen) or self.generic_visit(node)

    return Unbox().visit(fn)


def _helpers(rewrite: _Rewrite) -> dict:
    """The names the rewritten code refers to: ``_math``, ``_dr`` and the bound ``mi.<name>``
    (``mi.Vector3f`` as :class:`Vec3`)."""
    names = {f"_mi_{name}": getattr(mi, name) for name in rewrite.mitsuba}
    names.update(_math=math, _dr=dr, _mi_vector_class=mi.Vector3f)
    if "Vector3f" in rewrite.mitsuba:
        names["_mi_Vector3f"] = Vec3
    return names


def _kinds(names: dict) -> dict:
    """The names among ``names`` (name -> value) bound to :class:`Vec3` ('new'),
    :func:`read_vector` ('read') and :func:`to_mitsuba` ('out'), for :func:`_unbox`."""
    known = ((Vec3, "new"), (read_vector, "read"), (to_mitsuba, "out"))
    return {name: k for name, value in names.items() for obj, k in known if value is obj}


#: Serialises compiling (plugins may be constructed on Mitsuba's scene-loading threads).
_lock = threading.RLock()


def specialise_class(cls: type, tools: str = "V", skip=("__init__",)) -> type:
    """
    Mark ``cls`` to be compiled for Python floats (:func:`compiled_class`) when its first
    instance is configured (:func:`configure`), so that a process that loads a scalar variant
    but never makes one pays nothing for it; its module's globals are kept for then.
    """
    cls.__specialise__ = (vars(sys.modules[cls.__module__]), tools, skip)
    return cls


def compiled_class(cls: type) -> type:
    """``cls`` compiled by :func:`_compile_class` (once), where :func:`specialise_class` marked
    it; returned."""
    with _lock:
        if "__generic_methods__" not in vars(cls) and "__specialise__" in vars(cls):
            _compile_class(cls, *cls.__specialise__)
    return cls


def _compile_class(cls: type, g: dict, tools: str, skip) -> type:
    """
    ``cls`` with its methods compiled for Python floats, in place: the rewrites of
    :func:`specialise`, the inlining of the terms of the compiled modules it holds as module
    globals (``mf = V.terms(microfacet)``; ``mf.pdf_ndf(d, m)`` becomes ``d * m.z``) and the
    rewrites of the variant tools ``tools`` (the module docstring's second table), and then
    the bodies of its single-exit methods taken in where another method calls them on
    ``self`` (so a method replaced on an instance or subclass is not seen by the others).
    Methods in ``skip``, and those that use ``super`` or ``__class__``, are kept. The
    originals stay in ``cls.__generic_methods__`` (for tests); :func:`compiled_source` gives
    the compiled source. For scalar variants only: the rewrites assume the
    values of ``dr.maximum``, ``dr.minimum`` and ``dr.select`` in the methods are numbers.
    ``g`` is the globals of the class's module (its own: the module is loaded afresh for
    each variant, and ``sys.modules`` holds the last one).
    """
    terms = {alias: value for alias, value in g.items()
             if type(value) is SimpleNamespace and hasattr(value, "_inline")}
    inline = {(alias, name): target for alias, value in terms.items()
              for name, target in value._inline.items()}
    bodies = {(alias, name): entry for alias, value in terms.items()
              for name, entry in value._bodies.items()}
    rewrite = _Rewrite(_constants(g), inline, tools, bodies)
    tree = next(node for node in ast.parse(inspect.getsource(cls)).body
                if isinstance(node, ast.ClassDef) and node.name == cls.__name__)
    methods = [node for node in tree.body if isinstance(node, ast.FunctionDef)
               and node.name not in skip and not any(
                   isinstance(n, ast.Name) and n.id in ("super", "__class__")
                   for n in ast.walk(node))]
    methods = [rewrite.visit(node) for node in methods]
    # then the bodies of its own single-exit methods taken in where they are called on self
    # (static methods and the kept ones excepted), callees finished before their callers
    by_name = {node.name: node for node in methods}
    eligible = {name for name, node in by_name.items() if _body(node)}
    callees = {name: {n.func.attr for n in ast.walk(node) if isinstance(n, ast.Call)
                      and isinstance(n.func, ast.Attribute) and isinstance(n.func.value, ast.Name)
                      and n.func.value.id == "self" and n.func.attr in eligible}
               for name, node in by_name.items()}
    finished: dict = {}

    def finish(name, path=()):
        """Take in the bodies of ``name``'s callees, each finished first (callees before
        callers: one pass; a call back into the path stays a call)."""
        if name in finished:
            return
        for callee in callees[name] - {name, *path}:
            finish(callee, (*path, name))
        own = {("self", c): (finished[c], None) for c in callees[name] if c in finished}
        finished[name] = _Rewrite(bodies=own).visit(by_name[name]) if own else by_name[name]

    for name in by_name:
        finish(name)
    methods = [finished[node.name] for node in methods]
    kinds = _kinds({**_helpers(rewrite), **rewrite.injected})
    # kept for configure(): the methods before the last two passes, which folding may widen
    cls.__taken__ = (ast.Module([_copy(node) for node in methods], []), kinds, tools, g)
    cls.__configured__ = {}
    methods = [_scalarise(_unbox(node, kinds, tools)) for node in methods]
    code = compile(ast.fix_missing_locations(ast.Module(methods, [])),
                   f"<{cls.__module__}.{cls.__name__} for floats>", "exec",
                   flags=__future__.annotations.compiler_flag, dont_inherit=True)
    for name, value in {**_helpers(rewrite), **rewrite.injected}.items():
        g.setdefault(name, value)
    compiled: dict = {}
    exec(code, g, compiled)  # noqa: S102 - the package's own source, rewritten above
    cls.__generic_methods__ = {name: vars(cls)[name] for name in compiled}
    cls.__compiled__ = ast.Module(methods, [])
    for name, fn in compiled.items():
        setattr(cls, name, fn)
    return cls


def compiled_source(compiled) -> str:
    """The source :func:`specialise` (its namespace) or :func:`specialise_class` (the class)
    compiled, as Python text: what runs in scalar variants."""
    tree = compiled._compiled if isinstance(compiled, SimpleNamespace) else compiled.__compiled__
    return ast.unparse(tree)


# -------------------------------------------------------------------------------------------------
# Compiled for one configuration
# -------------------------------------------------------------------------------------------------

#: Calls of an instance's configured methods (all together) after which :func:`configure`
#: compiles them (and the class, the first time): compiling takes 0.1-0.6 s, which a few
#: thousand calls of the methods as written cost less than, and a render makes millions.
PROMOTE_AFTER = 20_000


def configure(obj, values: tuple, nones: tuple = (), methods: tuple = ("eval_pdf", "sample")):
    """
    Give ``obj`` (an instance of a class marked by :func:`specialise_class`) its own
    ``methods``, compiled for its configuration: the attributes ``values`` (strings, bools or
    None: which distribution, which lobes) and whether each of ``nones`` is None (a constant
    parameter read once, a lobe that is absent) are put in as constants, and every test they
    decide is folded away (:func:`_fold`), so that a switch that is off costs nothing, not
    even its test. The compiled methods are cached per class and configuration and bound to
    the instance, where Mitsuba's calls find them first. A configuration not compiled yet is
    compiled after :data:`PROMOTE_AFTER` calls (the class's methods serve until then). Call
    again whenever the configuration may have changed (``parameters_changed``).
    """
    cls = type(obj)
    config = {f"self.{a}": getattr(obj, a) for a in values}
    if not all(v is None or type(v) in (str, bool, int) for v in config.values()):
        return  # (not a configuration: keep the class's methods)
    known = {f"self.{a}": getattr(obj, a) is None for a in nones}
    key = (tuple(config.items()), tuple(known.items()), methods)
    functions = vars(cls).get("__configured__", {}).get(key)
    if functions is not None:
        _bind(obj, functions)
    elif PROMOTE_AFTER > 0:
        _count_calls(obj, methods, lambda: _promote(obj, key, config, known, methods))
    else:
        _promote(obj, key, config, known, methods)


def _bind(obj, functions: dict) -> None:
    """Make ``functions`` ``obj``'s own methods (where Mitsuba's calls find them first)."""
    for name, fn in functions.items():
        obj.__dict__[name] = types.MethodType(fn, obj)


def _promote(obj, key, config: dict, known: dict, methods) -> None:
    """Compile ``obj``'s class (once) and its configuration (once), bind them to ``obj``."""
    with _lock:
        cls = compiled_class(type(obj))
        functions = cls.__configured__.get(key) or _configured(cls, config, known, methods)
        cls.__configured__[key] = functions
    _bind(obj, functions)


def _count_calls(obj, methods, promote) -> None:
    """Bind to ``obj`` stand-ins of ``methods`` that call the class's methods and, at the
    :data:`PROMOTE_AFTER`-th call of any, ``promote()`` (which binds the compiled ones)."""
    left = [PROMOTE_AFTER]
    cls = type(obj)

    def counted(name):
        def method(*args, **kwargs):
            left[0] -= 1
            if left[0] == 0:
                promote()
            return getattr(cls, name)(obj, *args, **kwargs)
        method.__name__ = name
        return method

    for name in methods:
        obj.__dict__[name] = counted(name)


def _configured(cls, config: dict, known: dict, methods) -> dict:
    """:func:`configure`'s functions for one configuration, compiled."""
    tree, kinds, tools, g = cls.__taken__  # (g: the globals of the class's own module)
    nodes = [_copy(node) for node in tree.body if node.name in methods]
    nodes = [_scalarise(_unbox(_fold(node, config, known), kinds, tools)) for node in nodes]
    code = compile(ast.fix_missing_locations(ast.Module(nodes, [])),
                   f"<{cls.__module__}.{cls.__name__} for floats, configured>", "exec",
                   flags=__future__.annotations.compiler_flag, dont_inherit=True)
    functions: dict = {}
    exec(code, g, functions)  # noqa: S102 - the package's own source, rewritten above
    return functions


def _dotted(node) -> str | None:
    """'self.name' for an attribute of a name, else None."""
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return f"{node.value.id}.{node.attr}"
    return None


def _truth(node):
    """(True, value) where ``node`` is a constant, else (False, None)."""
    if isinstance(node, ast.Constant):
        return True, node.value
    return False, None


def _fold(fn: ast.FunctionDef, values: dict, nones: dict) -> ast.FunctionDef:
    """
    ``fn`` with the attributes of ``values`` ('self.name' -> value) put in, the None tests
    of ``nones`` ('self.name' -> whether it is None) decided, also through local names
    assigned from them once, and everything constant folded: comparisons, ``not``, leading
    constants of ``and``/``or``, conditional expressions and ``if`` statements with constant
    tests (the branch not taken is dropped), and local names assigned a constant once.
    """
    constants: dict = {}
    local_nones: dict = {}
    for _ in range(6):
        folder = _Folder(values, nones, constants, local_nones)
        fn = folder.visit(fn)
        # the locals assigned once (outside loops) a constant, or an attribute of nones, in
        # what is left: put in by the next round
        c = _Census(fn)
        single = {name for name, count in c.stores.items()
                  if count == 1 and name not in c.params | c.nested | c.looped
                  and len(c.assigned.get(name, ())) == 1}
        found = {name: c.assigned[name][0].value for name in single
                 if isinstance(c.assigned[name][0], ast.Constant)}
        found_nones = {name: nones[_dotted(c.assigned[name][0])] for name in single
                       if _dotted(c.assigned[name][0]) in nones}
        if not folder.changed and found.keys() <= constants.keys() and \
                found_nones.keys() <= local_nones.keys():
            break
        constants, local_nones = found, found_nones
    return fn


class _Folder(ast.NodeTransformer):
    """One round of :func:`_fold`."""

    def __init__(self, values, nones, constants, local_nones):
        self.values, self.nones = values, nones
        self.constants, self.local_nones = constants, local_nones
        self.changed = False

    def _const(self, value, node):
        self.changed = True
        return ast.copy_location(ast.Constant(value), node)

    def visit_Attribute(self, node):
        name = _dotted(node)
        if name in self.values and isinstance(node.ctx, ast.Load):
            return self._const(self.values[name], node)
        return self.generic_visit(node)

    def visit_Name(self, node):
        if isinstance(node.ctx, ast.Load) and node.id in self.constants:
            return self._const(self.constants[node.id], node)
        return node

    def visit_Compare(self, node):
        # x is None / x is not None, for an attribute of nones or a local assigned from one
        if len(node.ops) == 1 and isinstance(node.ops[0], (ast.Is, ast.IsNot)) and \
                isinstance(node.comparators[0], ast.Constant) and \
                node.comparators[0].value is None:
            left = node.left
            known = None
            if _dotted(left) in self.nones:
                known = self.nones[_dotted(left)]
            elif isinstance(left, ast.Name) and left.id in self.local_nones:
                known = self.local_nones[left.id]
            if known is not None:
                return self._const(known if isinstance(node.ops[0], ast.Is) else not known,
                                   node)
        node = self.generic_visit(node)
        operands = [node.left, *node.comparators]
        if all(isinstance(o, ast.Constant) for o in operands):
            ops = {ast.Eq: lambda a, b: a == b, ast.NotEq: lambda a, b: a != b,
                   ast.Is: lambda a, b: a is b, ast.IsNot: lambda a, b: a is not b}
            if all(type(op) in ops for op in node.ops):
                result = all(ops[type(op)](a.value, b.value)
                             for op, a, b in zip(node.ops, operands, operands[1:]))
                return self._const(result, node)
        return node

    def visit_UnaryOp(self, node):
        node = self.generic_visit(node)
        if isinstance(node.op, ast.Not) and isinstance(node.operand, ast.Constant):
            return self._const(not node.operand.value, node)
        return node

    def visit_BoolOp(self, node):
        node = self.generic_visit(node)
        values = list(node.values)
        stop = isinstance(node.op, ast.Or)  # the truth that ends the evaluation
        while len(values) > 1 and isinstance(values[0], ast.Constant):
            if bool(values[0].value) == stop:
                return self._const(values[0].value, node)
            values.pop(0)
            self.changed = True
        if len(values) == 1:
            return values[0]
        node.values = values
        return node

    def visit_IfExp(self, node):
        node = self.generic_visit(node)
        known, value = _truth(node.test)
        if known:
            self.changed = True
            return node.body if value else node.orelse
        return node

    def visit_If(self, node):
        node = self.generic_visit(node)
        known, value = _truth(node.test)
        if not known:
            return node
        self.changed = True
        kept = node.body if value else node.orelse
        return kept or ast.copy_location(ast.Pass(), node)
