"""The Taylor crossing loop on SIMD lanes, the method's only implementation: LANES orbits advance
in lockstep (a lone orbit is one lane), each lane bit for bit the scalar oracle
tests/integrate/taylor_oracle.py whatever the thread count.  Design and the scalar/vector split:
docs/methods.md (Parallelism), docs/architecture.md (The system seam).  Kernel contract: explorer/kernels/__init__.py.
"""
import numpy as np

from explorer._jit import get_num_threads, njit, prange
from explorer.integrate._lanes_generated import N_WORK, NVAR, taylor_coefficients_lanes
from explorer.integrate.drivers import (
    LIMIT_ROOM,
    LIMIT_TARGET,
    keep_crossing,
    read_carry,
    save_carry,
    store_orbit,
)
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
    vlt,
    vmax_gt,
    vmin_lt,
    vmul,
    vor,
    vradius_power_core,
    vselect,
    vsplat,
    vstore,
    vsub,
    vzero,
)
from explorer.kernels import STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE, STATUS_STEP_UNDERFLOW, STATUS_TMAX
from explorer.kernels import taylor as tk
from explorer.kernels.checks import is_finite
from explorer.kernels.clock import advance_time, clip_step, compensated_add, resolves
from explorer.kernels.events import (
    ISOLATE_STACK,
    MAX_STEP_ROOTS,
    excluded_by_variation,
    poly_step_roots,
    sign_change,
    sin_diff,
    tail_term,
)
from explorer.kernels.power import is_normal
from explorer.model.equations import section_g

_IDLE = -1
#: rows of the step_norms_lanes output
N_NORMS = 7
#: rows of the orbit (p1, p2, M, g1, g2) in every lane array: the rows that choose the step
N_ORBIT = 5
#: rows of sin(phi) = g1 and cos(phi) = g2 in the state (p1, p2, M, g1, g2)
_G1 = 3
_G2 = 4


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


@njit
def variation_lanes(X, order, h, cphi, sphi, out):
    """out[l] = sum_{k>=1} |c_k| h[l]^k, c_k the step's Taylor coefficients of sin(phi - phi0): the
    variation bound of kernels.events.excluded_by_variation, per lane."""
    cv = vsplat(cphi)
    sv = vsplat(sphi)
    hv = vload(h, 0)
    acc = vzero()
    for k in range(order, 0, -1):
        acc = vmul(vadd(acc, vabs(_sin_diff_lanes(X, k, 0, LANES, cv, sv))), hv)
    vstore(out, 0, acc)


@njit(inline="always")
def _sin_diff_lanes(X, k, c, w, cv, sv):
    o = k * (NVAR * w) + c
    return sin_diff(vload(X, o + _G1 * w), vload(X, o + _G2 * w), cv, sv)


@njit(inline="always")
def monotone_lanes(X, order, hv, cv, sv, c, w):
    """kernels.events.monotone_within(gc, order, h) for the group of LANES lanes at ``c``, built
    from the scalar functions on vectors, so the mask is the scalar test's answer."""
    h = vload(hv, c)
    rk = vsplat(1.0)
    s = vzero()
    for k in range(2, order + 1):
        s, rk = tail_term(s, rk, h, float(k), _sin_diff_lanes(X, k, c, w, cv, sv))
    return excluded_by_variation(_sin_diff_lanes(X, 1, c, w, cv, sv), s)


