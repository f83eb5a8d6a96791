"""The engine's Taylor crossings on SIMD lanes, and the lane kernels its tangent driver shares
(:mod:`explorer.integrate.tangent_lanes`).  The crossings are those of every System
(:mod:`explorer.integrate.codegen_lanes`, rendered into :mod:`explorer.integrate._lanes_generated` for
``chaplygin.system()``): the section phi = phi0 is the hyperplane sin(phi - phi0) = g1 cos phi0 - g2 sin phi0
= 0, its half cos(phi - phi0) = g2 cos phi0 + g1 sin phi0 > 0 kept (docs/model.md; docs/architecture.md,
The system seam).  Each lane is bit for bit the scalar oracle tests/integrate/taylor_oracle.py, whatever
the thread count.  Kernel contract: explorer/kernels/__init__.py.
"""
import numpy as np

from explorer._jit import get_num_threads, njit, prange
from explorer.integrate import _lanes_generated as G
from explorer.integrate.layout import CARRY_T
from explorer.integrate.simd import (
    LANES,
    atomic_fetch_add,
    next_bit,
    vabs,
    vadd,
    vand,
    vandnot,
    vbits,
    vdiv,
    vge,
    vgt,
    vload,
    vmax_gt,
    vmin_lt,
    vmul,
    vradius_power_core,
    vselect,
    vsplat,
    vstore,
    vsub,
    vzero,
)
from explorer.kernels import STATUS_NONFINITE, STATUS_STEP_UNDERFLOW
from explorer.kernels import taylor as tk
from explorer.kernels.checks import is_finite
from explorer.kernels.clock import clip_step, resolves
from explorer.kernels.power import is_normal

_IDLE = -1
#: rows of the step_norms_lanes output
N_NORMS = 7
#: rows of the orbit (p1, p2, M, g1, g2) in every lane array: the rows that choose the step
N_ORBIT = 5


@njit
def step_constants(order):
    """(factor, e_p, e_q) of the steps of ``order``: the safety factor and the exponents 1/p,
    1/(p-1) of kernels.taylor.step_size."""
    return tk.safety_factor(order), 1.0 / order, 1.0 / (order - 1)


@njit
def evaluate_lanes(X, order, h, out, base):
    """out[base + i, l] = sum_k X[k, base + i, l] h[l]^k for i = 0..4 per lane (Horner: per lane
    exactly kernels.taylor.evaluate); LANES lanes."""
    w = LANES
    stride = X.shape[1] * w
    hv = vload(h, 0)
    o = order * stride + base * w
    a0 = vload(X, o)
    a1 = vload(X, o + w)
    a2 = vload(X, o + 2 * w)
    a3 = vload(X, o + 3 * w)
    a4 = vload(X, o + 4 * w)
    for k in range(order - 1, -1, -1):
        o = k * stride + base * w
        a0 = vadd(vmul(a0, hv), vload(X, o))
        a1 = vadd(vmul(a1, hv), vload(X, o + w))
        a2 = vadd(vmul(a2, hv), vload(X, o + 2 * w))
        a3 = vadd(vmul(a3, hv), vload(X, o + 3 * w))
        a4 = vadd(vmul(a4, hv), vload(X, o + 4 * w))
    o = base * w
    vstore(out, o, a0)
    vstore(out, o + w, a1)
    vstore(out, o + 2 * w, a2)
    vstore(out, o + 3 * w, a3)
    vstore(out, o + 4 * w, a4)


@njit
def step_norms_lanes(X, order, e_p, e_q, out):
    """Per lane, the norms of kernels.taylor.step_size in its order (out (N_NORMS, LANES)): out[0],
    out[1] the sums of X[order] and X[order - 1] (finiteness), out[2] = a, out[3] = bm, out[4] = s/a,
    out[5] = s/bm, out[6] = min((s/a)^e_p, (s/bm)^e_q) (valid where both are positive normal)."""
    w = LANES
    stride = X.shape[1] * w
    op = order * stride
    oq = (order - 1) * stride
    f = vload(X, op)
    g = vload(X, oq)
    for i in range(1, N_ORBIT):
        f = vadd(f, vload(X, op + i * w))
        g = vadd(g, vload(X, oq + i * w))
    s = vsplat(1.0)
    a = vzero()
    bm = vzero()
    for i in range(N_ORBIT):
        s = vmax_gt(vabs(vload(X, i * w)), s)
        a = vmax_gt(vabs(vload(X, op + i * w)), a)
        bm = vmax_gt(vabs(vload(X, oq + i * w)), bm)
    u = vdiv(s, a)
    v = vdiv(s, bm)
    # kernels.taylor.radius_min's rho = u^e_p; if v^e_q < rho: rho = v^e_q, for all lanes
    pu = vradius_power_core(u, e_p)
    pv = vradius_power_core(v, e_q)
    vstore(out, 6 * w, vmin_lt(pv, pu))
    vstore(out, 0, f)
    vstore(out, w, g)
    vstore(out, 2 * w, a)
    vstore(out, 3 * w, bm)
    vstore(out, 4 * w, u)
    vstore(out, 5 * w, v)


