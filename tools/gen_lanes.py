#!/usr/bin/env python
"""Write the lane (SIMD) Taylor recurrences: ``src/explorer/integrate/_lanes_generated.py`` (the
orbit) and ``_tangent_lanes_generated.py`` (the orbit with deviation vectors).

Both files come from one template (:data:`MODULE`): a header, the vector operations they use
(imported from the hand-written :mod:`explorer.integrate.simd`), the rows of their lane array,
and kernels *translated* from the source (Python AST) of the scalar recurrences
:func:`explorer.model.equations.taylor_coefficients` and ``taylor_coefficients_tangent``.  The
lane arrays have the layout ``X[k, row, lane]`` (lanes contiguous), and every binary operation of
the scalar source becomes exactly one vector operation with the same operands in the same order,
so each lane computes bit for bit what the scalar recurrence computes (no fast-math flag is ever
set: no reassociation, no FMA contraction).  A call statement of another function of
``equations.py`` (``next_coefficients``) is first replaced by that function's statements, its
parameters by the call's arguments (:func:`expand`); a call inside an expression
(``taylor_constants(P)``, scalars) is kept and imported.  Only the recurrences are generated: the Horner sums
and step norms of ``kernels.taylor`` are a few lines, written once by hand in
:mod:`explorer.integrate.lanes`.

Regenerate after changing a recurrence in ``equations.py`` (tests/integrate/test_lanes.py and
test_tangent_lanes.py check that the files are up to date)::

    python tools/gen_lanes.py            # writes both files
    python tools/gen_lanes.py --check    # exit 1 if a file is stale
    python tools/gen_lanes.py -o FILE [--tangent-output FILE2]    # write elsewhere
"""
from __future__ import annotations

import argparse
import ast
import copy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EQUATIONS = ROOT / "src" / "explorer" / "model" / "equations.py"
OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_lanes_generated.py"
TANGENT_OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_tangent_lanes_generated.py"

#: the one template of a generated file: ``source`` the scalar function(s) translated, ``doc``
#: the module docstring, ``ops`` the names imported from explorer.integrate.simd, ``constants``
#: the rows of the lane array, ``kernels`` the translated functions
MODULE = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.{source}
# (translated operation by operation).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""{doc}