@njit(inline="always")
def end_steps_lanes(X, order, ynew, vary, hv, L_t, L_tc, L_gprev, L_steps, L_left, L_on, L_fast, L_last, cphi, sphi,
                    direction, tmax, max_steps, c, w):
    """The end of the step, in vector form, for the lanes of the group at ``c`` whose step needs only
    bookkeeping: taken in vector form, not the last, finite, no root possible (variation bound, or
    monotone without a sign change) and no stop; they take the new state, sin(phi - phi0), the
    compensated time and the step count as the scalar loop would.  Returns the bits of the other
    lanes holding an orbit (lane c + i bit i), whose step end :func:`run_worker` runs per lane."""
    zero = vzero()
    live = vgt(vload(L_on, c), zero)
    ok = vandnot(vgt(vload(L_fast, c), zero), vgt(vload(L_last, c), zero))
    y0 = vload(ynew, c)
    y1 = vload(ynew, w + c)
    y2 = vload(ynew, 2 * w + c)
    y3 = vload(ynew, 3 * w + c)
    y4 = vload(ynew, 4 * w + c)
    ok = vand(ok, is_finite(vadd(vadd(vadd(vadd(vadd(zero, y0), y1), y2), y3), y4)))
    cv = vsplat(cphi)
    sv = vsplat(sphi)
    none = excluded_by_variation(_sin_diff_lanes(X, 0, c, w, cv, sv), vload(vary, c))
    gnew = sin_diff(y3, y4, cv, sv)
    if vbits(vandnot(vand(live, ok), none)) != 0:
        cross = sign_change(vload(L_gprev, c), gnew, direction)
        none = vor(none, vandnot(monotone_lanes(X, order, hv, cv, sv, c, w), cross))
    ok = vand(ok, none)
    t = vload(L_t, c)
    tc = vload(L_tc, c)
    tn, tcn = compensated_add(t, tc, vload(hv, c))
    steps = vload(L_steps, c)
    sn = vadd(steps, vsplat(1.0))
    ok = vand(ok, vand(vand(vlt(tn, vsplat(tmax)), vlt(sn, vsplat(max_steps))), vgt(vload(L_left, c), zero)))
    vstore(L_t, c, vselect(ok, tn, t))
    vstore(L_tc, c, vselect(ok, tcn, tc))
    vstore(L_steps, c, vselect(ok, sn, steps))
    vstore(L_gprev, c, vselect(ok, gnew, vload(L_gprev, c)))
    vstore(X, c, vselect(ok, y0, vload(X, c)))
    vstore(X, w + c, vselect(ok, y1, vload(X, w + c)))
    vstore(X, 2 * w + c, vselect(ok, y2, vload(X, 2 * w + c)))
    vstore(X, 3 * w + c, vselect(ok, y3, vload(X, 3 * w + c)))
    vstore(X, 4 * w + c, vselect(ok, y4, vload(X, 4 * w + c)))
    return vbits(vandnot(live, ok))


@njit
def _evaluate_lane(X, order, l, h, out):
    """out[i] = sum_k X[k, i, l] h^k: kernels.taylor.evaluate on lane l."""
    for i in range(NVAR):
        acc = X[order, i, l]
        for k in range(order - 1, -1, -1):
            acc = acc * h + X[k, i, l]
        out[i] = acc


@njit
def _finish(j, l, X, count, status, t, tc, gprev, steps, carry, out_count, out_status, out_final,
            out_info):
    for i in range(NVAR):
        out_final[j, i] = X[0, i, l]
    save_carry(carry[j], t, tc, gprev, steps)
    store_orbit(j, count, status, t, steps, out_count, out_status, out_final, out_info)


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