@njit
def lane_step_size(a, bm, u, v, rho, e_p, e_q, factor):
    """kernels.taylor.step_size of lane l from its norms (:func:`step_norms_lanes`); a vanishing or
    subnormal norm takes kernels.taylor.radius_min, as step_size does."""
    if is_normal(u) and is_normal(v):
        return rho * factor
    return tk.radius_min(a, bm, u, v, e_p, e_q) * factor


@njit(inline="always")
def lane_step(l, norms, t, tend, e_p, e_q, factor):
    """The checks and the step of :func:`explorer.integrate._systems_generated.taylor_step_reduced` for lane l from
    its norms (step_norms_lanes): finiteness of the last two coefficients, the step size, clipped
    to ``tend``, and the underflow test."""
    if not (is_finite(norms[0, l]) and is_finite(norms[1, l])):
        return STATUS_NONFINITE, 0.0, False
    h = lane_step_size(norms[2, l], norms[3, l], norms[4, l], norms[5, l], norms[6, l], e_p, e_q, factor)
    h, last = clip_step(t, h, tend)
    if not resolves(t, h):
        return STATUS_STEP_UNDERFLOW, 0.0, False
    return -1, h, last


@njit(inline="always")
def step_lanes(L_on, norms, L_t, tend, e_p, e_q, factor, hv, L_last, L_fast, L_status, L_stop, w):
    """:func:`lane_step` for every lane (``w`` of them) that holds an orbit (``L_on[l]`` 1.0, else
    0.0): its step in ``hv`` (0 for idle and stopped lanes) and ``L_last`` (1.0 for the step that
    ends on ``tend``, else 0.0), or its stop in ``L_status``/``L_stop``."""
    for l in range(w):
        L_stop[l] = False
    zero = vzero()
    one = vsplat(1.0)
    tv = vsplat(tend)
    for c in range(0, w, LANES):
        t = vload(L_t, c)
        u = vload(norms, 4 * w + c)
        v = vload(norms, 5 * w + c)
        h = vmul(vload(norms, 6 * w + c), vsplat(factor))
        last = vge(vadd(t, h), tv)
        h = vselect(last, vsub(tv, t), h)
        live = vgt(vload(L_on, c), zero)
        ok = is_finite(vload(norms, c)) & is_finite(vload(norms, w + c)) & (is_normal(u) & is_normal(v))
        ok = vand(vand(live, ok), resolves(t, h))
        vstore(hv, c, vselect(ok, h, zero))
        vstore(L_last, c, vselect(last, one, zero))
        vstore(L_fast, c, vselect(ok, one, zero))
        bits = vbits(vandnot(live, ok))
        while bits != 0:
            ib, bits = next_bit(bits)
            l = c + ib
            code, hl, lastl = lane_step(l, norms, L_t[l], tend, e_p, e_q, factor)
            if code >= 0:
                stop_lane(l, code, L_status, L_stop)
            else:
                hv[l] = hl
                L_last[l] = 1.0 if lastl else 0.0


@njit(inline="always")
def stop_lane(l, status, L_status, L_stop):
    """Lane l's orbit stops with ``status`` (written out and replaced at the end of the step)."""
    L_status[l] = status
    L_stop[l] = True


@njit(inline="always")
def stop_unless_finite(l, znew, first, last, L_status, L_stop):
    """Stop lane l (STATUS_NONFINITE) unless rows first..last - 1 of znew[:, l] are finite
    (kernels.checks.all_finite, written out)."""
    s = 0.0
    for i in range(first, last):
        s += znew[i, l]
    if not is_finite(s):
        stop_lane(l, STATUS_NONFINITE, L_status, L_stop)


