#!/usr/bin/env python
"""Roofline of the Taylor lanes (issue 24): this machine's peak floating-point throughput, the
work of a Taylor step as the generator counts it, and the fraction of that peak W4, the chaos map
and one orbit reach.

1. Peak: numba kernels that run C independent chains x = x * m + c on vectors of 4 doubles
   (256 bit) or 8 doubles (512 bit; two 256-bit halves on an AVX2 machine), C = 1 (one
   dependent chain: the latency) up to 16 (enough to fill every pipe), once as a fused
   multiply-add (llvm.fma) and once as a multiply then an add (what the lanes do: the
   recurrence's order of operations is fixed for bit-identity, so no contraction).  The chains
   are explicit vector values (as in explorer.integrate.simd): without fast-math LLVM may not
   reassociate a reduction, so its loop vectoriser cannot keep independent accumulators in
   registers by itself.  Each kernel's loop is checked in its assembly (numba's inspect_asm):
   the count of vfmadd / vmulpd / vaddpd per iteration, the register width, and whether
   accumulators spill to the stack.
2. Work per Taylor step (``tools/gen_lanes.operation_counts``: the generated recurrence run with
   counting stand-ins), plus the Horner sums and the section values and variation bound of a step.
3. Achieved: the recurrence alone (a loop over one lane array), W4 (64 x 2000 crossings, tol
   1e-12, order 15, 1 and 2 threads), the 400-orbit chaos map (mu = 1, T = 1000, MEGNO) and one
   orbit (30,000 crossings): measured steps, steps per crossing, flops / s and the fraction of
   the measured peak (per core used).  3b: each vector stage of a step alone as the generated lane
   drivers call it (recurrence, step size, Horner, the section's variation bound; libm's log of the
   tangent step end) per orbit-step, so that what a workload's step spends outside the recurrence
   is split into its parts (issue 34).
4. The recurrence alone: CPU per orbit-step and its Cauchy-product loop's multiplies, adds and
   stack accesses (a fresh compile of the kernel, read with inspect_asm).
5. Steps per crossing of explorer and of heyoka's taylor_adaptive on the same W4 orbits to the
   same time (20 crossings, before the chaotic paths part, and 500), if heyoka is installed.

    python benchmarks/bench_roofline.py            # prints the tables (~1-2 min warm)
    python benchmarks/bench_roofline.py --quick    # shorter workloads
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tools"))
import _common as C  # noqa: E402
import gen_lanes  # noqa: E402

CHAINS = (1, 4, 8, 12, 16)
WIDTHS = (4, 8)


def timed(fn, repeats):
    """(best wall seconds, best CPU seconds of this thread) over ``repeats`` calls.  On a machine
    shared with other jobs the wall time counts the time the thread waits for a core; the CPU
    time of the calling thread does not, and is what the one-thread rows divide by (the work of a
    one-thread run, a lone orbit and the peak kernels runs on the calling thread).  ``timed.proc``
    is the best CPU time of the whole process: the one-thread rows take it instead when the work
    ran on another thread (the calling thread's CPU a small part of it)."""
    wall, cpu, proc = [], [], []
    for _ in range(repeats):
        t0, c0, p0 = time.perf_counter(), time.thread_time(), time.process_time()
        out = fn()
        cpu.append(time.thread_time() - c0)
        proc.append(time.process_time() - p0)
        wall.append(time.perf_counter() - t0)
    timed.last = out
    timed.proc = min(proc)
    return min(wall), min(cpu)


# ----------------------------------------------------------------------------- 1. peak kernels
def _vector_ops(width):
    """numba intrinsics on <width x double> values: splat, fma, mul, add, sum."""
    from llvmlite import ir
    from numba.core import cgutils, types
    from numba.extending import intrinsic, models, register_model

    class Vec(types.Type):
        def __init__(self):
            super().__init__(name=f"roofline_f64x{width}")

    vec = Vec()
    VT = ir.VectorType(ir.DoubleType(), width)

    @register_model(Vec)
    class _Model(models.PrimitiveModel):
        def __init__(self, dmm, fe_type):
            super().__init__(dmm, fe_type, VT)

    @intrinsic
    def splat(typingctx, x):
        def codegen(context, builder, sig, args):
            v = ir.Constant(VT, ir.Undefined)
            for i in range(width):
                v = builder.insert_element(v, args[0], ir.Constant(ir.IntType(32), i))
            return v
        return vec(types.float64), codegen

    @intrinsic
    def fma(typingctx, a, b, c):
        def codegen(context, builder, sig, args):
            fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(VT, [VT, VT, VT]),
                                                f"llvm.fma.v{width}f64")
            return builder.call(fn, list(args))
        return vec(vec, vec, vec), codegen

    @intrinsic
    def mul(typingctx, a, b):
        return vec(vec, vec), lambda context, builder, sig, args: builder.fmul(args[0], args[1])

    @intrinsic
    def add(typingctx, a, b):
        return vec(vec, vec), lambda context, builder, sig, args: builder.fadd(args[0], args[1])

    @intrinsic
    def total(typingctx, a):
        def codegen(context, builder, sig, args):
            s = builder.extract_element(args[0], ir.Constant(ir.IntType(32), 0))
            for i in range(1, width):
                s = builder.fadd(s, builder.extract_element(args[0], ir.Constant(ir.IntType(32), i)))
            return s
        return types.float64(vec), codegen

    return {"splat": splat, "fma": fma, "mul": mul, "add": add, "total": total}


