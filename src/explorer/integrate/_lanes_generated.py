# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients
# (translated operation by operation).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernel of the Taylor method: the recurrence of R3 for LANES orbits per vector,
coefficient arrays X[k, var, lane] (C-contiguous, lanes contiguous).  Used by
:mod:`explorer.integrate.lanes`.

Each lane computes bit for bit what the scalar recurrence computes (the same IEEE operations in
the same order; the vector operations of :mod:`explorer.integrate.simd`: no fast-math, no FMA).
"""
from explorer._jit import njit
from explorer.integrate.simd import (
    LANES,
    vadd,
    vload,
    vmul,
    vneg,
    vsplat,
    vstore,
    vsub,
    vzero,
)

#: state variables (p1, p2, M, g1, g2): the rows of X
NVAR = 5


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
