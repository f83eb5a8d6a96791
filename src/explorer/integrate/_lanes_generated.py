# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients
# (translated operation by operation).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernel of the Taylor method: the recurrence of R3 for G groups of LANES orbits (one
vector per group), coefficient arrays X[k, var, lane] (C-contiguous, lanes contiguous).
Used by :mod:`explorer.integrate.lanes`.

Each lane computes bit for bit what the scalar recurrence computes (the same IEEE operations in
the same order; the vector operations of :mod:`explorer.integrate.simd`: no fast-math, no FMA).
"""
from explorer._jit import njit
from explorer.integrate.simd import (
    LANES,
    by_groups,
    vadd,
    vload,
    vmul,
    vneg,
    vsplat,
    vstore,
    vsub,
    vzero,
)
from explorer.model.equations import taylor_constants

#: state variables (p1, p2, M, g1, g2): the rows of X
NVAR = 5
#: the numbers of lane groups the kernels are written for
GROUPS = (1, 2)


@njit
def taylor_coefficients_lanes_1(P, X, order):
    """taylor_coefficients_lanes for G = 1 group of LANES lanes."""
    C = taylor_constants(P)
    for k in range(order):
        wp2 = vzero()
        wp1 = vzero()
        p12 = vzero()
        wg2 = vzero()
        wg1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj = vload(X, (j) * (NVAR * LANES) + (2) * LANES)
            wp2 = vadd(wp2, vmul(wj, vload(X, (i) * (NVAR * LANES) + (1) * LANES)))
            wp1 = vadd(wp1, vmul(wj, vload(X, (i) * (NVAR * LANES) + (0) * LANES)))
            p12 = vadd(p12, vmul(vload(X, (j) * (NVAR * LANES) + (0) * LANES), vload(X, (i) * (NVAR * LANES) + (1) * LANES)))
            wg2 = vadd(wg2, vmul(wj, vload(X, (i) * (NVAR * LANES) + (4) * LANES)))
            wg1 = vadd(wg1, vmul(wj, vload(X, (i) * (NVAR * LANES) + (3) * LANES)))
        inv_b, c12, la1, la2, ca2, za1, chi, zeta, mu, mxi, meta = C
        r = 1.0 / (k + 1)
        wk = vmul(vload(X, (k) * (NVAR * LANES) + (2) * LANES), vsplat(inv_b))
        vstore(X, (k + 1) * (NVAR * LANES) + (0) * LANES, vmul(vsub(vsub(vsub(vmul(wp2, vsplat(inv_b)), vmul(vsplat(zeta), wk)), vmul(vsplat(mu), vload(X, (k) * (NVAR * LANES) + (3) * LANES))), vmul(vsplat(la2), vload(X, (k) * (NVAR * LANES) + (1) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (1) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1), vsplat(inv_b)), vmul(vsplat(chi), wk)), vmul(vsplat(mu), vload(X, (k) * (NVAR * LANES) + (4) * LANES))), vmul(vsplat(la1), vload(X, (k) * (NVAR * LANES) + (0) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (2) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12), vmul(vsplat(ca2), vload(X, (k) * (NVAR * LANES) + (1) * LANES))), vmul(vsplat(za1), vload(X, (k) * (NVAR * LANES) + (0) * LANES))), vmul(vsplat(mxi), vload(X, (k) * (NVAR * LANES) + (4) * LANES))), vmul(vsplat(meta), vload(X, (k) * (NVAR * LANES) + (3) * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (3) * LANES, vmul(vmul(wg2, vsplat(inv_b)), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * LANES) + (4) * LANES, vmul(vmul(vneg(wg1), vsplat(inv_b)), vsplat(r)))


@njit
def taylor_coefficients_lanes_2(P, X, order):
    """taylor_coefficients_lanes for G = 2 groups of LANES lanes."""
    C = taylor_constants(P)
    for k in range(order):
        wp2_0 = vzero()
        wp2_1 = vzero()
        wp1_0 = vzero()
        wp1_1 = vzero()
        p12_0 = vzero()
        p12_1 = vzero()
        wg2_0 = vzero()
        wg2_1 = vzero()
        wg1_0 = vzero()
        wg1_1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj_0 = vload(X, (j) * (NVAR * 2 * LANES) + (2) * 2 * LANES)
            wj_1 = vload(X, (j) * (NVAR * 2 * LANES) + (2) * 2 * LANES + 1 * LANES)
            wp2_0 = vadd(wp2_0, vmul(wj_0, vload(X, (i) * (NVAR * 2 * LANES) + (1) * 2 * LANES)))
            wp2_1 = vadd(wp2_1, vmul(wj_1, vload(X, (i) * (NVAR * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)))
            wp1_0 = vadd(wp1_0, vmul(wj_0, vload(X, (i) * (NVAR * 2 * LANES) + (0) * 2 * LANES)))
            wp1_1 = vadd(wp1_1, vmul(wj_1, vload(X, (i) * (NVAR * 2 * LANES) + (0) * 2 * LANES + 1 * LANES)))
            p12_0 = vadd(p12_0, vmul(vload(X, (j) * (NVAR * 2 * LANES) + (0) * 2 * LANES), vload(X, (i) * (NVAR * 2 * LANES) + (1) * 2 * LANES)))
            p12_1 = vadd(p12_1, vmul(vload(X, (j) * (NVAR * 2 * LANES) + (0) * 2 * LANES + 1 * LANES), vload(X, (i) * (NVAR * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)))
            wg2_0 = vadd(wg2_0, vmul(wj_0, vload(X, (i) * (NVAR * 2 * LANES) + (4) * 2 * LANES)))
            wg2_1 = vadd(wg2_1, vmul(wj_1, vload(X, (i) * (NVAR * 2 * LANES) + (4) * 2 * LANES + 1 * LANES)))
            wg1_0 = vadd(wg1_0, vmul(wj_0, vload(X, (i) * (NVAR * 2 * LANES) + (3) * 2 * LANES)))
            wg1_1 = vadd(wg1_1, vmul(wj_1, vload(X, (i) * (NVAR * 2 * LANES) + (3) * 2 * LANES + 1 * LANES)))
        inv_b, c12, la1, la2, ca2, za1, chi, zeta, mu, mxi, meta = C
        r = 1.0 / (k + 1)
        wk_0 = vmul(vload(X, (k) * (NVAR * 2 * LANES) + (2) * 2 * LANES), vsplat(inv_b))
        wk_1 = vmul(vload(X, (k) * (NVAR * 2 * LANES) + (2) * 2 * LANES + 1 * LANES), vsplat(inv_b))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (0) * 2 * LANES, vmul(vsub(vsub(vsub(vmul(wp2_0, vsplat(inv_b)), vmul(vsplat(zeta), wk_0)), vmul(vsplat(mu), vload(X, (k) * (NVAR * 2 * LANES) + (3) * 2 * LANES))), vmul(vsplat(la2), vload(X, (k) * (NVAR * 2 * LANES) + (1) * 2 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (0) * 2 * LANES + 1 * LANES, vmul(vsub(vsub(vsub(vmul(wp2_1, vsplat(inv_b)), vmul(vsplat(zeta), wk_1)), vmul(vsplat(mu), vload(X, (k) * (NVAR * 2 * LANES) + (3) * 2 * LANES + 1 * LANES))), vmul(vsplat(la2), vload(X, (k) * (NVAR * 2 * LANES) + (1) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (1) * 2 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1_0), vsplat(inv_b)), vmul(vsplat(chi), wk_0)), vmul(vsplat(mu), vload(X, (k) * (NVAR * 2 * LANES) + (4) * 2 * LANES))), vmul(vsplat(la1), vload(X, (k) * (NVAR * 2 * LANES) + (0) * 2 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (1) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1_1), vsplat(inv_b)), vmul(vsplat(chi), wk_1)), vmul(vsplat(mu), vload(X, (k) * (NVAR * 2 * LANES) + (4) * 2 * LANES + 1 * LANES))), vmul(vsplat(la1), vload(X, (k) * (NVAR * 2 * LANES) + (0) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (2) * 2 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12_0), vmul(vsplat(ca2), vload(X, (k) * (NVAR * 2 * LANES) + (1) * 2 * LANES))), vmul(vsplat(za1), vload(X, (k) * (NVAR * 2 * LANES) + (0) * 2 * LANES))), vmul(vsplat(mxi), vload(X, (k) * (NVAR * 2 * LANES) + (4) * 2 * LANES))), vmul(vsplat(meta), vload(X, (k) * (NVAR * 2 * LANES) + (3) * 2 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (2) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12_1), vmul(vsplat(ca2), vload(X, (k) * (NVAR * 2 * LANES) + (1) * 2 * LANES + 1 * LANES))), vmul(vsplat(za1), vload(X, (k) * (NVAR * 2 * LANES) + (0) * 2 * LANES + 1 * LANES))), vmul(vsplat(mxi), vload(X, (k) * (NVAR * 2 * LANES) + (4) * 2 * LANES + 1 * LANES))), vmul(vsplat(meta), vload(X, (k) * (NVAR * 2 * LANES) + (3) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (3) * 2 * LANES, vmul(vmul(wg2_0, vsplat(inv_b)), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (3) * 2 * LANES + 1 * LANES, vmul(vmul(wg2_1, vsplat(inv_b)), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (4) * 2 * LANES, vmul(vmul(vneg(wg1_0), vsplat(inv_b)), vsplat(r)))
        vstore(X, (k + 1) * (NVAR * 2 * LANES) + (4) * 2 * LANES + 1 * LANES, vmul(vmul(vneg(wg1_1), vsplat(inv_b)), vsplat(r)))


#: taylor_coefficients_lanes for each G
_TAYLOR_COEFFICIENTS_LANES = {1: taylor_coefficients_lanes_1, 2: taylor_coefficients_lanes_2}


def taylor_coefficients_lanes(P, X, order, groups):
    """Lane twin of equations.taylor_coefficients, translated from its source by
    tools/gen_lanes.py: X[k, i, l] = y_i^(k)(0)/k! of lane l for k = 1..order, given
    X[0, :, :]; X has shape (order + 1, NVAR, G * LANES), G in GROUPS.

    ``groups``: a tuple of G zeros.  Its length is part of its type, so a compiled caller is
    specialised to one G and compiles only that kernel."""
    _TAYLOR_COEFFICIENTS_LANES[len(groups)](P, X, order)


@by_groups(taylor_coefficients_lanes)
def _taylor_coefficients_lanes(P, X, order, groups):
    kernel = _TAYLOR_COEFFICIENTS_LANES[len(groups)]

    def impl(P, X, order, groups):
        kernel(P, X, order)
    return impl
