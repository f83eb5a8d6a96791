"""The engine's Taylor crossings, every System's lane driver (explorer.integrate.codegen_lanes rendered
into _lanes_generated for chaplygin.system(), run by explorer.integrate.lanes), are bit for bit the
scalar oracle (tests/integrate/taylor_oracle.py): the lane kernels, step size, whole batches (parameter
sets, orbit counts not multiple of LANES, very different orbit lengths and stop reasons, threads, orbit
order); the generated file is up to date."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import PARAM_SETS, assert_threads_and_order_keep_the_bits, random_states
from taylor_oracle import run_taylor_batch

from explorer import model
from explorer._jit import get_num_threads, njit, set_num_threads
from explorer.analysis import sections
from explorer.integrate import _lanes_generated as G
from explorer.integrate import drivers, lane_parts, lanes, simd
from explorer.integrate import systems as sy
from explorer.kernels import (
    STATUS_DONE,
    STATUS_MAX_STEPS,
    STATUS_NONFINITE,
    STATUS_STEP_UNDERFLOW,
    STATUS_TMAX,
    clock,
    events,
)
from explorer.kernels import taylor as tk

ROOT = Path(__file__).resolve().parents[2]
L = simd.LANES


# ---------------------------------------------------------------- the generated file
def test_gen_lanes_check_passes_on_the_repository_and_fails_on_a_stale_file(tmp_path):
    # --check compares each of the three generated files with what the generator writes now
    gen = [sys.executable, str(ROOT / "tools" / "gen_lanes.py")]
    ok = subprocess.run([*gen, "--check"], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    stale = tmp_path / "stale.py"
    stale.write_text((ROOT / "src" / "explorer" / "integrate" / "_lanes_generated.py").read_text() + "# edited\n")
    r = subprocess.run([*gen, "-o", str(stale), "--check"], capture_output=True, text=True)
    assert r.returncode == 1 and "out of date" in r.stderr


# ---------------------------------------------------------------- kernels
def _lane_h(l, fin, normal, NORM, order, t=0.0, tend=1e300):
    """lane_parts.lane_step of lane l from its norms: (status, h, last), status -1 for a step."""
    hv, L_last, L_go, L_t = np.zeros(L), np.zeros(L), np.zeros(L), np.full(L, t)
    st = lane_parts.lane_step(l, fin, normal, NORM, 1.0 / order, 1.0 / (order - 1), tk.safety_factor(order), L_t,
                              tend, hv, L_last, L_go)
    return st, hv[l], L_last[l] == 1.0


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
@pytest.mark.parametrize("order", [4, 5, 15, 16, 19, 27])
def test_kernels_match_scalar_bitwise(name, order):
    """Every lane of the generated recurrence, the Horner sums, the step norms and the step is the
    scalar kernel's double."""
    P = PARAM_SETS[name].as_array()
    rng = np.random.default_rng(order)
    W = L
    X = np.zeros((order + 1, 5, W))
    X[0] = random_states(PARAM_SETS[name], W, seed=order, scale=2.0).T
    X[0, :, 0] = 0.0      # an idle lane
    X[0, 2, W - 1] = 1e150    # a lane whose coefficients overflow
    G.taylor_coefficients_lanes(P, X, order, np.zeros((order + 1, max(G.N_WORK, 1), W)))
    h = rng.uniform(0.0, 0.5, W)
    out = np.empty((5, W))
    G._evaluate_lanes(X, order, h, out)
    NORM = np.empty((5, W))
    with np.errstate(all="ignore"):
        fin, normal = lane_parts.norms_lanes(X, order, 5, 1.0 / order, 1.0 / (order - 1), NORM)
        for l in range(W):
            _check_lane(P, X, order, h, out, NORM, fin, normal, l)