def _kernel(width, chains, op, ops):
    """A compiled loop of ``reps`` iterations advancing ``chains`` independent vector chains."""
    from explorer._jit import njit

    step = "x{i} = fma(x{i}, m, c)" if op == "fma" else "x{i} = add(mul(x{i}, m), c)"
    lines = ["def kernel(reps, a, b):", "    m = splat(a)", "    c = splat(b)"]
    lines += [f"    x{i} = splat(1.0 + {i} * 1e-3)" for i in range(chains)]
    lines += ["    for _ in range(reps):"] + ["        " + step.format(i=i) for i in range(chains)]
    lines += ["    s = 0.0"] + [f"    s += total(x{i})" for i in range(chains)] + ["    return s"]
    ns = dict(ops)
    exec("\n".join(lines), ns)
    return njit(cache=False)(ns["kernel"])


def _loop_asm(kernel):
    """Instruction counts in the innermost loop of the compiled kernel: the block that jumps to
    itself (the chains' loop)."""
    asm = next(iter(kernel.inspect_asm().values()))
    lines = asm.splitlines()
    best = None
    for n, line in enumerate(lines):
        m = re.match(r"^(\.LBB\d+_\d+):", line)
        if not m:
            continue
        label = m.group(1)
        body = []
        for tail in lines[n + 1:]:
            body.append(tail.strip())
            if re.match(rf"\s*j\w+\s+{re.escape(label)}\b", tail):
                if best is None or len(body) > len(best):
                    best = body
                break
            if re.match(r"^\.LBB\d+_\d+:", tail):
                break
    best = best or []

    def count(pat):
        return sum(1 for x in best if re.search(pat, x))
    return {"fma": count(r"^vfmadd"), "mul": count(r"^vmulpd"), "add": count(r"^vaddpd"),
            "zmm": count(r"zmm"), "ymm": count(r"ymm"), "spill": count(r"rsp")}


def peak_table(seconds_per_kernel=0.8):
    rows = []
    for width in WIDTHS:
        ops = _vector_ops(width)
        for op in ("fma", "muladd"):
            for chains in CHAINS:
                k = _kernel(width, chains, op, ops)
                k(10, 0.999999, 1e-6)
                reps = 1000
                while True:
                    t0 = time.perf_counter()
                    k(reps, 0.999999, 1e-6)
                    dt = time.perf_counter() - t0
                    if dt > seconds_per_kernel / 4:
                        break
                    reps *= 4
                _wall, dt = timed(lambda: k(reps, 0.999999, 1e-6), 5)
                flops = 2.0 * reps * chains * width
                rows.append(dict(width=width * 64, op=op, chains=chains, gflops=flops / dt / 1e9,
                                 ns_per_iter=dt / reps * 1e9, asm=_loop_asm(k)))
    return rows


