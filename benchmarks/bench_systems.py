#!/usr/bin/env python
"""Benchmark SYSTEMS: a System's section crossings and chaos map against heyoka on the same equations.

Workload: Hénon–Heiles (lam = 1) as an ``explorer.System``; 64 orbits started on the section
x = 0 at E = 1/8 with py = 0, y across 95 % of the allowed interval and px > 0 from the energy;
2000 crossings of x = 0 with px > 0 (direction +1) each, tol 1e-12.

Rows: ``ex.crossings(system, ...)`` (numba threads = default, and 1 thread; ``driver`` of
explorer.analysis.system_sections: the automatic choice, the SIMD lanes and the scalar
integrator) and heyoka ``taylor_adaptive_batch`` (batch = recommended SIMD width, the equations
converted from the same SymPy expressions with ``heyoka.from_sympy``, the section a terminal
``t_event_batch`` on x, direction positive, whose callback records each crossing; bench_w4's
harness: :class:`bench_w4.HeyokaSections`' queue of orbits over the batch lanes) in 1 and 2
processes.  Agreement: max |explorer - heyoka| over the crossing rows (t and the state) of the
first 100 crossings of the regular orbits (those where explorer at tol 1e-12 and at tol 1e-15
agree to 1e-9 over those crossings).  First use: a fresh process with an empty
``EXPLORER_SYSTEMS_CACHE`` (generation and compilation), then a second fresh process (rerun).

Chaos map: 400 points of the section x = 0 at E = 1/8 (a 20 x 20 grid in (y, py) inside the energy
curve, lifted to states by ``ex.SectionMap(...).states``), MEGNO and mLCE to T = 1000, tol 1e-12,
one deviation vector (:func:`explorer.analysis.system_indicators.default_vectors`).  Rows:
``system_indicators`` (what ``ex.indicators(system, ...)`` calls; the SIMD lanes and the scalar
driver) and heyoka ``taylor_adaptive_batch`` on the System's variational equations
(``System.variational(1)``: the state and one deviation vector, its SymPy expressions through
``heyoka.from_sympy``; heyoka's tutorial "The variational equations" forms them the same way,
``var_ode_sys`` would carry the whole n x n matrix), the vector renormalised every time unit and
MEGNO accumulated over those units with the engine's formulas (bench_chaos's harness), 1 and 2
processes.  Agreement: the class (<Y> > 4) per orbit, and |<Y>| and mLCE of the regular orbits.

    python benchmarks/bench_systems.py            # full run (~4 min on 2 cores)
    python benchmarks/bench_systems.py --quick    # smoke test (16 orbits x 200 crossings; chaos map 64 orbits, T = 100)
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time

import _common as C
import numpy as np
from _common import Recorder, heyoka_lanes, round_robin, runs_note, spawned

E_LEVEL = 1.0 / 8.0
TOL = 1e-12
TMAX_PER_CROSSING = 100.0       # the default time budget of ex.crossings (100 * K)
START_EPS = 1e-9                # an event this close to t = 0 is the start point on the section
AGREE_K = 100                   # crossings compared with heyoka
REGULAR = 1e-9                  # explorer tol 1e-12 vs 1e-15 within this over AGREE_K crossings: regular

HH_SOURCE = """
import sympy as sp
import explorer as ex
x, y, px, py, lam = sp.symbols("x y px py lam")
hh = ex.System({x: px, y: py, px: -x - 2*lam*x*y, py: -y - lam*(x**2 - y**2)}, parameters={lam: 1.0},
               energy=(px**2 + py**2)/2 + (x**2 + y**2)/2 + lam*(x**2*y - y**3/3), name="henon_heiles")
