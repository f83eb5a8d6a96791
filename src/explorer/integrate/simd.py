"""Vector values for the lane (SIMD) kernels: ``f64vec``, LANES float64 values held as one LLVM
``<LANES x double>`` value, and its operations as numba intrinsics.

Every operation is one LLVM vector instruction with no fast-math flag (no reassociation, no FMA
contraction): IEEE fadd/fsub/fmul/fdiv/fneg on a vector are lane-wise the same operations as on
a scalar, so a lane computes bit for bit what scalar code with the same expression tree
computes.  Used by the Taylor lane kernels (:mod:`explorer.integrate.lanes`,
:mod:`explorer.integrate.tangent_lanes`) and by the recurrences that ``tools/gen_lanes.py``
translates into ``_lanes_generated.py`` and ``_tangent_lanes_generated.py``.

- :func:`vload` / :func:`vstore`: LANES consecutive elements of a C-contiguous float64 array
  (addressed by the flat index of the first);
- :func:`vzero`, :func:`vsplat`, :func:`vadd`, :func:`vsub`, :func:`vmul`, :func:`vdiv`,
  :func:`vneg`, :func:`vabs`, :func:`vsqrt`, :func:`vmax_gt` (the scalar ``if v > s: s = v``), :func:`vmin_lt`;
- masks (``<LANES x i1>``, lane-wise booleans): the ordered comparisons :func:`vgt`,
  :func:`vge`, :func:`vlt`, :func:`veq` (lane-wise the scalar ``a > b`` ...: false where either is
  NaN), :func:`vand`, :func:`vandnot`, :func:`vor`, :func:`vselect` (``a if m else b`` per lane)
  and :func:`vbits` (the mask as the bits of an integer, lane i bit i: the lanes that a scalar
  loop must visit, one after the other by :func:`next_bit`), :func:`vmask` (bits back to a mask);
- :func:`vradius_power_core`: the step size's power ``kernels.power.radius_power_core`` on every
  lane (the same IR, emitted for a vector: lane-wise the scalar's double);
- :func:`atomic_fetch_add`: the shared queue of orbits of the lane workers;
- :func:`by_groups`: how a compiled caller of a generated recurrence gets the kernel of its
  number of lane groups G (a tuple of G zeros; only that kernel is compiled).

Why explicit vectors and not unrolled scalar lanes plus ``numba.config.SLP_VECTORIZE``: with
lanes unrolled into scalar accumulators, LLVM's SLP vectorizer vectorizes the loop body but
keeps the 5 x LANES accumulators as scalar phi nodes (a shuffle storm every iteration) and
only runs when the flag is on at the moment of compilation (which on-disk caching does not
record).  Explicit vector values need no flag: order 15, ~42 ns per orbit-step at LANES = 8
on AVX-512 (vs ~150 ns with SLP, ~225 ns scalar).

With ``EXPLORER_NOJIT=1`` the operations are numpy twins on arrays of LANES (elementwise: the
same IEEE operations).
"""
import numpy as np

from explorer._jit import NOJIT, njit
from explorer.kernels.power import emit_radius_power, radius_power_core