# ----------------------------------------------------------------------------- 2. work per step
def step_flops(order, tangent=False, nvec=1):
    """Flops of the vector part of one Taylor step of one orbit (one lane): the recurrence
    (generator's count of ``taylor_coefficients_lanes``: the orbit's, or the indicators module's with
    ``nvec`` vectors), the Horner sums (5 rows per vector: order mul + add each) and, for
    the crossings, ``_section_lanes``: the new state's sum and s(y) (15), a . X[k] for k = 0..order
    (10 each, + b), the tail bounds of s and s' (4 per term: orders 1..order and 2..order) and the two
    variation tests (3 each)."""
    if tangent:
        c = gen_lanes.operation_counts(order, nvec)
        rec = c["vadd"] + c["vsub"] + c["vmul"]
        return rec, rec + (1 + nvec) * 5 * 2 * order, c
    c = gen_lanes.operation_counts(order)
    rec = c["vadd"] + c["vsub"] + c["vmul"]
    section = 15 + 10 * (order + 1) + 1 + 4 * order + 4 * (order - 1) + 2 * 3
    return rec, rec + 5 * 2 * order + section, c


# ----------------------------------------------------------------------------- 3. achieved
def _recurrence(tangent):
    """(module, its lane recurrence ``taylor_coefficients_lanes``) that the crossings (the generated module of
    ``chaplygin.system()``, :mod:`explorer.integrate._lanes_generated`) or the indicators (that of
    ``chaplygin.variational(1)``, :func:`explorer.integrate.tangent.indicators_module`) step with."""
    from explorer.integrate import _lanes_generated as LG
    from explorer.integrate import tangent as tg

    mod = tg.indicators_module(1) if tangent else LG
    return mod, mod.taylor_coefficients_lanes


def recurrence_alone(order, tangent, reps=20000):
    """Seconds of CPU per orbit-step of the generated recurrence alone (LANES lanes, one thread)."""
    from explorer import model
    from explorer._jit import njit
    from explorer.integrate.simd import LANES

    mod, rec = _recurrence(tangent)
    P = model.FIGURE4.with_(mu=0.5).as_array()
    rng = np.random.default_rng(1)

    @njit(cache=False)
    def loop(P, X, order, reps, g):
        for _ in range(reps):
            rec(P, X, order, g)
    X = np.zeros((order + 1, mod.DIM, LANES))   # the lane array X[k, row, lane] of the generated drivers
    X[0] = rng.uniform(-0.5, 0.5, (mod.DIM, LANES))
    g = np.zeros((order + 1, max(mod.N_WORK, 1), LANES))
    loop(P, X, order, 1, g)
    _wall, cpu = timed(lambda: loop(P, X, order, reps, g), 5)
    return cpu / (reps * LANES)


