"""The power x^e of the Taylor step size, branch-free and written once as LLVM IR for doubles and
for vectors of lanes, so every Taylor loop takes the same steps bit for bit; relative error
below :data:`POWER_REL_ERR` for positive normal x, 0 < e <= 1/3 (docs/architecture.md).
"""
import math

import numpy as np

from explorer._jit import NOJIT, njit

#: 2 / ln 2 / (2j + 1), j = 0..8: log2(m) = t sum_j LOG2_ATANH[j] t^(2j), t = (m - 1)/(m + 1)
#: (log m = 2 atanh t), |t| <= 0.1716 on [sqrt(1/2), sqrt(2)): the first omitted term is
#: < 3e-13 relative to t
LOG2_ATANH = tuple(2.0 / math.log(2.0) / (2 * j + 1) for j in range(9))
#: 1/k!, k = 0..12: exp(g) for |g| <= ln(2)/2 (2^f, |f| <= 1/2), first omitted term < 2e-15
EXP_TAYLOR = tuple(1.0 / math.factorial(k) for k in range(13))
LN2 = math.log(2.0)
SQRT2 = math.sqrt(2.0)
#: a bound of the relative error of radius_power against the exact power (tested)
POWER_REL_ERR = 1e-13
#: the positive normal doubles: the domain of radius_power_core
TINY = 2.2250738585072014e-308
HUGE = 1.7976931348623157e308
_MANTISSA = 0x000FFFFFFFFFFFFF
_ONE = 0x3FF0000000000000


def emit_radius_power(builder, x, e, width=None):
    """LLVM IR of :func:`radius_power_core` (x a double, or a vector of ``width`` doubles; e a
    double): the one text of the algorithm, emitted for a scalar here and for a vector of lanes
    by :func:`explorer.integrate.simd.vradius_power_core`.  Plain IEEE operations with no
    fast-math flag (no FMA contraction): a lane of the vector computes the scalar's double."""
    from llvmlite import ir
    from numba.core import cgutils

    i64 = ir.IntType(64)
    ft = ir.DoubleType() if width is None else ir.VectorType(ir.DoubleType(), width)
    it = i64 if width is None else ir.VectorType(i64, width)

    def fc(c):
        return ir.Constant(ft, c if width is None else [c] * width)

    def ic(c):
        return ir.Constant(it, c if width is None else [c] * width)

    if width is None:
        ev = e
    else:
        i32 = ir.IntType(32)
        ev = builder.insert_element(ir.Constant(ft, ir.Undefined), e, ir.Constant(i32, 0))
        ev = builder.shuffle_vector(ev, ir.Constant(ft, ir.Undefined),
                                    ir.Constant(ir.VectorType(i32, width), [0] * width))
    b = builder.bitcast(x, it)
    k = builder.sub(builder.ashr(b, ic(52)), ic(1023))
    m = builder.bitcast(builder.or_(builder.and_(b, ic(_MANTISSA)), ic(_ONE)), ft)
    big = builder.fcmp_ordered(">", m, fc(SQRT2))
    m = builder.select(big, builder.fmul(m, fc(0.5)), m)
    kf = builder.sitofp(builder.select(big, builder.add(k, ic(1)), k), ft)
    t = builder.fdiv(builder.fsub(m, fc(1.0)), builder.fadd(m, fc(1.0)))
    t2 = builder.fmul(t, t)
    p = fc(LOG2_ATANH[-1])
    for c in LOG2_ATANH[-2::-1]:
        p = builder.fadd(builder.fmul(p, t2), fc(c))
    y = builder.fadd(builder.fmul(ev, kf), builder.fmul(ev, builder.fmul(t, p)))
    floor = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ft, [ft]),
                                           "llvm.floor.f64" if width is None else "llvm.floor.v%df64" % width)
    n = builder.call(floor, [builder.fadd(y, fc(0.5))])
    g = builder.fmul(builder.fsub(y, n), fc(LN2))
    q = fc(EXP_TAYLOR[-1])
    for c in EXP_TAYLOR[-2::-1]:
        q = builder.fadd(builder.fmul(q, g), fc(c))
    scale = builder.bitcast(builder.shl(builder.add(builder.fptosi(n, it), ic(1023)), ic(52)), ft)
    return builder.fmul(q, scale)


if NOJIT:  # pragma: no cover - plain-Python twin (numpy float64: the same IEEE operations)
    def radius_power_core(x, e):
        x = np.float64(x)
        b = int(np.array(x).view(np.int64))
        k = (b >> 52) - 1023
        m = np.array((b & _MANTISSA) | _ONE, np.int64).view(np.float64)[()]
        big = m > SQRT2
        m = m * 0.5 if big else m
        kf = np.float64(k + 1 if big else k)
        t = (m - 1.0) / (m + 1.0)
        t2 = t * t
        p = np.float64(LOG2_ATANH[-1])
        for c in LOG2_ATANH[-2::-1]:
            p = p * t2 + c
        y = e * kf + e * (t * p)
        n = np.floor(y + 0.5)
        g = (y - n) * LN2
        q = np.float64(EXP_TAYLOR[-1])
        for c in EXP_TAYLOR[-2::-1]:
            q = q * g + c
        return float(q * np.array((int(n) + 1023) << 52, np.int64).view(np.float64)[()])
else:
    from numba.core import types as _types
    from numba.extending import intrinsic as _intrinsic

    @_intrinsic
    def radius_power_core(typingctx, x, e):
        """x^e for positive normal finite x and 0 < e <= 1/3 (relative error < POWER_REL_ERR);
        garbage for other x.  Branch-free (:func:`emit_radius_power`)."""
        if not (isinstance(x, _types.Float) and isinstance(e, _types.Float)):
            return None

        def codegen(context, builder, sig, args):
            return emit_radius_power(builder, args[0], args[1])
        return _types.float64(_types.float64, _types.float64), codegen


@njit(inline="always")
def is_normal(x):
    """x is a positive normal finite double (the domain of radius_power_core).  ``&``, not
    ``and``: the same test lane-wise on a vector of lanes (explorer.integrate.simd)."""
    return (x >= TINY) & (x <= HUGE)


@njit
def radius_power(x, e):
    """x^e (0 < e <= 1/3) as the Taylor step size takes it: :func:`radius_power_core` for a
    positive normal x, else ``x ** e`` (0, subnormal, inf: libm's pow)."""
    if is_normal(x):
        return radius_power_core(x, e)
    return x ** e