Each lane computes bit for bit what the scalar recurrence computes (the same IEEE operations in
the same order; the vector operations of :mod:`explorer.integrate.simd`: no fast-math, no FMA).
"""
from explorer._jit import njit
from explorer.integrate.simd import (
{ops}
)
{imports}
{constants}
{kernels}'''

#: one translated function in the template
KERNEL = '''

@njit
def {name}({args}):
    """{doc}"""
{body}
'''

#: the names a generated file may import from explorer.integrate.simd (those its code uses)
SIMD_NAMES = ("LANES", "by_groups", "vadd", "vload", "vmul", "vneg", "vsplat", "vstore", "vsub", "vzero")


def module(source, doc, constants, *groups):
    """A generated file from :data:`MODULE`; ``groups`` are the results of :func:`grouped`: the
    kernels (name, args, docstring, body lines) and the text of their dispatcher."""
    code = "".join(KERNEL.format(name=name, args=args, doc=kdoc, body="\n".join(body))
                   for kernels, _ in groups for name, args, kdoc, body in kernels)
    code += "".join(dispatch for _, dispatch in groups)
    ops = "\n".join(f"    {n}," for n in SIMD_NAMES if n == "LANES" or f"{n}(" in code)
    called = sorted(n for n in equations_functions() if f"{n}(" in code)
    imports = f"from explorer.model.equations import {', '.join(called)}\n" if called else ""
    return MODULE.format(source=source, doc=doc, ops=ops, imports=imports, constants=constants, kernels=code)


# ----------------------------------------------------------------------------- translation
class Untranslatable(Exception):
    pass


class Translator:
    """Scalar statements of ``taylor_coefficients`` (X[var, k] layout) -> lane-vector statements
    (X[k, var, lane] layout).  A name is a vector once it is assigned a value that depends on X
    or on a vector; everything else stays scalar and is copied verbatim.  Every binary operation
    becomes exactly one vector operation with the same operands in the same order (a scalar
    operand is splatted), so the per-lane expression tree equals the scalar one."""

    BINOPS = {ast.Add: "vadd", ast.Sub: "vsub", ast.Mult: "vmul"}

    def __init__(self, array_name, arrays=None, stride="NVAR", groups=1):
        """``arrays`` maps each scalar array name to (lane array, first row): several scalar
        arrays (the state X and a deviation D) can live in one lane array of ``stride`` rows.
        ``groups``: G groups of LANES lanes side by side in each row (X[k, row, G * LANES]); every
        vector statement is written G times in turn, once per group (its vector names get the
        suffix _g), so the G groups' independent chains of one statement stand next to each
        other for LLVM to interleave; scalar statements are written once."""
        self.X = array_name
        self.arrays = arrays if arrays is not None else {array_name: (array_name, None)}
        self.stride = stride
        self.groups = groups
        self.g = 0
        self.vectors = set()

    def width(self):
        """The lanes of one row: LANES, or G * LANES."""
        return "LANES" if self.groups == 1 else f"{self.groups} * LANES"

    def vname(self, name):
        """The name of vector ``name`` in the current group."""
        return name if self.groups == 1 else f"{name}_{self.g}"

    def is_x(self, node):
        return isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id in self.arrays

    def lane_array(self, node):
        return self.arrays[node.value.id][0]

    def offset(self, node):
        idx = node.slice
        if not (isinstance(idx, ast.Tuple) and len(idx.elts) == 2):
            raise Untranslatable(ast.unparse(node))
        var, k = idx.elts
        row = ast.unparse(var)
        first = self.arrays[node.value.id][1]
        if first is not None:
            row = f"{first} + ({row})"
        w = self.width()
        group = f" + {self.g} * LANES" if self.g else ""
        return f"({ast.unparse(k)}) * ({self.stride} * {w}) + ({row}) * {w}{group}"

    def uses_vector(self, node):
        for sub in ast.walk(node):
            if self.is_x(sub) or (isinstance(sub, ast.Name) and sub.id in self.vectors):
                return True
        return False

    def expr(self, node):
        """(code, is_vector)."""
        if self.is_x(node):
            return f"vload({self.lane_array(node)}, {self.offset(node)})", True
        if not self.uses_vector(node):
            return ast.unparse(node), False
        if isinstance(node, ast.Name):
            return self.vname(node.id), True
        if isinstance(node, ast.BinOp) and type(node.op) in self.BINOPS:
            a, va = self.expr(node.left)
            b, vb = self.expr(node.right)
            a = a if va else f"vsplat({a})"
            b = b if vb else f"vsplat({b})"
            return f"{self.BINOPS[type(node.op)]}({a}, {b})", True
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            a, _ = self.expr(node.operand)
            return f"vneg({a})", True
        raise Untranslatable(ast.unparse(node))

    def stmts(self, body, indent):
        out = []
        pad = " " * indent
        for st in body:
            if isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant):
                continue  # docstring
            if isinstance(st, ast.For):
                if st.orelse:
                    raise Untranslatable(ast.unparse(st))
                out.append(f"{pad}for {ast.unparse(st.target)} in {ast.unparse(st.iter)}:")
                out += self.stmts(st.body, indent + 4)
            elif self.is_vector_statement(st):
                for g in range(self.groups):   # the statement once per group, in turn
                    self.g = g
                    out.append(pad + self.vector_statement(st))
                self.g = 0
            else:
                out.append(pad + self.scalar_statement(st))
        return out

    def is_vector_statement(self, st):
        """Whether ``st`` computes lane values (written once per group) or scalars (once)."""
        if isinstance(st, ast.Assign) and len(st.targets) == 1:
            tgt = st.targets[0]
            if self.is_x(tgt):
                return True
            if isinstance(tgt, ast.Name) and isinstance(st.value, ast.Constant) and st.value.value == 0.0 \
                    and isinstance(st.value.value, float):
                return True   # an accumulator: a float zero in the lane loop is a zero vector
            if isinstance(tgt, ast.Name):
                return self.uses_vector(st.value)
            return False
        if isinstance(st, ast.AugAssign) and isinstance(st.target, ast.Name) and type(st.op) in self.BINOPS:
            return st.target.id in self.vectors
        raise Untranslatable(ast.unparse(st))

    def vector_statement(self, st):
        tgt = st.targets[0] if isinstance(st, ast.Assign) else st.target
        if isinstance(st, ast.Assign) and self.is_x(tgt):
            code, vec = self.expr(st.value)
            code = code if vec else f"vsplat({code})"
            return f"vstore({self.lane_array(tgt)}, {self.offset(tgt)}, {code})"
        if isinstance(st, ast.Assign) and isinstance(st.value, ast.Constant):
            self.vectors.add(tgt.id)
            return f"{self.vname(tgt.id)} = vzero()"
        if isinstance(st, ast.Assign):
            code, _ = self.expr(st.value)
            self.vectors.add(tgt.id)
            return f"{self.vname(tgt.id)} = {code}"
        # numba evaluates  a op= e  as  a = a op e
        code, vec = self.expr(st.value)
        code = code if vec else f"vsplat({code})"
        name = self.vname(tgt.id)
        return f"{name} = {self.BINOPS[type(st.op)]}({name}, {code})"

    def scalar_statement(self, st):
        if isinstance(st, ast.Assign) and isinstance(st.targets[0], ast.Name) and st.targets[0].id in self.vectors:
            raise Untranslatable(f"{st.targets[0].id} changes from vector to scalar: {ast.unparse(st)}")
        if self.uses_vector(st):
            raise Untranslatable(ast.unparse(st))
        return ast.unparse(st)


def scalar_function(path, name):
    tree = ast.parse(Path(path).read_text())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return node
    raise SystemExit(f"{name} not found in {path}")


def equations_functions():
    """The functions defined in equations.py, by name."""
    tree = ast.parse(EQUATIONS.read_text())
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef)}


def _assigned_names(stmts):
    return {n.id for st in stmts for n in ast.walk(st) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}


class _Rename(ast.NodeTransformer):
    """Parameters -> the call's arguments (copies), locals -> their names at this call."""

    def __init__(self, args, local):
        self.args = args
        self.local = local

    def visit_Name(self, node):
        if node.id in self.args:
            return ast.copy_location(ast.parse(ast.unparse(self.args[node.id]), mode="eval").body, node)
        if node.id in self.local:
            return ast.copy_location(ast.Name(id=self.local[node.id], ctx=node.ctx), node)
        return node


