# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.equations.taylor_coefficients_tangent
# (translated operation by operation).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""Lane kernels of the tangent Taylor method: LANES orbits per vector, each with its state and
up to two deviation vectors in Z[k, row, lane] (C-contiguous, NROWS rows: 0..4 the orbit,
5..9 the first deviation vector, 10..14 the second).  Used by
:mod:`explorer.integrate.tangent_lanes`.

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

#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)
NROWS = 15
#: first row of each deviation vector
DEV1 = 5
DEV2 = 10


@njit
def tangent_coefficients_lanes(P, Z, order, db):
    """Lane twin of equations.taylor_coefficients_tangent, translated from its source by
    tools/gen_lanes.py: the orbit's coefficients in rows 0..4 and those of the deviation
    vector in rows db..db + 4 of Z[k, row, lane], k = 1..order, given Z[0]."""
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
            wp1 = vadd(wp1, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (0) * LANES)))
            p12 = vadd(p12, vmul(vload(Z, (j) * (NROWS * LANES) + (0) * LANES), vload(Z, (i) * (NROWS * LANES) + (1) * LANES)))
            wg2 = vadd(wg2, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (4) * LANES)))
            wg1 = vadd(wg1, vmul(wj, vload(Z, (i) * (NROWS * LANES) + (3) * LANES)))
            dwp2 = vadd(dwp2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            dwp1 = vadd(dwp1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (0) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (0)) * LANES))))
            dp12 = vadd(dp12, vadd(vmul(vload(Z, (j) * (NROWS * LANES) + (db + (0)) * LANES), vload(Z, (i) * (NROWS * LANES) + (1) * LANES)), vmul(vload(Z, (j) * (NROWS * LANES) + (0) * LANES), vload(Z, (i) * (NROWS * LANES) + (db + (1)) * LANES))))
            dwg2 = vadd(dwg2, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (4) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (4)) * LANES))))
            dwg1 = vadd(dwg1, vadd(vmul(dwj, vload(Z, (i) * (NROWS * LANES) + (3) * LANES)), vmul(wj, vload(Z, (i) * (NROWS * LANES) + (db + (3)) * LANES))))
        r = 1.0 / (k + 1)
        wk = vmul(vload(Z, (k) * (NROWS * LANES) + (2) * LANES), vsplat(inv_b))
        vstore(Z, (k + 1) * (NROWS * LANES) + (0) * LANES, vmul(vsub(vsub(vsub(vmul(wp2, vsplat(inv_b)), vmul(vsplat(zeta), wk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (3) * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * LANES) + (1) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (1) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(wp1), vsplat(inv_b)), vmul(vsplat(chi), wk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (4) * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * LANES) + (0) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (2) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), p12), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * LANES) + (1) * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * LANES) + (0) * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * LANES) + (4) * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * LANES) + (3) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (3) * LANES, vmul(vmul(wg2, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (4) * LANES, vmul(vmul(vneg(wg1), vsplat(inv_b)), vsplat(r)))
        dwk = vmul(vload(Z, (k) * (NROWS * LANES) + (db + (2)) * LANES), vsplat(inv_b))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (0)) * LANES, vmul(vsub(vsub(vsub(vmul(dwp2, vsplat(inv_b)), vmul(vsplat(zeta), dwk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (1)) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1), vsplat(inv_b)), vmul(vsplat(chi), dwk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (2)) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), dp12), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (3)) * LANES, vmul(vmul(dwg2, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (4)) * LANES, vmul(vmul(vneg(dwg1), vsplat(inv_b)), vsplat(r)))


@njit
def deviation_coefficients_lanes(P, Z, order, db):
    """The deviation vector's part of taylor_coefficients_tangent only (its statements that
    the stores into D need, unchanged; tools/gen_lanes.py prune): rows db..db + 4 of Z
    from the orbit's coefficients already in rows 0..4 (the same numbers the full
    recurrence recomputes for them)."""
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
        r = 1.0 / (k + 1)
        dwk = vmul(vload(Z, (k) * (NROWS * LANES) + (db + (2)) * LANES), vsplat(inv_b))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (0)) * LANES, vmul(vsub(vsub(vsub(vmul(dwp2, vsplat(inv_b)), vmul(vsplat(zeta), dwk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vmul(vsplat(la2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (1)) * LANES, vmul(vadd(vsub(vadd(vmul(vneg(dwp1), vsplat(inv_b)), vmul(vsplat(chi), dwk)), vmul(vsplat(mu), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(la1), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (2)) * LANES, vmul(vadd(vsub(vadd(vsub(vmul(vsplat(c12), dp12), vmul(vsplat(ca2), vload(Z, (k) * (NROWS * LANES) + (db + (1)) * LANES))), vmul(vsplat(za1), vload(Z, (k) * (NROWS * LANES) + (db + (0)) * LANES))), vmul(vsplat(mxi), vload(Z, (k) * (NROWS * LANES) + (db + (4)) * LANES))), vmul(vsplat(meta), vload(Z, (k) * (NROWS * LANES) + (db + (3)) * LANES))), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (3)) * LANES, vmul(vmul(dwg2, vsplat(inv_b)), vsplat(r)))
        vstore(Z, (k + 1) * (NROWS * LANES) + (db + (4)) * LANES, vmul(vmul(vneg(dwg1), vsplat(inv_b)), vsplat(r)))
