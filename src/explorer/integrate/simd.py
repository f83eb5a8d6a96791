"""Vector values for the lane kernels: ``f64vec``, LANES float64 in one LLVM ``<LANES x double>``,
its operations as numba intrinsics (one vector instruction each, no fast-math: lane-wise the
scalar IEEE operations) and Python's operators on it, so a kernel written with operators compiles
for vectors as for doubles (docs/architecture.md, Scalar and vector forms from one definition).
With ``EXPLORER_NOJIT=1`` they are numpy twins.
"""
import numpy as np

from explorer._jit import NOJIT, njit
from explorer.kernels.power import emit_radius_power, radius_power_core

#: orbits advanced in lockstep by one vector instruction: 8 doubles = one AVX-512 register (two
#: AVX2 registers elsewhere).
LANES = 8


if NOJIT:  # pragma: no cover - plain-Python twins (numpy elementwise = the same IEEE ops)
    def vload(a, i):
        return a.reshape(-1)[i:i + LANES].copy()

    def vstore(a, i, v):
        a.reshape(-1)[i:i + LANES] = v

    def vget(a, k, r):
        return a[k, r].copy()

    def vset(a, k, r, v):
        a[k, r] = v

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

    def _is_c_f64_3d(a):
        return _is_c_f64(a) and a.ndim == 3

    def _row_ptr(context, builder, sig, args):
        """The address of a[k, r, 0] (a of shape (K, R, LANES), C-contiguous) as a vector pointer: the
        offset (k R + r) LANES computed from the array's own R."""
        ary = context.make_array(sig.args[0])(context, builder, args[0])
        rows = _cgutils.unpack_tuple(builder, ary.shape, 3)[1]
        idx = builder.mul(builder.add(builder.mul(args[1], rows), args[2]), _ir.Constant(rows.type, LANES))
        return builder.bitcast(builder.gep(ary.data, [idx]), _VT.as_pointer())

    @_intrinsic
    def vget(typingctx, a, k, r):
        """a[k, r, 0:LANES] as a vector, a of shape (K, R, LANES): the recurrences' coefficient k of row
        r (one call, where ``vload`` at the flat offset ``(k R + r) LANES`` also gives numba that
        offset's arithmetic to type and lower)."""
        if not (_is_c_f64_3d(a) and isinstance(k, _types.Integer) and isinstance(r, _types.Integer)):
            return None
        return f64vec(a, _types.intp, _types.intp), lambda context, builder, sig, args: builder.load(
            _row_ptr(context, builder, sig, args), align=8)

    @_intrinsic
    def vset(typingctx, a, k, r, v):
        """a[k, r, 0:LANES] = v, a of shape (K, R, LANES) (:func:`vget`)."""
        if not (_is_c_f64_3d(a) and isinstance(k, _types.Integer) and isinstance(r, _types.Integer)
                and v == f64vec):
            return None

        def codegen(context, builder, sig, args):
            builder.store(args[3], _row_ptr(context, builder, sig, args), align=8)
            return context.get_dummy_value()
        return _types.void(a, _types.intp, _types.intp, f64vec), codegen

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
    vgt = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered(">", x, y))
    vge = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered(">=", x, y))
    vlt = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("<", x, y))
    vle = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("<=", x, y))
    veq = _lanewise(_F2, b1vec, lambda b, x, y: b.fcmp_ordered("==", x, y))
    _M2 = (b1vec, b1vec)
    vand = _lanewise(_M2, b1vec, lambda b, x, y: b.and_(x, y))
    vor = _lanewise(_M2, b1vec, lambda b, x, y: b.or_(x, y))
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


@njit(inline="always")
def next_bit(bits):
    """(i, rest) for bits > 0: the index i of its lowest set bit and bits without it; a scalar
    loop visits the lanes of a mask ``bits = vbits(m)`` as ``while bits: i, bits = next_bit(bits)``."""
    return _cttz(bits), bits & (bits - 1)