def _check_lane(P, X, order, h, out, NORM, fin, normal, l):
    """Lane l of the vector kernels against the scalar ones."""
    Xs = np.zeros((5, order + 1))
    Xs[:, 0] = X[0, :, l]
    G.taylor_coefficients(P, Xs, order)
    np.testing.assert_array_equal(Xs.T, X[:, :, l])
    ys = np.empty(5)
    tk.evaluate(Xs, order, h[l], ys)
    np.testing.assert_array_equal(ys, out[:, l])
    finite = sy.finite_column(Xs, order, 5) and sy.finite_column(Xs, order - 1, 5)
    assert bool(fin >> l & 1) == finite
    if finite:
        s = max(1.0, np.abs(Xs[:, 0]).max())
        assert NORM[0, l] == np.abs(Xs[:, order]).max() and NORM[1, l] == np.abs(Xs[:, order - 1]).max()
        assert NORM[2, l] == s / NORM[0, l] and NORM[3, l] == s / NORM[1, l]
        st, got, _last = _lane_h(l, fin, normal, NORM, order)
        assert st == -1 and got == clock.clip_step(0.0, tk.step_size(Xs, order, tk.safety_factor(order)), 1e300)[0]


@pytest.mark.parametrize("order", [4, 15, 16, 25, 40])
def test_lane_step_size_is_step_size_near_ties_and_for_vanishing_or_subnormal_norms(order):
    """The vector powers of lane_parts.norms_lanes and lane_parts.lane_step give step_size's double when the
    two radii are nearly equal (either may be the minimum), far apart, and when a norm is 0 or
    subnormal (the scalar path)."""
    rng = np.random.default_rng(order)
    e_p, e_q = 1.0 / order, 1.0 / (order - 1)
    factor = tk.safety_factor(order)
    W = L
    cases = []
    for _ in range(400):
        s = max(1.0, 10.0 ** rng.uniform(-1, 3))
        a = 10.0 ** rng.uniform(-300, 5)
        # bm such that (s/bm)^e_q = (s/a)^e_p (1 + rel), rel from exact ties to far apart
        rel = rng.choice([0.0, 1e-16, -1e-16, 1e-13, -1e-13, 1e-9, -1e-9, 1e-5, -1e-5, 0.1, -0.5])
        with np.errstate(all="ignore"):
            bm = s / ((s / a) ** (e_p / e_q) * (1.0 + rel) ** (1.0 / e_q))
        if np.isfinite(bm) and bm > 0.0:
            cases.append((s, a, bm))
    cases += [(1.0, a, bm) for a, bm in [(0.0, 0.0), (0.0, 1e-3), (1e-3, 0.0), (5e-324, 1e-3), (1e-3, 5e-324)]]
    for c0 in range(0, len(cases), W):
        X = np.zeros((order + 1, 5, W))
        chunk = cases[c0:c0 + W]
        for l, (s, a, bm) in enumerate(chunk):
            X[0, 2, l], X[order, 3, l], X[order - 1, 1, l] = s, -a, bm
        NORM = np.empty((5, W))
        with np.errstate(all="ignore"):
            fin, normal = lane_parts.norms_lanes(X, order, 5, e_p, e_q, NORM)
        for l in range(len(chunk)):
            want = tk.step_size(np.ascontiguousarray(X[:, :, l].T), order, factor)
            st, got, _last = _lane_h(l, fin, normal, NORM, order)
            assert st == -1 and got == clock.clip_step(0.0, want, 1e300)[0]


# ---------------------------------------------------------------- the step in vector form
_SPECIAL = np.array([0.0, -0.0, 1.0, -1.0, np.nan, np.inf, -np.inf, 5e-324, 2.2250738585072014e-308, 1e308])


@njit(cache=False)
def _mask_bits(a, b, out):
    """The bits of every vector comparison and mask operation of a[0:LANES] against b[0:LANES]."""
    x = simd.vload(a, 0)
    y = simd.vload(b, 0)
    gt, ge, lt, eq = simd.vgt(x, y), simd.vge(x, y), simd.vlt(x, y), simd.veq(x, y)
    out[0], out[1], out[2], out[3] = simd.vbits(gt), simd.vbits(ge), simd.vbits(lt), simd.vbits(eq)
    out[4], out[5] = simd.vbits(simd.vand(gt, eq)), simd.vbits(simd.vor(gt, eq))
    simd.vstore(a, 0, simd.vselect(gt, x, y))


@njit(cache=False)
def _visit(bits, out):
    """The lanes next_bit visits in ``bits``, in order, into out; returns how many."""
    n = 0
    while bits != 0:
        i, bits = simd.next_bit(bits)
        out[n] = i
        n += 1
    return n


