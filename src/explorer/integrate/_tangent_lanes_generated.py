# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.chaplygin.system(), variational(1) and (2) by explorer.integrate.codegen
# (generator version 9).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""The Taylor recurrence of R3 with deviation vectors (its variational equations), generated:
the scalar form for :mod:`explorer.integrate.tangent`, the lane form its operations on
LANES orbits at once (tests/integrate/test_tangent_lanes.py).

Each lane of a ``*_lanes`` kernel computes bit for bit what its scalar twin computes (the same
IEEE operations in the same order; the vector operations of :mod:`explorer.integrate.simd`: no
fast-math, no FMA).
"""
import numpy as np

from explorer._jit import njit
from explorer.integrate.simd import LANES, vload, vsplat, vstore, vzero  # noqa: F401

#: rows of the lane array: the orbit (5) and two deviation vectors (5 each)
NROWS = 15
#: first row of each deviation vector
DEV1 = 5
DEV2 = 10
#: rows of the work array W[k, r, l] of both recurrences (at least 1)
N_WORK_TANGENT = 1
#: flat strides of one order in the lane arrays X[k, i, l] and W[k, r, l]
XS = NROWS * LANES
WS_TANGENT = N_WORK_TANGENT * LANES


# error_model="numpy": a division by zero gives inf/nan (the integrators' non-finite status), not an exception
@njit(error_model="numpy")
def tangent_coefficients_into(P, X, order, W):
    """R3 and its variational equations from X[:, 0] (rows 0..4: the orbit's recurrence's
    operations, so its values): X[i, k] = x_i^(k)(0)/k! for k = 1..order in rows 0..9,
    with the parameters P (the packed vector) and the work array W[N_WORK_TANGENT, >= order]."""
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
    s65 = s3 / s9
    s70 = s3 / s14
    s79 = s19 * s65
    s85 = s19 * s70
    s96 = s70 * s23
    s100 = s65 * s70
    s101 = s100 * s45
    s107 = s27 * s65
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
    v73 = X[2, 0] * X[6, 0]
    v75 = X[7, 0] * X[1, 0]
    v77 = (s5 * v73) + (s5 * v75)
    v78 = v77 - (s1 * X[8, 0])
    v81 = v78 - (s79 * X[6, 0])
    v83 = v81 - (s24 * X[7, 0])
    v87 = (s28 * X[7, 0]) + (s85 * X[5, 0])
    v88 = v87 - (s1 * X[9, 0])
    v89 = X[5, 0] * X[2, 0]
    v91 = v88 - (s5 * v89)
    v92 = X[0, 0] * X[7, 0]
    v94 = v91 - (s5 * v92)
    v98 = (s38 * X[8, 0]) + (s96 * X[5, 0])
    v99 = X[0, 0] * X[6, 0]
    v103 = v98 + (s101 * v99)
    v104 = X[1, 0] * X[5, 0]
    v106 = v103 + (s101 * v104)
    v109 = v106 - (s107 * X[6, 0])
    v111 = v109 - (s53 * X[9, 0])
    v112 = X[9, 0] * X[2, 0]
    v114 = X[4, 0] * X[7, 0]
    v116 = (s5 * v112) + (s5 * v114)
    v117 = X[8, 0] * X[2, 0]
    v119 = -(s5 * v117)
    v120 = X[3, 0] * X[7, 0]
    v122 = v119 - (s5 * v120)
    X[0, 1] = v26
    X[1, 1] = v36
    X[2, 1] = v55
    X[3, 1] = (s5 * v56)
    X[4, 1] = v60
    X[5, 1] = v83
    X[6, 1] = v94
    X[7, 1] = v111
    X[8, 1] = v116
    X[9, 1] = v122
    for k in range(1, order):
        m16 = 0.0
        m34 = 0.0
        m43 = 0.0
        m56 = 0.0
        m58 = 0.0
        m73 = 0.0
        m75 = 0.0
        m89 = 0.0
        m92 = 0.0
        m99 = 0.0
        m104 = 0.0
        m112 = 0.0
        m114 = 0.0
        m117 = 0.0
        m120 = 0.0
        for j in range(k + 1):
            m16 = m16 + X[2, j] * X[1, k - j]
            m34 = m34 + X[0, j] * X[2, k - j]
            m43 = m43 + X[1, j] * X[0, k - j]
            m56 = m56 + X[4, j] * X[2, k - j]
            m58 = m58 + X[3, j] * X[2, k - j]
            m73 = m73 + X[2, j] * X[6, k - j]
            m75 = m75 + X[7, j] * X[1, k - j]
            m89 = m89 + X[5, j] * X[2, k - j]
            m92 = m92 + X[0, j] * X[7, k - j]
            m99 = m99 + X[0, j] * X[6, k - j]
            m104 = m104 + X[1, j] * X[5, k - j]
            m112 = m112 + X[9, j] * X[2, k - j]
            m114 = m114 + X[4, j] * X[7, k - j]
            m117 = m117 + X[8, j] * X[2, k - j]
            m120 = m120 + X[3, j] * X[7, k - j]
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v73 = m73
        v75 = m75
        v89 = m89
        v92 = m92
        v99 = m99
        v104 = m104
        v112 = m112
        v114 = m114
        v117 = m117
        v120 = m120
        v32 = (s28 * X[2, k]) + (s30 * X[0, k])
        v42 = (s38 * X[3, k]) + (s40 * X[0, k])
        v87 = (s28 * X[7, k]) + (s85 * X[5, k])
        v98 = (s38 * X[8, k]) + (s96 * X[5, k])
        v18 = (s5 * v16) - (s1 * X[3, k])
        v33 = v32 - (s1 * X[4, k])
        v48 = v42 + (s46 * v43)
        v60 = -(s5 * v58)
        v77 = (s5 * v73) + (s5 * v75)
        v88 = v87 - (s1 * X[9, k])
        v103 = v98 + (s101 * v99)
        v116 = (s5 * v112) + (s5 * v114)
        v119 = -(s5 * v117)
        v22 = v18 - (s20 * X[1, k])
        v36 = v33 - (s5 * v34)
        v51 = v48 - (s49 * X[1, k])
        v78 = v77 - (s1 * X[8, k])
        v91 = v88 - (s5 * v89)
        v106 = v103 + (s101 * v104)
        v122 = v119 - (s5 * v120)
        v26 = v22 - (s24 * X[2, k])
        v55 = v51 - (s53 * X[4, k])
        v81 = v78 - (s79 * X[6, k])
        v94 = v91 - (s5 * v92)
        v109 = v106 - (s107 * X[6, k])
        v83 = v81 - (s24 * X[7, k])
        v111 = v109 - (s53 * X[9, k])
        r = 1.0 / (k + 1)
        X[0, k + 1] = v26 * r
        X[1, k + 1] = v36 * r
        X[2, k + 1] = v55 * r
        X[3, k + 1] = (s5 * v56) * r
        X[4, k + 1] = v60 * r
        X[5, k + 1] = v83 * r
        X[6, k + 1] = v94 * r
        X[7, k + 1] = v111 * r
        X[8, k + 1] = v116 * r
        X[9, k + 1] = v122 * r


@njit(error_model="numpy")
def tangent_coefficients(P, X, order):
    """:func:`tangent_coefficients_into` with its own work array."""
    W = np.empty((max(N_WORK_TANGENT, 1), order + 1))
    tangent_coefficients_into(P, X, order, W)


@njit(error_model="numpy")
def tangent_coefficients_lanes(P, X, order, W):
    """LANES orbits at once: rows 0..9 of X[k, row, l] (C-contiguous, XS / LANES rows), k = 1..order,
    W of shape (order + 1, max(N_WORK_TANGENT, 1), LANES).  Each lane equals tangent_coefficients_into bit for bit."""
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
    s65 = s3 / s9
    s70 = s3 / s14
    s79 = s19 * s65
    s85 = s19 * s70
    s96 = s70 * s23
    s100 = s65 * s70
    s101 = s100 * s45
    s107 = s27 * s65
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
    v73 = vload(X, (0) * XS + 2 * LANES) * vload(X, (0) * XS + 6 * LANES)
    v75 = vload(X, (0) * XS + 7 * LANES) * vload(X, (0) * XS + 1 * LANES)
    v77 = (s5 * v73) + (s5 * v75)
    v78 = v77 - (s1 * vload(X, (0) * XS + 8 * LANES))
    v81 = v78 - (s79 * vload(X, (0) * XS + 6 * LANES))
    v83 = v81 - (s24 * vload(X, (0) * XS + 7 * LANES))
    v87 = (s28 * vload(X, (0) * XS + 7 * LANES)) + (s85 * vload(X, (0) * XS + 5 * LANES))
    v88 = v87 - (s1 * vload(X, (0) * XS + 9 * LANES))
    v89 = vload(X, (0) * XS + 5 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v91 = v88 - (s5 * v89)
    v92 = vload(X, (0) * XS + 0 * LANES) * vload(X, (0) * XS + 7 * LANES)
    v94 = v91 - (s5 * v92)
    v98 = (s38 * vload(X, (0) * XS + 8 * LANES)) + (s96 * vload(X, (0) * XS + 5 * LANES))
    v99 = vload(X, (0) * XS + 0 * LANES) * vload(X, (0) * XS + 6 * LANES)
    v103 = v98 + (s101 * v99)
    v104 = vload(X, (0) * XS + 1 * LANES) * vload(X, (0) * XS + 5 * LANES)
    v106 = v103 + (s101 * v104)
    v109 = v106 - (s107 * vload(X, (0) * XS + 6 * LANES))
    v111 = v109 - (s53 * vload(X, (0) * XS + 9 * LANES))
    v112 = vload(X, (0) * XS + 9 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v114 = vload(X, (0) * XS + 4 * LANES) * vload(X, (0) * XS + 7 * LANES)
    v116 = (s5 * v112) + (s5 * v114)
    v117 = vload(X, (0) * XS + 8 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v119 = -(s5 * v117)
    v120 = vload(X, (0) * XS + 3 * LANES) * vload(X, (0) * XS + 7 * LANES)
    v122 = v119 - (s5 * v120)
    vstore(X, (1) * XS + 0 * LANES, v26)
    vstore(X, (1) * XS + 1 * LANES, v36)
    vstore(X, (1) * XS + 2 * LANES, v55)
    vstore(X, (1) * XS + 3 * LANES, (s5 * v56))
    vstore(X, (1) * XS + 4 * LANES, v60)
    vstore(X, (1) * XS + 5 * LANES, v83)
    vstore(X, (1) * XS + 6 * LANES, v94)
    vstore(X, (1) * XS + 7 * LANES, v111)
    vstore(X, (1) * XS + 8 * LANES, v116)
    vstore(X, (1) * XS + 9 * LANES, v122)
    for k in range(1, order):
        m16 = vzero()
        m34 = vzero()
        m43 = vzero()
        m56 = vzero()
        m58 = vzero()
        m73 = vzero()
        m75 = vzero()
        m89 = vzero()
        m92 = vzero()
        m99 = vzero()
        m104 = vzero()
        m112 = vzero()
        m114 = vzero()
        m117 = vzero()
        m120 = vzero()
        for j in range(k + 1):
            m16 = m16 + vload(X, (j) * XS + 2 * LANES) * vload(X, (k - j) * XS + 1 * LANES)
            m34 = m34 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m43 = m43 + vload(X, (j) * XS + 1 * LANES) * vload(X, (k - j) * XS + 0 * LANES)
            m56 = m56 + vload(X, (j) * XS + 4 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m58 = m58 + vload(X, (j) * XS + 3 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m73 = m73 + vload(X, (j) * XS + 2 * LANES) * vload(X, (k - j) * XS + 6 * LANES)
            m75 = m75 + vload(X, (j) * XS + 7 * LANES) * vload(X, (k - j) * XS + 1 * LANES)
            m89 = m89 + vload(X, (j) * XS + 5 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m92 = m92 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 7 * LANES)
            m99 = m99 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 6 * LANES)
            m104 = m104 + vload(X, (j) * XS + 1 * LANES) * vload(X, (k - j) * XS + 5 * LANES)
            m112 = m112 + vload(X, (j) * XS + 9 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m114 = m114 + vload(X, (j) * XS + 4 * LANES) * vload(X, (k - j) * XS + 7 * LANES)
            m117 = m117 + vload(X, (j) * XS + 8 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m120 = m120 + vload(X, (j) * XS + 3 * LANES) * vload(X, (k - j) * XS + 7 * LANES)
        v16 = m16
        v34 = m34
        v43 = m43
        v56 = m56
        v58 = m58
        v73 = m73
        v75 = m75
        v89 = m89
        v92 = m92
        v99 = m99
        v104 = m104
        v112 = m112
        v114 = m114
        v117 = m117
        v120 = m120
        v32 = (s28 * vload(X, (k) * XS + 2 * LANES)) + (s30 * vload(X, (k) * XS + 0 * LANES))
        v42 = (s38 * vload(X, (k) * XS + 3 * LANES)) + (s40 * vload(X, (k) * XS + 0 * LANES))
        v87 = (s28 * vload(X, (k) * XS + 7 * LANES)) + (s85 * vload(X, (k) * XS + 5 * LANES))
        v98 = (s38 * vload(X, (k) * XS + 8 * LANES)) + (s96 * vload(X, (k) * XS + 5 * LANES))
        v18 = (s5 * v16) - (s1 * vload(X, (k) * XS + 3 * LANES))
        v33 = v32 - (s1 * vload(X, (k) * XS + 4 * LANES))
        v48 = v42 + (s46 * v43)
        v60 = -(s5 * v58)
        v77 = (s5 * v73) + (s5 * v75)
        v88 = v87 - (s1 * vload(X, (k) * XS + 9 * LANES))
        v103 = v98 + (s101 * v99)
        v116 = (s5 * v112) + (s5 * v114)
        v119 = -(s5 * v117)
        v22 = v18 - (s20 * vload(X, (k) * XS + 1 * LANES))
        v36 = v33 - (s5 * v34)
        v51 = v48 - (s49 * vload(X, (k) * XS + 1 * LANES))
        v78 = v77 - (s1 * vload(X, (k) * XS + 8 * LANES))
        v91 = v88 - (s5 * v89)
        v106 = v103 + (s101 * v104)
        v122 = v119 - (s5 * v120)
        v26 = v22 - (s24 * vload(X, (k) * XS + 2 * LANES))
        v55 = v51 - (s53 * vload(X, (k) * XS + 4 * LANES))
        v81 = v78 - (s79 * vload(X, (k) * XS + 6 * LANES))
        v94 = v91 - (s5 * v92)
        v109 = v106 - (s107 * vload(X, (k) * XS + 6 * LANES))
        v83 = v81 - (s24 * vload(X, (k) * XS + 7 * LANES))
        v111 = v109 - (s53 * vload(X, (k) * XS + 9 * LANES))
        r = 1.0 / (k + 1)
        vstore(X, (k + 1) * XS + 0 * LANES, v26 * r)
        vstore(X, (k + 1) * XS + 1 * LANES, v36 * r)
        vstore(X, (k + 1) * XS + 2 * LANES, v55 * r)
        vstore(X, (k + 1) * XS + 3 * LANES, (s5 * v56) * r)
        vstore(X, (k + 1) * XS + 4 * LANES, v60 * r)
        vstore(X, (k + 1) * XS + 5 * LANES, v83 * r)
        vstore(X, (k + 1) * XS + 6 * LANES, v94 * r)
        vstore(X, (k + 1) * XS + 7 * LANES, v111 * r)
        vstore(X, (k + 1) * XS + 8 * LANES, v116 * r)
        vstore(X, (k + 1) * XS + 9 * LANES, v122 * r)


# error_model="numpy": a division by zero gives inf/nan (the integrators' non-finite status), not an exception
@njit(error_model="numpy")
def deviation_coefficients_into(P, X, order, W):
    """The second deviation vector alone (the orbit's coefficients given in rows 0..4): X[i, k] = x_i^(k)(0)/k! for k = 1..order in rows 10..14,
    with the parameters P (the packed vector) and the work array W[N_WORK_TANGENT, >= order]."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s8 = P[1]
    s9 = s3 / s8
    s16 = P[0]
    s17 = s3 / s16
    s20 = s16 - s8
    s28 = P[3]
    s29 = s28 * s9
    s32 = P[5]
    s33 = s5 * s32
    s36 = P[4]
    s37 = s36 * s5
    s39 = s28 * s17
    s50 = P[8]
    s51 = s50 * s1
    s53 = s17 * s32
    s57 = s9 * s17
    s58 = s57 * s20
    s64 = s36 * s9
    s67 = P[7]
    s68 = s1 * s67
    v21 = X[2, 0] * X[11, 0]
    v24 = X[12, 0] * X[1, 0]
    v26 = (s5 * v21) + (s5 * v24)
    v27 = v26 - (s1 * X[13, 0])
    v31 = v27 - (s29 * X[11, 0])
    v35 = v31 - (s33 * X[12, 0])
    v41 = (s37 * X[12, 0]) + (s39 * X[10, 0])
    v42 = v41 - (s1 * X[14, 0])
    v43 = X[10, 0] * X[2, 0]
    v45 = v42 - (s5 * v43)
    v47 = X[0, 0] * X[12, 0]
    v49 = v45 - (s5 * v47)
    v55 = (s51 * X[13, 0]) + (s53 * X[10, 0])
    v56 = X[0, 0] * X[11, 0]
    v60 = v55 + (s58 * v56)
    v61 = X[1, 0] * X[10, 0]
    v63 = v60 + (s58 * v61)
    v66 = v63 - (s64 * X[11, 0])
    v70 = v66 - (s68 * X[14, 0])
    v71 = X[14, 0] * X[2, 0]
    v74 = X[4, 0] * X[12, 0]
    v76 = (s5 * v71) + (s5 * v74)
    v77 = X[13, 0] * X[2, 0]
    v79 = -(s5 * v77)
    v81 = X[3, 0] * X[12, 0]
    v83 = v79 - (s5 * v81)
    X[10, 1] = v35
    X[11, 1] = v49
    X[12, 1] = v70
    X[13, 1] = v76
    X[14, 1] = v83
    for k in range(1, order):
        m21 = 0.0
        m24 = 0.0
        m43 = 0.0
        m47 = 0.0
        m56 = 0.0
        m61 = 0.0
        m71 = 0.0
        m74 = 0.0
        m77 = 0.0
        m81 = 0.0
        for j in range(k + 1):
            m21 = m21 + X[2, j] * X[11, k - j]
            m24 = m24 + X[12, j] * X[1, k - j]
            m43 = m43 + X[10, j] * X[2, k - j]
            m47 = m47 + X[0, j] * X[12, k - j]
            m56 = m56 + X[0, j] * X[11, k - j]
            m61 = m61 + X[1, j] * X[10, k - j]
            m71 = m71 + X[14, j] * X[2, k - j]
            m74 = m74 + X[4, j] * X[12, k - j]
            m77 = m77 + X[13, j] * X[2, k - j]
            m81 = m81 + X[3, j] * X[12, k - j]
        v21 = m21
        v24 = m24
        v43 = m43
        v47 = m47
        v56 = m56
        v61 = m61
        v71 = m71
        v74 = m74
        v77 = m77
        v81 = m81
        v41 = (s37 * X[12, k]) + (s39 * X[10, k])
        v55 = (s51 * X[13, k]) + (s53 * X[10, k])
        v26 = (s5 * v21) + (s5 * v24)
        v42 = v41 - (s1 * X[14, k])
        v60 = v55 + (s58 * v56)
        v76 = (s5 * v71) + (s5 * v74)
        v79 = -(s5 * v77)
        v27 = v26 - (s1 * X[13, k])
        v45 = v42 - (s5 * v43)
        v63 = v60 + (s58 * v61)
        v83 = v79 - (s5 * v81)
        v31 = v27 - (s29 * X[11, k])
        v49 = v45 - (s5 * v47)
        v66 = v63 - (s64 * X[11, k])
        v35 = v31 - (s33 * X[12, k])
        v70 = v66 - (s68 * X[14, k])
        r = 1.0 / (k + 1)
        X[10, k + 1] = v35 * r
        X[11, k + 1] = v49 * r
        X[12, k + 1] = v70 * r
        X[13, k + 1] = v76 * r
        X[14, k + 1] = v83 * r


@njit(error_model="numpy")
def deviation_coefficients(P, X, order):
    """:func:`deviation_coefficients_into` with its own work array."""
    W = np.empty((max(N_WORK_TANGENT, 1), order + 1))
    deviation_coefficients_into(P, X, order, W)


@njit(error_model="numpy")
def deviation_coefficients_lanes(P, X, order, W):
    """LANES orbits at once: rows 10..14 of X[k, row, l] (C-contiguous, XS / LANES rows), k = 1..order,
    W of shape (order + 1, max(N_WORK_TANGENT, 1), LANES).  Each lane equals deviation_coefficients_into bit for bit."""
    s1 = P[6]
    s3 = 1.0
    s4 = P[2]
    s5 = s3 / s4
    s8 = P[1]
    s9 = s3 / s8
    s16 = P[0]
    s17 = s3 / s16
    s20 = s16 - s8
    s28 = P[3]
    s29 = s28 * s9
    s32 = P[5]
    s33 = s5 * s32
    s36 = P[4]
    s37 = s36 * s5
    s39 = s28 * s17
    s50 = P[8]
    s51 = s50 * s1
    s53 = s17 * s32
    s57 = s9 * s17
    s58 = s57 * s20
    s64 = s36 * s9
    s67 = P[7]
    s68 = s1 * s67
    v21 = vload(X, (0) * XS + 2 * LANES) * vload(X, (0) * XS + 11 * LANES)
    v24 = vload(X, (0) * XS + 12 * LANES) * vload(X, (0) * XS + 1 * LANES)
    v26 = (s5 * v21) + (s5 * v24)
    v27 = v26 - (s1 * vload(X, (0) * XS + 13 * LANES))
    v31 = v27 - (s29 * vload(X, (0) * XS + 11 * LANES))
    v35 = v31 - (s33 * vload(X, (0) * XS + 12 * LANES))
    v41 = (s37 * vload(X, (0) * XS + 12 * LANES)) + (s39 * vload(X, (0) * XS + 10 * LANES))
    v42 = v41 - (s1 * vload(X, (0) * XS + 14 * LANES))
    v43 = vload(X, (0) * XS + 10 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v45 = v42 - (s5 * v43)
    v47 = vload(X, (0) * XS + 0 * LANES) * vload(X, (0) * XS + 12 * LANES)
    v49 = v45 - (s5 * v47)
    v55 = (s51 * vload(X, (0) * XS + 13 * LANES)) + (s53 * vload(X, (0) * XS + 10 * LANES))
    v56 = vload(X, (0) * XS + 0 * LANES) * vload(X, (0) * XS + 11 * LANES)
    v60 = v55 + (s58 * v56)
    v61 = vload(X, (0) * XS + 1 * LANES) * vload(X, (0) * XS + 10 * LANES)
    v63 = v60 + (s58 * v61)
    v66 = v63 - (s64 * vload(X, (0) * XS + 11 * LANES))
    v70 = v66 - (s68 * vload(X, (0) * XS + 14 * LANES))
    v71 = vload(X, (0) * XS + 14 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v74 = vload(X, (0) * XS + 4 * LANES) * vload(X, (0) * XS + 12 * LANES)
    v76 = (s5 * v71) + (s5 * v74)
    v77 = vload(X, (0) * XS + 13 * LANES) * vload(X, (0) * XS + 2 * LANES)
    v79 = -(s5 * v77)
    v81 = vload(X, (0) * XS + 3 * LANES) * vload(X, (0) * XS + 12 * LANES)
    v83 = v79 - (s5 * v81)
    vstore(X, (1) * XS + 10 * LANES, v35)
    vstore(X, (1) * XS + 11 * LANES, v49)
    vstore(X, (1) * XS + 12 * LANES, v70)
    vstore(X, (1) * XS + 13 * LANES, v76)
    vstore(X, (1) * XS + 14 * LANES, v83)
    for k in range(1, order):
        m21 = vzero()
        m24 = vzero()
        m43 = vzero()
        m47 = vzero()
        m56 = vzero()
        m61 = vzero()
        m71 = vzero()
        m74 = vzero()
        m77 = vzero()
        m81 = vzero()
        for j in range(k + 1):
            m21 = m21 + vload(X, (j) * XS + 2 * LANES) * vload(X, (k - j) * XS + 11 * LANES)
            m24 = m24 + vload(X, (j) * XS + 12 * LANES) * vload(X, (k - j) * XS + 1 * LANES)
            m43 = m43 + vload(X, (j) * XS + 10 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m47 = m47 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 12 * LANES)
            m56 = m56 + vload(X, (j) * XS + 0 * LANES) * vload(X, (k - j) * XS + 11 * LANES)
            m61 = m61 + vload(X, (j) * XS + 1 * LANES) * vload(X, (k - j) * XS + 10 * LANES)
            m71 = m71 + vload(X, (j) * XS + 14 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m74 = m74 + vload(X, (j) * XS + 4 * LANES) * vload(X, (k - j) * XS + 12 * LANES)
            m77 = m77 + vload(X, (j) * XS + 13 * LANES) * vload(X, (k - j) * XS + 2 * LANES)
            m81 = m81 + vload(X, (j) * XS + 3 * LANES) * vload(X, (k - j) * XS + 12 * LANES)
        v21 = m21
        v24 = m24
        v43 = m43
        v47 = m47
        v56 = m56
        v61 = m61
        v71 = m71
        v74 = m74
        v77 = m77
        v81 = m81
        v41 = (s37 * vload(X, (k) * XS + 12 * LANES)) + (s39 * vload(X, (k) * XS + 10 * LANES))
        v55 = (s51 * vload(X, (k) * XS + 13 * LANES)) + (s53 * vload(X, (k) * XS + 10 * LANES))
        v26 = (s5 * v21) + (s5 * v24)
        v42 = v41 - (s1 * vload(X, (k) * XS + 14 * LANES))
        v60 = v55 + (s58 * v56)
        v76 = (s5 * v71) + (s5 * v74)
        v79 = -(s5 * v77)
        v27 = v26 - (s1 * vload(X, (k) * XS + 13 * LANES))
        v45 = v42 - (s5 * v43)
        v63 = v60 + (s58 * v61)
        v83 = v79 - (s5 * v81)
        v31 = v27 - (s29 * vload(X, (k) * XS + 11 * LANES))
        v49 = v45 - (s5 * v47)
        v66 = v63 - (s64 * vload(X, (k) * XS + 11 * LANES))
        v35 = v31 - (s33 * vload(X, (k) * XS + 12 * LANES))
        v70 = v66 - (s68 * vload(X, (k) * XS + 14 * LANES))
        r = 1.0 / (k + 1)
        vstore(X, (k + 1) * XS + 10 * LANES, v35 * r)
        vstore(X, (k + 1) * XS + 11 * LANES, v49 * r)
        vstore(X, (k + 1) * XS + 12 * LANES, v70 * r)
        vstore(X, (k + 1) * XS + 13 * LANES, v76 * r)
        vstore(X, (k + 1) * XS + 14 * LANES, v83 * r)
