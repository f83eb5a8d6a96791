"""The SIMD crossings driver appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``crossings_lanes_worker``, the crossings of ``crossings_orbit`` (:mod:`explorer.integrate.codegen_crossings`) for
LANES orbits at once with ``taylor_coefficients_lanes`` (docs/systems.md, "Crossings").

Each lane is the scalar driver bit for bit.  Written with the vectors of :mod:`explorer.integrate.simd`,
the same operations in the same order as the scalar kernels: the recurrence, the step size (norms,
power, clipping, underflow test), the Horner evaluation, the section's value and coefficients, the
first two tests of kernels.events.isolate_crossings, and the step's end of a lane with no root
possible.  A lane that may hold a root, or stops, is finished lane by lane with the scalar kernels.
A lane whose orbit stops takes the next one from a queue shared by the workers (one group of LANES lanes
per thread: analysis.system_sections.run_driver, or ``prange`` in :mod:`explorer.integrate.lanes` for the
engine's phi = phi0); an orbit's rows depend neither on its lane nor on the thread count.  A lane's start,
finish and status, the step's norms and the vector step size do not depend on the system: they are in
:mod:`explorer.integrate.lane_parts`, compiled once for all systems.
"""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- crossings on SIMD lanes (explorer.analysis.system_sections): each lane crossings_orbit bit for bit
from explorer.integrate.simd import next_bit, vbits, vmask, vselect  # noqa: E402
from explorer.kernels.clock import compensated_add  # noqa: E402
from explorer.kernels.events import excluded_by_variation, sign_change, tail_term  # noqa: E402
from explorer.integrate.lane_parts import (  # noqa: E402
    lane_finish, lane_start, lane_status, lane_step, norms_lanes, steps_lanes)

#: all lanes' bits
_ALL_LANES = (1 << LANES) - 1


@njit(error_model="numpy")
def _evaluate_lanes(X, order, hv, Y):
    """Y[i, l] = sum_k X[k, i, l] hv[l]^k: kernels.taylor.evaluate (Horner) per lane."""
    h = vload(hv, 0)
    o = order * XS
{eval_start}
    for k in range(order - 1, -1, -1):
        o = k * XS
{eval_step}
{eval_store}


@njit(error_model="numpy")
def _section_lanes(X, order, hv, Y, a, b, direction, L_g, GC, G):
    """Per lane, as crossings_orbit: G = _section_value(a, b, y) of the new state y = Y, GC[k] = a . X[k]
    (+ b at k = 0).  Returns the bits of the lanes whose new state is finite (kernels.checks.all_finite)
    and of those where kernels.events.isolate_crossings(GC, order, h, L_g, G, direction, ...) may find a
    root: its first two tests (no_root_within; monotone_within without a sign change) in vector form."""
    h = vload(hv, 0)
    sy = vzero()
    g = vsplat(b)
{section_y}
    vstore(G, 0, g)
    tail = vzero()
    rk = vsplat(1.0)
    dtail = vzero()
    drk = vsplat(1.0)
    for k in range(order + 1):
        o = k * XS
        c = vzero()
{section_c}
        if k == 0:
            c = c + b
        else:
            tail, rk = tail_term(tail, rk, h, 1.0, c)
            if k >= 2:
                dtail, drk = tail_term(dtail, drk, h, float(k), c)
        vstore(GC, k * LANES, c)
    excluded = vbits(excluded_by_variation(vload(GC, 0), tail))
    monotone = vbits(excluded_by_variation(vload(GC, LANES), dtail))
    cross = vbits(sign_change(vload(L_g, 0), g, direction))
    return vbits(is_finite(sy)), _ALL_LANES & ~excluded & (~monotone | cross)


@njit(error_model="numpy")
def _ends_lanes(X, Y, G, hv, L_go, L_last, finite, maybe, L_t, L_tc, L_steps, L_g, tmax, max_steps):
    """The end of crossings_orbit's step in vector form for the lanes whose step went on, is not the last,
    ends finite, cannot hold a root and leaves the orbit running: the compensated clock
    (kernels.clock.compensated_add), the step count, the state and the section's value.  Returns the bits
    of the other lanes whose step went on: their end is taken per lane."""
    go = vbits(vload(L_go, 0) > 0.0)
    t, tc = compensated_add(vload(L_t, 0), vload(L_tc, 0), vload(hv, 0))
    steps = vload(L_steps, 0) + 1.0
    ok = go & finite & ~maybe & ~vbits(vload(L_last, 0) > 0.0) & vbits((t < tmax) & (steps < float(max_steps)))
    m = vmask(ok)
    vstore(L_t, 0, vselect(m, t, vload(L_t, 0)))
    vstore(L_tc, 0, vselect(m, tc, vload(L_tc, 0)))
    vstore(L_steps, 0, vselect(m, steps, vload(L_steps, 0)))
    vstore(L_g, 0, vselect(m, vload(G, 0), vload(L_g, 0)))
    for i in range(DIM):
        vstore(X, i * LANES, vselect(m, vload(Y, i * LANES), vload(X, i * LANES)))
    return go & ~ok