@njit(cache=False)
def _copy_rows(a, b):
    """b[k, r] = a[k, r] for every k, r, through vget and vset."""
    for k in range(a.shape[0]):
        for r in range(a.shape[1]):
            simd.vset(b, k, r, simd.vget(a, k, r))


def test_vget_and_vset_address_coefficient_k_of_row_r_by_the_arrays_own_row_count():
    """vget(a, k, r) is a[k, r, :] and vset(b, k, r, v) writes b[k, r, :], whatever a's row count (the
    generated recurrences read and write X and W with them)."""
    for rows in (1, 3, 7):
        a = np.random.default_rng(rows).normal(size=(5, rows, L))
        b = np.zeros_like(a)
        _copy_rows(a, b)
        assert np.array_equal(a.view(np.uint64), b.view(np.uint64))


def test_next_bit_visits_the_set_lanes_of_a_mask_once_in_increasing_order():
    out = np.empty(64, np.int64)
    for bits in (1, 2, 0b10110010, (1 << L) - 1, 1 << 63 - 1, 0x5555):
        n = _visit(bits, out)
        assert out[:n].tolist() == [i for i in range(64) if bits >> i & 1]
    assert _visit(0, out) == 0


def test_vector_masks_are_the_scalar_comparisons_lane_by_lane_nan_included():
    """vgt, vge, vlt, veq are the scalar >, >=, <, == of each lane (false where a NaN is
    compared), vand/vor the logic of the lanes, vselect the scalar ``x if m else y`` and
    vbits puts lane i in bit i: what the vector step end decides is what the scalar code decides."""
    rng = np.random.default_rng(5)
    out = np.empty(6, np.int64)
    for _ in range(200):
        a = rng.choice(_SPECIAL, L)
        b = rng.choice(_SPECIAL, L)
        a0 = a.copy()
        _mask_bits(a, b, out)
        with np.errstate(invalid="ignore"):
            want = [a0 > b, a0 >= b, a0 < b, a0 == b]
        want += [want[0] & want[3], want[0] | want[3]]
        for got, m in zip(out, want):
            assert got == sum(1 << i for i in range(L) if m[i])
        sel = np.where(want[0], a0, b)
        assert np.array_equal(a.view(np.uint64), sel.view(np.uint64))


def test_vector_step_takes_lane_steps_double_and_leaves_the_rare_lanes_to_it():
    """lane_parts.steps_lanes on norms of every kind (finite, non-finite, vanishing, subnormal, steps
    that reach tend or underflow, idle lanes): every lane it steps gets the step and the flag of the last
    step of the scalar lane_step, and it leaves to that exactly the lanes holding an orbit whose
    coefficients are not finite, whose s/a, s/bm are not positive normal, or whose step underflows."""
    W = L
    rng = np.random.default_rng(1)
    order = 15
    factor, e_p, e_q = tk.safety_factor(order), 1.0 / order, 1.0 / (order - 1)
    tend = 50.0
    seen = set()
    for _ in range(40):
        NORM = np.empty((5, W))
        NORM[0] = rng.choice([0.0, 5e-324, 1e-3, 2.0], W)
        NORM[1] = rng.choice([0.0, 5e-324, 1e-3, 2.0], W)
        NORM[2] = rng.choice([np.inf, 1e-320, 3.0, 1e5, 1e-310], W, p=[0.1, 0.05, 0.4, 0.4, 0.05])
        NORM[3] = rng.choice([np.inf, 1e-320, 3.0, 1e5], W, p=[0.1, 0.05, 0.45, 0.4])
        NORM[4] = np.minimum(NORM[2] ** e_p, NORM[3] ** e_q)
        fin = sum(1 << l for l in range(W) if rng.random() < 0.85)
        normal = sum(1 << l for l in range(W) if all(2.2250738585072014e-308 <= v <= 1.7976931348623157e308
                                                     for v in NORM[2:4, l]))
        L_t = rng.choice([0.0, 10.0, 49.9, 50.0 - 1e-14, 1e17], W)
        L_on = rng.choice([0.0, 1.0], W, p=[0.2, 0.8])
        hv, L_last, L_go = np.full(W, -1.0), np.full(W, -1.0), np.full(W, -1.0)
        with np.errstate(all="ignore"):
            bits = lane_parts.steps_lanes(NORM, fin, normal, L_on, L_t, tend, factor, hv, L_last, L_go)
        for l in range(W):
            if L_on[l] == 0.0:
                assert hv[l] == 0.0 and L_go[l] == 0.0 and not bits >> l & 1
                continue
            st, h, last = _lane_h(l, fin, normal, NORM, order, L_t[l], tend)
            vector = bool(fin >> l & 1 and normal >> l & 1) and st == -1
            assert bool(bits >> l & 1) == (not vector)
            if vector:
                assert hv[l] == h and L_last[l] == (1.0 if last else 0.0) and L_go[l] == 1.0
            else:
                assert hv[l] == 0.0 and L_go[l] == 0.0
            seen.add((vector, st))
    assert {(True, -1), (False, -1), (False, STATUS_NONFINITE), (False, STATUS_STEP_UNDERFLOW)} <= seen