def expand(body, functions=None):
    """``body`` (statements of a scalar function) ready for :class:`Translator`: docstrings
    dropped; a tuple assignment of constants (``a, b = 0.0, 0.0``) split into one assignment per
    name; a call statement ``f(args)`` of a function ``f`` of equations.py replaced by the
    statements of ``f`` (recursively expanded), each parameter replaced by its argument.  The
    locals of ``f`` keep their names at its first call in ``body`` and get the suffix ``_n`` at
    its n-th, so that a later call does not reuse an earlier one's values (prune() sees them
    apart); ``f`` must not assign a parameter, return a value or use a name of the caller."""
    functions = equations_functions() if functions is None else functions
    calls = {}
    caller_names = {n.id for st in body for n in ast.walk(st) if isinstance(n, ast.Name)}

    def walk(stmts):
        out = []
        for st in stmts:
            if isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant):
                continue  # docstring
            if isinstance(st, ast.For):
                out.append(ast.For(target=st.target, iter=st.iter, body=walk(st.body), orelse=st.orelse))
            elif (isinstance(st, ast.Assign) and len(st.targets) == 1 and isinstance(st.targets[0], ast.Tuple)
                  and isinstance(st.value, ast.Tuple) and len(st.targets[0].elts) == len(st.value.elts)
                  and all(isinstance(v, ast.Constant) for v in st.value.elts)):
                out += [ast.Assign(targets=[t], value=v, lineno=st.lineno)
                        for t, v in zip(st.targets[0].elts, st.value.elts)]
            elif (isinstance(st, ast.Expr) and isinstance(st.value, ast.Call)
                  and isinstance(st.value.func, ast.Name) and st.value.func.id in functions):
                out += inline(st.value)
            else:
                out.append(st)
        return out

    def inline(call):
        fn = functions[call.func.id]
        params = [a.arg for a in fn.args.args]
        if call.keywords or len(call.args) != len(params):
            raise Untranslatable(ast.unparse(call))
        inner = expand(fn.body, functions)
        local = _assigned_names(inner)
        if local & set(params) or any(isinstance(n, ast.Return) for st in inner for n in ast.walk(st)):
            raise Untranslatable(f"{fn.name} assigns a parameter or returns a value")
        if local & caller_names:
            raise Untranslatable(f"{fn.name} uses names of its caller: {sorted(local & caller_names)}")
        n = calls[fn.name] = calls.get(fn.name, 0) + 1
        rename = _Rename(dict(zip(params, call.args)), {x: x if n == 1 else f"{x}_{n}" for x in local})
        return [ast.fix_missing_locations(rename.visit(copy.deepcopy(st))) for st in inner]

    return walk(body)