def stages_alone(order, tangent, reps=20000):
    """Seconds of CPU per orbit-step of each vector stage of a step alone, on LANES lanes holding W4's
    orbits (Figure 4, mu = 0.5) or the chaos map's (mu = 1, one deviation vector), one thread, as the
    generated lane drivers call them (``crossings_lanes_worker`` of :mod:`explorer.integrate.codegen_lanes`,
    ``indicators_lanes_worker`` of :mod:`explorer.integrate.codegen_indicators`): the recurrence, the step
    norms and the step size's two vector powers (``lane_parts.norms_lanes``, on the orbit's rows), the Horner sums (``_evaluate_lanes``, every row: the orbit and, for the tangent, its vector) and,
    for the crossings, the section's values and variation bound (``_section_lanes``).  What a workload's
    step costs beyond their sum is the rest: the step's checks (``_steps_lanes``), the vector step end
    (``_ends_lanes``, ``_indicator_ends_lanes``), the lanes that take the scalar step end (the roots, the
    stops, the history rows) and the loop; those depend on the lanes' states and are not timed alone."""
    from explorer import model
    from explorer._jit import njit
    from explorer.analysis import lyapunov
    from explorer.integrate import lane_parts, lanes
    from explorer.integrate.simd import LANES

    w = LANES
    mod, rec = _recurrence(tangent)
    prm = model.FIGURE4.with_(mu=1.0 if tangent else 0.5)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    Y = model.section_state(prm, c1 + r1 * np.linspace(-0.9, 0.9, w), np.zeros(w), 2.0)
    P = prm.as_array()
    e_p, e_q = 1.0 / order, 1.0 / (order - 1)    # the workers' exponents of the step size
    norm = np.zeros((5, w))
    X = np.zeros((order + 1, mod.DIM, w))
    X[0, :5] = Y.T
    if tangent:
        X[0, 5:10] = lyapunov.deviation_vector(P, Y).T
    g = np.zeros((order + 1, max(mod.N_WORK, 1), w))   # the recurrence's work array
    rec(P, X, order, g)
    hv = np.full(w, 0.05)
    out = np.zeros((mod.DIM, w))
    a, b, _keep = lanes.section_arrays(-1.0, 0.0)
    L_g = np.zeros(w)
    GC = np.zeros((order + 1, w))
    G = np.zeros(w)
    n_rows = 5    # the orbit's rows: the tangent's norms leave out its vector
    evaluate, section = mod._evaluate_lanes, mod._section_lanes

    @njit(cache=False)
    def recurrence(reps, P, X, order, g):
        for _ in range(reps):
            rec(P, X, order, g)

    norms = lane_parts.norms_lanes

    @njit(cache=False)
    def step_norms(reps, X, order, norm):
        for _ in range(reps):
            norms(X, order, n_rows, e_p, e_q, norm)

    @njit(cache=False)
    def horner(reps, X, order, hv, out):
        for _ in range(reps):
            evaluate(X, order, hv, out)

    @njit(cache=False)
    def variation(reps, X, order, hv, out, a, b, L_g, GC, G):
        for _ in range(reps):
            section(X, order, hv, out, a, b, 1, L_g, GC, G)

    stages = [("recurrence", recurrence, (P, X, order, g)),
              ("step norms and the step size's two powers", step_norms, (X, order, norm)),
              ("Horner sums" + (" (orbit and vector)" if tangent else ""), horner, (X, order, hv, out))]
    if not tangent:
        evaluate(X, order, hv, out)
        stages.append(("section values and variation bound", variation, (X, order, hv, out, a, b, L_g, GC, G)))
    rows = []
    for name, fn, args in stages:
        fn(1, *args)
        rows.append((name, timed(lambda: fn(reps, *args), 5)[1] / (reps * w)))
    return rows


def libm_log_per_lane(reps=2_000_000):
    """Seconds of CPU per lane of libm's log as the indicators' vector step end calls it
    (``indicator_ends_lanes`` of :mod:`explorer.integrate.lane_parts`: a loop over the lanes of a
    group, arguments near 1 as the norms of a renormalised deviation vector after a step), less the same
    loop without the log (whether a vector log is worth writing)."""
    import math

    from explorer._jit import njit
    from explorer.integrate.simd import LANES

    @njit(cache=False)
    def loop(nrm, on, reps, take_log):
        s = 0.0
        for r in range(reps):
            if take_log:
                for l in range(LANES):
                    if on[l] != 0.0:
                        nrm[l] = math.log(nrm[l])
            s += nrm[0]
            for l in range(LANES):
                nrm[l] = 1.0 + 1e-3 * (l + 1) + 1e-9 * r
        return s

    nrm, on = np.ones(LANES), np.ones(LANES)
    loop(nrm, on, 10, True)
    loop(nrm, on, 10, False)
    with_log = timed(lambda: loop(nrm, on, reps, True), 5)[1]
    without = timed(lambda: loop(nrm, on, reps, False), 5)[1]
    return (with_log - without) / (reps * LANES)