@njit(nogil=True, error_model="numpy")
def crossings_lanes_worker(next_orbit, Y0, P, a, b, keep, cols, direction, tmax, order, max_steps, carry, limits,
                           data, count, status, final, info, backward):
    """One group of LANES lanes: orbits from the queue ``next_orbit`` until it is empty, each lane
    crossings_orbit's loop (the arguments and outputs of crossings_taylor_worker, ``backward`` its
    (-1)^k X[k])."""
    X = np.zeros((order + 1, DIM, LANES))
    W = np.zeros((order + 1, max(N_WORK, 1), LANES))
    Y = np.zeros((DIM, LANES))
    GC = np.zeros((order + 1, LANES))
    NORM = np.zeros((5, LANES))
    # per lane: the step, the clock, the section's values, E0, the step count, and flags as 1.0 / 0.0
    hv = np.zeros(LANES)
    G = np.zeros(LANES)
    L_t = np.zeros(LANES)
    L_tc = np.zeros(LANES)
    L_g = np.zeros(LANES)
    L_E0 = np.zeros(LANES)
    L_steps = np.zeros(LANES)
    L_on = np.zeros(LANES)
    L_last = np.zeros(LANES)
    L_go = np.zeros(LANES)
    orb = np.full(LANES, -1, np.int64)
    L_n = np.zeros(LANES, np.int64)
    L_target = np.zeros(LANES, np.int64)
    L_room = np.zeros(LANES, np.int64)
    yc = np.empty(DIM)
    gc, work, roots, brackets, stack = root_workspace(order)
    factor = safety_factor(order)
    e_p = 1.0 / order
    e_q = 1.0 / (order - 1)
    active = 0
    for l in range(LANES):
        active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t, L_tc, L_g,
                              L_E0, L_n, L_steps, L_target, L_room, count, status, final, info)
    while active > 0:
        taylor_coefficients_lanes(P, X, order, W)
        if backward:
            for k in range(1, order + 1, 2):
                for i in range(DIM):
                    for l in range(LANES):
                        X[k, i, l] = -X[k, i, l]
        fin, normal = norms_lanes(X, order, DIM, e_p, e_q, NORM)
        bits = steps_lanes(NORM, fin, normal, L_on, L_t, tmax, factor, hv, L_last, L_go)
        while bits != 0:
            l, bits = next_bit(bits)
            st = lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, tmax, hv, L_last, L_go)
            if st >= 0:
                lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info)
                active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t,
                                      L_tc, L_g, L_E0, L_n, L_steps, L_target, L_room, count, status, final,
                                      info) - 1
        _evaluate_lanes(X, order, hv, Y)
        finite, maybe = _section_lanes(X, order, hv, Y, a, b, direction, L_g, GC, G)
        bits = _ends_lanes(X, Y, G, hv, L_go, L_last, finite, maybe, L_t, L_tc, L_steps, L_g, tmax, max_steps)
        while bits != 0:
            l, bits = next_bit(bits)
            L_steps[l] += 1.0
            st = STATUS_NONFINITE
            if (finite >> l) & 1:
                j = orb[l]
                t = L_t[l]
                tc = L_tc[l]
                h = hv[l]
                n = L_n[l]
                nroots = 0
                if (maybe >> l) & 1:
                    for k in range(order + 1):
                        gc[k] = GC[k, l]
                    nroots = poly_step_roots(gc, order, h, L_g[l], G[l], direction, roots, brackets, work, stack)
                kept = n
                for r in range(nroots):
                    if n >= L_room[l]:
                        break
                    tau = roots[r]
                    evaluate(X[:, :, l].T, order, tau, yc)
                    kept = _record(data, j, n, (t - tc) + tau, yc, P, L_E0[l], keep, cols)
                    if kept < 0:
                        break
                    n = kept
                L_n[l] = n
                if kept >= 0:
                    t, tc = advance_time(t, tc, h, L_last[l] != 0.0, tmax)
                    L_t[l] = t
                    L_tc[l] = tc
                    for i in range(DIM):
                        X[0, i, l] = Y[i, l]
                    L_g[l] = G[l]
                    st = lane_status(n, L_target[l], t, tmax, L_steps[l], max_steps)
            if st >= 0:
                lane_finish(l, st, X, orb, L_t, L_tc, L_g, L_n, L_steps, carry, count, status, final, info)
                active += lane_start(l, next_orbit, Y0, tmax, max_steps, carry, limits, X, orb, L_on, L_t,
                                      L_tc, L_g, L_E0, L_n, L_steps, L_target, L_room, count, status, final,
                                      info) - 1
'''


def _lines(template, dim, indent):
    return "\n".join(" " * indent + template.format(i=i) for i in range(dim))


def render(system) -> str:
    """The driver's source for ``system``: the loops over the state written out, one vector each."""
    n = system.dimension
    section_y = "\n".join(f"    y{i} = vload(Y, {i} * LANES)\n    sy = sy + y{i}\n    g = g + a[{i}] * y{i}"
                          for i in range(n))
    return SOURCE.format(
        eval_start=_lines("y{i} = vload(X, o + {i} * LANES)", n, 4),
        eval_step=_lines("y{i} = y{i} * h + vload(X, o + {i} * LANES)", n, 8),
        eval_store=_lines("vstore(Y, {i} * LANES, y{i})", n, 4),
        section_y=section_y,
        section_c=_lines("c = c + a[{i}] * vload(X, o + {i} * LANES)", n, 8),
)
