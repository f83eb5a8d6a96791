"""The Taylor recurrence of a :class:`explorer.model.system.System`, derived from its equations
and emitted as compiled Python source (docs/systems.md).

1. **Decomposition** (:func:`decompose`): the right-hand sides, after SymPy's common-subexpression
   elimination (``sympy.cse``), become a list of elementary operations in dependency order (a DAG;
   equal subtrees are one node): ``u + v``, ``u - v``, ``-u``, ``u v``, ``u / v``, ``u^2``,
   ``u^alpha`` (alpha a constant or a parameter), ``sqrt u``, ``exp u``, ``log u``, ``sin u`` and
   ``cos u`` (a pair).  Integer powers are products and squares (exact at u_0 = 0), a negative one a
   division; ``tan u = sin u / cos u``; ``a^b`` with b not constant is ``exp(b log a)``.  A node whose
   operands do not depend on the state (numbers, parameters and operations on them) is a *scalar*,
   computed once per call.
2. **Automatic differentiation** (Jorba & Zou 2005, Exp. Math. 14, 99; the table in
   docs/systems.md): each series node w has normalised coefficients w_k = w^(k)(0)/k!;
   order 0 is the operation itself, order k >= 1 follows from the operands' coefficients up to k
   (the rules at :data:`RULES`), and x_{k+1} = f_k / (k + 1).
3. **Emission** (:func:`source`): a module with ``@njit`` functions (cache=True)
   ``taylor_coefficients(P, X, order)`` (X[i, k] for k = 0..order from X[:, 0]),
   ``taylor_coefficients_into(P, X, order, W)`` (with a work array of ``N_WORK`` rows),
   ``taylor_coefficients_lanes(P, X, order, W)`` (the SIMD form, LANES orbits at once, each lane bit
   for bit the scalar form), ``rhs(y, P, dy)`` and, when the system has one, ``energy(y, P)``.
   :func:`recurrence` gives one recurrence's source alone (also of some right-hand sides, stored in
   given rows): tools/gen_lanes.py writes the engine's Chaplygin recurrences with it.
   P holds the parameter values in the order of ``system.parameters`` (:meth:`System.parameter_array`):
   another value compiles nothing new.  At each order, the Cauchy products of one depth of the DAG
   share one loop over j, and homogeneous linear nodes are written where they are used (neither
   changes a value: each is the same sequence of operations).
4. **Cache** (:func:`load`): the module is written to ``<cache>/<name>_<key>.py``, with ``key`` the
   SHA-256 of the system's :attr:`~System.flow_hash` and :data:`GENERATOR_VERSION`, and imported from that
   file with importlib, so numba's on-disk cache (``cache=True``) applies to it; a second run finds
   the file and does not rewrite it.  The cache directory is ``$EXPLORER_SYSTEMS_CACHE``, else
   ``$XDG_CACHE_HOME/explorer/systems``, else ``~/.cache/explorer/systems``.

Division by a series whose value reaches zero gives inf or nan (``error_model="numpy"``), not an
exception: the integrators' non-finite status reports it.
"""
from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import os
import re
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp

from explorer.integrate import codegen_crossings, codegen_flow, codegen_indicators, codegen_lanes
from explorer.model.system import System
from explorer.model.validation import ParameterError

__all__ = ["GENERATOR_VERSION", "Decomposition", "cache_directory", "decompose", "load", "module_key", "source"]

#: changes whenever the emitted code changes, so that a cached module of an older generator is not used
GENERATOR_VERSION = 12

#: the modules that append drivers to the generated source: each has ``render(system) -> str``, code
#: that calls the recurrence (``taylor_coefficients_into``, ``taylor_coefficients_lanes``, ``energy``)
#: and is compiled beside it, so that numba's cache of it follows the recurrence
TEMPLATES = (codegen_crossings, codegen_indicators, codegen_lanes, codegen_flow)

#: the elementary operations and their recurrence at order k >= 1 (Jorba & Zou 2005)
RULES = {
    "add": "w_k = u_k + v_k",
    "sub": "w_k = u_k - v_k",
    "neg": "w_k = -u_k",
    "mul": "w_k = sum_{j=0..k} u_j v_{k-j}  (c u: w_k = c u_k)",
    "div": "w_k = (u_k - sum_{j=1..k} v_j w_{k-j}) / v_0",
    "square": "w_k = 2 sum_{j<k/2} u_j u_{k-j} + [k even] u_{k/2}^2",
    "pow": "w_k = sum_{j=0..k-1} (alpha (k-j) - j) u_{k-j} w_j / (k u_0)",
    "sqrt": "w_k = (u_k - sum_{j=1..k-1} w_j w_{k-j}) / (2 w_0)",
    "exp": "w_k = sum_{j=1..k} j u_j w_{k-j} / k",
    "log": "w_k = (u_k - sum_{j=1..k-1} j w_j u_{k-j} / k) / u_0",
    "sin": "s_k = sum_{j=1..k} j u_j c_{k-j} / k",
    "cos": "c_k = -sum_{j=1..k} j u_j s_{k-j} / k",
}