"""


def henon_heiles():
    ns = {}
    exec(HH_SOURCE, ns)
    return ns["hh"], ns["x"]


def starts(n):
    """(n, 4) states on x = 0 at E = 1/8, py = 0, px > 0, y across 95 % of the allowed interval."""
    roots = np.roots([-1.0 / 3.0, 0.5, 0.0, -E_LEVEL])        # y^2/2 - y^3/3 = E on x = 0, py = 0
    real = np.sort(roots[np.abs(roots.imag) < 1e-12].real)
    lo, hi = real[0], real[1]                                   # the bounded interval around y = 0
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    yy = mid + 0.95 * half * np.linspace(-1.0, 1.0, n)
    px = np.sqrt(2 * E_LEVEL - yy**2 + 2 * yy**3 / 3)
    return np.column_stack([np.zeros(n), yy, px, np.zeros(n)])


# ----------------------------------------------------------------------------- heyoka
class HeyokaSystemSections:
    """Crossings of a System's section with heyoka's batch mode: bench_w4's harness
    (:func:`_common.heyoka_lanes`: a queue of orbits over the lanes of one ``taylor_adaptive_batch``,
    a terminal event whose callback records the crossing and stops the lane after K), for the
    System's equations (``heyoka.from_sympy``) and its section EXPR = 0 in ``direction``."""

    def __init__(self, tol, simd):
        import heyoka as hy
        import sympy as sp
        t0 = time.perf_counter()
        system, xs = henon_heiles()
        self.simd = int(simd)
        vals = dict(system.parameters)
        hv = {s: hy.make_vars(s.name) for s in system.states}
        smap = {s: hv[s] for s in system.states}
        eqs = [(hv[s], hy.from_sympy(sp.sympify(f).subs(vals), smap)) for s, f in zip(system.states, system.rhs)]
        ev_expr = hy.from_sympy(xs, smap)
        self.dim = system.dimension
        rec = self.rec = Recorder(self.dim)

        def cb(ta, d_sgn, i):
            o = rec.lane[i]
            if o < 0:
                return True
            t = ta.time[i]
            if t < START_EPS:
                return True
            return rec.record(o, t, ta.state[:, i])

        ev = hy.t_event_batch(ev_expr, callback=cb, direction=hy.event_direction.positive)
        self.ta = hy.taylor_adaptive_batch(eqs, np.zeros((self.dim, self.simd)), t_events=[ev], tol=float(tol))
        self.order = int(self.ta.order)
        self.build_time = time.perf_counter() - t0

    def run(self, Y0, K, tmax):
        N = Y0.shape[0]
        self.rec.reset(N, K)
        steps = np.zeros(N, np.int64)
        t0 = time.perf_counter()
        heyoka_lanes(self.ta, self.rec, Y0, tmax, np.zeros(N, np.int64), steps)
        return dict(ts=self.rec.ts, ys=self.rec.ys, count=self.rec.count, steps=steps,
                    elapsed=time.perf_counter() - t0)


def _hy_worker(Y0, K, tol, simd, tmax, barrier, queue, tag):
    runner = HeyokaSystemSections(tol, simd)
    barrier.wait()
    start, c0 = time.monotonic(), time.process_time()
    out = runner.run(Y0, K, tmax)
    end, cpu = time.monotonic(), time.process_time() - c0
    queue.put(dict(tag=tag, ts=out["ts"], ys=out["ys"], count=out["count"], steps=out["steps"], start=start,
                   end=end, cpu=cpu, build=runner.build_time, order=runner.order))


def heyoka_processes(Y0, K, tol, simd, nproc, tmax):
    """Y0 over nproc spawned processes (orbit j to process j % nproc); wall = integration only
    (latest end - earliest start after a barrier), as bench_w4.heyoka_processes."""
    parts = [np.arange(r, Y0.shape[0], nproc) for r in range(nproc)]
    outs, wall, total = spawned(_hy_worker, [(Y0[idx], K, tol, simd, tmax) for idx in parts])
    N, dim = Y0.shape
    merged = dict(ts=np.full((N, K), np.nan), ys=np.full((N, K, dim), np.nan), count=np.zeros(N, np.int64),
                  steps=np.zeros(N, np.int64))
    for o in outs:
        for key in ("ts", "ys", "count", "steps"):
            merged[key][parts[o["tag"]]] = o[key]
    merged.update(wall=wall, total=total, build=max(o["build"] for o in outs), order=outs[0]["order"],
                  cpu=sum(o["cpu"] for o in outs))
    return merged


# ----------------------------------------------------------------------------- chaos map
CHAOS_T = 1000.0
CHAOS_SIDE = 20                 # 20 x 20 section points
CHAOS_THRESHOLD = 4.0           # <Y> > 4: chaotic (bench_chaos, the scene default)
CHAOS_REGULAR = 2.5             # <Y> below this for both codes: a regular orbit whose values are compared
ODE_T0 = 1e-6                   # heyoka's MEGNO as an ODE starts here (M' = 2 W / t)


