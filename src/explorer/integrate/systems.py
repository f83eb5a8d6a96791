"""The system seam (docs/architecture.md): what the scalar drivers' systems share -- the
constants of a step, the augmented field of R3 with one deviation vector, time reversal of Taylor
coefficients, the finiteness test of a step's coefficients.  Each method's step for each system is
rendered from one template by tools/gen_lanes.py into :mod:`explorer.integrate._systems_generated`
(``dop853_step_tangent``, ``taylor_step_backward``, ...).
"""
from explorer._jit import njit
from explorer.kernels.checks import is_finite
from explorer.model.equations import rhs, rhs_tangent

#: an accepted step (not a kernel status)
STEP_OK = -1
#: the ``h_abs`` a loop gives a DOP853 step before its first step (no step proposed yet)
FIRST_STEP = -1.0
#: rows of the orbit itself in every system's state (the rest: deviation vector, position)
N_ORBIT = 5


@njit
def rhs_augmented(z, P, dz):
    """dz = f(z) of R3 (rows 0..4) and its variational equations (rows 5..9, docs/model.md)."""
    rhs(z[:5], P, dz[:5])
    rhs_tangent(z[:5], z[5:], P, dz[5:])


@njit
def reverse_time(X, order):
    """The Taylor coefficients of y(t0 - s) from those of y(t0 + t): X[i, k] -> (-1)^k X[i, k]."""
    for k in range(1, order + 1, 2):
        for i in range(X.shape[0]):
            X[i, k] = -X[i, k]


@njit
def finite_column(X, k, n):
    """Whether X[:n, k] is finite (one sum: a non-finite term makes it non-finite)."""
    s = 0.0
    for i in range(n):
        s += X[i, k]
    return is_finite(s)