#: the order-0 value of each operation, from its operands' values a, b (alpha for pow)
_VALUE = {
    "add": "{a} + {b}", "sub": "{a} - {b}", "neg": "-{a}", "mul": "{a} * {b}", "div": "{a} / {b}",
    "square": "{a} * {a}", "pow": "{a} ** {b}", "sqrt": "math.sqrt({a})", "exp": "math.exp({a})",
    "log": "math.log({a})", "sin": "math.sin({a})", "cos": "math.cos({a})",
}


@dataclass(frozen=True)
class Node:
    """One quantity of the decomposition: ``kind`` is "state" (``index`` its row of X), "param"
    (``index`` its entry of P), "const" (``value``), or an operation of :data:`RULES` on the nodes
    ``args``.  ``scalar``: constant in time (no state among its operands)."""
    kind: str
    args: tuple = ()
    index: int = -1
    value: float = 0.0
    scalar: bool = False


@dataclass
class Decomposition:
    """The nodes in dependency order and, for each output expression, its node."""
    nodes: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    _index: dict = field(default_factory=dict)

    def add(self, node: Node) -> int:
        """The id of ``node``, appended unless an equal node exists (hash-consing)."""
        if node not in self._index:
            self._index[node] = len(self.nodes)
            self.nodes.append(node)
        return self._index[node]