def test_vector_step_end_is_the_scalar_one_and_leaves_roots_and_stops_to_the_scalar_loop():
    """The generated step end (_section_lanes, _ends_lanes of every System's lane driver, here of
    phi = phi0 as a . y + b): the section's value and coefficients are the scalar loop's doubles; a lane
    is ended in vector form exactly when the scalar loop would have nothing to do but the bookkeeping
    (its step went on, not the last, a finite new state, no root possible - by the variation bound, or
    a monotone polynomial without a sign change of the direction: isolate_crossings' two tests - and no
    stop by the clock or the step budget), and then its state, sin(phi - phi0), time, compensation and
    step count are the scalar loop's doubles; every other lane whose step went on is in the returned
    bits, untouched."""
    W = L
    rng = np.random.default_rng(11)
    order = 6
    a, b, _keep = lanes.section_arrays(math.cos(2.0), math.sin(2.0))
    tmax, max_steps = 100.0, 1000
    seen = set()
    for _ in range(60):
        X = np.zeros((order + 1, 5, W))
        X[0] = random_states(PARAM_SETS["figure4_mu0.5"], W, seed=int(rng.integers(1 << 30))).T
        X[1:] = rng.normal(size=(order, 5, W)) * rng.choice([0.1, 1.0, 10.0], (order, 1, W))
        X[1:, :, 0] *= 1e-9                       # a lane far from the section: excluded by the bound
        direction = int(rng.choice([-1, 0, 1]))
        hv = rng.uniform(0.01, 0.2, W)
        Y = np.empty((5, W))
        G._evaluate_lanes(X, order, hv, Y)
        Y[rng.integers(0, 5), rng.integers(0, W)] = rng.choice([np.nan, np.inf])
        L_g = rng.normal(size=W) * rng.choice([0.0, 1.0], W, p=[0.1, 0.9])
        GC, Gv = np.empty((order + 1, W)), np.empty(W)
        with np.errstate(all="ignore"):
            finite, maybe = G._section_lanes(X, order, hv, Y, a, b, direction, L_g, GC, Gv)
        L_t = rng.choice([1.0, 99.9, 100.0 - 1e-15], W, p=[0.8, 0.1, 0.1])
        L_tc = rng.normal(scale=1e-17, size=W)
        L_steps = rng.choice([3.0, 998.0, 999.0], W, p=[0.8, 0.1, 0.1])
        L_go = rng.choice([0.0, 1.0], W, p=[0.1, 0.9])
        L_last = rng.choice([0.0, 1.0], W, p=[0.9, 0.1])
        before = [x.copy() for x in (X, L_t, L_tc, L_g, L_steps)]
        with np.errstate(all="ignore"):
            bits = G._ends_lanes(X, Y, Gv, hv, L_go, L_last, finite, maybe, L_t, L_tc, L_steps, L_g, tmax, max_steps)
        for l in range(W):
            y = Y[:, l]
            gc = np.array([G._section_value(a, 0.0, before[0][k, :, l]) for k in range(order + 1)])
            assert np.array_equal(GC[:, l], gc, equal_nan=True)
            assert np.array_equal(Gv[l], G._section_value(a, b, y), equal_nan=True)
            with np.errstate(invalid="ignore"):
                assert bool(finite >> l & 1) == (sum(y, 0.0) - sum(y, 0.0) == 0.0)
            excluded = events.no_root_within(gc, order, hv[l])
            monotone = events.monotone_within(gc, order, hv[l])
            sign = events.sign_change(L_g_before := before[3][l], Gv[l], direction)
            seen.add((excluded, monotone, sign))
            assert bool(maybe >> l & 1) == (not excluded and (not monotone or sign))
            t, tc = clock.compensated_add(before[1][l], before[2][l], hv[l])
            vector = (L_go[l] == 1.0 and L_last[l] == 0.0 and bool(finite >> l & 1) and not maybe >> l & 1
                      and t < tmax and before[4][l] + 1 < max_steps)
            seen.add((vector, bool(maybe >> l & 1)))
            assert bool(bits >> l & 1) == (L_go[l] == 1.0 and not vector)
            if vector:
                assert np.array_equal(X[0, :, l], y) and L_g[l] == Gv[l]
                assert (L_t[l], L_tc[l], L_steps[l]) == (t, tc, before[4][l] + 1)
            else:
                assert np.array_equal(X[:, :, l], before[0][:, :, l])
                assert (L_t[l], L_tc[l], L_g[l], L_steps[l]) == (before[1][l], before[2][l], L_g_before, before[4][l])
    # both ends, and every answer of the three root tests, seen
    assert {(True, False), (False, True), (False, False)} <= seen
    assert {(e, m, c) for e in (False, True) for m in (False, True) for c in (False, True)} <= seen


