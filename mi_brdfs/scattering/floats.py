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
import copy
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
        self._bound: list[set] = []  # the names each enclosing function binds

    def visit_FunctionDef(self, node):
        self._bound.append(_bound_names(node))
        try:
            return self.generic_visit(node)
        finally:
            self._bound.pop()

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
        out = _Substitute(dict(zip(params, node.args)), names).visit(copy.deepcopy(expr))
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
        if not isinstance(call, ast.Call) or call.keywords or \
                any(isinstance(a, ast.Starred) for a in call.args):
            return None
        key = self._key(call.func)
        entry = self.bodies.get(key) if key is not None else None
        if entry is None:
            return None
        fn, home = entry
        params, defaults = [p.arg for p in fn.args.args], fn.args.defaults
        given = len(call.args)
        if not len(params) - len(defaults) <= given <= len(params):
            return None
        args = list(call.args) + [copy.deepcopy(d) for d in
                                  defaults[len(defaults) - (len(params) - given):]]
        body = _docless(fn.body)
        stored = {n.id for stmt in body for n in ast.walk(stmt)
                  if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
        tag = next(_unique)
        rename = {n: f"_i{tag}_{n}" for n in stored | set(params)}
        put = {p: a for p, a in zip(params, args) if p not in stored and _simple(a)}
        statements = [ast.Assign([ast.Name(rename[p], ast.Store())], a)
                      for p, a in zip(params, args) if p not in put]
        free = {}
        if home is not None:  # another module's term: its globals, bound here
            loads = {n.id for stmt in body for n in ast.walk(stmt) if isinstance(n, ast.Name)}
            for name in sorted(loads - set(rename)):
                if name in home:
                    free[name] = f"_g{next(_unique)}"
                    self.injected[free[name]] = home[name]
        out = _Substitute(put, {**rename, **free})
        statements += [out.visit(copy.deepcopy(stmt)) for stmt in body[:-1]]
        result = out.visit(copy.deepcopy(body[-1].value))
        for stmt in statements:
            ast.copy_location(stmt, call)
        return statements, result

    def _tools_call(self, node):
        """A call of the variant tools (:data:`TOOLS`) rewritten, or None."""
        func = node.func
        if not (self.tools and isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name)
                and func.value.id == self.tools) or node.keywords:
            return None
        args, name = node.args, func.attr
        if name == "select" and len(args) == 3:
            c, a, b = args
            if _simple(a):
                first, again = a, copy.deepcopy(a)
            else:  # a in each branch, evaluated in the one taken
                t = next(self._names)
                first = ast.NamedExpr(ast.Name(t, ast.Store()), a)
                again = ast.NamedExpr(ast.Name(t, ast.Store()), copy.deepcopy(a))
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
            return copy.deepcopy(self.nodes[node.id])
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
    """The names a function binds: its parameters and every name it stores (nested
    functions included)."""
    names = {a.arg for a in (*fn.args.posonlyargs, *fn.args.args, *fn.args.kwonlyargs)}
    names |= {a.arg for a in (fn.args.vararg, fn.args.kwarg) if a is not None}
    for sub in ast.walk(fn):
        if isinstance(sub, ast.Name) and isinstance(sub.ctx, (ast.Store, ast.Del)):
            names.add(sub.id)
        elif isinstance(sub, (ast.FunctionDef, ast.Lambda)) and sub is not fn:
            names |= {a.arg for a in sub.args.args}
    return names


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


def _body(fn: ast.FunctionDef) -> bool:
    """Whether callers may take in the body of ``fn`` (:meth:`_Rewrite._body_of`): positional
    parameters (defaults constant), no decorator, one ``return`` of a value, at its end, and
    nothing of :data:`_NOT_IN_BODIES` before it."""
    a, body = fn.args, _docless(fn.body)
    if (fn.decorator_list or a.posonlyargs or a.vararg or a.kwonlyargs or a.kwarg
            or not all(isinstance(d, ast.Constant) for d in a.defaults) or not body
            or not isinstance(body[-1], ast.Return) or body[-1].value is None):
        return False
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
    body, a = _docless(fn.body), fn.args
    if (len(body) != 1 or not isinstance(body[0], ast.Return) or body[0].value is None
            or fn.decorator_list or a.posonlyargs or a.vararg or a.kwonlyargs or a.kwarg
            or a.defaults):
        return None
    expr, params = body[0].value, [p.arg for p in a.args]
    temps = {n.target.id for n in ast.walk(expr) if isinstance(n, ast.NamedExpr)}
    for sub in ast.walk(expr):
        if not isinstance(sub, _PURE):
            return None
        if isinstance(sub, ast.Name) and sub.id not in params and sub.id not in temps \
                and sub.id not in _FREE:
            return None
    return params, expr