@njit
def _start_lane(l, X, orb, L_on, L_left, L_t, L_tc, L_gprev, L_H0, L_count, L_steps, L_target, L_room,
                next_orbit, Y0, tmax, max_steps, carry, limits, out_count, out_status, out_final, out_info):
    while True:
        j = next_lane_orbit(next_orbit, Y0.shape[0], orb, l, X, NVAR)
        if j < 0:
            L_on[l] = 0.0
            return 0
        for i in range(NVAR):
            X[0, i, l] = Y0[j, i]
        t, tc, g, steps, H0 = read_carry(carry[j])
        if limits[j, LIMIT_TARGET] == 0:
            _finish(j, l, X, 0, STATUS_DONE, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        if t >= tmax:
            _finish(j, l, X, 0, STATUS_TMAX, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        if steps >= max_steps:
            _finish(j, l, X, 0, STATUS_MAX_STEPS, t, tc, g, steps, carry, out_count, out_status, out_final,
                    out_info)
            continue
        orb[l] = j
        L_H0[l] = H0
        L_gprev[l] = g
        L_t[l] = t
        L_tc[l] = tc
        L_count[l] = 0
        L_steps[l] = steps
        L_target[l] = limits[j, LIMIT_TARGET]
        L_room[l] = limits[j, LIMIT_ROOM]
        L_on[l] = 1.0
        L_left[l] = float(L_target[l])
        return 1


#: the lane worker's work arrays: five n-dimensional ones, then the 1-D ones of workspace_views
WORKSPACE_ND = (("X", "(p + 1, NVAR, W)"), ("norms", "(N_NORMS, W)"), ("ynew", "(NVAR, W)"),
                ("brackets", "(MAX_STEP_ROOTS, 4)"), ("stack", "(ISOLATE_STACK, 5)"))
WORKSPACE_F = (("hv", "W"), ("vary", "W"), ("yl", "NVAR"), ("yc", "NVAR"), ("gc", "p + 1"),
               ("work", "p + 1"), ("roots", "MAX_STEP_ROOTS"), ("L_t", "W"), ("L_tc", "W"),
               ("L_gprev", "W"), ("L_H0", "W"), ("L_steps", "W"), ("L_on", "W"), ("L_left", "W"),
               ("L_fast", "W"), ("L_last", "W"))
WORKSPACE_I = ("orb", "L_count", "L_target", "L_room", "L_status")
WORKSPACE_B = ("L_stop",)
#: the float work arrays of W lanes (the first of WORKSPACE_F's flat buffer), the int ones
N_FLOAT_W = 11
N_INT_W = 5
#: length of the output of :func:`workspace_sizes`
N_WORKSPACE = 8
#: alignment (bytes) of the float work arrays: one cache line, one vector of LANES doubles
ALIGN = 64


@njit
def workspace_sizes(order, w, out):
    """Sizes of the worker's work arrays for ``order`` and ``w`` lanes: out[0:5] the elements of
    WORKSPACE_ND (X, norms, ynew, brackets, stack), out[5:8] the lengths of the flat float64,
    int64 and bool buffers of :func:`workspace_views`."""
    p1 = order + 1
    out[0] = p1 * NVAR * w
    out[1] = N_NORMS * w
    out[2] = NVAR * w
    out[3] = MAX_STEP_ROOTS * 4
    out[4] = ISOLATE_STACK * 5
    out[5] = N_FLOAT_W * w + 2 * NVAR + 2 * p1 + MAX_STEP_ROOTS
    out[6] = N_INT_W * w
    out[7] = w


@njit
def workspace_views(order, w, wf, wi, wb):
    """The 1-D work arrays (WORKSPACE_F, WORKSPACE_I, WORKSPACE_B) of ``w`` lanes as views of the
    flat buffers ``wf``, ``wi``, ``wb`` (slices: views that cost nothing)."""
    p1 = order + 1
    hv, vary, L_t, L_tc, L_gprev, L_H0 = (wf[0:w], wf[w:2 * w], wf[2 * w:3 * w], wf[3 * w:4 * w], wf[4 * w:5 * w],
                                          wf[5 * w:6 * w])
    L_steps, L_on, L_left, L_fast, L_last = (wf[6 * w:7 * w], wf[7 * w:8 * w], wf[8 * w:9 * w], wf[9 * w:10 * w],
                                             wf[10 * w:11 * w])
    orb, L_count, L_target, L_room, L_status = (wi[0:w], wi[w:2 * w], wi[2 * w:3 * w], wi[3 * w:4 * w],
                                                wi[4 * w:5 * w])
    a = N_FLOAT_W * w
    yl = wf[a:a + NVAR]
    yc = wf[a + NVAR:a + 2 * NVAR]
    a += 2 * NVAR
    gc = wf[a:a + p1]
    work = wf[a + p1:a + 2 * p1]
    a += 2 * p1
    roots = wf[a:a + MAX_STEP_ROOTS]
    L_stop = wb[0:w]
    return (hv, vary, yl, yc, gc, work, roots, L_t, L_tc, L_gprev, L_H0, L_steps, L_on, L_left, L_fast, L_last, orb,
            L_count, L_target, L_room, L_status, L_stop)


# nogil: the batch drivers Python calls release the GIL (docs/architecture.md, Parallelism)
@njit(nogil=True)
def _run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                out_cross, out_count, out_status, out_final, out_info):
    w = LANES
    n = np.zeros(N_WORKSPACE, np.int64)
    workspace_sizes(order, w, n)
    return run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry,
                      limits, out_cross, out_count, out_status, out_final, out_info,
                      aligned_zeros(n[0]).reshape((order + 1, NVAR, w)),
                      aligned_zeros(n[1]).reshape((N_NORMS, w)), aligned_zeros(n[2]).reshape((NVAR, w)),
                      aligned_zeros(n[3]).reshape((MAX_STEP_ROOTS, 4)),
                      aligned_zeros(n[4]).reshape((ISOLATE_STACK, 5)), aligned_zeros(n[5]),
                      np.zeros(n[6], np.int64), np.zeros(n[7], np.bool_))