# ---------------------------------------------------------------- whole batches
def _run(fn, Y0, P, K, *, order=15, tmax=None, max_steps=10**9, phi0=math.pi, direction=1, **kw):
    n = Y0.shape[0]
    g1, g2 = model.section_gamma(phi0)
    out = (np.full((n, K, 5), np.nan), np.zeros(n, np.int64), np.zeros(n, np.int64),
           np.zeros((n, 5)), np.zeros((n, 3)))
    tmax = 100.0 * K if tmax is None else tmax
    Y0 = np.ascontiguousarray(Y0)
    carry = np.empty((n, drivers.N_CARRY))
    drivers.start_carry(Y0, P, g2, g1, carry)
    limits = np.full((n, 2), K, np.int64)
    fn(Y0, P, g2, g1, direction, tmax, order, max_steps, carry, limits, *out, **kw)
    return out


def _assert_identical(a, b):
    for name, x, y in zip(("cross", "count", "status", "final", "info"), a, b):
        assert x.dtype == y.dtype and x.shape == y.shape, name
        np.testing.assert_array_equal(x, y, err_msg=name)   # bitwise (NaN rows too)
        assert np.array_equal(x.view(np.uint8), y.view(np.uint8)), name


def _mixed_states(prm, n, seed):
    """n start states: section states of the Figure-4 kind, random states, a libration about
    phi = 0 that never reaches phi = pi, and an orbit whose coefficients overflow (M = 1e150)."""
    h = 2.0
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1 = c1 + r1 * np.linspace(-0.9, 0.9, max(n, 2))[:n]
    Y = model.section_state(prm, p1, np.full(n, c2), h)
    R = random_states(prm, n, seed=seed)
    Y[1::3] = R[1::3]
    if n >= 3:
        Y[2] = [0.0, 0.0, 0.0, math.sin(0.05), math.cos(0.05)]
    if n >= 5:
        Y[4] = [0.1, -0.2, 1e150, 0.6, 0.8]
    return Y


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
@pytest.mark.parametrize("n", [1, 3, 7, 13, 64])
def test_batch_bitwise_identical(name, n):
    prm = PARAM_SETS[name]
    P = prm.as_array()
    Y0 = _mixed_states(prm, n, seed=n)
    K = 12
    ref = _run(run_taylor_batch, Y0, P, K)
    _assert_identical(ref, _run(lanes.run_taylor_lanes_batch, Y0, P, K))
    if n >= 5:
        assert ref[2][4] == STATUS_NONFINITE
    if n >= 3 and name == "figure4_mu0.5":
        assert ref[2][2] == STATUS_TMAX and ref[1][2] == 0


