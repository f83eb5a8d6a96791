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
  :func:`vge`, :func:`vlt`, :func:`vle`, :func:`veq` (lane-wise the scalar ``a > b`` ...: false where either is
  NaN), :func:`vand`, :func:`vandnot`, :func:`vor`, :func:`vselect` (``a if m else b`` per lane)
  and :func:`vbits` (the mask as the bits of an integer, lane i bit i: the lanes that a scalar
  loop must visit, one after the other by :func:`next_bit`), :func:`vmask` (bits back to a mask);
- Python's operators on vectors (``+ - * /``, unary ``-``, ``abs``, ``< <= > >= ==``, and ``&``,
  ``|`` on masks; a scalar operand splat), the intrinsics above: a kernel function written with
  operators compiles for vectors as well as for doubles, so the lane kernels call the one
  definition of a formula or a test (``kernels.events.sin_diff``, ``excluded_by_variation``,
  ``sign_change``, ``kernels.clock.compensated_add``, ``kernels.checks.is_finite``,
  ``kernels.power.is_normal`` ...) instead of a vector copy of it;
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

    def vle(a, b):
        return a <= b

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

    def _lanewise(argtypes, restype, emit):
        """The intrinsic of the operands ``argtypes`` (exactly those: f64vec or b1vec) whose value
        is ``emit(builder, *operands)``, one LLVM instruction (or intrinsic) on whole vectors."""
        sig = restype(*argtypes)

        def codegen(context, builder, sig, args):
            return emit(builder, *args)

        def typer(*operands):
            return (sig, codegen) if operands == argtypes else None

        if len(argtypes) == 1:
            return _intrinsic(lambda typingctx, a: typer(a))
        if len(argtypes) == 2:
            return _intrinsic(lambda typingctx, a, b: typer(a, b))
        return _intrinsic(lambda typingctx, m, a, b: typer(m, a, b))

    def _llvm_call(name):
        """``emit`` of the LLVM intrinsic ``llvm.<name>`` on a vector of doubles."""
        def emit(builder, x):
            fn = _cgutils.get_or_insert_function(builder.module, _ir.FunctionType(_VT, [_VT]),
                                                 "llvm.%s.v%df64" % (name, LANES))
            return builder.call(fn, [x])
        return emit

    _F1, _F2 = (f64vec,), (f64vec, f64vec)
    vadd = _lanewise(_F2, f64vec, lambda b, x, y: b.fadd(x, y))
    vsub = _lanewise(_F2, f64vec, lambda b, x, y: b.fsub(x, y))
    vmul = _lanewise(_F2, f64vec, lambda b, x, y: b.fmul(x, y))
    vdiv = _lanewise(_F2, f64vec, lambda b, x, y: b.fdiv(x, y))
    vneg = _lanewise(_F1, f64vec, lambda b, x: b.fneg(x))
    #: |a| (llvm.fabs, as numba's scalar abs)
    vabs = _lanewise(_F1, f64vec, _llvm_call("fabs"))
    #: the square root of every lane (llvm.sqrt, correctly rounded as numba's scalar math.sqrt)
    vsqrt = _lanewise(_F1, f64vec, _llvm_call("sqrt"))
    #: v where v > s else s: the scalar ``if v > s: s = v`` (fcmp ogt + select)
    vmax_gt = _lanewise(_F2, f64vec, lambda b, v, s: b.select(b.fcmp_ordered(">", v, s), v, s))
    #: v where v < s else s: the scalar ``s = v if v < s else s`` (fcmp olt + select)
    vmin_lt = _lanewise(_F2, f64vec, lambda b, v, s: b.select(b.fcmp_ordered("<", v, s), v, s))
    # the ordered comparisons (false where either operand is NaN, as the scalar ones)
    vgt = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered(">", x, y))
    vge = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered(">=", x, y))
    vlt = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("<", x, y))
    vle = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("<=", x, y))
    veq = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("==", x, y))
    _M2 = (b1vec, b1vec)
    vand = _lanewise(_M2, b1vec, lambda b, x, y: b.and_(x, y))
    vor = _lanewise(_M2, b1vec, lambda b, x, y: b.or_(x, y))
    vandnot = _lanewise(_M2, b1vec, lambda b, x, y: b.and_(x, b.not_(y)))
    #: a where m else b, lane by lane
    vselect = _lanewise((b1vec, f64vec, f64vec), f64vec, lambda b, m, x, y: b.select(m, x, y))

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


    # ------------------------------------------------------------ Python operators on vectors
    # ``a + b``, ``a * 2.0``, ``abs(a)``, ``a < 0.0``, ``m & k`` ... on f64vec (and b1vec) are the
    # intrinsics above (a scalar operand is splat first: lane-wise the scalar's IEEE operation), so
    # a kernel function written with operators on scalars - kernels.events.sin_diff,
    # excluded_by_variation, sign_change, kernels.clock.compensated_add ... - compiles for vectors
    # too, and the lane kernels call that one definition (numba's public extension API:
    # ``overload`` of the operator; the scalar types keep numba's own implementations).
    import operator as _op

    from numba.extending import overload as _overload

    def _is_scalar(x):
        return isinstance(x, (_types.Float, _types.Integer))

    def _vector_operator(op, vop, mask=False):
        """``op(a, b)`` as ``vop`` where an operand is a vector (f64vec; b1vec for ``mask``)."""
        vt = b1vec if mask else f64vec

        @_overload(op)
        def ov(a, b):
            if a == vt and b == vt:
                return lambda a, b: vop(a, b)
            if mask:
                return None
            if a == vt and _is_scalar(b):
                return lambda a, b: vop(a, vsplat(b))
            if _is_scalar(a) and b == vt:
                return lambda a, b: vop(vsplat(a), b)
            return None

    for _o, _v in ((_op.add, vadd), (_op.sub, vsub), (_op.mul, vmul), (_op.truediv, vdiv),
                   (_op.gt, vgt), (_op.ge, vge), (_op.lt, vlt), (_op.eq, veq)):
        _vector_operator(_o, _v)
    _vector_operator(_op.le, vle)
    _vector_operator(_op.and_, vand, mask=True)
    _vector_operator(_op.or_, vor, mask=True)

    @_overload(_op.neg)
    def _vector_neg(a):
        if a == f64vec:
            return lambda a: vneg(a)
        return None

    @_overload(abs)
    def _vector_abs(a):
        if a == f64vec:
            return lambda a: vabs(a)
        return None

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
