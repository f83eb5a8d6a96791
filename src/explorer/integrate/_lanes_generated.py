# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.chaplygin.system() by explorer.integrate.codegen
# (generator version 9).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""The Taylor recurrence of Chaplygin's R3 (docs/model.md), generated: the scalar form for the
scalar drivers (:mod:`explorer.integrate._systems_generated`), the lane form for
:mod:`explorer.integrate.lanes`.

Each lane of a ``*_lanes`` kernel computes bit for bit what its scalar twin computes (the same
IEEE operations in the same order; the vector operations of :mod:`explorer.integrate.simd`: no
fast-math, no FMA).
"""
import numpy as np

from explorer._jit import njit
from explorer.integrate.simd import LANES, vload, vsplat, vstore, vzero  # noqa: F401

#: state variables (p1, p2, M, g1, g2): the rows of X
NVAR = 5
#: rows of the work array
N_WORK = 0
#: flat strides of one order in the lane arrays X[k, i, l] and W[k, r, l]
XS = NVAR * LANES
WS = max(N_WORK, 1) * LANES


# error_model="numpy": a division by zero gives inf/nan (the integrators' non-finite status), not an exception
@njit(error_model="numpy")
def taylor_coefficients_into(P, X, order, W):
    """The Taylor coefficients of R3 from X[:, 0]: X[i, k] = x_i^(k)(0)/k! for k = 1..order in rows 0..4,
    with the parameters P (the packed vector) and the work array W[N_WORK, >= order]."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s9 = P[1]
    s14 = P[0]
    s19 = P[3]
    s20 = s19 / s9
    s23 = P[5]
    s24 = s5 * s23
    s27 = P[4]
    s28 = s27 * s5
    s30 = s19 / s14
    s37 = P[8]
    s38 = s37 * s1
    s40 = s23 / s14
    s44 = s9 * s14
    s45 = s14 - s9
    s46 = s45 / s44
    s49 = s27 / s9
    s52 = P[7]
    s53 = s1 * s52
    v16 = X[2, 0] * X[1, 0]
    v18 = (s5 * v16) - (s1 * X[3, 0])
    v22 = v18 - (s20 * X[1, 0])
    v26 = v22 - (s24 * X[2, 0])
    v32 = (s28 * X[2, 0]) + (s30 * X[0, 0])
    v33 = v32 - (s1 * X[4, 0])
    v34 = X[0, 0] * X[2, 0]
    v36 = v33 - (s5 * v34)
    v42 = (s38 * X[3, 0]) + (s40 * X[0, 0])
    v43 = X[1, 0] * X[0, 0]
    v48 = v42 + (s46 * v43)
    v51 = v48 - (s49 * X[1, 0])
    v55 = v51 - (s53 * X[4, 0])
    v56 = X[4, 0] * X[2, 0]
    v58 = X[3, 0] * X[2, 0]
    v60 = -(s5 * v58)
    X[0, 1] = v26
    X[1, 1] = v36
    X[2, 1] = v55
    X[3, 1] = (s5 * v56)
    X[4, 1] = v60
    for k in range(1, order):
        m16 = 0.0
        m34 = 0.0
        m43 = 0.0
        m56 = 0.0
        m58 = 0.0
        for j in range(k + 1):
            m16 = m16 + X[2, j] * X[1, k - j]
            m34 = m34 + X[0, j] * X[2, k - j]
            m43 = m43 + X[1, j] * X[0, k - j]
            m56 = m56 + X[4, j] * X[2, k - j]
            m58 = m58 + X[3, j] * X[2, k - j]
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v32 = (s28 * X[2, k]) + (s30 * X[0, k])
        v42 = (s38 * X[3, k]) + (s40 * X[0, k])
        v18 = (s5 * v16) - (s1 * X[3, k])
        v33 = v32 - (s1 * X[4, k])
        v48 = v42 + (s46 * v43)
        v60 = -(s5 * v58)
        v22 = v18 - (s20 * X[1, k])
        v36 = v33 - (s5 * v34)
        v51 = v48 - (s49 * X[1, k])
        v26 = v22 - (s24 * X[2, k])
        v55 = v51 - (s53 * X[4, k])
        r = 1.0 / (k + 1)
        X[0, k + 1] = v26 * r
        X[1, k + 1] = v36 * r
        X[2, k + 1] = v55 * r
        X[3, k + 1] = (s5 * v56) * r
        X[4, k + 1] = v60 * r


@njit(error_model="numpy")
def taylor_coefficients(P, X, order):
    """:func:`taylor_coefficients_into` with its own work array."""
    W = np.empty((max(N_WORK, 1), order + 1))
    taylor_coefficients_into(P, X, order, W)