# ----------------------------------------------------------------------------- the two files
#: the numbers G of lane groups a kernel is written for (one specialisation each: G is fixed
#: when the code is written, so every offset is a constant and each group's chains are separate
#: values); the lane arrays have G * LANES lanes.  G = 4 was written too until it had been
#: measured slower than G = 1 on every CPU tried (Zen 3: 1.5-2.3x; an AVX-512 EPYC: slower than
#: G = 2; its accumulators spill, 86 stack accesses per iteration, benchmarks/RESULTS.md): its
#: kernels only cost compile time, so they are no longer written
GROUPS = (1, 2)
GROUPS_DOC = f"#: the numbers of lane groups the kernels are written for\nGROUPS = {GROUPS}"


#: the function a caller calls: the kernel of its G, chosen when the caller is compiled
DISPATCH = '''

#: {name} for each G
_{upper} = {{{table}}}


def {name}({args}, groups):
    """{doc}

    ``groups``: a tuple of G zeros.  Its length is part of its type, so a compiled caller is
    specialised to one G and compiles only that kernel."""
    _{upper}[len(groups)]({args})


@by_groups({name})
def _{name}({args}, groups):
    kernel = _{upper}[len(groups)]

    def impl({args}, groups):
        kernel({args})
    return impl
'''


def grouped(name, args, doc, translate):
    """The kernels ``name_G`` for every G of GROUPS (``translate(G)`` gives the body) and the
    text of ``name(args, groups)``, which calls the kernel of G = len(groups)."""
    kernels = [(f"{name}_{g}", args, f"{name} for G = {g} group{'s' if g > 1 else ''} of LANES lanes.", translate(g))
               for g in GROUPS]
    table = ", ".join(f"{g}: {name}_{g}" for g in GROUPS)
    return kernels, DISPATCH.format(name=name, upper=name.upper(), table=table, args=args, doc=doc)


