#!/usr/bin/env python
"""Write ``src/explorer/integrate/_lanes_generated.py``: the lane (SIMD) kernels of the Taylor method.

The generated kernels advance LANES orbits in lockstep.  Their coefficient arrays have the
layout ``X[k, var, lane]`` (lanes contiguous), and every lane-parallel operation is one LLVM
vector instruction on ``<LANES x double>`` (numba intrinsics defined in the generated
module).  IEEE fadd/fsub/fmul/fneg on a vector are lane-wise the same operations as on a
scalar, and no fast-math flag is ever set (no reassociation, no FMA contraction), so each
lane computes bit for bit what the scalar kernels compute - provided the expression trees are
the same.  That is why the coefficient kernel is not written by hand: it is *translated* from
the source of the scalar :func:`explorer.model.equations.taylor_coefficients` (its Python AST), so
every formula keeps its operation order; the Horner and step-norm kernels mirror the few
lines of :func:`explorer.kernels.taylor.evaluate` / ``step_size``.

Why explicit vectors and not unrolled scalar lanes plus ``numba.config.SLP_VECTORIZE``: with
lanes unrolled into scalar accumulators, LLVM's SLP vectorizer vectorizes the loop body but
keeps the 5 x LANES accumulators as scalar phi nodes (a shuffle storm every iteration) and
only runs when the flag is on at the moment of compilation (which on-disk caching does not
record).  Explicit vector values need no flag: order 15, ~42 ns per orbit-step at LANES = 8
on AVX-512 (vs ~150 ns with SLP, ~225 ns scalar).

Regenerate after changing ``equations.taylor_coefficients`` (tests/test_lanes.py checks that
the file is up to date)::

    python tools/gen_lanes.py            # writes src/explorer/integrate/_lanes_generated.py
    python tools/gen_lanes.py --check    # exit 1 if the file is stale
    python tools/gen_lanes.py -o FILE    # write elsewhere
"""
from __future__ import annotations

import argparse
import ast
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EQUATIONS = ROOT / "src" / "explorer" / "model" / "equations.py"
OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_lanes_generated.py"
TANGENT_OUTPUT = ROOT / "src" / "explorer" / "integrate" / "_tangent_lanes_generated.py"

#: lanes per vector: 8 doubles = one AVX-512 register (two AVX2 registers elsewhere).
#: Measured (order 15, coefficients per orbit-step): 4 lanes ~62 ns, 8 lanes ~42 ns, 16 lanes
#: ~37 ns; 8 is chosen because whole-run throughput also pays for idle lanes at block ends.
DEFAULT_LANES = 8
NVAR = 5