def chaos_seeds(hh, side):
    """side x side section points (y, py) inside the energy curve of x = 0 at E = 1/8 (y at equal steps
    across the allowed interval, py at equal steps across 98 % of the allowed range at that y), lifted
    to states (px > 0) by the System's SectionMap."""
    import explorer as ex
    xs, y, px, py = hh.states
    roots = np.roots([-1.0 / 3.0, 0.5, 0.0, -E_LEVEL])
    lo, hi = np.sort(roots[np.abs(roots.imag) < 1e-12].real)[:2]
    yy = lo + (hi - lo) * (np.arange(side) + 0.5) / side
    top = np.sqrt(2 * E_LEVEL - yy**2 + 2 * yy**3 / 3)
    u = 0.98 * (2 * (np.arange(side) + 0.5) / side - 1)
    pts = np.array([(a, b * u_) for a, b in zip(yy, top) for u_ in u])
    smap = ex.SectionMap(hh, E_LEVEL, section=xs, direction=+1, coords=(y, py), solve=px)
    return np.ascontiguousarray(smap.states(pts))


def _hy_chaos_system(hh, ode):
    """heyoka equations of the System's variational system (state, one deviation vector d); with ``ode``
    two more: W' = t (d . d')/(d . d) and M' = 2 W / t, so that MEGNO <Y>(T) = M(T)/T needs no
    renormalisation (Cincotta & Simó 2000: W = int s d ln|d|, Y = 2 W / t)."""
    import heyoka as hy
    import sympy as sp
    var = hh.variational(1)
    hv = {s: hy.make_vars(s.name) for s in var.states}
    vals = dict(var.parameters)
    rhs = [hy.from_sympy(sp.sympify(f).subs(vals), hv) for f in var.rhs]
    eqs = [(hv[s], f) for s, f in zip(var.states, rhs)]
    if ode:
        n = hh.dimension
        d = [hv[s] for s in var.states[n:]]
        W, M = hy.make_vars("W_megno", "M_megno")
        eqs += [(W, hy.time * hy.sum([a * b for a, b in zip(d, rhs[n:])]) / hy.sum([a * a for a in d])),
                (M, 2.0 * W / hy.time)]
    return eqs


def _hy_chaos_worker(Y0, v0, T, tol, simd, ode, barrier, queue, tag):
    import heyoka as hy
    from bench_chaos import _hy_accumulate
    t0 = time.perf_counter()
    hh, _ = henon_heiles()
    n = hh.dimension
    dim = 2 * n + (2 if ode else 0)
    ta = hy.taylor_adaptive_batch(_hy_chaos_system(hh, ode), np.zeros((dim, simd)), tol=float(tol))
    build = time.perf_counter() - t0
    N = Y0.shape[0]
    megno, mlce = np.full(N, np.nan), np.full(N, np.nan)
    barrier.wait()
    start, c0 = time.monotonic(), time.process_time()
    for a in range(0, N, simd):
        b = min(a + simd, N)
        st = ta.state
        st[:n, :] = Y0[a][:, None]                  # a short last batch padded with its first orbit
        st[:n, :b - a] = Y0[a:b].T
        st[n:2 * n, :] = v0[:, None]
        if ode:
            st[2 * n:, :] = 0.0
            ta.set_time(np.full(simd, ODE_T0))      # M' = 2 W / t: started just after t = 0 (W = O(t^2))
            ta.propagate_until(float(T))
            st = ta.state
            megno[a:b] = (st[2 * n + 1] / T)[:b - a]
            mlce[a:b] = (np.log(np.sqrt(np.sum(st[n:2 * n] ** 2, axis=0))) / T)[:b - a]
            continue
        ta.set_time(np.zeros(simd))
        acc = np.zeros((6, simd))
        for k in range(1, int(round(T)) + 1):
            ta.propagate_until(float(k))
            st = ta.state
            norm = np.sqrt(np.sum(st[n:] ** 2, axis=0))
            st[n:] /= norm
            _hy_accumulate(acc, float(k - 1), float(k), np.log(norm))
        megno[a:b] = (acc[2] / acc[5])[:b - a]
        mlce[a:b] = (acc[0] / acc[5])[:b - a]
    end, cpu = time.monotonic(), time.process_time() - c0
    queue.put(dict(tag=tag, megno=megno, mlce=mlce, start=start, end=end, cpu=cpu, build=build, order=int(ta.order)))