#: orbits advanced in lockstep by one vector instruction: 8 doubles = one AVX-512 register (two
#: AVX2 registers elsewhere).  Measured (order 15, coefficients per orbit-step): 4 lanes ~62 ns,
#: 8 lanes ~42 ns, 16 lanes ~37 ns; 8 is chosen because whole-run throughput also pays for idle
#: lanes at block ends.
LANES = 8


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

    def vsqrt(a):
        with np.errstate(invalid="ignore"):
            return np.sqrt(a)

    def vmax_gt(v, s):
        return np.where(v > s, v, s)

    def vmin_lt(v, s):
        return np.where(v < s, v, s)

    def vgt(a, b):
        return a > b

    def vge(a, b):
        return a >= b

    def vlt(a, b):
        return a < b

    def veq(a, b):
        return a == b

    def vand(a, b):
        return a & b

    def vandnot(a, b):
        return a & ~b

    def vor(a, b):
        return a | b

    def vselect(m, a, b):
        return np.where(m, a, b)

    def vbits(m):
        return int(sum(1 << i for i in range(LANES) if m[i]))

    def vmask(bits):
        return np.array([bool(bits >> i & 1) for i in range(LANES)])

    def _cttz(bits):
        return (bits & -bits).bit_length() - 1

    def vradius_power_core(v, e):
        with np.errstate(all="ignore"):
            return np.array([radius_power_core(x, e) for x in v])

    def vdiv(a, b):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return a / b

    def atomic_fetch_add(a, i, v):
        old = a[i]
        a[i] += v
        return old

    def by_groups(stub):
        """Nothing to register: the plain-Python ``stub`` runs as it is."""
        return lambda typer: typer
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
    def vsqrt(typingctx, a):
        """The square root of every lane (llvm.sqrt, correctly rounded as numba's scalar math.sqrt)."""
        if a != f64vec:
            return None

        def codegen(context, builder, sig, args):
            fn = _cgutils.get_or_insert_function(builder.module, _ir.FunctionType(_VT, [_VT]),
                                                 "llvm.sqrt.v%df64" % LANES)
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
    def vmin_lt(typingctx, v, s):
        """v where v < s else s (the scalar ``s = v if v < s else s``; fcmp olt + select)."""
        if not (v == f64vec and s == f64vec):
            return None

        def codegen(context, builder, sig, args):
            return builder.select(builder.fcmp_ordered("<", args[0], args[1]), args[0], args[1])
        return f64vec(f64vec, f64vec), codegen

    class B1Vec(_types.Type):
        """LANES booleans held as one LLVM ``<LANES x i1>`` value (a lane mask)."""

        def __init__(self):
            super().__init__(name="b1x%d" % LANES)

    b1vec = B1Vec()
    _MT = _ir.VectorType(_ir.IntType(1), LANES)

    @_register_model(B1Vec)
    class _B1VecModel(_models.PrimitiveModel):
        def __init__(self, dmm, fe_type):
            super().__init__(dmm, fe_type, _MT)

    def _compare(op):
        @_intrinsic
        def f(typingctx, a, b):
            if not (a == f64vec and b == f64vec):
                return None

            def codegen(context, builder, sig, args):
                return builder.fcmp_ordered(op, args[0], args[1])
            return b1vec(f64vec, f64vec), codegen
        return f

    vgt = _compare(">")
    vge = _compare(">=")
    vlt = _compare("<")
    veq = _compare("==")

    def _logic(emit):
        @_intrinsic
        def f(typingctx, a, b):
            if not (a == b1vec and b == b1vec):
                return None

            def codegen(context, builder, sig, args):
                return emit(builder, args[0], args[1])
            return b1vec(b1vec, b1vec), codegen
        return f

    vand = _logic(lambda b, x, y: b.and_(x, y))
    vor = _logic(lambda b, x, y: b.or_(x, y))
    vandnot = _logic(lambda b, x, y: b.and_(x, b.not_(y)))

    @_intrinsic
    def vselect(typingctx, m, a, b):
        """a where m else b, lane by lane."""
        if not (m == b1vec and a == f64vec and b == f64vec):
            return None

        def codegen(context, builder, sig, args):
            return builder.select(args[0], args[1], args[2])
        return f64vec(b1vec, f64vec, f64vec), codegen

    @_intrinsic
    def vbits(typingctx, m):
        """The mask as an int64: bit i set iff lane i is true."""
        if m != b1vec:
            return None

        def codegen(context, builder, sig, args):
            return builder.zext(builder.bitcast(args[0], _ir.IntType(LANES)), _ir.IntType(64))
        return _types.int64(b1vec), codegen

    @_intrinsic
    def vmask(typingctx, bits):
        """The mask of the low LANES bits of an integer: lane i true iff bit i is set (vbits' inverse)."""
        if not isinstance(bits, _types.Integer):
            return None

        def codegen(context, builder, sig, args):
            x = context.cast(builder, args[0], sig.args[0], _types.int64)
            return builder.bitcast(builder.trunc(x, _ir.IntType(LANES)), _MT)
        return b1vec(bits), codegen

    @_intrinsic
    def _cttz(typingctx, bits):
        """The index of the lowest set bit of bits > 0 (llvm.cttz)."""
        if not isinstance(bits, _types.Integer):
            return None

        def codegen(context, builder, sig, args):
            i64 = _ir.IntType(64)
            fn = _cgutils.get_or_insert_function(builder.module, _ir.FunctionType(i64, [i64, _ir.IntType(1)]),
                                                 "llvm.cttz.i64")
            return builder.call(fn, [context.cast(builder, args[0], sig.args[0], _types.int64),
                                     _ir.Constant(_ir.IntType(1), 1)])
        return _types.int64(bits), codegen

    @_intrinsic
    def vradius_power_core(typingctx, v, e):
        """kernels.power.radius_power_core on every lane of v: the IR of
        kernels.power.emit_radius_power for a vector (lane-wise the scalar's IEEE operations)."""
        if not (v == f64vec and isinstance(e, _types.Float)):
            return None

        def codegen(context, builder, sig, args):
            return emit_radius_power(builder, args[0], args[1], LANES)
        return f64vec(f64vec, _types.float64), codegen

    @_intrinsic
    def atomic_fetch_add(typingctx, a, i, v):
        """old = a[i]; a[i] += v, atomically (a: C-contiguous int64 array)."""
        if not (isinstance(a, _types.Array) and a.dtype == _types.int64 and a.layout == "C"):
            return None

        def codegen(context, builder, sig, args):
            ary = context.make_array(sig.args[0])(context, builder, args[0])
            return builder.atomic_rmw("add", builder.gep(ary.data, [args[1]]), args[2], "seq_cst")
        return _types.int64(a, _types.intp, _types.int64), codegen


    def by_groups(stub):
        """Register the decorated typer as the compiled implementation of the plain-Python
        ``stub(..., groups)`` of a generated file (numba's ``overload``): it is asked when a
        caller is compiled, with the types of the arguments; the length of the tuple ``groups``
        is part of its type, so it picks the kernel of that G and only that kernel is compiled
        (each G a kernel of its own, compiled only when a caller uses it)."""
        from numba.extending import overload

        # inline="always": the kernel is inlined into its caller in numba's IR.  Without it the
        # overload's implementation stayed a function of its own that LLVM did not inline into
        # the lane worker (the plain njit call before lane groups was inlined), and W4 taylor
        # lost 4-6 % (issue 34; benchmarks/RESULTS.md)
        return overload(stub, inline="always")


@njit(inline="always")
def next_bit(bits):
    """(i, rest) for bits > 0: the index i of its lowest set bit and bits without it; a scalar
    loop visits the lanes of a mask ``bits = vbits(m)`` as ``while bits: i, bits = next_bit(bits)``."""
    return _cttz(bits), bits & (bits - 1)
