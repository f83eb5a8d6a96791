"""A dynamical system from its equations, written with SymPy (docs/systems.md).

:class:`System` holds the right-hand sides of ``dx/dt = f(x; p)`` as SymPy expressions, one per
state variable in the order of the dictionary given, the parameters ``p`` with their values, and
optionally the energy (a conserved function of the state) and a name::

    x, y, px, py, lam = sympy.symbols("x y px py lam")
    hh = System({x: px, y: py, px: -x - 2*lam*x*y, py: -y - lam*(x**2 - y**2)},
                parameters={lam: 1.0},
                energy=(px**2 + py**2)/2 + (x**2 + y**2)/2 + lam*(x**2*y - y**3/3),
                name="henon_heiles")

Parameters are runtime values: :meth:`System.with_` gives the same equations with other values,
and :attr:`System.content_hash` (which keys the generated code of
:mod:`explorer.integrate.codegen`) depends on the equations and on which symbols are parameters,
not on their values, so a sweep over a parameter compiles once.

The right-hand sides may use numbers, parameters, ``+ - * /``, powers (integer, rational, real or
a parameter as exponent), ``sqrt``, ``exp``, ``log``, ``sin``, ``cos`` and ``tan``
(:data:`SUPPORTED_FUNCTIONS`); anything else is refused with a :class:`ParameterError` naming it.

A ``reversor`` (a dict {state symbol: image}, or a list of them) declares an involution R of the
state with ``f(R x) = -DR(x) f(x)`` (and ``H(R x) = H(x)``): ``R x(-t)`` is an orbit whenever
``x(t)`` is (docs/systems.md, "Reversors").
"""
from __future__ import annotations

import hashlib
import math
import numbers

import numpy as np
import sympy as sp

from explorer.model.validation import ParameterError, did_you_mean

__all__ = ["SUPPORTED_FUNCTIONS", "System"]

#: the functions a right-hand side may call (besides +, -, *, / and powers): the elementary
#: operations whose Taylor recurrences explorer.integrate.codegen knows (Jorba & Zou 2005)
SUPPORTED_FUNCTIONS = (sp.exp, sp.log, sp.sin, sp.cos, sp.tan)

#: version of the symbolic form hashed by :attr:`System.content_hash`
HASH_FORMAT = 1


def _symbol(label, s):
    """``s`` if it is a SymPy Symbol, else a ParameterError naming ``label``."""
    if not isinstance(s, sp.Symbol):
        raise ParameterError(f"{label} must be a sympy Symbol, got {s!r} ({type(s).__name__})")
    return s


def _expression(label, e):
    """``e`` as a SymPy expression (numbers allowed), else a ParameterError naming ``label``."""
    if e is None:
        raise ParameterError(f"{label} has no equation (None): give its derivative as a sympy expression")
    if isinstance(e, bool):
        raise ParameterError(f"{label} must be a sympy expression or a number, got {e!r}")
    try:
        e = sp.sympify(e, strict=True)
    except (sp.SympifyError, TypeError) as err:
        raise ParameterError(f"{label} must be a sympy expression or a number, got {e!r}") from err
    if not isinstance(e, sp.Expr):
        raise ParameterError(f"{label} must be a sympy expression, got {e!r} ({type(e).__name__})")
    if e.has(sp.I) or e.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ParameterError(f"{label} must be real and finite, got {e}")
    return e


def _value(name, v):
    """A parameter value: a finite real Python or numpy number (not a bool, not a string)."""
    if isinstance(v, bool) or not isinstance(v, numbers.Real):
        raise ParameterError(f"parameter {name} must be a real number, got {v!r} ({type(v).__name__})")
    v = float(v)
    if not math.isfinite(v):
        raise ParameterError(f"parameter {name} must be finite, got {v!r}")
    return v


def _vanishes(e) -> bool:
    """False only when SymPy shows ``e`` is not identically zero (``equals`` decides numerically
    where simplification does not)."""
    e = sp.expand(e)
    return e == 0 or e.equals(0) is not False


def _names(symbols):
    return ", ".join(s.name for s in symbols) or "none"