@njit
def aligned_zeros(n):
    """n float64 zeros starting on a cache line (ALIGN bytes)."""
    buf = np.zeros(n + ALIGN // 8)
    skip = ((ALIGN - buf.ctypes.data % ALIGN) % ALIGN) // 8
    return buf[skip:skip + n]


@njit
def run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
               out_cross, out_count, out_status, out_final, out_info, X, norms, ynew, brackets, stack, wf, wi, wb):
    """Integrate orbits taken from the shared counter ``next_orbit`` on up to ``nlanes`` lanes
    until none is left: the Taylor crossing loop, each lane one orbit, LANES lanes (the last axis
    of X)."""
    w = LANES
    # the recurrence's work array (explorer.integrate.codegen: rows of the nodes whose past it reads)
    Wr = aligned_zeros((order + 1) * max(N_WORK, 1) * w).reshape((order + 1, max(N_WORK, 1), w))
    (hv, vary, yl, yc, gc, work, roots, L_t, L_tc, L_gprev, L_H0, L_steps, L_on, L_left, L_fast, L_last, orb,
     L_count, L_target, L_room, L_status, L_stop) = workspace_views(order, w, wf, wi, wb)
    for l in range(w):
        orb[l] = _IDLE
        L_on[l] = 0.0
    factor, e_p, e_q = step_constants(order)
    active = 0
    for l in range(nlanes):
        active += _start_lane(l, X, orb, L_on, L_left, L_t, L_tc, L_gprev, L_H0, L_count, L_steps, L_target,
                              L_room, next_orbit, Y0, tmax, max_steps, carry, limits,
                              out_count, out_status, out_final, out_info)

    while active > 0:
        taylor_coefficients_lanes(P, X, order, Wr)
        step_norms_lanes(X, order, e_p, e_q, norms)
        step_lanes(L_on, norms, L_t, tmax, e_p, e_q, factor, hv, L_last, L_fast, L_status, L_stop, w)
        evaluate_lanes(X, order, hv, ynew, 0)
        variation_lanes(X, order, hv, cphi, sphi, vary)
        for c in range(0, w, LANES):
            bits = end_steps_lanes(X, order, ynew, vary, hv, L_t, L_tc, L_gprev, L_steps, L_left, L_on, L_fast,
                                   L_last, cphi, sphi, direction, tmax, max_steps, c, w)
            while bits != 0:
                ib, bits = next_bit(bits)
                l = c + ib
                j = orb[l]
                if not L_stop[l]:
                    L_steps[l] += 1.0
                    s = 0.0
                    for i in range(NVAR):
                        yl[i] = ynew[i, l]
                        s += yl[i]
                    if not is_finite(s):
                        stop_lane(l, STATUS_NONFINITE, L_status, L_stop)
                if not L_stop[l]:
                    h = hv[l]
                    t = L_t[l]
                    tc = L_tc[l]
                    gprev = L_gprev[l]
                    count = L_count[l]
                    gnew = section_g(yl, cphi, sphi)
                    nroots = 0
                    if not excluded_by_variation(sin_diff(X[0, _G1, l], X[0, _G2, l], cphi, sphi), vary[l]):
                        for k in range(order + 1):
                            gc[k] = sin_diff(X[k, _G1, l], X[k, _G2, l], cphi, sphi)
                        nroots = poly_step_roots(gc, order, h, gprev, gnew, direction, roots,
                                                 brackets, work, stack)
                    for r in range(nroots):
                        if count >= L_room[l]:
                            break
                        tau = roots[r]
                        _evaluate_lane(X, order, l, tau, yc)
                        kept = keep_crossing(out_cross[j], count, (t - tc) + tau, yc, P, L_H0[l], cphi, sphi)
                        if kept < 0:
                            stop_lane(l, STATUS_NONFINITE, L_status, L_stop)
                            break
                        count = kept
                        L_count[l] = count
                        L_left[l] = float(L_target[l] - count)
                if not L_stop[l]:
                    t, tc = advance_time(t, tc, h, L_last[l] != 0.0, tmax)
                    L_t[l] = t
                    L_tc[l] = tc
                    for i in range(NVAR):
                        X[0, i, l] = yl[i]
                    L_gprev[l] = gnew
                    if count >= L_target[l]:
                        stop_lane(l, STATUS_DONE, L_status, L_stop)
                    elif t >= tmax:
                        stop_lane(l, STATUS_TMAX, L_status, L_stop)
                    elif L_steps[l] >= max_steps:
                        stop_lane(l, STATUS_MAX_STEPS, L_status, L_stop)
                if L_stop[l]:
                    _finish(j, l, X, L_count[l], L_status[l], L_t[l], L_tc[l], L_gprev[l], L_steps[l], carry,
                            out_count, out_status, out_final, out_info)
                    active += _start_lane(l, X, orb, L_on, L_left, L_t, L_tc, L_gprev, L_H0, L_count, L_steps,
                                          L_target, L_room, next_orbit, Y0, tmax, max_steps, carry, limits,
                                          out_count, out_status, out_final, out_info) - 1
    return 0