def heyoka_chaos(Y0, v0, T, tol, simd, nproc, ode):
    """The chaos map's MEGNO and mLCE with heyoka over nproc spawned processes (orbit j to process
    j % nproc); wall = integration only, after a barrier."""
    parts = [np.arange(r, Y0.shape[0], nproc) for r in range(nproc)]
    outs, wall, total = spawned(_hy_chaos_worker, [(Y0[idx], v0, T, tol, simd, ode) for idx in parts])
    megno, mlce = np.full(Y0.shape[0], np.nan), np.full(Y0.shape[0], np.nan)
    for o in outs:
        megno[parts[o["tag"]]] = o["megno"]
        mlce[parts[o["tag"]]] = o["mlce"]
    return dict(megno=megno, mlce=mlce, wall=wall, total=total, cpu=sum(o["cpu"] for o in outs),
                build=max(o["build"] for o in outs), order=outs[0]["order"])


def chaos_map(hh, quick, repeats, budget, threads, simd):
    """The chaos map's rows (explorer's drivers on ``threads`` and 1 thread, heyoka in 1 and 2
    processes, interleaved runs) and the agreement of the two codes."""
    from explorer.analysis import system_indicators as si
    T = 100.0 if quick else CHAOS_T
    Y0 = chaos_seeds(hh, 8 if quick else CHAOS_SIDE)
    v0, _ = si.default_vectors(hh.dimension)
    kw = dict(tmax=T, method=None, tol=TOL, history=0, v0=v0, w0=None, max_steps=10**9, which=("megno", "mlce"),
              early_stop=False, early_sali=0.0, early_megno=4.0, early_time=0.0)
    ex_rows = [("auto", threads), ("scalar", threads), ("auto", 1), ("scalar", 1)]

    def explorer_job(driver, th):
        def job():
            t0, c0 = time.perf_counter(), time.process_time()
            r = si.system_indicators(hh, states=Y0, threads=th, driver=driver, **kw)
            sec = time.perf_counter() - t0
            return sec, sec, (r, time.process_time() - c0)
        return job

    jobs = [explorer_job(d, th) for d, th in ex_rows]
    for d in ("auto", "scalar"):
        si.system_indicators(hh, states=Y0[:16], threads=threads, driver=d, **dict(kw, tmax=1.0))  # compile / load

    hy_rows = [(1, False), (2, False), (1, True), (2, True)]

    def heyoka_job(nproc, ode):
        def job():
            r = heyoka_chaos(Y0, v0, T, TOL, simd, nproc, ode)
            return r["wall"], r["total"], r
        return job

    jobs += [heyoka_job(*c) for c in hy_rows]
    print(f"SYSTEMS chaos map: {len(Y0)} orbits, T = {T:g}, {len(jobs)} rows", flush=True)
    timings = round_robin(jobs, repeats, budget)
    rows = []
    for (driver, th), tm in zip(ex_rows, timings):
        r, cpu = tm["res"]
        rows.append(dict(name=f"explorer ex.indicators, driver {driver}", setting=f"tol {TOL:.0e}, order "
                         f"{r['settings']['order']}, {th} thread{'s' if th > 1 else ''}", wall=tm["best"],
                         times=tm["times"], cpu=cpu, megno=r["values"]["megno"], mlce=r["values"]["mlce"],
                         steps=int(r["steps"].sum()), driver=driver, threads=th))
    for (nproc, ode), tm in zip(hy_rows, timings[len(ex_rows):]):
        r = tm["res"]
        how = "MEGNO as 2 more ODEs, one propagate_until" if ode else "renormalised every time unit"
        rows.append(dict(name=f"heyoka taylor_adaptive_batch (batch {simd}), {how}", setting=f"tol {TOL:.0e}, "
                         f"order {r['order']}, {nproc} process{'es' if nproc > 1 else ''}", wall=tm["best"],
                         times=tm["times"], cpu=r["cpu"], megno=r["megno"], mlce=r["mlce"], processes=nproc, ode=ode,
                         build=r["build"], total=r["total"]))
    ex_ref = next(r for r in rows if r.get("driver") == "auto" and r["threads"] == threads)
    hy2 = next(r for r in rows if r.get("processes") == 2 and not r["ode"])
    me, mh = ex_ref["megno"], hy2["megno"]
    reg = (me < CHAOS_REGULAR) & (mh < CHAOS_REGULAR)
    agree = dict(n=len(Y0), T=T, fraction_explorer=float(np.mean(me > CHAOS_THRESHOLD)),
                 fraction_heyoka=float(np.mean(mh > CHAOS_THRESHOLD)),
                 same_class=float(np.mean((me > CHAOS_THRESHOLD) == (mh > CHAOS_THRESHOLD))), n_regular=int(reg.sum()),
                 megno_regular=float(np.max(np.abs(me - mh)[reg])) if reg.any() else float("nan"),
                 mlce_regular=float(np.max(np.abs(ex_ref["mlce"] - hy2["mlce"])[reg])) if reg.any() else float("nan"),
                 same_class_ode=float(np.mean((me > CHAOS_THRESHOLD) == (next(
                     r for r in rows if r.get("processes") == 2 and r["ode"])["megno"] > CHAOS_THRESHOLD))),
                 drivers_identical=bool(all(np.array_equal(r["megno"], ex_ref["megno"]) for r in rows if "driver" in r)),
                 steps_per_orbit=ex_ref["steps"] / len(Y0))
    return rows, agree