def generate():
    """``_lanes_generated.py``: the orbit's recurrence on lanes."""
    fn = scalar_function(EQUATIONS, "taylor_coefficients")
    args = [a.arg for a in fn.args.args]
    if args != ["P", "X", "order"]:
        raise Untranslatable(f"unexpected signature {args}")
    doc = ("Lane twin of equations.taylor_coefficients, translated from its source by\n"
           "    tools/gen_lanes.py: X[k, i, l] = y_i^(k)(0)/k! of lane l for k = 1..order, given\n"
           "    X[0, :, :]; X has shape (order + 1, NVAR, G * LANES), G in GROUPS.")
    return module(
        "taylor_coefficients",
        "Lane kernel of the Taylor method: the recurrence of R3 for G groups of LANES orbits (one\n"
        "vector per group), coefficient arrays X[k, var, lane] (C-contiguous, lanes contiguous).\n"
        "Used by :mod:`explorer.integrate.lanes`.",
        f"#: state variables (p1, p2, M, g1, g2): the rows of X\nNVAR = 5\n{GROUPS_DOC}",
        grouped("taylor_coefficients_lanes", "P, X, order", doc,
                lambda g: Translator("X", groups=g).stmts(expand(fn.body), 4)))


#: rows of the tangent lane array Z[k, row, lane]: the orbit, then up to two deviation vectors
TANGENT_ROWS = 15


def _loaded_names(node):
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}


def prune(body, keep_array):
    """The statements of ``body`` that the stores into ``keep_array`` need (a backward slice):
    a store into another array is dropped, an assignment to a name is kept when a kept
    statement reads that name, a loop when its body keeps something.  Statements are not
    reordered or changed, so every kept expression is the scalar one."""
    needed = set()

    def walk(stmts, mark):
        out = []
        for st in stmts:
            if isinstance(st, ast.Expr) and isinstance(st.value, ast.Constant):
                continue
            if isinstance(st, ast.For):
                inner = walk(st.body, mark)
                if inner:
                    loop = ast.For(target=st.target, iter=st.iter, body=inner, orelse=[])
                    out.append(loop)
                    if mark:
                        needed.update(_loaded_names(st.iter))
                continue
            if isinstance(st, ast.Assign):
                tgt = st.targets[0]
                if isinstance(tgt, ast.Subscript):
                    keep = isinstance(tgt.value, ast.Name) and tgt.value.id == keep_array
                    if keep:
                        if mark:
                            needed.update(_loaded_names(st.value) | _loaded_names(tgt.slice))
                        out.append(st)
                    continue
                names = {n.id for n in ast.walk(tgt) if isinstance(n, ast.Name)}
                if names & needed:
                    if mark:
                        needed.update(_loaded_names(st.value))
                    out.append(st)
                continue
            if isinstance(st, ast.AugAssign) and isinstance(st.target, ast.Name):
                if st.target.id in needed:
                    if mark:
                        needed.update(_loaded_names(st.value))
                    out.append(st)
                continue
            raise Untranslatable(ast.unparse(st))
        return out

    while True:
        before = set(needed)
        walk(body, True)
        if needed == before:
            return walk(body, False)