HEADER = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients (translated
# operation by operation) and templates mirroring explorer.kernels.taylor.
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernels of the Taylor method: LANES = {L} orbits per vector, coefficient arrays
X[k, var, lane] (C-contiguous, lanes contiguous).  Each lane computes bit for bit what the
scalar kernels compute (same IEEE operations in the same order, no fast-math, no FMA).
Used by :mod:`explorer.integrate.lanes`.
"""
import numpy as np

from explorer._jit import NOJIT, njit

#: orbits advanced in lockstep by one vector instruction
LANES = {L}
#: state variables (p1, p2, M, g1, g2)
NVAR = {NVAR}
#: log2(1 + x) ~ sum_k LOG2_POLY[k] x^k on [0, 1) (max error 2.05e-4) and a bound of the
#: error of vlog2_approx (tests/test_lanes.py checks it)
LOG2_POLY = (2.0426737e-4, 1.4360970, -0.66951221, 0.31221131, -0.079149502)
LOG2_APPROX_ERR = 4e-4
'''

SIMD = '''

# ---------------------------------------------------------------------------- vector values
# f64vec is <LANES x double> in LLVM.  vload/vstore address a C-contiguous float64 array by
# its flat element index; the arithmetic is plain fadd/fsub/fmul/fneg (no fast-math flags).
if NOJIT:  # pragma: no cover - plain-Python twins (numpy elementwise = the same IEEE ops)
    def vload(a, i):
        return a.reshape(-1)[i:i + LANES].copy()

    def vstore(a, i, v):
        a.reshape(-1)[i:i + LANES] = v

    def vzero():
        return np.zeros(LANES)

    def vsplat(x):
        return np.full(LANES, x)

    def vadd(a, b):
        return a + b

    def vsub(a, b):
        return a - b

    def vmul(a, b):
        return a * b

    def vneg(a):
        return -a

    def vabs(a):
        return np.abs(a)

    def vmax_gt(v, s):
        return np.where(v > s, v, s)

    def vdiv(a, b):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return a / b

    def vlog2_approx(v):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log2(v)

    def atomic_fetch_add(a, i, v):
        old = a[i]
        a[i] += v
        return old
else:
    from llvmlite import ir as _ir
    from numba.core import cgutils as _cgutils
    from numba.core import types as _types
    from numba.extending import intrinsic as _intrinsic
    from numba.extending import models as _models
    from numba.extending import register_model as _register_model

    class F64Vec(_types.Type):
        """LANES float64 values held as one LLVM vector value."""

        def __init__(self):
            super().__init__(name="f64x%d" % LANES)

    f64vec = F64Vec()
    _VT = _ir.VectorType(_ir.DoubleType(), LANES)

    @_register_model(F64Vec)
    class _F64VecModel(_models.PrimitiveModel):
        def __init__(self, dmm, fe_type):
            super().__init__(dmm, fe_type, _VT)

    def _is_c_f64(a):
        return isinstance(a, _types.Array) and a.dtype == _types.float64 and a.layout == "C"

    def _vec_ptr(context, builder, arrty, arr, idx):
        ary = context.make_array(arrty)(context, builder, arr)
        return builder.bitcast(builder.gep(ary.data, [idx]), _VT.as_pointer())

    @_intrinsic
    def vload(typingctx, a, i):
        """a.flat[i:i + LANES] as a vector."""
        if not (_is_c_f64(a) and isinstance(i, _types.Integer)):
            return None

        def codegen(context, builder, sig, args):
            return builder.load(_vec_ptr(context, builder, sig.args[0], args[0], args[1]), align=8)
        return f64vec(a, _types.intp), codegen

    @_intrinsic
    def vstore(typingctx, a, i, v):
        """a.flat[i:i + LANES] = v."""
        if not (_is_c_f64(a) and isinstance(i, _types.Integer) and v == f64vec):
            return None

        def codegen(context, builder, sig, args):
            builder.store(args[2], _vec_ptr(context, builder, sig.args[0], args[0], args[1]), align=8)
            return context.get_dummy_value()
        return _types.void(a, _types.intp, f64vec), codegen

    @_intrinsic
    def vzero(typingctx):
        def codegen(context, builder, sig, args):
            return _ir.Constant(_VT, [0.0] * LANES)
        return f64vec(), codegen

    @_intrinsic
    def vsplat(typingctx, x):
        """(x, x, ..., x)."""
        if not isinstance(x, (_types.Float, _types.Integer)):
            return None

        def codegen(context, builder, sig, args):
            i32 = _ir.IntType(32)
            v = builder.insert_element(_ir.Constant(_VT, _ir.Undefined), args[0], _ir.Constant(i32, 0))
            return builder.shuffle_vector(v, _ir.Constant(_VT, _ir.Undefined),
                                          _ir.Constant(_ir.VectorType(i32, LANES), [0] * LANES))
        return f64vec(_types.float64), codegen

    def _binary(op):
        @_intrinsic
        def f(typingctx, a, b):
            if not (a == f64vec and b == f64vec):
                return None

            def codegen(context, builder, sig, args):
                return getattr(builder, op)(args[0], args[1])
            return f64vec(f64vec, f64vec), codegen
        return f

    vadd = _binary("fadd")
    vsub = _binary("fsub")
    vmul = _binary("fmul")
    vdiv = _binary("fdiv")

    @_intrinsic
    def vneg(typingctx, a):
        if a != f64vec:
            return None

        def codegen(context, builder, sig, args):
            return builder.fneg(args[0])
        return f64vec(f64vec), codegen

    @_intrinsic
    def vabs(typingctx, a):
        """|a| (llvm.fabs, as numba's scalar abs)."""
        if a != f64vec:
            return None

        def codegen(context, builder, sig, args):
            fn = _cgutils.get_or_insert_function(builder.module, _ir.FunctionType(_VT, [_VT]),
                                                 "llvm.fabs.v%df64" % LANES)
            return builder.call(fn, [args[0]])
        return f64vec(f64vec), codegen

    @_intrinsic
    def vmax_gt(typingctx, v, s):
        """v where v > s else s (the scalar ``if v > s: s = v``; fcmp ogt + select)."""
        if not (v == f64vec and s == f64vec):
            return None

        def codegen(context, builder, sig, args):
            return builder.select(builder.fcmp_ordered(">", args[0], args[1]), args[0], args[1])
        return f64vec(f64vec, f64vec), codegen

    @_intrinsic
    def vlog2_approx(typingctx, v):
        """log2(v) within LOG2_APPROX_ERR for positive normal finite v (exponent field plus a
        degree-4 polynomial of the mantissa); garbage for other values."""
        if v != f64vec:
            return None

        def codegen(context, builder, sig, args):
            i64 = _ir.IntType(64)
            IT = _ir.VectorType(i64, LANES)

            def isplat(c):
                return _ir.Constant(IT, [c] * LANES)

            def fsplat(c):
                return _ir.Constant(_VT, [c] * LANES)
            bits = builder.bitcast(args[0], IT)
            e = builder.sitofp(builder.sub(builder.lshr(bits, isplat(52)), isplat(1023)), _VT)
            m = builder.bitcast(builder.or_(builder.and_(bits, isplat(0x000FFFFFFFFFFFFF)),
                                            isplat(0x3FF0000000000000)), _VT)
            x = builder.fsub(m, fsplat(1.0))
            p = fsplat(LOG2_POLY[-1])
            for c in LOG2_POLY[-2::-1]:
                p = builder.fadd(builder.fmul(p, x), fsplat(c))
            return builder.fadd(e, p)
        return f64vec(f64vec), codegen

    @_intrinsic
    def atomic_fetch_add(typingctx, a, i, v):
        """old = a[i]; a[i] += v, atomically (a: C-contiguous int64 array)."""
        if not (isinstance(a, _types.Array) and a.dtype == _types.int64 and a.layout == "C"):
            return None

        def codegen(context, builder, sig, args):
            ary = context.make_array(sig.args[0])(context, builder, args[0])
            return builder.atomic_rmw("add", builder.gep(ary.data, [args[1]]), args[2], "seq_cst")
        return _types.int64(a, _types.intp, _types.int64), codegen
'''

EVALUATE = '''

@njit
def evaluate_lanes(X, order, h, out):
    """out[i, l] = sum_k X[k, i, l] h[l]^k per lane (Horner), h of shape (LANES,), out (NVAR, LANES);
    per lane exactly kernels.taylor.evaluate.  The NVAR chains are interleaved (independent)."""
    hv = vload(h, 0)
    o = order * (NVAR * LANES)
{init}
    for k in range(order - 1, -1, -1):
        o = k * (NVAR * LANES)
{body}
{store}


@njit
def step_norms_lanes(X, order, e_p, e_q, out):
    """Per lane, for the checks and the step size of drivers.orbit_taylor: out has shape (7, LANES);
    out[0] = sum_i X[order, i] and out[1] = sum_i X[order - 1, i] (in the order of
    systems._finite_column: non-finite iff a coefficient is, or the sum overflows);
    with s = max(1, max_i |X[0, i]|), a = max_i |X[order, i]|, bm = max_i |X[order - 1, i]| (the
    norms of kernels.taylor.step_size, in its order): out[2] = a, out[3] = bm, out[4] = s / a,
    out[5] = s / bm (the arguments of its two pow) and out[6] = e_q log2(s / bm) - e_p log2(s / a)
    with vlog2_approx (its sign tells which pow is smaller when it is not too close to 0)."""
    o0 = 0
    op = order * (NVAR * LANES)
    oq = (order - 1) * (NVAR * LANES)
{norms}
'''


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

    def __init__(self, array_name, arrays=None, stride="NVAR"):
        """``arrays`` maps each scalar array name to (lane array, first row): several scalar
        arrays (the state X and a deviation D) can live in one lane array of ``stride`` rows."""
        self.X = array_name
        self.arrays = arrays if arrays is not None else {array_name: (array_name, None)}
        self.stride = stride
        self.vectors = set()

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
        return f"({ast.unparse(k)}) * ({self.stride} * LANES) + ({row}) * LANES"

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
            return node.id, True
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
            elif isinstance(st, ast.Assign) and len(st.targets) == 1:
                tgt = st.targets[0]
                if self.is_x(tgt):
                    code, vec = self.expr(st.value)
                    code = code if vec else f"vsplat({code})"
                    out.append(f"{pad}vstore({self.lane_array(tgt)}, {self.offset(tgt)}, {code})")
                elif isinstance(tgt, ast.Name) and isinstance(st.value, ast.Constant) and st.value.value == 0.0 \
                        and isinstance(st.value.value, float):
                    # an accumulator: a float zero in the lane loop is a zero vector
                    self.vectors.add(tgt.id)
                    out.append(f"{pad}{tgt.id} = vzero()")
                elif isinstance(tgt, ast.Name):
                    code, vec = self.expr(st.value)
                    if vec:
                        self.vectors.add(tgt.id)
                    elif tgt.id in self.vectors:
                        raise Untranslatable(f"{tgt.id} changes from vector to scalar: {ast.unparse(st)}")
                    out.append(f"{pad}{tgt.id} = {code}")
                else:  # tuple unpacking of scalars (the parameters)
                    if self.uses_vector(st):
                        raise Untranslatable(ast.unparse(st))
                    out.append(pad + ast.unparse(st))
            elif isinstance(st, ast.AugAssign) and isinstance(st.target, ast.Name) \
                    and type(st.op) in self.BINOPS:
                name = st.target.id
                if name not in self.vectors:
                    if self.uses_vector(st.value):
                        raise Untranslatable(ast.unparse(st))
                    out.append(pad + ast.unparse(st))
                    continue
                # numba evaluates  a op= e  as  a = a op e
                code, vec = self.expr(st.value)
                code = code if vec else f"vsplat({code})"
                out.append(f"{pad}{name} = {self.BINOPS[type(st.op)]}({name}, {code})")
            else:
                raise Untranslatable(ast.unparse(st))
        return out


def scalar_function(path, name):
    tree = ast.parse(Path(path).read_text())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == name:
            return node
    raise SystemExit(f"{name} not found in {path}")


def coefficients_kernel():
    fn = scalar_function(EQUATIONS, "taylor_coefficients")
    args = [a.arg for a in fn.args.args]
    if args != ["P", "X", "order"]:
        raise Untranslatable(f"unexpected signature {args}")
    tr = Translator("X")
    body = tr.stmts(fn.body, 4)
    doc = ('    """Lane twin of equations.taylor_coefficients, translated from its source by\n'
           '    tools/gen_lanes.py: X[k, i, l] = y_i^(k)(0)/k! of lane l for k = 1..order, given\n'
           '    X[0, :, :]; X has shape (order + 1, NVAR, LANES)."""')
    return "\n\n@njit\ndef taylor_coefficients_lanes(P, X, order):\n" + doc + "\n" + "\n".join(body) + "\n"


def horner_and_norms(arr, store_row):
    """The template pieces shared by both generated files, for the coefficient array ``arr``
    (X or Z): Horner's init, loop body and store (``store_row(i)`` = the out row of variable i),
    and the step norms (kernels.taylor.step_size and the finiteness sums)."""
    pad = " " * 4
    init = "\n".join(f"{pad}a{i} = vload({arr}, o + {i} * LANES)" for i in range(NVAR))
    body = "\n".join(f"{pad * 2}a{i} = vadd(vmul(a{i}, hv), vload({arr}, o + {i} * LANES))" for i in range(NVAR))
    store = "\n".join(f"{pad}vstore(out, {store_row(i)} * LANES, a{i})" for i in range(NVAR))
    norms = []
    for name, base in (("f", "op"), ("g", "oq")):
        terms = [f"vload({arr}, {base} + {i} * LANES)" for i in range(NVAR)]
        acc = terms[0]
        for t in terms[1:]:
            acc = f"vadd({acc}, {t})"
        norms.append(f"{pad}{name} = {acc}")
    norms.append(f"{pad}s = vsplat(1.0)")
    norms.append(f"{pad}a = vzero()")
    norms.append(f"{pad}bm = vzero()")
    for i in range(NVAR):
        norms.append(f"{pad}s = vmax_gt(vabs(vload({arr}, o0 + {i} * LANES)), s)")
        norms.append(f"{pad}a = vmax_gt(vabs(vload({arr}, op + {i} * LANES)), a)")
        norms.append(f"{pad}bm = vmax_gt(vabs(vload({arr}, oq + {i} * LANES)), bm)")
    norms.append(f"{pad}u = vdiv(s, a)")
    norms.append(f"{pad}v = vdiv(s, bm)")
    norms.append(f"{pad}d = vsub(vmul(vsplat(e_q), vlog2_approx(v)), vmul(vsplat(e_p), vlog2_approx(u)))")
    for r, name in enumerate(("f", "g", "a", "bm", "u", "v", "d")):
        norms.append(f"{pad}vstore(out, {r} * LANES, {name})")
    return dict(init=init, body=body, store=store, norms="\n".join(norms))


def evaluate_kernel():
    return EVALUATE.format(**horner_and_norms("X", lambda i: i))


def generate(lanes=DEFAULT_LANES):
    return (HEADER.format(L=lanes, NVAR=NVAR) + SIMD + coefficients_kernel() + evaluate_kernel())


# ----------------------------------------------------------------------------- tangent lanes
#: rows of the tangent lane array Z[k, row, lane]: the orbit, then up to two deviation vectors
TANGENT_ROWS = 15

TANGENT_HEADER = '''\
# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients_tangent
# (translated operation by operation) and templates mirroring explorer.kernels.taylor.
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernels of the tangent Taylor method: LANES orbits per vector, each with its state and
up to two deviation vectors in Z[k, row, lane] (C-contiguous, NROWS rows: 0..4 the orbit,
5..9 the first deviation vector, 10..14 the second).  Each lane computes bit for bit what
equations.taylor_coefficients_tangent and kernels.taylor compute for it (same IEEE operations
in the same order, no fast-math, no FMA).  Used by :mod:`explorer.integrate.tangent_lanes`.
"""
from explorer._jit import njit
from explorer.integrate._lanes_generated import (  # noqa: F401 - the vector operations
    LANES,
    vabs,
    vadd,
    vdiv,
    vload,
    vlog2_approx,
    vmax_gt,
    vmul,
    vneg,
    vsplat,
    vstore,
    vsub,
    vzero,
)

#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)
NROWS = {rows}
#: first row of each deviation vector
DEV1 = 5
DEV2 = 10
'''

TANGENT_TEMPLATES = '''

@njit
def evaluate5_lanes(Z, order, h, out, base):
    """out[base + i, l] = sum_k Z[k, base + i, l] h[l]^k for i = 0..4 (Horner, five interleaved
    chains), out of shape (NROWS, LANES); per lane exactly kernels.taylor.evaluate."""
    hv = vload(h, 0)
    o = order * (NROWS * LANES) + base * LANES
{init}
    for k in range(order - 1, -1, -1):
        o = k * (NROWS * LANES) + base * LANES
{body}
{store}


@njit
def tangent_step_norms_lanes(Z, order, e_p, e_q, out):
    """The step norms of the orbit rows 0..4 (systems.taylor_step: finiteness of the last two
    coefficients, kernels.taylor.step_size on rows 0..4 only), as _lanes_generated.step_norms_lanes:
    out (7, LANES) = (f, g, a, bm, s / a, s / bm, d)."""
    o0 = 0
    op = order * (NROWS * LANES)
    oq = (order - 1) * (NROWS * LANES)
{norms}
'''


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


def tangent_kernels():
    fn = scalar_function(EQUATIONS, "taylor_coefficients_tangent")
    args = [a.arg for a in fn.args.args]
    if args != ["P", "X", "D", "order"]:
        raise Untranslatable(f"unexpected signature {args}")
    arrays = {"X": ("Z", None), "D": ("Z", "db")}
    full = Translator("X", arrays, stride="NROWS").stmts(fn.body, 4)
    dev = Translator("X", arrays, stride="NROWS").stmts(prune(fn.body, "D"), 4)
    doc_full = ('    """Lane twin of equations.taylor_coefficients_tangent, translated from its source by\n'
                '    tools/gen_lanes.py: the orbit\'s coefficients in rows 0..4 and those of the deviation\n'
                '    vector in rows db..db + 4 of Z[k, row, lane], k = 1..order, given Z[0]."""')
    doc_dev = ('    """The deviation vector\'s part of taylor_coefficients_tangent only (its statements that\n'
               '    the stores into D need, unchanged; tools/gen_lanes.py prune): rows db..db + 4 of Z\n'
               '    from the orbit\'s coefficients already in rows 0..4 (the same numbers the full\n'
               '    recurrence recomputes for them)."""')
    return ("\n\n@njit\ndef tangent_coefficients_lanes(P, Z, order, db):\n" + doc_full + "\n" + "\n".join(full)
            + "\n\n\n@njit\ndef deviation_coefficients_lanes(P, Z, order, db):\n" + doc_dev + "\n"
            + "\n".join(dev) + "\n"
            + TANGENT_TEMPLATES.format(**horner_and_norms("Z", lambda i: f"(base + {i})")))


def generate_tangent():
    return TANGENT_HEADER.format(rows=TANGENT_ROWS) + tangent_kernels()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=OUTPUT)
    ap.add_argument("--lanes", type=int, default=DEFAULT_LANES, help="orbits per vector (power of 2)")
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if the output differs")
    ap.add_argument("--tangent-output", type=Path, default=None,
                    help=f"where the tangent lane kernels go (default {TANGENT_OUTPUT.name} when -o is not given)")
    args = ap.parse_args(argv)
    if args.lanes < 1 or args.lanes & (args.lanes - 1):
        ap.error("--lanes must be a power of 2")
    outputs = [(args.output, generate(args.lanes))]
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
        print(f"wrote {path} (LANES = {args.lanes})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
