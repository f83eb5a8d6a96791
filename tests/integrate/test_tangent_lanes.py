"""Tangent dynamics on SIMD lanes are bit for bit the scalar tangent Taylor driver: the
generated lane kernels lane by lane their scalar twins, whole batches (one and two deviation vectors, early
classification, history rows, orbits stopping for every reason) for several thread counts,
lane widths and orbit orderings; the generated file is up to date."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import PARAM_SETS, random_states

from explorer import model
from explorer._jit import get_num_threads, set_num_threads
from explorer.analysis import lyapunov
from explorer.integrate import _tangent_lanes_generated as G
from explorer.integrate import lanes, tangent, tangent_lanes
from explorer.kernels import STATUS_MAX_STEPS, STATUS_NONFINITE
from explorer.kernels import tangent as tg
from explorer.kernels import taylor as tk

ROOT = Path(__file__).resolve().parents[2]
L = G.LANES


def test_generated_tangent_file_is_up_to_date(tmp_path):
    out = tmp_path / "gen.py"
    tout = tmp_path / "tgen.py"
    subprocess.run([sys.executable, str(ROOT / "tools" / "gen_lanes.py"), "-o", str(out), "--tangent-output",
                    str(tout)], check=True, capture_output=True)
    assert tout.read_text() == (ROOT / "src/explorer/integrate/_tangent_lanes_generated.py").read_text(), \
        "src/explorer/integrate/_tangent_lanes_generated.py is stale: run tools/gen_lanes.py"


@pytest.mark.parametrize("name", sorted(PARAM_SETS))
@pytest.mark.parametrize("order", [4, 15, 20])
def test_tangent_lane_kernels_match_the_scalar_recurrence_bitwise(name, order):
    """Every lane of the generated lane kernels (the orbit and a vector; a second vector alone) is
    their scalar twin, as the scalar driver calls them (tangent.orbit_tangent_taylor_ext)."""
    P = PARAM_SETS[name].as_array()
    rng = np.random.default_rng(order)
    W = L
    Z = np.zeros((order + 1, G.NROWS, W))
    Z[0, :5] = random_states(PARAM_SETS[name], W, seed=order, scale=2.0).T
    Z[0, 5:] = rng.normal(size=(10, W))
    Z[0, :, 0] = 0.0      # an idle lane
    work = np.zeros((order + 1, G.N_WORK_TANGENT, W))
    G.tangent_coefficients_lanes(P, Z, order, work)
    G.deviation_coefficients_lanes(P, Z, order, work)
    h = rng.uniform(0.0, 0.5, W)
    out = np.empty((G.NROWS, W))
    for base in (0, G.DEV1, G.DEV2):
        lanes.evaluate_lanes(Z, order, h, out, base)
    for l in range(W):
        S = np.zeros((G.NROWS, order + 1))
        S[:, 0] = Z[0, :, l]
        G.tangent_coefficients(P, S[:10], order)
        G.deviation_coefficients(P, S, order)
        np.testing.assert_array_equal(S.T, Z[:, :, l])
        for rows in (slice(0, 5), slice(5, 10), slice(10, 15)):
            y = np.empty(5)
            tk.evaluate(S[rows], order, h[l], y)
            np.testing.assert_array_equal(y, out[rows, l])


# ---------------------------------------------------------------- the step end in vector form
@pytest.mark.parametrize("nvec", [1, 2])
def test_vector_step_end_is_the_scalar_one_and_leaves_stops_and_history_rows_to_the_scalar_loop(nvec):
    """end_steps_tangent_lanes: a lane holding an orbit is ended in vector form
    exactly when the scalar loop has only the bookkeeping to do (a step taken in vector form, not
    the last, a finite new state and vectors, no stop by T or the step budget, no history row due),
    and then its state, unit deviation vectors (kernels.tangent.renormalize), accumulators
    (kernels.tangent.accumulate), time and step count are the scalar loop's doubles; every other
    lane that holds an orbit is in the returned bits, untouched."""
    W = L
    rng = np.random.default_rng(21 + nvec)
    T, max_steps = 100.0, 1000
    seen = set()
    for _ in range(40):
        Z = rng.normal(size=(3, G.NROWS, W))
        znew = rng.normal(size=(G.NROWS, W)) * rng.choice([1e-3, 1.0, 1e3], (1, W))
        znew[rng.integers(0, G.NROWS), rng.integers(0, W)] = rng.choice([np.nan, np.inf])
        hv = rng.uniform(0.01, 0.2, W)
        nrm = np.zeros(W)
        acc = rng.normal(size=(tg.N_ACC, W))
        acc[tg.ACC_T] = rng.choice([0.0, 1.0], W)
        L_t = rng.choice([0.0, 5.0, 99.9, 100.0 - 1e-15], W, p=[0.2, 0.6, 0.1, 0.1])
        L_steps = rng.choice([3.0, 998.0, 999.0], W, p=[0.8, 0.1, 0.1])
        L_hnext = rng.choice([np.inf, 5.05, 50.0], W)
        L_on = rng.choice([0.0, 1.0], W, p=[0.1, 0.9])
        L_fast = rng.choice([0.0, 1.0], W, p=[0.1, 0.9]) * L_on    # step_lanes: idle lanes are not fast
        L_last = rng.choice([0.0, 1.0], W, p=[0.9, 0.1])
        before = [a.copy() for a in (Z, acc, L_t, L_steps)]
        bits = 0
        for c in range(0, W, L):
            with np.errstate(all="ignore"):
                bits |= tangent_lanes.end_steps_tangent_lanes(Z, znew, hv, nrm, acc, L_t, L_steps, L_hnext, L_on,
                                                              L_fast, L_last, nvec, T, max_steps, c, W) << c
        for l in range(W):
            tn = before[2][l] + hv[l]
            with np.errstate(all="ignore"):
                finite = (np.isfinite(sum(znew[:10, l].tolist()))
                          and (nvec == 1 or np.isfinite(sum(znew[10:, l].tolist()))))
            vector = (L_fast[l] == 1.0 and L_last[l] == 0.0 and finite and tn < T and before[3][l] + 1 < max_steps
                      and tn < L_hnext[l])
            seen.add(vector)
            if L_on[l] == 1.0:
                assert bool(bits >> l & 1) == (not vector)
            else:
                assert not bits >> l & 1
            if vector:
                v = znew[5:10, l].copy()
                dlog = tg.renormalize(v, 5)
                a = before[1][:, l].copy()
                tg.accumulate(a, before[2][l], tn, dlog)
                w = znew[10:, l].copy()
                if nvec == 2:
                    tg.renormalize(w, 5)
                else:
                    w[:] = 0.0
                assert np.array_equal(Z[0, :, l], np.concatenate([znew[:5, l], v, w]))
                assert np.array_equal(acc[:, l], a) and (L_t[l], L_steps[l]) == (tn, before[3][l] + 1)
            else:
                assert np.array_equal(Z[:, :, l], before[0][:, :, l]) and np.array_equal(acc[:, l], before[1][:, l])
                assert (L_t[l], L_steps[l]) == (before[2][l], before[3][l])
    assert seen == {True, False}



@pytest.mark.parametrize("nvec", [1, 2])
def test_vector_early_classification_stops_the_lanes_the_scalar_rule_stops(nvec):
    """early_lanes on every lane of a group that the vector step end ended (holding an orbit, not
    in the scalar loop's bits): it stops by SALI or by MEGNO exactly the lanes integrate.tangent._early
    stops with that code, and leaves them and the other lanes' ``since`` as the scalar rule does
    (the vectors near-aligned or not, <Y> above and below its level, since before and after t/2,
    t before and after tmin); lanes left to the scalar loop and idle lanes are untouched."""
    rng = np.random.default_rng(40 + nvec)
    sali_stop, level, tmin = 1e-3, 6.0, 10.0
    codes = set()
    for _ in range(60):
        Z = rng.normal(size=(1, G.NROWS, L))
        Z[0, 5:10] /= np.linalg.norm(Z[0, 5:10], axis=0)
        sign = rng.choice([-1.0, 1.0], L)
        near = rng.choice([0.0, 1e-5, 1e-2], L)
        Z[0, 10:] = sign * Z[0, 5:10] + near * rng.normal(size=(5, L))
        Z[0, 10:] /= np.linalg.norm(Z[0, 10:], axis=0)
        acc = rng.normal(size=(tg.N_ACC, L))
        t = rng.choice([0.0, 5.0, 20.0, 40.0], L)
        acc[tg.ACC_T] = t
        acc[tg.ACC_YINT] = t * rng.choice([1.0, 5.9, 6.1, 30.0], L)
        L_since = np.where(rng.random(L) < 0.3, -1.0, t * rng.choice([0.2, 0.5, 0.51, 1.0], L))
        L_on = rng.choice([0.0, 1.0], L, p=[0.1, 0.9])
        bits = int(rng.integers(0, 1 << L)) & int(rng.integers(0, 1 << L))
        since0 = L_since.copy()
        stop_sali, stop_megno = tangent_lanes.early_lanes(Z, acc, L_since, L_on, bits, nvec, sali_stop, level, tmin,
                                                          0, L)
        assert stop_sali & stop_megno == 0
        for l in range(L):
            got = tg.EARLY_SALI if stop_sali >> l & 1 else tg.EARLY_MEGNO if stop_megno >> l & 1 else tg.EARLY_NONE
            if L_on[l] == 0.0 or bits >> l & 1:
                assert got == tg.EARLY_NONE and L_since[l] == since0[l]
                continue
            code, since = tangent._early(acc[:, l], Z[0, 5:10, l].copy(), Z[0, 10:, l].copy(), nvec, sali_stop,
                                         level, tmin, since0[l])
            codes.add(code)
            assert got == code and L_since[l] == since
    assert codes == ({tg.EARLY_NONE, tg.EARLY_MEGNO} | ({tg.EARLY_SALI} if nvec == 2 else set()))


# ---------------------------------------------------------------- whole batches
def _orbits(n, seed=3):
    """Orbits of Figure 4 at mu = 1 (regular and chaotic) and asymmetric sets, with a few that
    stop early: a step budget, a non-finite start."""
    prm = model.FIGURE4.with_(mu=1.0)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    rng = np.random.default_rng(seed)
    rad = np.sqrt(rng.uniform(0, 0.8, n))
    ang = rng.uniform(0, 2 * np.pi, n)
    Y0 = model.section_state(prm, c1 + r1 * rad * np.cos(ang), c2 + r2 * rad * np.sin(ang), 2.0)
    P = prm.as_array()
    V0 = lyapunov.deviation_vector(P, Y0)
    W0 = lyapunov.second_deviation_vector(P, Y0)
    return P, np.ascontiguousarray(Y0), np.ascontiguousarray(V0), np.ascontiguousarray(W0)


def _run(fn, P, Y0, V0, W0, nvec, early, T=60.0, order=16, max_steps=10**9, H=4, **kw):
    n = Y0.shape[0]
    hist_t = np.geomspace(1.0, T, H)
    out = (np.full((n, H, 5), np.nan), np.zeros((n, 5)), np.zeros((n, 3)), np.zeros(n, np.int64),
           np.zeros((n, 5)), np.zeros(n, np.int64), np.full((n, 2, 5), np.nan))
    fn(Y0, V0, W0, nvec, P, T, order, max_steps, early, 1e-8, 6.0, 10.0, hist_t, *out, **kw)
    return out


def _scalar_batch(Y0, V0, W0, nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level, early_tmin, hist_t,
                  out_hist, out_res, out_ext, out_status, out_final, out_steps, out_w):
    """The scalar reference: tangent.orbit_tangent_taylor_ext orbit by orbit, in the layout of
    tangent_lanes.run_tangent_lanes_batch."""
    for j in range(Y0.shape[0]):
        out_status[j], out_steps[j] = tangent.orbit_tangent_taylor_ext(
            Y0[j], V0[j], W0[j], nvec, P, T, order, max_steps, early_stop, sali_stop, megno_level, early_tmin, hist_t,
            out_hist[j], out_res[j], out_ext[j], out_w[j], out_final[j])


def _assert_same(a, b):
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("nvec,early", [(1, False), (2, False), (2, True), (1, True)])
def test_lane_batches_equal_the_scalar_reference_for_any_threads_lanes_and_order(nvec, early):
    P, Y0, V0, W0 = _orbits(37)
    ref = _run(_scalar_batch, P, Y0, V0, W0, nvec, early)
    if early:
        assert np.any(ref[2][:, 2] > 0) and np.any(ref[2][:, 2] == 0)   # both kinds of orbits
    old = get_num_threads()
    try:
        for threads in (1, 2):
            set_num_threads(threads)
            for max_lanes in (1, 3, L):
                _assert_same(_run(tangent_lanes.run_tangent_lanes_batch, P, Y0, V0, W0, nvec, early,
                                  max_lanes=max_lanes), ref)
        perm = np.random.default_rng(0).permutation(len(Y0))
        got = _run(tangent_lanes.run_tangent_lanes_batch, P, Y0[perm], V0[perm], W0[perm], nvec, early)
        _assert_same([g[np.argsort(perm)] for g in got], ref)
    finally:
        set_num_threads(old)


def test_one_vector_lanes_equal_orbit_tangent_taylor():
    """With one deviation vector and no early stop the lanes give what the scalar driver of the
    method registry (tangent.orbit_tangent_taylor) gives, bit for bit."""
    P, Y0, V0, W0 = _orbits(21, seed=5)
    n, H, T = len(Y0), 4, 60.0
    hist_t = np.geomspace(1.0, T, H)
    hist, res, st = np.full((n, H, 5), np.nan), np.zeros((n, 5)), np.zeros(n, np.int64)
    fin, steps = np.zeros((n, 5)), np.zeros(n, np.int64)
    tangent.run_tangent_taylor_batch(Y0, V0, P, T, 16, 10**9, hist_t, hist, res, st, fin, steps)
    got = _run(tangent_lanes.run_tangent_lanes_batch, P, Y0, V0, W0, 1, False)
    _assert_same((hist, res, st, fin, steps), (got[0], got[1], got[3], got[4], got[5]))


def test_orbits_stopping_for_every_reason_are_written_as_the_scalar_driver_writes_them():
    P, Y0, V0, W0 = _orbits(11, seed=7)
    Y0[4, 2] = 1e200          # coefficients overflow: non-finite
    for max_steps in (0, 7, 10**9):
        ref = _run(_scalar_batch, P, Y0, V0, W0, 2, True, max_steps=max_steps)
        got = _run(tangent_lanes.run_tangent_lanes_batch, P, Y0, V0, W0, 2, True, max_steps=max_steps)
        _assert_same(got, ref)
    assert ref[3][4] == STATUS_NONFINITE
    ref = _run(_scalar_batch, P, Y0, V0, W0, 2, False, max_steps=7)
    assert np.all(ref[3][np.arange(11) != 4] == STATUS_MAX_STEPS)
