# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients (translated
# operation by operation) and templates mirroring explorer.kernels.taylor.
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernels of the Taylor method: LANES = 8 orbits per vector, coefficient arrays
X[k, var, lane] (C-contiguous, lanes contiguous).  Each lane computes bit for bit what the
scalar kernels compute (same IEEE operations in the same order, no fast-math, no FMA).
Used by :mod:`explorer.integrate.lanes`.
"""
import numpy as np

from explorer._jit import NOJIT, njit

#: orbits advanced in lockstep by one vector instruction
LANES = 8
#: state variables (p1, p2, M, g1, g2)
NVAR = 5
#: log2(1 + x) ~ sum_k LOG2_POLY[k] x^k on [0, 1) (max error 2.05e-4) and a bound of the
#: error of vlog2_approx (tests/test_lanes.py checks it)
LOG2_POLY = (2.0426737e-4, 1.4360970, -0.66951221, 0.31221131, -0.079149502)
LOG2_APPROX_ERR = 4e-4


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


@njit
def taylor_coefficients_lanes(P, X, order):
    """Lane twin of equations.taylor_coefficients, translated from its source by
    tools/gen_lanes.py: X[k, i, l] = y_i^(k)(0)/k! of lane l for k = 1..order, given
    X[0, :, :]; X has shape (order + 1, NVAR, LANES)."""
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (P[0], P[1], P[2], P[3], P[4], P[5], P[6], P[7], P[8])
    inv_b = 1.0 / b
    c12 = 1.0 / a2 - 1.0 / a1
    la1 = lam / a1
    la2 = lam / a2
    ca2 = chi / a2
    za1 = zeta / a1
    mxi = mu * xi
    meta = mu * eta
    for k in range(order):
        wp2 = vzero()
        wp1 = vzero()
        p12 = vzero()
        wg2 = vzero()
        wg1 = vzero()
        for j in range(k + 1):
            wj = vload(X, (j) * (NVAR * LANES) + (2) * LANES)
            i = k - j
            wp2 = vadd(wp2, vmul(wj, vload(X, (i) * (NVAR * LANES) + (1) * LANES)))
            wp1 = vadd(wp1, vmul(wj, vload(X, (i) * (NVAR * LANES) + (0) * LANES)))
            p12 = vadd(p12, vmul(vload(X, (j) * (NVAR * LANES) + (0) * LANES), vload(X, (i) * (NVAR * LANES) + (1) * LANES)))
            wg2 = vadd(wg2, vmul(wj, vload(X, (i) * (NVAR * LANES) + (4) * LANES)))
            wg1 = vadd(wg1, vmul(wj, vload(X, (i) * (NVAR * LANES) + (3) * LANES)))
        wk = vmul(vload(X, (k) * (NVAR * LANES) + (2) * LANES), vsplat(inv_b))
        wp2 = vmul(wp2, vsplat(inv_b))
        wp1 = vmul(wp1, vsplat(inv_b))
        wg2 = vmul(wg2, vsplat(inv_b))
        wg1 = vmul(wg1, vsplat(inv_b))
        r = 1.0 / (k + 1)
        vstore(X, (k + 1) * (NVAR * LANES) + (0) * LANES, vmul(vsub(vsub(vsub(wp2, vmul(vsplat(zeta), wk)), vmul(vsplat(mu), vload(X, (k) * (NVAR * LANES) + (3) * LANES))), vmul(vsplat(la2), vload(X, (k) * (NVAR * LANES) + (1) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (1) * LANES, vmul(vadd(vsub(vadd(vneg(wp1), vmul(vsplat(chi), wk)), vmul(vsplat(mu), vload(X, (k) * (NVAR * LANES) + (4) * LANES))), vmul(vsplat(la1), vload(X, (k) * (NVAR * LANES) + (0) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (2) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12), vmul(vsplat(ca2), vload(X, (k) * (NVAR * LANES) + (1) * LANES))), vmul(vsplat(za1), vload(X, (k) * (NVAR * LANES) + (0) * LANES))), vmul(vsplat(mxi), vload(X, (k) * (NVAR * LANES) + (4) * LANES))), vmul(vsplat(meta), vload(X, (k) * (NVAR * LANES) + (3) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (3) * LANES, vmul(wg2, vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (4) * LANES, vmul(vneg(wg1), vsplat(r)))


@njit
def evaluate_lanes(X, order, h, out):
    """out[i, l] = sum_k X[k, i, l] h[l]^k per lane (Horner), h of shape (LANES,), out (NVAR, LANES);
    per lane exactly kernels.taylor.evaluate.  The NVAR chains are interleaved (independent)."""
    hv = vload(h, 0)
    o = order * (NVAR * LANES)
    a0 = vload(X, o + 0 * LANES)
    a1 = vload(X, o + 1 * LANES)
    a2 = vload(X, o + 2 * LANES)
    a3 = vload(X, o + 3 * LANES)
    a4 = vload(X, o + 4 * LANES)
    for k in range(order - 1, -1, -1):
        o = k * (NVAR * LANES)
        a0 = vadd(vmul(a0, hv), vload(X, o + 0 * LANES))
        a1 = vadd(vmul(a1, hv), vload(X, o + 1 * LANES))
        a2 = vadd(vmul(a2, hv), vload(X, o + 2 * LANES))
        a3 = vadd(vmul(a3, hv), vload(X, o + 3 * LANES))
        a4 = vadd(vmul(a4, hv), vload(X, o + 4 * LANES))
    vstore(out, 0 * LANES, a0)
    vstore(out, 1 * LANES, a1)
    vstore(out, 2 * LANES, a2)
    vstore(out, 3 * LANES, a3)
    vstore(out, 4 * LANES, a4)


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
    f = vadd(vadd(vadd(vadd(vload(X, op + 0 * LANES), vload(X, op + 1 * LANES)), vload(X, op + 2 * LANES)), vload(X, op + 3 * LANES)), vload(X, op + 4 * LANES))
    g = vadd(vadd(vadd(vadd(vload(X, oq + 0 * LANES), vload(X, oq + 1 * LANES)), vload(X, oq + 2 * LANES)), vload(X, oq + 3 * LANES)), vload(X, oq + 4 * LANES))
    s = vsplat(1.0)
    a = vzero()
    bm = vzero()
    s = vmax_gt(vabs(vload(X, o0 + 0 * LANES)), s)
    a = vmax_gt(vabs(vload(X, op + 0 * LANES)), a)
    bm = vmax_gt(vabs(vload(X, oq + 0 * LANES)), bm)
    s = vmax_gt(vabs(vload(X, o0 + 1 * LANES)), s)
    a = vmax_gt(vabs(vload(X, op + 1 * LANES)), a)
    bm = vmax_gt(vabs(vload(X, oq + 1 * LANES)), bm)
    s = vmax_gt(vabs(vload(X, o0 + 2 * LANES)), s)
    a = vmax_gt(vabs(vload(X, op + 2 * LANES)), a)
    bm = vmax_gt(vabs(vload(X, oq + 2 * LANES)), bm)
    s = vmax_gt(vabs(vload(X, o0 + 3 * LANES)), s)
    a = vmax_gt(vabs(vload(X, op + 3 * LANES)), a)
    bm = vmax_gt(vabs(vload(X, oq + 3 * LANES)), bm)
    s = vmax_gt(vabs(vload(X, o0 + 4 * LANES)), s)
    a = vmax_gt(vabs(vload(X, op + 4 * LANES)), a)
    bm = vmax_gt(vabs(vload(X, oq + 4 * LANES)), bm)
    u = vdiv(s, a)
    v = vdiv(s, bm)
    d = vsub(vmul(vsplat(e_q), vlog2_approx(v)), vmul(vsplat(e_p), vlog2_approx(u)))
    vstore(out, 0 * LANES, f)
    vstore(out, 1 * LANES, g)
    vstore(out, 2 * LANES, a)
    vstore(out, 3 * LANES, bm)
    vstore(out, 4 * LANES, u)
    vstore(out, 5 * LANES, v)
    vstore(out, 6 * LANES, d)