def chaos_lines(rows, agree, threads):
    exr = {(r["driver"], r["threads"]): r for r in rows if "driver" in r}
    hyb = {p: min((r for r in rows if r.get("processes") == p), key=lambda r: r["wall"]) for p in (1, 2)}
    auto, auto1 = exr[("auto", threads)], exr[("auto", 1)]
    out = ["", f"### Chaos map: {agree['n']} orbits of the section x = 0 at E = 1/8, MEGNO and mLCE to "
           f"T = {agree['T']:g}", "",
           "| row | setting | wall (s) | CPU (s) | orbits/s | chaotic fraction (<Y> > 4) | runs |",
           "|---|---|---:|---:|---:|---:|---|"]
    for r in rows:
        out.append(f"| {r['name']} | {r['setting']} | {r['wall']:.3f} | {r['cpu']:.3f} | {agree['n'] / r['wall']:,.0f} | "
                   f"{np.mean(r['megno'] > CHAOS_THRESHOLD):.4f} | {runs_note(r['times'])}"
                   + (f"; heyoka build {r['build']:.1f} s, process total {r['total']:.1f} s" if "build" in r else "")
                   + " |")
    out += ["", f"- Speed-up (wall-time ratios, against the faster of heyoka's two forms: {hyb[2]['name']} in 2 "
            f"processes): explorer `ex.indicators` ({threads} threads, the SIMD lanes) against "
            f"heyoka batch in 2 processes **{hyb[2]['wall'] / auto['wall']:.2f}x** (goal >= 3x), in 1 process "
            f"{hyb[1]['wall'] / auto['wall']:.2f}x; explorer on 1 thread against heyoka in 1 process "
            f"{hyb[1]['wall'] / auto1['wall']:.2f}x; the SIMD lanes against the scalar driver "
            f"{exr[('scalar', threads)]['wall'] / auto['wall']:.2f}x ({threads} threads), "
            f"{exr[('scalar', 1)]['wall'] / auto1['wall']:.2f}x (1 thread).",
            f"- CPU time: heyoka 2 processes / explorer {threads} threads **{hyb[2]['cpu'] / auto['cpu']:.2f}**, heyoka "
            f"1 process / explorer 1 thread {hyb[1]['cpu'] / auto1['cpu']:.2f}.",
            f"- Agreement: the same class (<Y> > 4) for {agree['same_class']:.4f} of the orbits against heyoka "
            f"renormalised every time unit ({agree['same_class_ode']:.4f} against heyoka's MEGNO ODEs; chaotic fractions "
            f"{agree['fraction_explorer']:.4f} explorer, {agree['fraction_heyoka']:.4f} heyoka); on the "
            f"{agree['n_regular']} orbits regular for both (<Y> < {CHAOS_REGULAR:g}) max |difference| of <Y> "
            f"{C.fmt_e(agree['megno_regular'])} and of the mLCE {C.fmt_e(agree['mlce_regular'])} (explorer "
            "renormalises and accumulates after every step, about "
            f"{agree['steps_per_orbit'] / agree['T']:.1f} a time unit; heyoka here once a time unit: "
            "two quadratures of the same integrals); the drivers and thread counts of explorer give identical "
            f"values: {'yes' if agree['drivers_identical'] else 'NO'}."]
    return out