def test_batch_statuses_and_settings():
    """Budgets (time, steps), both directions, another section angle, another order: every
    stop reason of the W4-like batch."""
    prm = PARAM_SETS["asym_lam_neg"]
    P = prm.as_array()
    Y0 = _mixed_states(prm, 23, seed=3)
    cases = [dict(K=10, max_steps=300), dict(K=40, tmax=25.0), dict(K=6, direction=-1, phi0=1.0),
             dict(K=6, direction=0, order=19), dict(K=5, order=4, tmax=30.0)]
    seen = set()
    for kw in cases:
        kw = dict(kw)
        K = kw.pop("K")
        ref = _run(run_taylor_batch, Y0, P, K, **kw)
        seen.update(ref[2].tolist())
        _assert_identical(ref, _run(lanes.run_taylor_lanes_batch, Y0, P, K, **kw))
    assert {STATUS_DONE, STATUS_TMAX, STATUS_MAX_STEPS, STATUS_NONFINITE} <= seen


def test_batch_degenerate_budgets():
    """Orbits that stop before their first step: K = 0, tmax <= 0, max_steps = 0."""
    prm = PARAM_SETS["figure4_mu0.5"]
    P = prm.as_array()
    Y0 = _mixed_states(prm, 9, seed=1)
    for K, kw in [(0, {}), (3, dict(tmax=0.0)), (3, dict(max_steps=0)), (3, dict(max_steps=1))]:
        ref = _run(run_taylor_batch, Y0, P, K, **kw)
        _assert_identical(ref, _run(lanes.run_taylor_lanes_batch, Y0, P, K, **kw))


def test_threads_do_not_change_results():
    prm = PARAM_SETS["figure4_mu0.5"]
    P = prm.as_array()
    Y0 = _mixed_states(prm, 29, seed=7)
    ref = _run(run_taylor_batch, Y0, P, 25, order=16)
    old = get_num_threads()
    try:
        for threads in (1, 2):
            set_num_threads(threads)
            assert get_num_threads() == threads
            _assert_identical(ref, _run(lanes.run_taylor_lanes_batch, Y0, P, 25, order=16))
    finally:
        set_num_threads(old)


def test_threads_and_orbit_order_do_not_change_a_bit():
    """1 and 2 threads, the orbits permuted: the raw arrays (crossings, counts, statuses, final
    states, time and steps) equal those of one thread bit for bit."""
    prm = PARAM_SETS["figure4_mu0.5"]
    P = prm.as_array()
    Y0 = _mixed_states(prm, 53, seed=9)
    assert_threads_and_order_keep_the_bits(
        lambda order: _run(lanes.run_taylor_lanes_batch, Y0[order], P, 20), len(Y0), seed=4)


def test_a_batch_that_one_group_of_lanes_holds_runs_on_one_worker_and_a_larger_one_on_every_thread():
    """lanes.lane_workers: a group steps all LANES lanes whether they hold an orbit or not, so a
    second worker on a batch one group holds would step a second group for nothing (the same wall
    time, up to twice the CPU); from LANES + 1 orbits on, one worker per thread."""
    old = get_num_threads()
    try:
        set_num_threads(2)
        assert [lanes.lane_workers(n) for n in (0, 1, 2, L, L + 1, 10 * L)] == [1, 1, 1, 1, 2, 2]
        set_num_threads(1)
        assert lanes.lane_workers(10 * L) == 1
    finally:
        set_num_threads(old)


def test_sections_taylor_uses_the_lanes_and_matches_the_scalar_oracle():
    prm = PARAM_SETS["figure4_mu0.5"]
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    p1 = c1 + r1 * np.linspace(-0.95, 0.95, 11)
    res = sections.crossings(prm, 2.0, np.column_stack([p1, np.zeros(11)]), n_crossings=30, method="taylor", tol=1e-12)
    Y0 = model.section_state(prm, p1, np.zeros(11), 2.0)
    ref = _run(run_taylor_batch, Y0, prm.as_array(), 30, order=res.settings["order"])
    _assert_identical(ref, (res.data, res.count, res.status, res.final, res.info))