@njit(parallel=True, nogil=True)
def _run_lanes(nworkers, nlanes, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
               out_cross, out_count, out_status, out_final, out_info):
    """nworkers workers (prange) of nlanes lanes each, fed from one shared queue of orbits."""
    next_orbit = np.zeros(1, np.int64)
    for w in prange(nworkers):
        _run_worker(nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                    out_cross, out_count, out_status, out_final, out_info)
    return 0


def run_taylor_lanes_batch(Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                           out_cross, out_count, out_status, out_final, out_info, max_lanes=None):
    """Crossings of the section by the Taylor method of ``order`` for every orbit of Y0: the
    arguments and outputs of every batch driver (:mod:`explorer.integrate.drivers`: the carry, the
    limits of a block, the outputs)."""
    n = Y0.shape[0]
    nworkers = lane_workers(n, max_lanes)
    nlanes = worker_lanes(n, nworkers, max_lanes)
    if nworkers == 1:
        return _run_worker(nlanes, np.zeros(1, np.int64), Y0, P, cphi, sphi, int(direction), float(tmax),
                           int(order), int(max_steps), carry, limits, out_cross, out_count, out_status, out_final,
                           out_info)
    return _run_lanes(nworkers, nlanes, Y0, P, cphi, sphi, int(direction), float(tmax), int(order),
                      int(max_steps), carry, limits, out_cross, out_count, out_status, out_final, out_info)


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