# ----------------------------------------------------------------------------- first use
FIRST_USE = HH_SOURCE + r"""
import json, time, numpy as np
t1 = time.perf_counter()
Y0 = np.array(STARTS)
r = ex.crossings(hh, states=Y0, n_crossings=5, section=x, direction=+1, tol=TOL)
assert (r.count == 5).all()
print(json.dumps({"define": t1 - T0, "first_crossings": time.perf_counter() - t1,
                  "in_process": time.perf_counter() - T0}))
"""


def first_use(n_orbits, repeats):
    """Process wall time to the first crossings (n_orbits x 5) of Hénon–Heiles: with an empty
    EXPLORER_SYSTEMS_CACHE (generation and compilation), then reruns with it filled."""
    script = "import time\nT0 = time.perf_counter()\n" + FIRST_USE.replace("STARTS", repr(starts(n_orbits).tolist()))
    script = script.replace("TOL", repr(TOL))
    tmp = tempfile.mkdtemp(prefix="bench_systems_cache_")
    env = dict(os.environ, EXPLORER_SYSTEMS_CACHE=tmp)
    out = {}
    try:
        for name, runs in (("first", 1), ("rerun", repeats)):
            walls, cpus, inner = [], [], []
            for _ in range(runs):
                T0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
                p = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                                   timeout=1800, cwd=C.ROOT)
                walls.append(time.perf_counter() - T0)
                r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpus.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
                if p.returncode != 0:
                    raise RuntimeError(f"{name} subprocess failed:\n{p.stderr}")
                inner.append(json.loads(p.stdout.strip().splitlines()[-1]))
            b = int(np.argmin(walls))
            out[name] = dict(process=walls[b], cpu=cpus[b], runs=walls, **inner[b])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return out


