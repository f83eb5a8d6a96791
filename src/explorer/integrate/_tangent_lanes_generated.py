# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients_tangent
# (translated operation by operation).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernels of the tangent Taylor method: G groups of LANES orbits (one vector per group),
each orbit with its state and up to two deviation vectors in Z[k, row, lane] (C-contiguous,
NROWS rows: 0..4 the orbit, 5..9 the first deviation vector, 10..14 the second).  Used by
:mod:`explorer.integrate.tangent_lanes`.

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

#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)
NROWS = 15
#: first row of each deviation vector
DEV1 = 5
DEV2 = 10
#: the numbers of lane groups the kernels are written for
GROUPS = (1, 2)


@njit
def tangent_coefficients_lanes_1(P, Z, order, db):
    """tangent_coefficients_lanes for G = 1 group of LANES lanes."""
    C = taylor_constants(P)
    for k in range(order):
        wp2 = vzero()
        wp1 = vzero()
        p12 = vzero()
        wg2 = vzero()
        wg1 = vzero()
        dwp2 = vzero()
        dwp1 = vzero()
        dp12 = vzero()
        dwg2 = vzero()
        dwg1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj = vload(Z, (j) * (NROWS * LANES) + (2) * LANES)
            dwj = vload(Z, (j) * (NROWS * LANES) + (db + (2)) * LANES)
            wp2 = vadd(wp2, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (1) * LANES)))
            dwp2 = vadd(dwp2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            wp1 = vadd(wp1, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (0) * LANES)))
            dwp1 = vadd(dwp1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (0) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (0)) * LANES))))
            p12 = vadd(p12, vmul(vload(Z, (j) * (NROWS * LANES) + (0) * LANES), vload(Z, (i) * (NROWS * LANES) + (1) * LANES)))
            dp12 = vadd(dp12, vadd(vmul(vload(Z, (j) * (NROWS * LANES) + (db + (0)) * LANES), vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(vload(Z, (j) * (NROWS * LANES) + (0) * LANES), vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            wg2 = vadd(wg2, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (4) * LANES)))
            dwg2 = vadd(dwg2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (4) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (4)) * LANES))))
            wg1 = vadd(wg1, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (3) * LANES)))
            dwg1 = vadd(dwg1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (3) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (3)) * LANES))))
        inv_b, c12, la1, la2, ca2, za1, chi, zeta, mu, mxi, meta = C
        r = 1.0 / (k + 1)
        wk = vmul(vload(Z, (k) * (NROWS * LANES) + (2) * LANES), vsplat(inv_b))
        vstore(Z, (k + 1) * (NROWS * LANES) + (0) * LANES, vmul(vsub(vsub(vsub(vmul(wp2, vsplat(inv_b)), vmul(vsplat(zeta), wk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (3) * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * LANES) + (1) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (1) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1), vsplat(inv_b)), vmul(vsplat(chi), wk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (4) * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * LANES) + (0) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (2) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * LANES) + (1) * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * LANES) + (0) * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * LANES) + (4) * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * LANES) + (3) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (3) * LANES, vmul(vmul(wg2, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (4) * LANES, vmul(vmul(vneg(wg1), vsplat(inv_b)), vsplat(r)))
        inv_b_2, c12_2, la1_2, la2_2, ca2_2, za1_2, chi_2, zeta_2, mu_2, mxi_2, meta_2 = C
        r_2 = 1.0 / (k + 1)
        wk_2 = vmul(vload(Z, (k) * (NROWS * LANES) + (db + (2)) * LANES), vsplat(inv_b_2))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (0)) * LANES, vmul(vsub(vsub(vsub(vmul(dwp2, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (1)) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (2)) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (3)) * LANES, vmul(vmul(dwg2, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (4)) * LANES, vmul(vmul(vneg(dwg1), vsplat(inv_b_2)), vsplat(r_2)))


@njit
def tangent_coefficients_lanes_2(P, Z, order, db):
    """tangent_coefficients_lanes for G = 2 groups of LANES lanes."""
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
        dwp2_0 = vzero()
        dwp2_1 = vzero()
        dwp1_0 = vzero()
        dwp1_1 = vzero()
        dp12_0 = vzero()
        dp12_1 = vzero()
        dwg2_0 = vzero()
        dwg2_1 = vzero()
        dwg1_0 = vzero()
        dwg1_1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj_0 = vload(Z, (j) * (NROWS * 2 * LANES) + (2) * 2 * LANES)
            wj_1 = vload(Z, (j) * (NROWS * 2 * LANES) + (2) * 2 * LANES + 1 * LANES)
            dwj_0 = vload(Z, (j) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES)
            dwj_1 = vload(Z, (j) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES)
            wp2_0 = vadd(wp2_0, vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)))
            wp2_1 = vadd(wp2_1, vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)))
            dwp2_0 = vadd(dwp2_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))))
            dwp2_1 = vadd(dwp2_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))))
            wp1_0 = vadd(wp1_0, vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES)))
            wp1_1 = vadd(wp1_1, vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES)))
            dwp1_0 = vadd(dwp1_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))))
            dwp1_1 = vadd(dwp1_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))))
            p12_0 = vadd(p12_0, vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)))
            p12_1 = vadd(p12_1, vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)))
            dp12_0 = vadd(dp12_0, vadd(vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)), vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))))
            dp12_1 = vadd(dp12_1, vadd(vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)), vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))))
            wg2_0 = vadd(wg2_0, vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES)))
            wg2_1 = vadd(wg2_1, vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES)))
            dwg2_0 = vadd(dwg2_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))))
            dwg2_1 = vadd(dwg2_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))))
            wg1_0 = vadd(wg1_0, vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES)))
            wg1_1 = vadd(wg1_1, vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES)))
            dwg1_0 = vadd(dwg1_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))))
            dwg1_1 = vadd(dwg1_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))))
        inv_b, c12, la1, la2, ca2, za1, chi, zeta, mu, mxi, meta = C
        r = 1.0 / (k + 1)
        wk_0 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (2) * 2 * LANES), vsplat(inv_b))
        wk_1 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (2) * 2 * LANES + 1 * LANES), vsplat(inv_b))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (0) * 2 * LANES, vmul(vsub(vsub(vsub(vmul(wp2_0, vsplat(inv_b)), vmul(vsplat(zeta), wk_0)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * 2 * LANES) + (3) * 2 * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * 2 * LANES) + (1) * 2 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES, vmul(vsub(vsub(vsub(vmul(wp2_1, vsplat(inv_b)), vmul(vsplat(zeta), wk_1)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (1) * 2 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1_0), vsplat(inv_b)), vmul(vsplat(chi), wk_0)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * 2 * LANES) + (4) * 2 * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * 2 * LANES) + (0) * 2 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1_1), vsplat(inv_b)), vmul(vsplat(chi), wk_1)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (2) * 2 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12_0), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * 2 * LANES) + (1) * 2 * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * 2 * LANES) + (0) * 2 * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * 2 * LANES) + (4) * 2 * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * 2 * LANES) + (3) * 2 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (2) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12_1), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (3) * 2 * LANES, vmul(vmul(wg2_0, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES, vmul(vmul(wg2_1, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (4) * 2 * LANES, vmul(vmul(vneg(wg1_0), vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES, vmul(vmul(vneg(wg1_1), vsplat(inv_b)), vsplat(r)))
        inv_b_2, c12_2, la1_2, la2_2, ca2_2, za1_2, chi_2, zeta_2, mu_2, mxi_2, meta_2 = C
        r_2 = 1.0 / (k + 1)
        wk_2_0 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES), vsplat(inv_b_2))
        wk_2_1 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES), vsplat(inv_b_2))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES, vmul(vsub(vsub(vsub(vmul(dwp2_0, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2_0)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES, vmul(vsub(vsub(vsub(vmul(dwp2_1, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2_1)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1_0), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2_0)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1_1), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2_1)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12_0), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12_1), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES, vmul(vmul(dwg2_0, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES, vmul(vmul(dwg2_1, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES, vmul(vmul(vneg(dwg1_0), vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES, vmul(vmul(vneg(dwg1_1), vsplat(inv_b_2)), vsplat(r_2)))


@njit
def deviation_coefficients_lanes_1(P, Z, order, db):
    """deviation_coefficients_lanes for G = 1 group of LANES lanes."""
    C = taylor_constants(P)
    for k in range(order):
        dwp2 = vzero()
        dwp1 = vzero()
        dp12 = vzero()
        dwg2 = vzero()
        dwg1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj = vload(Z, (j) * (NROWS * LANES) + (2) * LANES)
            dwj = vload(Z, (j) * (NROWS * LANES) + (db + (2)) * LANES)
            dwp2 = vadd(dwp2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            dwp1 = vadd(dwp1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (0) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (0)) * LANES))))
            dp12 = vadd(dp12, vadd(vmul(vload(Z, (j) * (NROWS * LANES) + (db + (0)) * LANES), vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(vload(Z, (j) * (NROWS * LANES) + (0) * LANES), vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            dwg2 = vadd(dwg2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (4) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (4)) * LANES))))
            dwg1 = vadd(dwg1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (3) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (3)) * LANES))))
        inv_b_2, c12_2, la1_2, la2_2, ca2_2, za1_2, chi_2, zeta_2, mu_2, mxi_2, meta_2 = C
        r_2 = 1.0 / (k + 1)
        wk_2 = vmul(vload(Z, (k) * (NROWS * LANES) + (db + (2)) * LANES), vsplat(inv_b_2))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (0)) * LANES, vmul(vsub(vsub(vsub(vmul(dwp2, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (1)) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (2)) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (3)) * LANES, vmul(vmul(dwg2, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (4)) * LANES, vmul(vmul(vneg(dwg1), vsplat(inv_b_2)), vsplat(r_2)))


@njit
def deviation_coefficients_lanes_2(P, Z, order, db):
    """deviation_coefficients_lanes for G = 2 groups of LANES lanes."""
    C = taylor_constants(P)
    for k in range(order):
        dwp2_0 = vzero()
        dwp2_1 = vzero()
        dwp1_0 = vzero()
        dwp1_1 = vzero()
        dp12_0 = vzero()
        dp12_1 = vzero()
        dwg2_0 = vzero()
        dwg2_1 = vzero()
        dwg1_0 = vzero()
        dwg1_1 = vzero()
        for j in range(k + 1):
            i = k - j
            wj_0 = vload(Z, (j) * (NROWS * 2 * LANES) + (2) * 2 * LANES)
            wj_1 = vload(Z, (j) * (NROWS * 2 * LANES) + (2) * 2 * LANES + 1 * LANES)
            dwj_0 = vload(Z, (j) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES)
            dwj_1 = vload(Z, (j) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES)
            dwp2_0 = vadd(dwp2_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))))
            dwp2_1 = vadd(dwp2_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))))
            dwp1_0 = vadd(dwp1_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))))
            dwp1_1 = vadd(dwp1_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))))
            dp12_0 = vadd(dp12_0, vadd(vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES)), vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))))
            dp12_1 = vadd(dp12_1, vadd(vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (1) * 2 * LANES + 1 * LANES)), vmul(vload(Z, (j) * (NROWS * 2 * LANES) + (0) * 2 * LANES + 1 * LANES), vload(Z, (i) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))))
            dwg2_0 = vadd(dwg2_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))))
            dwg2_1 = vadd(dwg2_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (4) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))))
            dwg1_0 = vadd(dwg1_0, vadd(vmul(dwj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES)), vmul(wj_0, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))))
            dwg1_1 = vadd(dwg1_1, vadd(vmul(dwj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (3) * 2 * LANES + 1 * LANES)), vmul(wj_1, vload(Z, (i) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))))
        inv_b_2, c12_2, la1_2, la2_2, ca2_2, za1_2, chi_2, zeta_2, mu_2, mxi_2, meta_2 = C
        r_2 = 1.0 / (k + 1)
        wk_2_0 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES), vsplat(inv_b_2))
        wk_2_1 = vmul(vload(Z, (k) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES), vsplat(inv_b_2))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES, vmul(vsub(vsub(vsub(vmul(dwp2_0, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2_0)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES, vmul(vsub(vsub(vsub(vmul(dwp2_1, vsplat(inv_b_2)), vmul(vsplat(zeta_2), wk_2_1)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))), vmul(vsplat(la2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1_0), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2_0)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1_1), vsplat(inv_b_2)), vmul(vsplat(chi_2), wk_2_1)), vmul(vsplat(mu_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))), vmul(vsplat(la1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12_0), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (2)) * 2 * LANES + 1 * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12_2), dp12_1), vmul(vsplat(ca2_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (1)) * 2 * LANES + 1 * LANES))), vmul(vsplat(za1_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (0)) * 2 * LANES + 1 * LANES))), vmul(vsplat(mxi_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES))), vmul(vsplat(meta_2), vload(Z, (k) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES))), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES, vmul(vmul(dwg2_0, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (3)) * 2 * LANES + 1 * LANES, vmul(vmul(dwg2_1, vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES, vmul(vmul(vneg(dwg1_0), vsplat(inv_b_2)), vsplat(r_2)))
        vstore(Z, (k + 1) * (NROWS * 2 * LANES) + (db + (4)) * 2 * LANES + 1 * LANES, vmul(vmul(vneg(dwg1_1), vsplat(inv_b_2)), vsplat(r_2)))


#: tangent_coefficients_lanes for each G
_TANGENT_COEFFICIENTS_LANES = {1: tangent_coefficients_lanes_1, 2: tangent_coefficients_lanes_2}


def tangent_coefficients_lanes(P, Z, order, db, groups):
    """Lane twin of equations.taylor_coefficients_tangent, translated from its source by
    tools/gen_lanes.py: the orbit's coefficients in rows 0..4 and those of the deviation
    vector in rows db..db + 4 of Z[k, row, lane], k = 1..order, given Z[0].

    ``groups``: a tuple of G zeros.  Its length is part of its type, so a compiled caller is
    specialised to one G and compiles only that kernel."""
    _TANGENT_COEFFICIENTS_LANES[len(groups)](P, Z, order, db)


@by_groups(tangent_coefficients_lanes)
def _tangent_coefficients_lanes(P, Z, order, db, groups):
    kernel = _TANGENT_COEFFICIENTS_LANES[len(groups)]

    def impl(P, Z, order, db, groups):
        kernel(P, Z, order, db)
    return impl


#: deviation_coefficients_lanes for each G
_DEVIATION_COEFFICIENTS_LANES = {1: deviation_coefficients_lanes_1, 2: deviation_coefficients_lanes_2}


def deviation_coefficients_lanes(P, Z, order, db, groups):
    """The deviation vector's part of taylor_coefficients_tangent only (its statements that
    the stores into D need, unchanged; tools/gen_lanes.py prune): rows db..db + 4 of Z
    from the orbit's coefficients already in rows 0..4 (the same numbers the full
    recurrence recomputes for them).

    ``groups``: a tuple of G zeros.  Its length is part of its type, so a compiled caller is
    specialised to one G and compiles only that kernel."""
    _DEVIATION_COEFFICIENTS_LANES[len(groups)](P, Z, order, db)


@by_groups(deviation_coefficients_lanes)
def _deviation_coefficients_lanes(P, Z, order, db, groups):
    kernel = _DEVIATION_COEFFICIENTS_LANES[len(groups)]

    def impl(P, Z, order, db, groups):
        kernel(P, Z, order, db)
    return impl