def recurrence_asm(tangent):
    """The Cauchy-product loop of the generated recurrence (a fresh, uncached compile of the kernel,
    so that numba can show its assembly)."""
    from numba import types

    from explorer._jit import njit

    _mod, rec = _recurrence(tangent)
    k = njit(cache=False, error_model="numpy")(rec.py_func)
    arr1, arr3 = types.Array(types.float64, 1, "C"), types.Array(types.float64, 3, "C")
    k.compile((arr1, arr3, types.int64, arr3))
    return _loop_asm(k)


def workloads(quick):
    from bench_chaos import polar_seeds

    from explorer import model
    from explorer.analysis import lyapunov, sections

    out = []
    prm4 = model.FIGURE4.with_(mu=0.5)
    c1, c2, r1, r2 = model.allowed_ellipse(prm4, 2.0)
    p1 = c1 + r1 * np.linspace(-0.95, 0.95, 64)
    K = 200 if quick else 2000
    for threads in (1, 2):
        sections.crossings(prm4, 2.0, np.column_stack([p1[:2], np.zeros(2)]), n_crossings=5, tol=1e-12, threads=threads)
        wall, cpu = timed(lambda: sections.crossings(prm4, 2.0, np.column_stack([p1, np.zeros(64)]), n_crossings=K, tol=1e-12, threads=threads), 3)
        r = timed.last
        out.append(dict(name=f"W4 64 x {K}, {threads} thread{'s' * (threads > 1)}", wall=wall, cpu=cpu, proc=timed.proc,
                        threads=threads, steps=float(r.info[:, 1].sum()), crossings=int(r.count.sum()),
                        tangent=False))
    # one orbit: one of the LANES lanes does work
    n1 = 3000 if quick else 30000
    sections.crossings(prm4, 2.0, np.column_stack([p1[:1], np.zeros(1)]), n_crossings=5, tol=1e-12)
    wall, cpu = timed(lambda: sections.crossings(prm4, 2.0, np.column_stack([p1[:1], np.zeros(1)]), n_crossings=n1, tol=1e-12), 3)
    r = timed.last
    out.append(dict(name=f"one orbit x {n1}", wall=wall, cpu=cpu, proc=timed.proc, threads=1, steps=float(r.info[:, 1].sum()),
                    crossings=int(r.count.sum()), tangent=False))
    prm1 = model.FIGURE4.with_(mu=1.0)
    Y = polar_seeds(prm1)
    T = 100.0 if quick else 1000.0
    for threads in (1, 2):
        lyapunov.indicators(prm1, states=Y[:8], tmax=1.0, tol=1e-12, threads=threads)
        wall, cpu = timed(lambda: lyapunov.indicators(prm1, states=Y, tmax=T, tol=1e-12, threads=threads), 3)
        out.append(dict(name=f"chaos map 400 orbits, T = {T:g}, {threads} thread{'s' * (threads > 1)}", wall=wall,
                        cpu=cpu, proc=timed.proc, threads=threads, steps=float(np.sum(timed.last.steps)), crossings=0, tangent=True))
    return out