# ----------------------------------------------------------------------------- main
def regular_orbits(ex, hh, x, Y0, k):
    a = ex.crossings(hh, states=Y0, n_crossings=k, section=x, direction=+1, tol=TOL).data[..., :5]
    b = ex.crossings(hh, states=Y0, n_crossings=k, section=x, direction=+1, tol=1e-15).data[..., :5]
    return np.max(np.abs(a - b), axis=(1, 2)) <= REGULAR


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="16 orbits x 200 crossings, 1 run; RESULTS.md untouched")
    ap.add_argument("--repeats", type=int, default=None, help="max timing runs per row (default 5)")
    ap.add_argument("--row-budget", type=float, default=None, help="cumulative seconds per row (default 30)")
    ap.add_argument("--skip-first-use", action="store_true", help="no first-use / rerun subprocesses")
    ap.add_argument("--skip-chaos", action="store_true", help="no chaos map")
    ap.add_argument("--no-write", action="store_true", help="print only")
    ap.add_argument("--note", default=None, help="a line about the run's conditions for the RESULTS.md section")
    args = ap.parse_args(argv)
    quick = args.quick
    N, K = (16, 200) if quick else (64, 2000)
    repeats = args.repeats or (1 if quick else 5)
    budget = args.row_budget if args.row_budget is not None else (5.0 if quick else 30.0)
    import heyoka
    import numba

    import explorer as ex
    from explorer.analysis import system_sections as ss

    started, load0, T_START = C.now(), C.loadavg(), time.perf_counter()
    hh, x = henon_heiles()
    Y0 = starts(N)
    tmax = TMAX_PER_CROSSING * K
    simd = int(heyoka.recommended_simd_size())
    threads = numba.get_num_threads()
    drivers = [d for d in ("auto", "lanes", "scalar") if d == "auto" or d in getattr(ss, "DRIVERS", ())]
    ex_rows = [(d, threads) for d in drivers] + [(d, 1) for d in drivers]

    def explorer_job(driver, th):
        kw = {} if driver == "auto" else {"driver": driver}

        def job():
            t0, c0 = time.perf_counter(), time.process_time()
            r = ss.system_crossings(hh, Y0, n_crossings=K, section=x, direction=+1, tol=TOL, threads=th, **kw)
            sec = time.perf_counter() - t0
            return sec, sec, (r, time.process_time() - c0)
        return job

    jobs = [explorer_job(d, th) for d, th in ex_rows]
    for j in jobs[:len(drivers)]:
        j()                                                    # compile / load the cache
    hy_cfgs = [(1,), (2,)]

    def heyoka_job(nproc):
        def job():
            r = heyoka_processes(Y0, K, TOL, simd, nproc, tmax)
            return r["wall"], r["total"], r
        return job

    jobs += [heyoka_job(*c) for c in hy_cfgs]
    print(f"SYSTEMS: {N} orbits x {K} crossings, {len(jobs)} rows, up to {repeats} interleaved rounds", flush=True)
    timings = round_robin(jobs, repeats, budget)
    rows = []
    for (driver, th), tm in zip(ex_rows, timings):
        (data, count, status, final, info, _, settings), cpu = tm["res"]
        rows.append(dict(name=f"explorer ex.crossings, driver {driver}", setting=f"tol {TOL:.0e}, order "
                         f"{settings['order']}, {th} thread{'s' if th > 1 else ''}", wall=tm["best"],
                         times=tm["times"], cpu=cpu, crossings=int(count.sum()), steps=int(info[:, 1].sum()),
                         max_dE=float(np.nanmax(np.abs(data[..., 5]))), threads=th, driver=driver,
                         rows=data if (driver == "auto" and th == threads) else None))
    for (nproc,), tm in zip(hy_cfgs, timings[len(ex_rows):]):
        r = tm["res"]
        E0 = hh_energy(Y0)
        dE = hh_energy(r["ys"]) - E0[:, None]
        rows.append(dict(name=f"heyoka taylor_adaptive_batch (batch {simd})",
                         setting=f"tol {TOL:.0e}, order {r['order']}, {nproc} process{'es' if nproc > 1 else ''}",
                         wall=tm["best"], times=tm["times"], cpu=r["cpu"], crossings=int(r["count"].sum()),
                         steps=int(r["steps"].sum()), max_dE=float(np.nanmax(np.abs(dE))), processes=nproc,
                         build=r["build"], total=r["total"], rows=np.concatenate([r["ts"][..., None], r["ys"]], axis=2)))

    # agreement on the regular orbits
    ref = next(r for r in rows if r["name"].startswith("explorer") and r["rows"] is not None)["rows"]
    hy2 = next(r for r in rows if r.get("processes") == 2)["rows"]
    k = min(AGREE_K, K)
    reg = regular_orbits(ex, hh, x, Y0, k)
    diff = np.abs(ref[:, :k, :5] - hy2[:, :k, :5])
    agree_reg = float(np.max(diff[reg])) if reg.any() else float("nan")
    agree_all_first = float(np.max(diff[:, :10]))

    chaos = None if args.skip_chaos else chaos_map(hh, quick, repeats, budget, threads, simd)
    startup = None if args.skip_first_use else first_use(N, 1 if quick else 3)
    exr = {(r["driver"], r["threads"]): r for r in rows if r["name"].startswith("explorer")}
    hyb = {r["processes"]: r for r in rows if r.get("processes")}
    elapsed = time.perf_counter() - T_START
    command = C.command_line("bench_systems.py", argv)
    lines, meta = C.header("SYSTEMS: Hénon–Heiles sections and chaos map against heyoka", command, started, elapsed, load0,
                           extra=[f"Workload: Hénon–Heiles (lam = 1) as an explorer.System, {N} orbits on x = 0 at "
                                  f"E = 1/8 (py = 0, y across 95 % of the allowed interval, px > 0), {K} crossings "
                                  f"of x = 0 with px > 0 each, tol {TOL:.0e} for both.",
                                  "explorer: `explorer.analysis.system_sections.system_crossings` (what "
                                  "`ex.crossings(system, ...)` calls) with each driver; warm (module and numba "
                                  "cache loaded); best of up to "
                                  f"{repeats} interleaved runs within {budget:.0f} s a row.",
                                  f"heyoka {heyoka.__version__}: `taylor_adaptive_batch`, batch "
                                  f"{simd} (`recommended_simd_size()`), the equations from the System's SymPy "
                                  "expressions (`heyoka.from_sympy`), the section a terminal `t_event_batch` on x "
                                  "(direction positive) whose Python callback records the crossing (bench_w4's "
                                  "harness); wall = integration only, after a barrier; 2 processes: "
                                  "`multiprocessing` 'spawn', orbits interleaved."] + ([args.note] if args.note else []))
    lines += ["", "| row | setting | wall (s) | CPU (s) | crossings/s | steps/crossing | max abs E - E0 | runs |",
              "|---|---|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['name']} | {r['setting']} | {r['wall']:.3f} | {r['cpu']:.3f} | {r['crossings'] / r['wall']:,.0f} | "
                     f"{r['steps'] / max(1, r['crossings']):.1f} | {C.fmt_e(r['max_dE'])} | {runs_note(r['times'])}"
                     + (f"; heyoka build {r['build']:.1f} s, process total {r['total']:.1f} s" if "build" in r else "")
                     + " |")
    auto, auto1 = exr[("auto", threads)], exr[("auto", 1)]
    lines += ["", f"- Speed-up (wall-time ratios): explorer `ex.crossings` ({threads} threads) against heyoka batch in "
              f"2 processes **{hyb[2]['wall'] / auto['wall']:.2f}x**, in 1 process {hyb[1]['wall'] / auto['wall']:.2f}x; "
              f"explorer on 1 thread against heyoka in 1 process {hyb[1]['wall'] / auto1['wall']:.2f}x"
              + (f"; the SIMD lanes against the scalar driver {exr[('scalar', threads)]['wall'] / exr[('lanes', threads)]['wall']:.2f}x "
                 f"({threads} threads), {exr[('scalar', 1)]['wall'] / exr[('lanes', 1)]['wall']:.2f}x (1 thread)"
                 if ("lanes", 1) in exr else "") + ".",
              f"- CPU time (all threads or processes of the best run; less sensitive to other jobs on the machine): "
              f"heyoka 2 processes / explorer {threads} threads **{hyb[2]['cpu'] / auto['cpu']:.2f}**, heyoka 1 process / "
              f"explorer 1 thread {hyb[1]['cpu'] / auto1['cpu']:.2f}.",
              f"- Agreement with heyoka (2 processes): max |difference| of (t, x, y, px, py) over the first {k} "
              f"crossings of the {int(reg.sum())} regular orbits (explorer tol 1e-12 and 1e-15 within "
              f"{REGULAR:g}): {C.fmt_e(agree_reg)}; over the first 10 crossings of all {N} orbits: "
              f"{C.fmt_e(agree_all_first)}."]
    if startup:
        f, rr = startup["first"], startup["rerun"]
        lines += [f"- First use (a fresh process, empty EXPLORER_SYSTEMS_CACHE: the module generated and compiled), "
                  f"to the first crossings of {N} orbits: **{f['process']:.1f} s** of process wall, {f['cpu']:.1f} "
                  f"CPU-s (define the System {f['define']:.1f} s from the start, first crossings "
                  f"{f['first_crossings']:.1f} s); rerun (a fresh process, the cache filled): **{rr['process']:.1f} s**, "
                  f"{rr['cpu']:.1f} CPU-s (best of {len(rr['runs'])}: {', '.join(f'{v:.1f}' for v in rr['runs'])}; "
                  f"first crossings {rr['first_crossings']:.2f} s)."]
    if chaos:
        lines += chaos_lines(*chaos, threads)
    record = not (quick or args.no_write)
    if not args.no_write:
        C.write_json(C.OUT_DIR / ("systems_quick.json" if quick else "systems.json"),
                     dict(meta, rows=[{k2: v for k2, v in r.items() if k2 != "rows"} for r in rows], startup=startup,
                          agreement=dict(regular=agree_reg, n_regular=int(reg.sum()), first10=agree_all_first),
                          chaos=None if not chaos else dict(
                              rows=[{k2: v for k2, v in r.items() if k2 not in ("megno", "mlce")} for r in chaos[0]],
                              agreement=chaos[1])))
    return C.report("SYSTEMS", lines, record)


def hh_energy(y):
    x, yy, px, py = (y[..., i] for i in range(4))
    return (px**2 + py**2) / 2 + (x**2 + yy**2) / 2 + (x**2 * yy - yy**3 / 3)


if __name__ == "__main__":
    sys.exit(main())