class System:
    """``dx/dt = f(x; p)`` from a dict {state symbol: derivative expression} (state order = dict
    order), ``parameters`` {symbol: value}, an optional ``energy`` (an expression of the state
    and the parameters) and a ``name``.  Immutable; :meth:`with_` changes parameter values.

    Raises :class:`ParameterError` naming what is wrong: a key that is not a Symbol, a state
    without an equation, a symbol that is neither a state variable nor a parameter, a parameter
    that is also a state, two symbols with one name, a value that is not a finite real number,
    an unsupported function, a ``reversor`` that is not an involution of the state reversing the
    equations (and keeping the energy).
    """

    def __init__(self, equations, parameters=None, energy=None, name=None, reversor=None):
        if not isinstance(equations, dict) or not equations:
            raise ParameterError("equations must be a non-empty dict {state symbol: derivative expression}, "
                                 f"got {equations!r}")
        states = tuple(_symbol("a state variable (a key of equations)", s) for s in equations)
        rhs = tuple(_expression(f"d{s.name}/dt", equations[s]) for s in states)
        if parameters is None:
            parameters = {}
        if not isinstance(parameters, dict):
            raise ParameterError(f"parameters must be a dict {{symbol: value}}, got {parameters!r}")
        params = tuple(_symbol("a parameter (a key of parameters)", p) for p in parameters)
        values = tuple(_value(p.name, parameters[p]) for p in params)
        both = [p.name for p in params if p in states]
        if both:
            raise ParameterError(f"{', '.join(both)} is both a state variable and a parameter")
        seen = {}
        for s in states + params:
            if s.name in seen and seen[s.name] != s:
                raise ParameterError(f"two different symbols are named {s.name} (their assumptions differ): "
                                     "use one symbol for each name")
            seen[s.name] = s
        if name is not None and not isinstance(name, str):
            raise ParameterError(f"name must be a string, got {name!r}")
        self.states = states
        self.rhs = rhs
        self.parameters = dict(zip(params, values))
        self.name = name if name is not None else "system"
        for s, e in zip(states, rhs):
            self._check_expression(f"the equation of d{s.name}/dt", e)
        self.energy = None
        if energy is not None:
            self.energy = _expression("energy", energy)
            self._check_expression("the energy", self.energy)
        self.reversors = self._reversors(reversor)

    def _reversors(self, reversor) -> tuple:
        """The reversors as tuples of images in state order, each checked: every state variable
        mapped, an involution, ``f(R x) + DR f(x) = 0``, ``H(R x) = H(x)``."""
        if reversor is None:
            return ()
        given = [reversor] if isinstance(reversor, dict) else reversor
        if not isinstance(given, (list, tuple)) or not given or not all(isinstance(r, dict) for r in given):
            raise ParameterError(f"reversor must be a dict {{state symbol: image}} (or a list of them), "
                                 f"got {reversor!r}")
        out = []
        for r in given:
            for k in r:
                if k not in self.states:
                    raise ParameterError(f"reversor maps {k!r}, which is not a state variable of {self.name} "
                                         f"({_names(self.states)}): a reversor is a map of states")
            missing = [s for s in self.states if s not in r]
            if missing:
                raise ParameterError(f"reversor gives no image of {_names(missing)}: a reversor maps every state "
                                     f"variable ({_names(self.states)})")
            images = tuple(_expression(f"the reversor's image of {s.name}", r[s]) for s in self.states)
            for s, e in zip(self.states, images):
                self._check_expression(f"the reversor's image of {s.name}", e)
            R = dict(zip(self.states, images))
            for s, e in zip(self.states, images):
                if not _vanishes(e.subs(R, simultaneous=True) - s):
                    raise ParameterError(f"reversor is not an involution: it maps {s.name} to {e}, and that back to "
                                         f"{sp.expand(e.subs(R, simultaneous=True))}, not {s.name}")
            for i, (s, e) in enumerate(zip(self.states, images)):
                flow = sum((sp.diff(e, v) * f for v, f in zip(self.states, self.rhs)), sp.Integer(0))
                if not _vanishes(self.rhs[i].subs(R, simultaneous=True) + flow):
                    raise ParameterError(f"reversor does not reverse the equations: d{s.name}/dt at the image is "
                                         f"{self.rhs[i].subs(R, simultaneous=True)}, but reversing needs "
                                         f"{sp.expand(-flow)} (minus the rate of its image {e})")
            if self.energy is not None and not _vanishes(self.energy.subs(R, simultaneous=True) - self.energy):
                raise ParameterError("reversor does not keep the energy: H(R x) differs from H(x)")
            out.append(images)
        return tuple(out)

    def _check_expression(self, where, e):
        """Every symbol of ``e`` a state or a parameter; every function a supported one."""
        known = set(self.states) | set(self.parameters)
        unknown = sorted((s for s in e.free_symbols if s not in known), key=lambda s: s.name)
        if unknown:
            u = unknown[0]
            if u.name in {s.name for s in known}:
                raise ParameterError(f"{where} uses a symbol {u.name} that differs from the state variable or "
                                     f"parameter {u.name} (two different symbols are named {u.name}: their "
                                     "assumptions differ): use one symbol for each name")
            hint = did_you_mean(u.name, [s.name for s in known])
            raise ParameterError(
                f"{where} uses {u.name}, which is neither a state variable ({_names(self.states)}) nor a parameter "
                f"({_names(self.parameters)}){hint}: a state variable needs an equation, a parameter a value")
        for f in e.atoms(sp.Function):
            if not isinstance(f, SUPPORTED_FUNCTIONS):
                allowed = ", ".join(g.__name__ for g in SUPPORTED_FUNCTIONS)
                raise ParameterError(f"{where} uses {type(f).__name__}, which is not supported "
                                     f"(+, -, *, /, powers, sqrt, {allowed})")
        for a in sp.preorder_traversal(e):
            if not isinstance(a, (sp.Symbol, sp.Number, sp.Add, sp.Mul, sp.Pow, sp.NumberSymbol)
                              + SUPPORTED_FUNCTIONS):
                raise ParameterError(f"{where} contains {a} ({type(a).__name__}), which is not supported")

    # ------------------------------------------------------------------ values
    @property
    def dimension(self) -> int:
        """The number of state variables."""
        return len(self.states)

    def parameter_array(self) -> np.ndarray:
        """The parameter values in the order of ``parameters`` (the array the generated code reads)."""
        return np.array(list(self.parameters.values()), dtype=np.float64)

    def with_(self, **changes) -> System:
        """The same equations with other parameter values, by name: ``system.with_(lam=0.5)``."""
        by_name = {p.name: p for p in self.parameters}
        values = dict(self.parameters)
        for key, v in changes.items():
            if key not in by_name:
                raise ParameterError(f"{self.name} has no parameter {key}{did_you_mean(key, by_name)} "
                                     f"(its parameters: {_names(self.parameters)})")
            values[by_name[key]] = _value(key, v)
        out = object.__new__(System)      # the same checked content, other values
        out.__dict__.update(self.__dict__, parameters=values)
        return out

    def variational(self, vectors: int = 1) -> System:
        """The system with ``vectors`` deviation vectors: states x, then d1_x..., d2_x..., with
        dd/dt = J(x) d, J the symbolic Jacobian of the right-hand sides (its entries
        ``sympy.diff``).  Same parameters (same order and values); no energy."""
        if isinstance(vectors, bool) or not isinstance(vectors, numbers.Integral) or vectors < 1:
            raise ParameterError(f"vectors must be an integer >= 1, got {vectors!r}")
        taken = {s.name for s in self.states} | {p.name for p in self.parameters}
        prefix = "d"
        while any(n.startswith(prefix) for n in taken):
            prefix = "_" + prefix
        jac = [[sp.diff(f, x) for x in self.states] for f in self.rhs]
        equations = dict(zip(self.states, self.rhs))
        for v in range(1, vectors + 1):
            dev = [sp.Symbol(f"{prefix}{v}_{x.name}") for x in self.states]
            for i, d in enumerate(dev):
                equations[d] = sum((jac[i][j] * dev[j] for j in range(self.dimension) if jac[i][j] != 0), sp.Integer(0))
        return System(equations, parameters=dict(self.parameters), name=f"{self.name}_variational{vectors}")

    # ------------------------------------------------------------------ identity
    def _hash(self, key: str, reversors: bool) -> str:
        if key not in self.__dict__:
            parts = [f"format {HASH_FORMAT}", sp.srepr(self.states), sp.srepr(self.rhs),
                     sp.srepr(tuple(self.parameters)), sp.srepr(self.energy)]
            if reversors and self.reversors:
                parts.append("reversors " + sp.srepr(self.reversors))
            self.__dict__[key] = hashlib.sha256("\n".join(parts).encode()).hexdigest()
        return self.__dict__[key]

    @property
    def content_hash(self) -> str:
        """SHA-256 (hex) of the symbolic content: ``srepr`` of the states, right-hand sides,
        parameter symbols (in order), energy and reversors (when there are any), and
        :data:`HASH_FORMAT`.  Not of the parameter values (runtime data) nor the name."""
        return self._hash("_content_hash", True)

    @property
    def flow_hash(self) -> str:
        """:attr:`content_hash` without the reversors: what the generated code depends on
        (:func:`explorer.integrate.codegen.module_key`), so declaring a reversor compiles nothing new."""
        return self._hash("_flow_hash", False)

    def __repr__(self):
        eqs = ", ".join(f"d{s.name}/dt = {e}" for s, e in zip(self.states, self.rhs))
        pars = ", ".join(f"{p.name}={v!r}" for p, v in self.parameters.items())
        return f"System({self.name!r}: {eqs}; {pars})"
