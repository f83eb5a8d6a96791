"""Which points lie inside a closed polygon of the section (even-odd rule), compiled, the
arithmetic of the numpy formulation bit for bit."""
import numpy as np

from explorer._jit import njit, prange


@njit(parallel=True, nogil=True)
def inside_even_odd(P, X, out):  # pragma: no cover - compiled
    """out[i] = X[i] inside the closed polygon P (k, 2), even-odd rule; NaN points are outside
    (every comparison with NaN is false, so no edge straddles them)."""
    k = P.shape[0]
    for i in prange(X.shape[0]):
        x = X[i, 0]
        y = X[i, 1]
        n = 0
        for j in range(k):
            j1 = j + 1 if j + 1 < k else 0
            ay = P[j, 1]
            by = P[j1, 1]
            if (ay > y) != (by > y):
                ax = P[j, 0]
                xc = ax + (y - ay) * (P[j1, 0] - ax) / (by - ay)
                if x < xc:
                    n += 1
        out[i] = (n % 2) == 1


def inside(polygon, X) -> np.ndarray:
    """Whether each point of X (m, 2) lies inside the closed ``polygon`` (k, 2) (even-odd rule)."""
    P = np.ascontiguousarray(polygon, dtype=np.float64)
    Y = np.ascontiguousarray(np.asarray(X, dtype=np.float64).reshape(-1, 2))
    out = np.zeros(len(Y), np.bool_)
    if len(P) and len(Y):
        inside_even_odd(P, Y, out)
    return out