class _Builder:
    """SymPy expression -> nodes of a :class:`Decomposition`."""

    def __init__(self, system: System, d: Decomposition):
        self.d = d
        self.states = {s: i for i, s in enumerate(system.states)}
        self.params = {p: j for j, p in enumerate(system.parameters)}
        self.memo: dict = {}

    def node(self, kind, *args):
        scalar = all(self.d.nodes[a].scalar for a in args)
        return self.d.add(Node(kind, tuple(args), scalar=scalar))

    def const(self, value):
        return self.d.add(Node("const", value=float(value), scalar=True))

    def visit(self, e):
        if e in self.memo:
            return self.memo[e]
        r = self._visit(e)
        self.memo[e] = r
        return r

    def _visit(self, e):
        if e in self.states:
            return self.d.add(Node("state", index=self.states[e]))
        if e in self.params:
            return self.d.add(Node("param", index=self.params[e], scalar=True))
        if e.is_Number or isinstance(e, sp.NumberSymbol):
            return self.const(e)
        if isinstance(e, sp.Add):
            return self._add(e)
        if isinstance(e, sp.Mul):
            return self._mul(e)
        if isinstance(e, sp.Pow):
            return self._pow(e.base, e.exp)
        if isinstance(e, sp.tan):
            u = self.visit(e.args[0])
            return self.node("div", self._sincos(u)[0], self._sincos(u)[1])
        if isinstance(e, (sp.sin, sp.cos)):
            s, c = self._sincos(self.visit(e.args[0]))
            return s if isinstance(e, sp.sin) else c
        if isinstance(e, sp.exp):
            return self.node("exp", self.visit(e.args[0]))
        if isinstance(e, sp.log):
            return self.node("log", self.visit(e.args[0]))
        raise ParameterError(f"{e} ({type(e).__name__}) is not an operation the Taylor generator knows")

    def _sincos(self, u):
        """sin u and cos u, always together (each one's recurrence needs the other)."""
        return self.node("sin", u), self.node("cos", u)

    def _add(self, e):
        """A sum, terms with a negative coefficient subtracted: a - 2b is sub(a, 2b)."""
        plus, minus = [], []
        for t in e.args:
            c, _ = t.as_coeff_Mul()
            (minus if c.is_negative else plus).append(-t if c.is_negative else t)
        if plus:
            acc = self.visit(plus[0])
            rest = plus[1:]
        else:
            acc = self.node("neg", self.visit(minus[0]))
            minus = minus[1:]
            rest = []
        for t in rest:
            acc = self.node("add", acc, self.visit(t))
        for t in minus:
            acc = self.node("sub", acc, self.visit(t))
        return acc

    def _mul(self, e):
        """A product: -1 * u is neg(u); factors with a negative numeric exponent divide."""
        c, rest = e.as_coeff_Mul()
        if c == -1:
            return self.node("neg", self.visit(rest))
        num, den = [], []
        for f in e.args:
            if isinstance(f, sp.Pow) and f.exp.is_Number and f.exp.is_negative:
                den.append(sp.Pow(f.base, -f.exp))
            elif f.is_Rational and not f.is_Integer and f.p == 1:
                den.append(sp.Integer(f.q))   # u/2 as a division by 2, not a product with 0.5
            else:
                num.append(f)
        acc = self._product(num) if num else self.const(1)
        if den:
            acc = self.node("div", acc, self._product(den))
        return acc

    def _product(self, factors):
        # c (u v) / d: the series' Cauchy product, then one scaling by the scalars, a factor c u or
        # u / d giving its scalar to the scaling (not a scaled operand in every term of the sum)
        acc = c = d = None
        for f in factors:
            i = self.visit(f)
            n = self.d.nodes[i]
            parts = [(i, False)]
            if n.kind in ("mul", "div") and not n.scalar and self.d.nodes[n.args[-1]].scalar:
                parts = [(n.args[0], False), (n.args[1], n.kind == "div")]
            elif n.kind == "mul" and not n.scalar and self.d.nodes[n.args[0]].scalar:
                parts = [(n.args[0], False), (n.args[1], False)]
            for j, den in parts:
                if den:
                    d = j if d is None else self.node("mul", d, j)
                elif self.d.nodes[j].scalar:
                    c = j if c is None else self.node("mul", c, j)
                else:
                    acc = j if acc is None else self.node("mul", acc, j)
        if d is not None:
            c = self.node("div", self.const(1) if c is None else c, d)
        return c if acc is None else acc if c is None else self.node("mul", c, acc)

    def _pow(self, base, ex):
        if ex.is_Integer:
            n = int(ex)
            if n < 0:
                return self.node("div", self.const(1), self._pow(base, -ex))
            if n == 0:
                return self.const(1)
            u = self.visit(base)
            return self._int_pow(u, n)
        if ex == sp.Rational(1, 2):
            return self.node("sqrt", self.visit(base))
        if ex.is_Number:
            return self.node("pow", self.visit(base), self.const(ex))
        alpha = self.visit(ex)
        if self.d.nodes[alpha].scalar:
            return self.node("pow", self.visit(base), alpha)
        # a^b with b a series: exp(b log a)
        return self.node("exp", self.node("mul", alpha, self.node("log", self.visit(base))))

    def _int_pow(self, u, n):
        """u^n, n >= 1, by squaring: exact where u_0 = 0 (unlike the u^alpha rule)."""
        if n == 1:
            return u
        half = self._int_pow(u, n // 2)
        sq = self.node("square", half)
        return self.node("mul", sq, u) if n % 2 else sq


def decompose(system: System, expressions=None, into: Decomposition | None = None) -> Decomposition:
    """The elementary operations of ``expressions`` (default: the right-hand sides), common
    subexpressions shared (``sympy.cse``, then equal subtrees are one node).  ``into``: a
    decomposition to extend (its nodes and outputs kept as they are, equal nodes shared; the
    states' and parameters' indices must be the same in both systems)."""
    exprs = list(system.rhs if expressions is None else expressions)
    replacements, reduced = sp.cse(exprs, order="none")
    d = Decomposition() if into is None else into
    b = _Builder(system, d)
    for sym, e in replacements:
        b.memo[sym] = b.visit(e)
    d.outputs = d.outputs + [b.visit(e) for e in reduced]
    return d


def decompose_extending(orbit: System, system: System) -> Decomposition:
    """The decomposition of ``orbit`` extended by the rest of ``system`` (whose first states and
    parameters are the orbit's), one block of ``orbit.dimension`` rows after another: the orbit's rows
    are its own operations, so their values those of the orbit's recurrence bit for bit."""
    d = decompose(orbit)
    n = orbit.dimension
    for k in range(n, system.dimension, n):
        decompose(system, system.rhs[k:k + n], into=d)
    return d


# ---------------------------------------------------------------------- emission
class _Emitter:
    """Source lines of one decomposition: scalars once, order 0, then orders k >= 1.

    ``lanes``: the SIMD form (:mod:`explorer.integrate.simd`): X[k, i, l] and W[k, r, l] with
    LANES lanes contiguous, each coefficient a vector (vget/vset), the same operations in the
    same order as the scalar form (so each lane equals the scalar recurrence bit for bit); the
    order-0 values of exp, log, sin, cos and real powers lane by lane with :mod:`math`.  ``rows``: the
    row of X of each output (default: output i in row i)."""

    def __init__(self, d: Decomposition, lanes: bool = False, rows=None):
        self.d = d
        self.lanes = lanes
        self.out_rows = list(range(len(d.outputs))) if rows is None else list(rows)
        # a homogeneous linear node (-u, c u, u / c, u +- v) whose operands are stored is not
        # stored: its coefficient of any order is written where it is used (the same operations,
        # so the same values; fewer rows of W to load)
        self.inline = set()
        for i, n in enumerate(d.nodes):
            if n.scalar or n.kind == "state" or any(a in self.inline for a in n.args):
                continue
            scal = [d.nodes[a].scalar for a in n.args]
            if (n.kind == "neg" or (n.kind == "mul" and scal[0] != scal[1])
                    or (n.kind == "div" and scal == [False, True])
                    or (n.kind in ("add", "sub") and scal == [False, False])):
                self.inline.add(i)
        # a row of W only for a node whose lower orders a rule reads (an operand of a nonlinear
        # node, or a rule on its own past: division, powers, functions); any other node is a local
        # value of the order being computed (the same operations, no store and load)
        history = set()

        def need(i):
            if not (d.nodes[i].scalar or d.nodes[i].kind == "state" or i in history):
                history.add(i)
                for a in d.nodes[i].args if i in self.inline else ():
                    need(a)
        for i, n in enumerate(d.nodes):
            if not (n.scalar or n.kind == "state" or i in self.inline or self.is_linear(i)):
                for a in n.args:
                    need(a)
                if not self.is_product(i):
                    need(i)
        self.row = {}
        for i, n in enumerate(d.nodes):
            if i in history and i not in self.inline:
                self.row[i] = len(self.row)

    def is_linear(self, i):
        """w_k from its operands' coefficients of order k alone: +, -, neg, a scaling."""
        n = self.d.nodes[i]
        return n.kind in ("add", "sub", "neg") or (n.kind in ("mul", "div") and self.d.nodes[n.args[1]].scalar) \
            or (n.kind == "mul" and self.d.nodes[n.args[0]].scalar)

    def linear(self, i, leaf):
        """The expression of inlined node i from its operands' ``leaf(a)``."""
        n = self.d.nodes[i]
        a = n.args[0]
        if n.kind == "neg":
            return f"(-{leaf(a)})"
        b = n.args[1]
        if n.kind == "mul":
            return f"(s{a} * {leaf(b)})" if self.d.nodes[a].scalar else f"({leaf(a)} * s{b})"
        if n.kind == "div":
            return f"({leaf(a)} / s{b})"
        return f"({leaf(a)} {'+' if n.kind == 'add' else '-'} {leaf(b)})"

    # -- access to one coefficient (a code string), scalar or vector
    def load(self, array, r, k):
        return f"vget({array}, {k}, {r})" if self.lanes else f"{array}[{r}, {k}]"

    def store(self, array, r, k, code):
        return f"vset({array}, {k}, {r}, {code})" if self.lanes else f"{array}[{r}, {k}] = {code}"

    def zero(self):
        return "vzero()" if self.lanes else "0.0"

    def coef(self, i, k):
        """The coefficient of series node i at order ``k``."""
        n = self.d.nodes[i]
        if n.kind == "state":
            return self.load("X", n.index, k)
        if i in self.inline:
            return self.linear(i, lambda a: self.coef(a, k))
        if i in self.row:
            return self.load("W", self.row[i], k)
        return self.local(i, k)

    @staticmethod
    def local(i, k):
        """The name of node i's local value (no row of W: read at the order being computed only):
        ``u<i>`` at order 0, ``v<i>`` at the orders k >= 1.  Two names, not one assigned twice, so that
        numba's SSA pass has no violator to fix for it: it rewrites the whole function once per name
        assigned more than once."""
        return f"u{i}" if k == 0 else f"v{i}"   # k: 0, or the code of an order k >= 1 ("k", "k - j")

    def w(self, r, k):
        return self.load("W", r, k)

    def value(self, i):
        """The order-0 value of node i."""
        n = self.d.nodes[i]
        if n.scalar:
            return f"s{i}"
        return self.coef(i, 0)

    def lane_value(self, i):
        """The order-0 value of node i in lane ``l`` (a float)."""
        n = self.d.nodes[i]
        if n.scalar:
            return f"s{i}"
        if n.kind == "state":
            return f"X[0, {n.index}, l]"
        if i in self.inline:
            return self.linear(i, self.lane_value)
        return f"W[0, {self.row[i]}, l]"

    def scalar_lines(self):
        out = []
        for i, n in enumerate(self.d.nodes):
            if not n.scalar:
                continue
            if n.kind == "param":
                code = f"P[{n.index}]"
            elif n.kind == "const":
                code = repr(n.value)
            else:
                code = self.op_value(n, self.value)
            out.append(f"s{i} = {code}")
        return out

    def op_value(self, n, value):
        a = value(n.args[0])
        b = value(n.args[1]) if len(n.args) > 1 else ""
        return _VALUE[n.kind].format(a=a, b=b)

    def put(self, i, k, code):
        """Node i's coefficient ``k`` (the order being computed) := code."""
        return self.store("W", self.row[i], k, code) if i in self.row else f"{self.local(i, k)} = {code}"

    def order0_lines(self):
        out = []
        for i, n in enumerate(self.d.nodes):
            if n.scalar or n.kind == "state" or i in self.inline:
                continue
            if i not in self.row:
                out.append(self.put(i, 0, self.op_value(n, self.value)))
            elif not self.lanes:
                out.append(self.store("W", self.row[i], 0, self.op_value(n, self.value)))
            elif n.kind == "sqrt":   # IEEE sqrt, correctly rounded: the vector one equals math.sqrt
                out.append(self.store("W", self.row[i], 0, f"vsqrt({self.value(n.args[0])})"))
            elif n.kind in ("pow", "exp", "log", "sin", "cos"):
                out += ["for l in range(LANES):",
                        f"    W[0, {self.row[i]}, l] = {self.op_value(n, self.lane_value)}"]
            else:
                out.append(self.store("W", self.row[i], 0, self.op_value(n, self.value)))
        return out

    def is_product(self, i):
        """A Cauchy product of two series (the nodes whose loops are fused)."""
        n = self.d.nodes[i]
        return n.kind == "mul" and not any(self.d.nodes[a].scalar for a in n.args)

    def depths(self):
        """Depth of each node in the DAG: 0 for states and scalars, else 1 + its operands' largest.
        Nodes of one depth do not depend on each other at any order."""
        depth = []
        for n in self.d.nodes:
            if n.scalar or n.kind == "state":
                depth.append(0)
            else:
                depth.append(1 + max(depth[a] for a in n.args))
        return depth

    def orderk_lines(self):
        """Statements for the coefficient k >= 1 of every series node (``k`` a loop variable);
        the rules of :data:`RULES`.  Depth by depth; the Cauchy products of one depth share one
        loop over j, each with its own sum (independent chains of additions, which the CPU
        overlaps; each sum is the same sequence of operations as alone)."""
        depth = self.depths()
        out = []
        for level in range(1, max(depth, default=0) + 1):
            here = [i for i, n in enumerate(self.d.nodes) if depth[i] == level and i not in self.inline]
            products = [i for i in here if self.is_product(i)]
            if products:
                z = self.zero()
                out += [f"m{i} = {z}" for i in products]
                out.append("for j in range(k + 1):")
                for i in products:
                    a, b = self.d.nodes[i].args
                    out.append(f"    m{i} = m{i} + {self.coef(a, 'j')} * {self.coef(b, 'k - j')}")
                out += [self.put(i, "k", f"m{i}") for i in products]
            for i in here:
                if not self.is_product(i):
                    out += self.node_lines(i)
        # acc = acc + x, not acc += x: the vector type has + but no in-place +
        return [re.sub(r"^(\s*)(acc2?) ([+-])= ", r"\1\2 = \2 \3 ", line) for line in out]

    def node_lines(self, i):
        """Statements for the coefficient k >= 1 of series node i (not a fused product)."""
        out = []
        nodes = self.d.nodes
        z = self.zero()
        n = nodes[i]
        w = self.row.get(i)
        a = n.args[0]
        sa = nodes[a].scalar
        b = n.args[-1]
        sb = nodes[b].scalar
        U = (lambda j, a=a: self.coef(a, j))  # noqa: E731
        V = (lambda j, b=b: self.coef(b, j))  # noqa: E731
        W = self.w
        put = (lambda code, i=i: self.put(i, "k", code))  # noqa: E731
        if n.kind in ("add", "sub"):
            if sa:
                code = f"-{V('k')}" if n.kind == "sub" else V("k")
            elif sb:
                code = U("k")
            else:
                code = f"{U('k')} {'+' if n.kind == 'add' else '-'} {V('k')}"
            out.append(put(code))
        elif n.kind == "neg":
            out.append(put(f"-{U('k')}"))
        elif n.kind == "mul":
            if sa:
                out.append(put(f"s{a} * {V('k')}"))
            else:   # a product of two series: fused in orderk_lines
                out.append(put(f"{U('k')} * s{b}"))
        elif n.kind == "div":
            if sb:
                out.append(put(f"{U('k')} / s{b}"))
            else:
                out += [f"acc = {z if sa else U('k')}", "for j in range(1, k + 1):",
                        f"    acc -= {V('j')} * {W(w, 'k - j')}", put(f"acc / {V(0)}")]
        elif n.kind == "square":
            out += [f"acc = {z}", "for j in range((k + 1) // 2):", f"    acc += {U('j')} * {U('k - j')}",
                    "acc = 2.0 * acc", "if k % 2 == 0:", f"    acc += {U('k // 2')} * {U('k // 2')}", put("acc")]
        elif n.kind == "pow":
            out += [f"acc = {z}", "for j in range(k):",
                    f"    acc += (s{b} * (k - j) - j) * {U('k - j')} * {W(w, 'j')}", put(f"acc / (k * {U(0)})")]
        elif n.kind == "sqrt":
            out += [f"acc = {U('k')}", "for j in range(1, k):", f"    acc -= {W(w, 'j')} * {W(w, 'k - j')}",
                    put(f"acc / (2.0 * {W(w, 0)})")]
        elif n.kind == "exp":
            out += [f"acc = {z}", "for j in range(1, k + 1):", f"    acc += j * {U('j')} * {W(w, 'k - j')}",
                    put("acc / k")]
        elif n.kind == "log":
            out += [f"acc = {z}", "for j in range(1, k):", f"    acc += j * {W(w, 'j')} * {U('k - j')}",
                    put(f"({U('k')} - acc / k) / {U(0)}")]
        elif n.kind == "sin":
            c = self.row[self.d._index[Node("cos", n.args)]]
            out += [f"acc = {z}", f"acc2 = {z}", "for j in range(1, k + 1):", f"    t = j * {U('j')}",
                    f"    acc += t * {W(c, 'k - j')}", f"    acc2 += t * {W(w, 'k - j')}",
                    put("acc / k"), self.store("W", c, "k", "-acc2 / k")]
        elif n.kind == "cos":
            pass  # with its sine
        else:  # pragma: no cover - every kind of _Builder is above
            raise AssertionError(n.kind)
        return out

    def output(self, i, k):
        """Coefficient ``k`` of output node i, zero for k >= 1 of a scalar."""
        n = self.d.nodes[i]
        if n.scalar:
            code = f"s{i}" if k == 0 else "0.0"
            return f"vsplat({code})" if self.lanes else code
        return self.coef(i, k)

    def next_lines(self):
        """x_1 = f_0 and x_{k+1} = f_k (1 / (k + 1))."""
        first = [self.store("X", i, 1, self.output(o, 0)) for i, o in zip(self.out_rows, self.d.outputs)]
        # one reciprocal per order: a product per row, not a division
        nxt = ["r = 1.0 / (k + 1)"] + [self.store("X", i, "k + 1", f"{self.output(o, 'k')} * r")
                                       for i, o in zip(self.out_rows, self.d.outputs)]
        return first, nxt


def _indent(lines, n):
    return "\n".join(" " * n + line for line in lines)


MODULE = '''\
# GENERATED FILE - DO NOT EDIT. Written by explorer.integrate.codegen (generator version {version})
# from the system {name!r}; the key {key} is of its content (explorer.model.system.System.flow_hash).
#
{equations}
"""The Taylor recurrence, right-hand side{and_energy} of the system {name!r} (explorer.integrate.codegen)."""
import math

import numpy as np

from explorer._jit import njit
from explorer.kernels.checks import all_finite, is_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.kernels.status import STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels.taylor import evaluate, step_size

#: state dimension, number of parameters, rows of the work array of taylor_coefficients_into
DIM = {dim}
N_PARAMS = {n_params}
N_WORK = {n_work}


{scalar_recurrence}

#: taylor_step's status of a step taken
STEP_OK = -1


@njit(error_model="numpy")
def _rows_finite(X, k, n):
    for i in range(n):
        if not is_finite(X[i, k]):
            return False
    return True


@njit(error_model="numpy")
def taylor_step(P, X, W, n, t, tend, order, factor, steps, ynew, backward):
    """One step of the adaptive Taylor method of ``order`` (Jorba & Zou 2005) from X[:, 0] at time
    t towards tend: the coefficients, the step from rows :n (the orbit's) clipped onto tend, ynew
    the state at its end.  ``backward``: t is the time elapsed backward, the coefficients those of
    y(t0 - t), (-1)^k X[:, k] (exactly the flow of -f's).  Returns (status, h, last, steps): STEP_OK,
    or why no step was taken (h = 0) or why its end is not finite."""
    taylor_coefficients_into(P, X, order, W)
    if backward:
        for k in range(1, order + 1, 2):
            for i in range(DIM):
                X[i, k] = -X[i, k]
    if not (_rows_finite(X, order, n) and _rows_finite(X, order - 1, n)):
        return STATUS_NONFINITE, 0.0, False, steps
    h = step_size(X[:n], order, factor)
    h, last = clip_step(t, h, tend)
    if not resolves(t, h):
        return STATUS_STEP_UNDERFLOW, 0.0, False, steps
    evaluate(X, order, h, ynew)
    steps += 1
    if not all_finite(ynew):
        return STATUS_NONFINITE, h, last, steps
    return STEP_OK, h, last, steps


@njit(error_model="numpy")
def rhs(y, P, dy):
    """dy = f(y) (the order-0 part of the recurrence)."""
    X = np.empty((DIM, 1))
    for i in range(DIM):
        X[i, 0] = y[i]
    W = np.empty((max(N_WORK, 1), 1))
{scalars}
{order0}
{rhs_out}


# ---- the SIMD form (explorer.integrate.simd): LANES orbits at once
from explorer.integrate.simd import (  # noqa: E402
    LANES, vadd, vdiv, vget, vload, vmul, vneg, vset, vsplat, vsqrt, vstore, vsub, vzero)

#: the flat stride of one order in the lane array X[k, i, l] (the drivers' helpers; the recurrence
#: addresses X and W by vget and vset)
XS = DIM * LANES


{lanes_recurrence}'''

#: the scalar recurrence ``{name}_into(P, X, order, W)`` and ``{name}(P, X, order)`` (its own W of
#: ``{n_work}`` rows)
SCALAR_RECURRENCE = '''\
# error_model="numpy": a division by zero gives inf/nan (the integrators' non-finite status), not an exception
@njit(error_model="numpy")
def {name}_into(P, X, order, W):
    """{doc}"""
{scalars}
{order0}
{first}
    for k in range(1, order):
{orderk}
{next_}


@njit(error_model="numpy")
def {name}(P, X, order):
    """:func:`{name}_into` with its own work array."""
    W = np.empty((max({n_work}, 1), order + 1))
    {name}_into(P, X, order, W)
'''

#: the SIMD recurrence ``{name}_lanes(P, X, order, W)``
LANES_RECURRENCE = '''\
@njit(error_model="numpy")
def {name}_lanes(P, X, order, W):
    """{doc}"""
{scalars}
{order0}
{first}
    for k in range(1, order):
{orderk}
{next_}
'''

#: the docstrings of a generated module's recurrences
SCALAR_DOC = ("X[i, k] = x_i^(k)(0)/k! for k = 0..order (order >= 1) from X[:, 0], with the parameters P and the\n"
              "    work array W[N_WORK, >= order] (automatic differentiation, Jorba & Zou 2005).")
LANES_DOC = ("LANES orbits at once: X[k, i, l] for k = 1..order from X[0] (X of shape (order + 1, DIM, LANES),\n"
             "    W of shape (order + 1, max(N_WORK, 1), LANES), both C-contiguous).  Each lane equals\n"
             "    taylor_coefficients_into bit for bit (the same operations in the same order).")


@dataclass(frozen=True)
class Recurrence:
    """The source of one recurrence (:func:`recurrence`): ``scalar`` (:data:`SCALAR_RECURRENCE`),
    ``lanes`` (:data:`LANES_RECURRENCE`), ``n_work`` the rows of its work array."""
    scalar: str
    lanes: str
    n_work: int


def recurrence(system: System, name: str = "taylor_coefficients", expressions=None, rows=None, *,
               n_work: str = "N_WORK", doc: str = SCALAR_DOC,
               lanes_doc: str = LANES_DOC, decomposition: Decomposition | None = None) -> Recurrence:
    """The scalar and SIMD recurrence of ``expressions`` (default: the right-hand sides; or of a
    ``decomposition`` already made; the output i stored in row ``rows[i]`` of X, default i), named
    ``name``; ``n_work``: the name of the module's constant of its work rows."""
    d = decompose(system, expressions) if decomposition is None else decomposition
    e = _Emitter(d, rows=rows)
    scalars = _indent(e.scalar_lines(), 4)
    first, next_ = e.next_lines()
    scalar = SCALAR_RECURRENCE.format(name=name, doc=doc, n_work=n_work, scalars=scalars,
                                      order0=_indent(e.order0_lines(), 4), first=_indent(first, 4),
                                      orderk=_indent(e.orderk_lines() or ["pass"], 8), next_=_indent(next_, 8))
    v = _Emitter(d, lanes=True, rows=rows)
    first, next_ = v.next_lines()
    lanes = LANES_RECURRENCE.format(name=name, doc=lanes_doc, scalars=scalars, order0=_indent(v.order0_lines(), 4),
                                    first=_indent(first, 4), orderk=_indent(v.orderk_lines() or ["pass"], 8),
                                    next_=_indent(next_, 8))
    return Recurrence(scalar, vector_calls(lanes), len(e.row))


#: the functions of explorer.integrate.simd that return a vector, and the one of each arithmetic operator
VECTOR_RESULTS = frozenset({"vget", "vzero", "vsplat", "vsqrt", "vadd", "vsub", "vmul", "vdiv", "vneg"})
VECTOR_OPERATORS = {ast.Add: "vadd", ast.Sub: "vsub", ast.Mult: "vmul", ast.Div: "vdiv"}


class _VectorCalls(ast.NodeTransformer):
    """Rewrites :func:`vector_calls`' arithmetic; a name is a vector from its first assignment of a
    vector (the emitted code assigns every name before it reads it, in program order)."""

    def __init__(self):
        self.vectors = set()

    def is_vector(self, node) -> bool:
        if isinstance(node, ast.Call):
            return isinstance(node.func, ast.Name) and node.func.id in VECTOR_RESULTS
        if isinstance(node, ast.Name):
            return node.id in self.vectors
        if isinstance(node, ast.BinOp):
            return self.is_vector(node.left) or self.is_vector(node.right)
        if isinstance(node, ast.UnaryOp):
            return self.is_vector(node.operand)
        return False

    def _vector(self, node):
        return node if self.is_vector(node) else ast.Call(ast.Name("vsplat", ast.Load()), [node], [])

    def visit_BinOp(self, node):
        if not self.is_vector(node):
            return node
        if type(node.op) not in VECTOR_OPERATORS:   # pragma: no cover - the emitter writes no other
            raise AssertionError(f"no vector form of {ast.unparse(node)}")
        node = self.generic_visit(node)
        return ast.Call(ast.Name(VECTOR_OPERATORS[type(node.op)], ast.Load()),
                        [self._vector(node.left), self._vector(node.right)], [])

    def visit_UnaryOp(self, node):
        if not self.is_vector(node):
            return node
        if not isinstance(node.op, ast.USub):   # pragma: no cover - the emitter writes no other
            raise AssertionError(f"no vector form of {ast.unparse(node)}")
        return ast.Call(ast.Name("vneg", ast.Load()), [self.visit(node.operand)], [])

    def visit_Assign(self, node):
        vector = self.is_vector(node.value)
        node = self.generic_visit(node)
        if vector:
            self.vectors.update(t.id for t in node.targets if isinstance(t, ast.Name))
        return node


def vector_calls(text: str) -> str:
    """``text`` (the source of SIMD functions) with every arithmetic operation on a vector written as
    the call of its :mod:`explorer.integrate.simd` intrinsic (``a * b`` as ``vmul(a, b)``, a scalar
    operand splatted: ``2.0 * acc`` as ``vmul(vsplat(2.0), acc)``, what the vector type's operators
    compile to: the same IEEE operations, so each lane keeps its bits).  Numba types an operator by
    trying each template of ``operator.mul`` and the like and compiles the overload it finds as a
    function of its own; a call of the intrinsic is typed by itself and lowered in place
    (docs/systems.md, "The cache")."""
    return ast.unparse(_VectorCalls().visit(ast.parse(text))) + "\n"


ENERGY = '''

@njit(error_model="numpy")
def energy(y, P):
    """The energy at the state y."""
    X = np.empty((DIM, 1))
    for i in range(DIM):
        X[i, 0] = y[i]
    W = np.empty((max(N_ENERGY_WORK, 1), 1))
{scalars}
{order0}
    return {out}


N_ENERGY_WORK = {n_work}
'''


def source(system: System, key: str = "", orbit: System | None = None) -> str:
    """The Python source of the generated module (see the module docstring); with ``orbit``, the
    recurrence of :func:`decompose_extending`."""
    d = decompose(system) if orbit is None else decompose_extending(orbit, system)
    e = _Emitter(d)
    dim = system.dimension
    scalars = _indent(e.scalar_lines(), 4)
    order0 = _indent(e.order0_lines(), 4)
    r = recurrence(system, decomposition=None if orbit is None else d)
    lanes, n_work = r.lanes, r.n_work
    if orbit is not None and system.dimension > 2 * orbit.dimension:
        lanes, n_work = _blocked_lanes(orbit, system, n_work)
    rhs_out = _indent([f"dy[{i}] = {e.output(o, 0)}" for i, o in enumerate(d.outputs)], 4)
    equations = "\n".join(f"#   d{s.name}/dt = {f}" for s, f in zip(system.states, system.rhs))
    equations += "\n#   parameters: " + (", ".join(p.name for p in system.parameters) or "none")
    text = MODULE.format(version=GENERATOR_VERSION, name=system.name, key=key, equations=equations,
                         and_energy=" and energy" if system.energy is not None else "", dim=dim,
                         n_params=len(system.parameters), n_work=n_work, scalars=scalars, order0=order0,
                         rhs_out=rhs_out, scalar_recurrence=r.scalar, lanes_recurrence=lanes)
    if system.energy is not None:
        de = decompose(system, [system.energy])
        ee = _Emitter(de)
        text += ENERGY.format(scalars=_indent(ee.scalar_lines(), 4), order0=_indent(ee.order0_lines(), 4),
                              out=ee.output(de.outputs[0], 0), n_work=len(ee.row))
    for template in TEMPLATES:
        text += template.render(system)
    return text


def _blocked_lanes(orbit: System, system: System, n_work: int):
    """The SIMD recurrence of :func:`decompose_extending` in loops over the orders of its blocks: the
    orbit with the first block, then each further block alone from the orbit's rows (the same values:
    tests/integrate/test_tangent_lanes.py); one loop over all rows keeps more vectors live than
    registers hold, and its stack spills run slower when the stack is not 64-byte aligned.  Returns
    (the source, the work rows of the largest)."""
    n = orbit.dimension
    head = decompose(orbit)
    decompose(system, system.rhs[n:2 * n], into=head)
    parts = [recurrence(system, "_block0", decomposition=head)]
    for k in range(2 * n, system.dimension, n):
        parts.append(recurrence(system, f"_block{k // n - 1}", system.rhs[k:k + n], range(k, k + n)))
    calls = "\n".join(f"    _block{i}_lanes(P, X, order, W)" for i in range(len(parts)))
    text = "\n\n".join(p.lanes for p in parts)
    text += f'''

@njit(error_model="numpy")
def taylor_coefficients_lanes(P, X, order, W):
    """{LANES_DOC}"""
{calls}
'''
    return text, max(n_work, *(p.n_work for p in parts))


# ---------------------------------------------------------------------- cache
def cache_directory() -> Path:
    """Where generated modules live: $EXPLORER_SYSTEMS_CACHE, else $XDG_CACHE_HOME/explorer/systems,
    else ~/.cache/explorer/systems."""
    env = os.environ.get("EXPLORER_SYSTEMS_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "explorer" / "systems"


@functools.lru_cache(maxsize=1)
def _callee_digest() -> str:
    """SHA-256 of the sources the generated code calls (explorer.kernels, explorer.integrate.simd,
    .layout and .lane_parts, explorer._jit) and of the templates (:data:`TEMPLATES`): numba's cache of
    a function does not follow a change of a callee in another file, so such a change gives the
    generated module another key (a new file, compiled afresh)."""
    root = Path(__file__).resolve().parent.parent
    files = (sorted((root / "kernels").glob("*.py"))
             + [root / "integrate" / n for n in ("simd.py", "layout.py", "lane_parts.py")] + [root / "_jit.py"]
             + [Path(t.__file__) for t in TEMPLATES])
    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def module_key(system: System, orbit: System | None = None) -> str:
    """The cache key: SHA-256 of the system's flow hash (its content but the reversors),
    :data:`GENERATOR_VERSION`, the sources the generated code calls (:func:`_callee_digest`) and
    the ``orbit`` of :func:`load`."""
    text = f"{system.flow_hash} generator {GENERATOR_VERSION} callees {_callee_digest()}"
    if orbit is not None:
        text += f" orbit {orbit.flow_hash} in blocks"   # _blocked_lanes
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _module_path(system: System, key: str) -> Path:
    stem = re.sub(r"\W", "_", system.name)[:40] or "system"
    return cache_directory() / f"{stem}_{key}.py"


def load(system: System, orbit: System | None = None):
    """The generated module of ``system``: imported once per process (``sys.modules``), written to
    the cache directory only if its file is missing (a rewrite would invalidate numba's cache).
    ``orbit``: the system of the first rows (:func:`decompose_extending`)."""
    key = module_key(system, orbit)
    path = _module_path(system, key)
    mod_name = f"explorer_system_{path.stem}"
    mod = sys.modules.get(mod_name)
    if mod is not None and Path(mod.__file__) == path:
        return mod
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            f.write(source(system, key, orbit))
        os.replace(tmp, path)   # atomic: a concurrent process or thread sees the whole file or none
    spec = importlib.util.spec_from_file_location(mod_name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = mod
    try:
        spec.loader.exec_module(mod)
    except BaseException:
        del sys.modules[mod_name]
        raise
    return mod