@njit(inline="always")
def count_step(l, znew, first, last, L_steps, L_status, L_stop):
    """After the vector step: unless lane l stopped in :func:`step_lanes`, count its step and check
    its new state, as at the end of systems.taylor_step."""
    if not L_stop[l]:
        L_steps[l] += 1
        stop_unless_finite(l, znew, first, last, L_status, L_stop)


@njit(inline="always")
def next_lane_orbit(next_orbit, n, orb, l, X, nrows):
    """The next unstarted orbit of a batch of ``n`` (the shared counter ``next_orbit``) for lane
    l, or -1 when the batch is handed out: the lane then idles on the zero state (its ``nrows``
    rows of X[0] set to 0: all its coefficients are 0, harmless)."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    if j >= n:
        orb[l] = _IDLE
        for i in range(nrows):
            X[0, i, l] = 0.0
        return -1
    return j


#: alignment (bytes) of the float work arrays: one cache line, one vector of LANES doubles
ALIGN = 64


@njit
def aligned_zeros(n):
    """n float64 zeros starting on a cache line (ALIGN bytes)."""
    buf = np.zeros(n + ALIGN // 8)
    skip = ((ALIGN - buf.ctypes.data % ALIGN) % ALIGN) // 8
    return buf[skip:skip + n]


#: the section phi = phi0 as every System's: s = a . y + b (sin(phi - phi0)), its half keep . (y, 1) > 0
#: (cos(phi - phi0)), the rows (t, p1, p2, M, H - H0)
ROW_STATES = np.array([0, 1, 2], np.int64)


def section_arrays(cphi, sphi):
    """(a, b, keep) of the section phi = phi0 (cphi, sphi = cos phi0, sin phi0) for the generated drivers."""
    return (np.array([0.0, 0.0, 0.0, cphi, -sphi]), 0.0, np.array([0.0, 0.0, 0.0, sphi, cphi, 0.0]))


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(parallel=True, nogil=True)
def _run_lanes(nworkers, Y0, P, a, b, keep, direction, tmax, order, max_steps, carry, limits, out_cross, out_count,
               out_status, out_final, out_info):
    """nworkers groups of LANES lanes (prange), fed from one shared queue of orbits."""
    next_orbit = np.zeros(1, np.int64)
    for w in prange(nworkers):
        G.crossings_lanes_worker(next_orbit, Y0, P, a, b, keep, ROW_STATES, direction, tmax, order, max_steps, carry,
                                 limits, out_cross, out_count, out_status, out_final, out_info, False)
    return 0


def run_taylor_lanes_batch(Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                           out_cross, out_count, out_status, out_final, out_info):
    """Crossings of the section by the Taylor method of ``order`` for every orbit of Y0: the
    arguments and outputs of every batch driver (:mod:`explorer.integrate.drivers`: the carry, the
    limits of a block, the outputs; info's time the clock's sum t and its last column the Casimir
    error g1^2 + g2^2 - 1 of the final state)."""
    a, b, keep = section_arrays(cphi, sphi)
    nworkers = lane_workers(Y0.shape[0])
    args = (Y0, P, a, b, keep, int(direction), float(tmax), int(order), int(max_steps), carry, limits, out_cross,
            out_count, out_status, out_final, out_info)
    if nworkers == 1:
        G.crossings_lanes_worker(np.zeros(1, np.int64), *args[:5], ROW_STATES, *args[5:], False)
    else:
        _run_lanes(nworkers, *args)
    out_info[:, 0] = carry[:, CARRY_T]
    out_info[:, 2] = out_final[:, 3] ** 2 + out_final[:, 4] ** 2 - 1.0
    return 0


def lane_workers(n, max_lanes=None):
    """How many lane workers a batch of ``n`` orbits runs on: one per numba thread, but no more
    than the batch fills workers of LANES lanes (of ``max_lanes`` when that is fewer), and at least
    one."""
    per = LANES if max_lanes is None else max(1, min(int(max_lanes), LANES))
    return max(1, min(get_num_threads(), -(-int(n) // per)))


def worker_lanes(n, nworkers, max_lanes=None):
    """The lanes each of ``nworkers`` workers fills for ``n`` orbits: min(max_lanes, LANES,
    ceil(n / nworkers))."""
    cap = LANES if max_lanes is None else min(int(max_lanes), LANES)
    return max(1, min(cap, -(-n // nworkers)))