def generate_tangent():
    """``_tangent_lanes_generated.py``: the orbit's and a deviation vector's recurrence, and the
    deviation's part alone (the second vector), on lanes."""
    fn = scalar_function(EQUATIONS, "taylor_coefficients_tangent")
    args = [a.arg for a in fn.args.args]
    if args != ["P", "X", "D", "order"]:
        raise Untranslatable(f"unexpected signature {args}")
    arrays = {"X": ("Z", None), "D": ("Z", "db")}
    body = expand(fn.body)
    pruned = prune(body, "D")
    doc_full = ("Lane twin of equations.taylor_coefficients_tangent, translated from its source by\n"
                "    tools/gen_lanes.py: the orbit's coefficients in rows 0..4 and those of the deviation\n"
                "    vector in rows db..db + 4 of Z[k, row, lane], k = 1..order, given Z[0].")
    doc_dev = ("The deviation vector's part of taylor_coefficients_tangent only (its statements that\n"
               "    the stores into D need, unchanged; tools/gen_lanes.py prune): rows db..db + 4 of Z\n"
               "    from the orbit's coefficients already in rows 0..4 (the same numbers the full\n"
               "    recurrence recomputes for them).")
    return module(
        "taylor_coefficients_tangent",
        "Lane kernels of the tangent Taylor method: G groups of LANES orbits (one vector per group),\n"
        "each orbit with its state and up to two deviation vectors in Z[k, row, lane] (C-contiguous,\n"
        "NROWS rows: 0..4 the orbit, 5..9 the first deviation vector, 10..14 the second).  Used by\n"
        ":mod:`explorer.integrate.tangent_lanes`.",
        f"#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)\nNROWS = {TANGENT_ROWS}\n"
        f"#: first row of each deviation vector\nDEV1 = 5\nDEV2 = 10\n{GROUPS_DOC}",
        grouped("tangent_coefficients_lanes", "P, Z, order, db", doc_full,
                lambda g: Translator("X", arrays, stride="NROWS", groups=g).stmts(body, 4)),
        grouped("deviation_coefficients_lanes", "P, Z, order, db", doc_dev,
                  lambda g: Translator("X", arrays, stride="NROWS", groups=g).stmts(pruned, 4)))


# ----------------------------------------------------------------------------- operation counts
def operation_counts(kernel, order, tangent=False, db=5):
    """The vector operations one call of the generated ``kernel`` (G = 1) executes at ``order``:
    {"vadd": n, "vsub": n, "vmul": n, "vneg": n}, each on one vector of LANES doubles (per lane:
    that many scalar operations).  Counted by running the generated text itself, with
    one-lane numpy stand-ins for the vector operations that count their calls (the roofline of
    benchmarks/bench_roofline.py divides the flops of a step by these)."""
    import re

    import numpy as np

    text = generate_tangent() if tangent else generate()
    text = re.sub(r"from explorer\._jit import njit\nfrom explorer\.integrate\.simd import \(.*?\)\n", "", text,
                  flags=re.S)
    counts = dict.fromkeys(("vadd", "vsub", "vmul", "vneg"), 0)

    def counted(name, fn):
        def op(*args):
            counts[name] += 1
            return fn(*args)
        return op

    ns = {"njit": lambda f: f, "by_groups": lambda stub: (lambda typer: typer), "LANES": 1,
          "vload": lambda a, i: a.reshape(-1)[i:i + 1].copy(),
          "vstore": lambda a, i, v: a.reshape(-1).__setitem__(slice(i, i + 1), v),
          "vzero": lambda: np.zeros(1), "vsplat": lambda x: np.full(1, x),
          "vadd": counted("vadd", np.add), "vsub": counted("vsub", np.subtract),
          "vmul": counted("vmul", np.multiply), "vneg": counted("vneg", np.negative)}
    exec(compile(text, "<generated>", "exec"), ns)
    rows = ns.get("NROWS", 5)
    X = np.zeros((order + 1, rows, 1))
    X[0] = 0.5
    args = (X, order, db) if tangent else (X, order)
    ns[kernel + "_1"](np.ones(9), *args)
    return counts


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=OUTPUT)
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if the output differs")
    ap.add_argument("--tangent-output", type=Path, default=None,
                    help=f"where the tangent lane kernels go (default {TANGENT_OUTPUT.name} when -o is not given)")
    args = ap.parse_args(argv)
    outputs = [(args.output, generate())]
    tangent_out = args.tangent_output
    if tangent_out is None and args.output == OUTPUT:
        tangent_out = TANGENT_OUTPUT
    if tangent_out is not None:
        outputs.append((tangent_out, generate_tangent()))
    if args.check:
        stale = 0
        for path, text in outputs:
            old = path.read_text() if path.exists() else ""
            if old != text:
                print(f"{path} is out of date; run tools/gen_lanes.py", file=sys.stderr)
                stale = 1
        return stale
    for path, text in outputs:
        path.write_text(text)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