def steps_check(K=500, picks=(0, 16, 32, 48)):
    """Steps per crossing of explorer (Jorba-Zou step size, kernels.taylor.step_size) and of
    heyoka's scalar taylor_adaptive (its own Jorba-Zou rule) on the same W4 orbits, same tol,
    each integrated to the time of explorer's K-th crossing; None if heyoka is not importable."""
    if not C.have("heyoka"):
        return None
    import heyoka as hy
    from bench_w4 import _hy_system

    from explorer import model
    from explorer.analysis import sections

    prm = model.FIGURE4.with_(mu=0.5)
    c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
    p1 = (c1 + r1 * np.linspace(-0.95, 0.95, 64))[list(picks)]
    r = sections.crossings(prm, 2.0, np.column_stack([p1, np.zeros(len(p1))]), n_crossings=K, tol=1e-12)
    Y0 = model.section_state(prm, p1, np.zeros(len(p1)), 2.0)
    eqs, _g1 = _hy_system(prm.as_array())
    rows = []
    for i in range(len(p1)):
        ta = hy.taylor_adaptive(eqs, [float(v) for v in Y0[i]], tol=1e-12)
        out = ta.propagate_until(float(r.info[i, 0]))
        rows.append(dict(orbit=picks[i], t=float(r.info[i, 0]), crossings=int(r.count[i]),
                         explorer=int(r.info[i, 1]), heyoka=int(out[3]), order=(r.settings["order"], ta.order)))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="shorter workloads (W4 200 crossings, map T = 100)")
    ap.add_argument("--write", action="store_true", help="record the tables in RESULTS.md (section ROOFLINE)")
    args = ap.parse_args(argv)
    started, load0 = C.now(), C.loadavg()
    emit = C.Emitter()
    lines = emit.lines
    from explorer.kernels.taylor_order import order_for_tolerance

    emit(f"# roofline on {C.machine_line(C.machine())}; load average at start {os.getloadavg()}")
    flags = open("/proc/cpuinfo").read().split("flags")[1].split("\n")[0].split() if os.path.exists("/proc/cpuinfo") else []
    emit(f"# vector flags: {' '.join(f for f in flags if f.startswith(('avx', 'fma')))}")
    rows = peak_table()
    emit("\n### 1. Peak: C independent chains x = x * m + c, one thread\n")
    emit("| bits | op | chains | GFLOP/s | ns / iteration | the loop's assembly |")
    emit("|---:|---|---:|---:|---:|---|")
    for r in rows:
        a = r["asm"]
        reg = "zmm" if a["zmm"] else "ymm"
        unroll = max(a["fma"], a["mul"]) / (r["chains"] * r["width"] // (256 if reg == "ymm" else 512))
        asm = (f"{a['fma']} vfmadd, {a['mul']} vmulpd, {a['add']} vaddpd on {reg} (loop unrolled x{unroll:g}); "
               f"{a['spill']} stack accesses")
        emit(f"| {r['width']} | {r['op']} | {r['chains']} | {r['gflops']:.1f} | {r['ns_per_iter']:.2f} | {asm} |")
    peak_fma = max(r["gflops"] for r in rows if r["op"] == "fma")
    peak_unfused = max(r["gflops"] for r in rows if r["op"] == "muladd")
    dep = min(r["ns_per_iter"] for r in rows if r["chains"] == 1 and r["op"] == "fma")
    emit(f"\nPeak per core: {peak_fma:.1f} GFLOP/s with FMA, {peak_unfused:.1f} GFLOP/s as mul + add; "
          f"one dependent FMA chain: {dep:.2f} ns per FMA (its latency).")

    order = order_for_tolerance(1e-12)
    emit(f"\n### 2. Work of one Taylor step of one orbit (order {order}, tol 1e-12)\n")
    emit("| kernel | vmul | vadd | vsub | vneg | recurrence flops | step flops (+ Horner, section) |")
    emit("|---|---:|---:|---:|---:|---:|---:|")
    work = {}
    for name, tangent, nvec in (("crossings (orbit)", False, 1), ("tangent, 1 vector (MEGNO, mLCE)", True, 1),
                                ("tangent, 2 vectors (SALI)", True, 2)):
        rec, step, c = step_flops(order, tangent, nvec)
        work[(tangent, nvec)] = (rec, step)
        emit(f"| {name} | {c['vmul']} | {c['vadd']} | {c['vsub']} | {c['vneg']} | {rec} | {step} |")

    emit("\n### 3. Achieved: flops of the vector part (section 2) per second of the thread's CPU time (one thread) "
          "or of wall time per core (two threads); fraction of the FMA peak per core, of the mul + add peak in "
          "brackets\n")
    emit("| workload | wall (s) | CPU of the thread (s) | steps | steps / crossing | ns / orbit-step | "
          "GFLOP/s per core | of peak |")
    emit("|---|---:|---:|---:|---:|---:|---:|---:|")
    for tangent in (False, True):
        ns = recurrence_alone(order, tangent)
        g = work[(tangent, 1)][0] / ns / 1e9
        emit(f"| {'tangent' if tangent else 'orbit'} recurrence alone (8 lanes, 1 thread) | | | | | {ns * 1e9:.1f} | "
              f"{g:.1f} | {g / peak_fma:.0%} ({g / peak_unfused:.0%}) |")
    for w in workloads(args.quick):
        seconds = w["cpu"] if w["threads"] == 1 else w["wall"] * w["threads"]
        if w["threads"] == 1 and w["cpu"] < 0.3 * w["proc"]:   # the work ran on another thread: the process's CPU
            seconds = w["proc"]     # (not the wall time: under load a thread waits for a core)
        g = w["steps"] * work[(w["tangent"], 1)][1] / seconds / 1e9
        spc = f"{w['steps'] / w['crossings']:.1f}" if w["crossings"] else ""
        cpu = f"{w['cpu']:.3f}" if w["threads"] == 1 else ""
        emit(f"| {w['name']} | {w['wall']:.3f} | {cpu} | {w['steps']:.3g} | {spc} | "
              f"{seconds / w['steps'] * 1e9:.1f} | {g:.1f} | {g / peak_fma:.0%} ({g / peak_unfused:.0%}) |")
    emit("\n### 3b. The step's vector stages alone (one thread; CPU per orbit-step): "
         "what the rest of a workload's step costs is its ns / orbit-step above less their sum\n")
    emit("| lanes | stage | ns / orbit-step |")
    emit("|---|---|---:|")
    for tangent in (False, True):
        total = 0.0
        for name, sec in stages_alone(order, tangent):
            total += sec
            emit(f"| {'tangent (1 vector)' if tangent else 'crossings'} | {name} | {sec * 1e9:.1f} |")
        emit(f"| {'tangent (1 vector)' if tangent else 'crossings'} | sum of the stages | {total * 1e9:.1f} |")
    emit(f"| tangent (1 vector) | libm's log, per lane, in the vector step end (not in the sum) | "
         f"{libm_log_per_lane() * 1e9:.1f} |")
    emit("\n### 4. The recurrence alone (one thread): CPU per orbit-step and its Cauchy-product loop\n")
    emit("| recurrence | ns / orbit-step | of FMA peak | loop: vmulpd, vaddpd, stack accesses |")
    emit("|---|---:|---:|---|")
    for tangent in (False, True):
        ns = recurrence_alone(order, tangent)
        a = recurrence_asm(tangent)
        f = work[(tangent, 1)][0] / ns / 1e9
        emit(f"| {'tangent' if tangent else 'orbit'} | {ns * 1e9:.1f} | {f / peak_fma:.0%} | "
             f"{a['mul']}, {a['add']}, {a['spill']} ({'zmm' if a['zmm'] else 'ymm'}) |")
    rows = None
    for K in (20, 100 if args.quick else 500):   # 20 crossings: before the chaotic paths part
        got = steps_check(K)
        rows = None if got is None else (rows or []) + got
    if rows:
        emit("\n### 5. Steps per crossing: explorer against heyoka taylor_adaptive (scalar), tol 1e-12, same "
              "orbits to the same time\n")
        emit("| W4 orbit | time | crossings | order (explorer, heyoka) | explorer steps / crossing | "
              "heyoka steps / crossing | explorer / heyoka |")
        emit("|---:|---:|---:|---|---:|---:|---:|")
        for r in rows:
            emit(f"| {r['orbit']} | {r['t']:.1f} | {r['crossings']} | {r['order'][0]}, {r['order'][1]} | "
                  f"{r['explorer'] / r['crossings']:.1f} | {r['heyoka'] / r['crossings']:.1f} | "
                  f"{r['explorer'] / r['heyoka']:.3f} |")
    emit(f"\n# load average at end {os.getloadavg()}")
    if args.write:
        head, _ = C.header("Roofline of the Taylor lanes (issue 24)", C.command_line("bench_roofline.py", argv), started,
                           (C.now() - started).total_seconds(), load0)
        C.update_section("ROOFLINE", head + [""] + [x for x in lines if not x.startswith("# ")])
    return 0


if __name__ == "__main__":
    sys.exit(main())