def _constants(module) -> dict:
    """The upper-case module-level ints, floats and strings of ``module`` (not bools)."""
    return {name: value for name, value in vars(module).items()
            if type(value) in (int, float, str) and name.lstrip("_")[:1].isupper()
            and name.lstrip("_").upper() == name.lstrip("_")}


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
    variant. The namespace's ``_inline`` and ``_bodies`` hold the terms that callers may
    inline and whose bodies they may take in, ``_source`` the compiled source.
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
    rewrite = _Rewrite(_constants(module), inline, bodies=bodies)
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
    result._inline, result._source = own, ast.unparse(ast.Module(functions, []))
    result._bodies = {name: (node, namespace) for name, node in own_bodies.items()}
    _cache[key] = result
    return result


def _helpers(rewrite: _Rewrite) -> dict:
    """The names the rewritten code refers to: ``_math``, ``_dr`` and the bound ``mi.<name>``
    (``mi.Vector3f`` as :class:`Vec3`)."""
    names = {f"_mi_{name}": getattr(mi, name) for name in rewrite.mitsuba}
    names.update(_math=math, _dr=dr)
    if "Vector3f" in rewrite.mitsuba:
        names["_mi_Vector3f"] = Vec3
    return names


def specialise_class(cls: type, tools: str = "V", skip=("__init__",)) -> type:
    """
    ``cls`` with its methods compiled for Python floats, in place: the rewrites of
    :func:`specialise`, the inlining of the terms of the compiled modules it holds as module
    globals (``mf = V.terms(microfacet)``; ``mf.pdf_ndf(d, m)`` becomes ``d * m.z``) and the
    rewrites of the variant tools ``tools`` (the module docstring's second table). Methods in
    ``skip``, and those that use ``super`` or ``__class__``, are kept. The originals stay in
    ``cls.__generic_methods__`` (for tests), the compiled source in
    ``cls.__compiled_source__``. For scalar variants only: the rewrites assume the
    values of ``dr.maximum``, ``dr.minimum`` and ``dr.select`` in the methods are numbers.
    """
    module = sys.modules[cls.__module__]
    g = vars(module)
    terms = {alias: value for alias, value in g.items()
             if type(value) is SimpleNamespace and hasattr(value, "_inline")}
    inline = {(alias, name): target for alias, value in terms.items()
              for name, target in value._inline.items()}
    bodies = {(alias, name): entry for alias, value in terms.items()
              for name, entry in value._bodies.items()}
    rewrite = _Rewrite(_constants(module), inline, tools, bodies)
    tree = next(node for node in ast.parse(inspect.getsource(module)).body
                if isinstance(node, ast.ClassDef) and node.name == cls.__name__)
    methods = [node for node in tree.body if isinstance(node, ast.FunctionDef)
               and node.name not in skip and not any(
                   isinstance(n, ast.Name) and n.id in ("super", "__class__")
                   for n in ast.walk(node))]
    methods = [rewrite.visit(node) for node in methods]
    code = compile(ast.fix_missing_locations(ast.Module(methods, [])),
                   f"<{module.__name__}.{cls.__name__} for floats>", "exec",
                   flags=__future__.annotations.compiler_flag, dont_inherit=True)
    for name, value in {**_helpers(rewrite), **rewrite.injected}.items():
        g.setdefault(name, value)
    compiled: dict = {}
    exec(code, g, compiled)  # noqa: S102 - the package's own source, rewritten above
    cls.__generic_methods__ = {name: vars(cls)[name] for name in compiled}
    cls.__compiled_source__ = ast.unparse(ast.Module(methods, []))
    for name, fn in compiled.items():
        setattr(cls, name, fn)
    return cls
