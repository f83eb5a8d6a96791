# GENERATED FILE - DO NOT EDIT.
# Written by tools/gen_lanes.py from explorer.model.chaplygin.system() and variational(1) by explorer.integrate.codegen
# (generator version 12).
# Regenerate:  python tools/gen_lanes.py     (check: --check)
"""The Taylor recurrence of R3 with a deviation vector (its variational equations), generated,
for the tangent loops of :mod:`explorer.integrate.tangent` (docs/systems.md)."""
import numpy as np

from explorer._jit import njit

#: first row of the deviation vector
DEV1 = 5
#: rows of the work array W[k, r] of the recurrence (at least 1)
N_WORK_TANGENT = 1


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
    u16 = X[2, 0] * X[1, 0]
    u18 = (s5 * u16) - (s1 * X[3, 0])
    u22 = u18 - (s20 * X[1, 0])
    u26 = u22 - (s24 * X[2, 0])
    u32 = (s28 * X[2, 0]) + (s30 * X[0, 0])
    u33 = u32 - (s1 * X[4, 0])
    u34 = X[0, 0] * X[2, 0]
    u36 = u33 - (s5 * u34)
    u42 = (s38 * X[3, 0]) + (s40 * X[0, 0])
    u43 = X[1, 0] * X[0, 0]
    u48 = u42 + (s46 * u43)
    u51 = u48 - (s49 * X[1, 0])
    u55 = u51 - (s53 * X[4, 0])
    u56 = X[4, 0] * X[2, 0]
    u58 = X[3, 0] * X[2, 0]
    u60 = -(s5 * u58)
    u73 = X[2, 0] * X[6, 0]
    u75 = X[7, 0] * X[1, 0]
    u77 = (s5 * u73) + (s5 * u75)
    u78 = u77 - (s1 * X[8, 0])
    u81 = u78 - (s79 * X[6, 0])
    u83 = u81 - (s24 * X[7, 0])
    u87 = (s28 * X[7, 0]) + (s85 * X[5, 0])
    u88 = u87 - (s1 * X[9, 0])
    u89 = X[5, 0] * X[2, 0]
    u91 = u88 - (s5 * u89)
    u92 = X[0, 0] * X[7, 0]
    u94 = u91 - (s5 * u92)
    u98 = (s38 * X[8, 0]) + (s96 * X[5, 0])
    u99 = X[0, 0] * X[6, 0]
    u103 = u98 + (s101 * u99)
    u104 = X[1, 0] * X[5, 0]
    u106 = u103 + (s101 * u104)
    u109 = u106 - (s107 * X[6, 0])
    u111 = u109 - (s53 * X[9, 0])
    u112 = X[9, 0] * X[2, 0]
    u114 = X[4, 0] * X[7, 0]
    u116 = (s5 * u112) + (s5 * u114)
    u117 = X[8, 0] * X[2, 0]
    u119 = -(s5 * u117)
    u120 = X[3, 0] * X[7, 0]
    u122 = u119 - (s5 * u120)
    X[0, 1] = u26
    X[1, 1] = u36
    X[2, 1] = u55
    X[3, 1] = (s5 * u56)
    X[4, 1] = u60
    X[5, 1] = u83
    X[6, 1] = u94
    X[7, 1] = u111
    X[8, 1] = u116
    X[9, 1] = u122
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