@njit(error_model="numpy")
def taylor_coefficients_lanes(P, X, order, W):
    """LANES orbits at once: rows 0..4 of X[k, row, l] (C-contiguous, XS / LANES rows), k = 1..order,
    W of shape (order + 1, max(N_WORK, 1), LANES).  Each lane equals taylor_coefficients_into bit for bit."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s9 = P[1]
    s14 = P[0]
    s19 = P[3]
    s20 = s19 / s9
    s23 = P[5]
    s24 = s5 * s23
    s27 = P[4]
    s28 = s27 * s5
    s30 = s19 / s14
    s37 = P[8]
    s38 = s37 * s1
    s40 = s23 / s14
    s44 = s9 * s14
    s45 = s14 - s9
    s46 = s45 / s44
    s49 = s27 / s9
    s52 = P[7]
    s53 = s1 * s52
    v16 = vload(X, (0) * XS + 2 * LANES) * vload(X, (0) * XS + 1 * LANES)
    v18 = (s5 * v16) - (s1 * vload(X, (0) * XS + 3 * LANES))
    v22 = v18 - (s20 * vload(X, (0) * XS + 1 * LANES))
    v26 = v22 - (s24 * vload(X, (0) * XS + 2 * LANES))
    v32 = (s28 * vload(X, (0) * XS + 2 * LANES)) + (s30 * vload(X, (0) * XS + 0 * LANES))
    v33 = v32 - (s1 * vload(X, (0) * XS + 4 * LANES))
    v34 = vload(X, (0) * XS + 0 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v36 = v33 - (s5 * v34)
    v42 = (s38 * vload(X, (0) * XS + 3 * LANES)) + (s40 * vload(X, (0) * XS + 0 * LANES))
    v43 = vload(X, (0) * XS + 1 * LANES) * vload(X, (0) * XS + 0 * LANES)
    v48 = v42 + (s46 * v43)
    v51 = v48 - (s49 * vload(X, (0) * XS + 1 * LANES))
    v55 = v51 - (s53 * vload(X, (0) * XS + 4 * LANES))
    v56 = vload(X, (0) * XS + 4 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v58 = vload(X, (0) * XS + 3 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v60 = -(s5 * v58)
    vstore(X, (1) * XS + 0 * LANES, v26)
    vstore(X, (1) * XS + 1 * LANES, v36)
    vstore(X, (1) * XS + 2 * LANES, v55)
    vstore(X, (1) * XS + 3 * LANES, (s5 * v56))
    vstore(X, (1) * XS + 4 * LANES, v60)
    for k in range(1, order):
        m16 = vzero()
        m34 = vzero()
        m43 = vzero()
        m56 = vzero()
        m58 = vzero()
        for j in range(k + 1):
            m16 = m16 + vload(X, (j) * XS + 2 * LANES) * vload(X, (k - j) * XS + 1 * LANES)
            m34 = m34 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m43 = m43 + vload(X, (j) * XS + 1 * LANES) * vload(X, (k - j) * XS + 0 * LANES)
            m56 = m56 + vload(X, (j) * XS + 4 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m58 = m58 + vload(X, (j) * XS + 3 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v32 = (s28 * vload(X, (k) * XS + 2 * LANES)) + (s30 * vload(X, (k) * XS + 0 * LANES))
        v42 = (s38 * vload(X, (k) * XS + 3 * LANES)) + (s40 * vload(X, (k) * XS + 0 * LANES))
        v18 = (s5 * v16) - (s1 * vload(X, (k) * XS + 3 * LANES))
        v33 = v32 - (s1 * vload(X, (k) * XS + 4 * LANES))
        v48 = v42 + (s46 * v43)
        v60 = -(s5 * v58)
        v22 = v18 - (s20 * vload(X, (k) * XS + 1 * LANES))
        v36 = v33 - (s5 * v34)
        v51 = v48 - (s49 * vload(X, (k) * XS + 1 * LANES))
        v26 = v22 - (s24 * vload(X, (k) * XS + 2 * LANES))
        v55 = v51 - (s53 * vload(X, (k) * XS + 4 * LANES))
        r = 1.0 / (k + 1)
        vstore(X, (k + 1) * XS + 0 * LANES, v26 * r)
        vstore(X, (k + 1) * XS + 1 * LANES, v36 * r)
        vstore(X, (k + 1) * XS + 2 * LANES, v55 * r)
        vstore(X, (k + 1) * XS + 3 * LANES, (s5 * v56) * r)
        vstore(X, (k + 1) * XS + 4 * LANES, v60 * r)
