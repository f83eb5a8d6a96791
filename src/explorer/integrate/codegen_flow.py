"""The flow driver appended to every generated module (:data:`explorer.integrate.codegen.TEMPLATES`):
``flow_taylor_worker``, the states of orbits at given times read off each adaptive Taylor step's polynomial
(docs/systems.md, "The flow at given times"), called by :mod:`explorer.analysis.system_flow`; and its SIMD
form ``flow_lanes_worker``, each lane ``flow_orbit`` bit for bit: the step of :mod:`explorer.integrate.codegen_lanes`
in vector form, a step's end in vector form for a lane with no sample in it, the samples lane by lane."""
from __future__ import annotations

__all__ = ["render"]

SOURCE = '''

# ---- the flow at given times (explorer.analysis.system_flow): generated here, beside the recurrence it
# calls, so that numba's cache of it follows the recurrence (docs/systems.md)
from explorer.integrate.simd import atomic_fetch_add  # noqa: E402
from explorer.kernels.checks import all_finite  # noqa: E402
from explorer.kernels.clock import advance_time  # noqa: E402
from explorer.kernels.status import STATUS_DONE, STATUS_MAX_STEPS, STATUS_NONFINITE  # noqa: E402
from explorer.kernels.taylor import evaluate, safety_factor  # noqa: E402


@njit(error_model="numpy")
def _flow_sample(j, m, y, P, E0, states, energy_error):
    for i in range(DIM):
        states[j, m, i] = y[i]
{energy_sample}


@njit(error_model="numpy")
def flow_orbit(j, y0, P, times, order, max_steps, states, energy_error, info):
    """Orbit j from y0 with the adaptive Taylor method of ``order`` (Jorba & Zou 2005, as
    ``crossings_orbit``) to the last of the sorted ``times``, its last step clipped onto it.  The
    samples do not change the steps: a time inside a step is the step's polynomial there
    (kernels.taylor.evaluate), the last time the end of the clipped step, t = 0 the start.
    states[j, m] and energy_error[j, m] = |E - E0| for each time reached; info[j] = (t, steps).
    Returns the status."""
    X = np.empty((DIM, order + 1))
    W = np.empty((max(N_WORK, 1), order + 1))
    ynew = np.empty(DIM)
    ys = np.empty(DIM)
    factor = safety_factor(order)
    for i in range(DIM):
        X[i, 0] = y0[i]
    E0 = {energy_start}
    M = times.shape[0]
    tend = times[M - 1]
    m = 0
    while m < M and times[m] <= 0.0:
        _flow_sample(j, m, y0, P, E0, states, energy_error)
        m += 1
    t = 0.0
    tc = 0.0
    steps = 0
    status = STATUS_DONE
    while m < M:
        if steps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        st, h, last, steps = taylor_step(P, X, W, DIM, t, tend, order, factor, steps, ynew, False)
        if st != STEP_OK:
            status = st
            break
        start = t - tc
        t, tc = advance_time(t, tc, h, last, tend)
        end = t - tc
        while m < M and (last or times[m] <= end):
            if last and times[m] == tend:
                _flow_sample(j, m, ynew, P, E0, states, energy_error)
            else:
                tau = min(max(times[m] - start, 0.0), h)
                evaluate(X, order, tau, ys)
                _flow_sample(j, m, ys, P, E0, states, energy_error)
            m += 1
        for i in range(DIM):
            X[i, 0] = ynew[i]
    info[j, 0] = t - tc
    info[j, 1] = steps
    return status


@njit(nogil=True, error_model="numpy")
def flow_taylor_worker(next_orbit, Y0, P, times, order, max_steps, states, energy_error, status, info):
    """:func:`flow_orbit` for the orbits (rows of Y0) of the queue ``next_orbit`` that threads share: each
    orbit is computed alone, so the result does not depend on the number of threads."""
    j = atomic_fetch_add(next_orbit, 0, 1)
    while j < Y0.shape[0]:
        status[j] = flow_orbit(j, Y0[j], P, times, order, max_steps, states, energy_error, info)
        j = atomic_fetch_add(next_orbit, 0, 1)

# ---- the flow on SIMD lanes: each lane flow_orbit bit for bit, with the vector step of crossings_lanes_worker
# (norms_lanes, steps_lanes, _evaluate_lanes: kernels.taylor's step and Horner evaluation per lane)
from explorer.integrate.lane_parts import flow_lane_finish, lane_step, lane_take, norms_lanes, steps_lanes  # noqa: E402
from explorer.integrate.simd import next_bit, vbits, vmask, vselect  # noqa: E402
from explorer.kernels.checks import is_finite  # noqa: E402
from explorer.kernels.clock import compensated_add  # noqa: E402

@njit(error_model="numpy")
def _flow_ends_lanes(Y, hv, L_go, L_last, L_next, L_t, L_tc, L_steps, X, max_steps):
    """flow_orbit's step end in vector form for the lanes whose step went on, is not the last, ends
    finite (kernels.checks.all_finite), before their next time, with steps left: the compensated clock,
    the step count, the state.  Returns the bits of the other lanes whose step went on."""
    go = vbits(vload(L_go, 0) > 0.0)
    t, tc = compensated_add(vload(L_t, 0), vload(L_tc, 0), vload(hv, 0))
    steps = vload(L_steps, 0) + 1.0
    sy = vzero()
{sum_y}
    ok = (go & vbits(is_finite(sy)) & ~vbits(vload(L_last, 0) > 0.0)
          & vbits(((t - tc) < vload(L_next, 0)) & (steps < float(max_steps))))
    m = vmask(ok)
    vstore(L_t, 0, vselect(m, t, vload(L_t, 0)))
    vstore(L_tc, 0, vselect(m, tc, vload(L_tc, 0)))
    vstore(L_steps, 0, vselect(m, steps, vload(L_steps, 0)))
    for i in range(DIM):
        vstore(X, i * LANES, vselect(m, vload(Y, i * LANES), vload(X, i * LANES)))
    return go & ~ok


@njit(error_model="numpy")
def _flow_lane_start(l, next_orbit, Y0, P, times, X, orb, L_on, L_t, L_tc, L_steps, L_m, L_next, L_E0, states,
                     energy_error, status, info):
    """Lane l takes the next orbit of the queue at its start (its samples at t <= 0 written, an orbit
    with no later time finished at once).  Returns 1, or 0 when the queue is empty (the lane idles)."""
    M = times.shape[0]
    while True:
        j = lane_take(l, next_orbit, Y0.shape[0], X, orb, L_on)
        if j < 0:
            return 0
        y0 = Y0[j]
        for i in range(DIM):
            X[0, i, l] = y0[i]
        E0 = {energy_start}
        m = 0
        while m < M and times[m] <= 0.0:
            _flow_sample(j, m, y0, P, E0, states, energy_error)
            m += 1
        orb[l] = j
        L_E0[l] = E0
        L_t[l] = 0.0
        L_tc[l] = 0.0
        L_steps[l] = 0.0
        L_m[l] = m
        if m < M:
            L_on[l] = 1.0
            L_next[l] = times[m]
            return 1
        flow_lane_finish(l, STATUS_DONE, orb, L_t, L_tc, L_steps, status, info)


@njit(nogil=True, error_model="numpy")
def flow_lanes_worker(next_orbit, Y0, P, times, order, max_steps, states, energy_error, status, info):
    """One group of LANES lanes: orbits from the queue ``next_orbit`` until it is empty, each lane
    flow_orbit's loop (its arguments and outputs)."""
    X = np.zeros((order + 1, DIM, LANES))
    W = np.zeros((order + 1, max(N_WORK, 1), LANES))
    Y = np.zeros((DIM, LANES))
    NORM = np.zeros((5, LANES))
    hv = np.zeros(LANES)
    L_t = np.zeros(LANES)
    L_tc = np.zeros(LANES)
    L_E0 = np.zeros(LANES)
    L_steps = np.zeros(LANES)
    L_on = np.zeros(LANES)
    L_last = np.zeros(LANES)
    L_go = np.zeros(LANES)
    L_next = np.zeros(LANES)
    L_m = np.zeros(LANES, np.int64)
    orb = np.full(LANES, -1, np.int64)
    ys = np.empty(DIM)
    yl = np.empty(DIM)
    M = times.shape[0]
    tend = times[M - 1]
    factor = safety_factor(order)
    e_p = 1.0 / order
    e_q = 1.0 / (order - 1)
    active = 0
    for l in range(LANES):
        active += _flow_lane_start(l, next_orbit, Y0, P, times, X, orb, L_on, L_t, L_tc, L_steps, L_m, L_next,
                                   L_E0, states, energy_error, status, info)
    while active > 0:
        taylor_coefficients_lanes(P, X, order, W)
        fin, normal = norms_lanes(X, order, DIM, e_p, e_q, NORM)
        bits = steps_lanes(NORM, fin, normal, L_on, L_t, tend, factor, hv, L_last, L_go)
        while bits != 0:
            l, bits = next_bit(bits)
            st = lane_step(l, fin, normal, NORM, e_p, e_q, factor, L_t, tend, hv, L_last, L_go)
            if st >= 0:
                flow_lane_finish(l, st, orb, L_t, L_tc, L_steps, status, info)
                active += _flow_lane_start(l, next_orbit, Y0, P, times, X, orb, L_on, L_t, L_tc, L_steps, L_m,
                                           L_next, L_E0, states, energy_error, status, info) - 1
        _evaluate_lanes(X, order, hv, Y)
        bits = _flow_ends_lanes(Y, hv, L_go, L_last, L_next, L_t, L_tc, L_steps, X, max_steps)
        while bits != 0:
            l, bits = next_bit(bits)
            L_steps[l] += 1.0
            for i in range(DIM):
                yl[i] = Y[i, l]
            st = STATUS_NONFINITE
            if all_finite(yl):
                j = orb[l]
                h = hv[l]
                last = L_last[l] != 0.0
                start = L_t[l] - L_tc[l]
                t, tc = advance_time(L_t[l], L_tc[l], h, last, tend)
                end = t - tc
                m = L_m[l]
                while m < M and (last or times[m] <= end):
                    if last and times[m] == tend:
                        _flow_sample(j, m, yl, P, L_E0[l], states, energy_error)
                    else:
                        tau = min(max(times[m] - start, 0.0), h)
                        evaluate(X[:, :, l].T, order, tau, ys)
                        _flow_sample(j, m, ys, P, L_E0[l], states, energy_error)
                    m += 1
                L_m[l] = m
                L_t[l] = t
                L_tc[l] = tc
                for i in range(DIM):
                    X[0, i, l] = yl[i]
                st = -1
                if m >= M:
                    st = STATUS_DONE
                elif L_steps[l] >= max_steps:
                    st = STATUS_MAX_STEPS
                else:
                    L_next[l] = times[m]
            if st >= 0:
                flow_lane_finish(l, st, orb, L_t, L_tc, L_steps, status, info)
                active += _flow_lane_start(l, next_orbit, Y0, P, times, X, orb, L_on, L_t, L_tc, L_steps, L_m,
                                           L_next, L_E0, states, energy_error, status, info) - 1
'''


def render(system) -> str:
    """The driver's source for ``system`` (|E - E0| at each sample when it has an energy)."""
    has_energy = system.energy is not None
    return SOURCE.format(
        sum_y="\n".join(f"    sy = sy + vload(Y, {i} * LANES)" for i in range(system.dimension)),
        energy_start="energy(y0, P)" if has_energy else "np.nan",
        energy_sample="    energy_error[j, m] = abs(energy(y, P) - E0)" if has_energy else "    return")
