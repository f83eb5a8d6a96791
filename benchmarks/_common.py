"""Helpers shared by the benchmark scripts (not a benchmark itself).

- machine(), versions(), loadavg(): what the numbers were measured on (lscpu, package versions,
  git revision; heyoka and scipy are optional);
- update_section(name, text): replace the section of benchmarks/RESULTS.md between
  ``<!-- BEGIN name -->`` and ``<!-- END name -->`` (appended when missing; the rest of the
  file is left alone);
- header(...): the common first lines of a section (date, command, machine, versions, load);
- best_of(fn, repeats, budget), round_robin(jobs, max_runs, budget), runs_note(times): timing runs;
  write_json(path, obj);
- heyoka's side of the side-by-side runs: Recorder (the crossings an event callback records),
  heyoka_lanes (a queue of orbits over the lanes of one ``taylor_adaptive_batch``) and spawned
  (workers in spawned processes, timed after a barrier).
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import multiprocessing as mp
import os
import platform
import re
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS_MD = HERE / "RESULTS.md"
OUT_DIR = HERE / "results"           # JSON and PNG of the new benchmarks


def now():
    return _dt.datetime.now().astimezone()


def loadavg():
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except OSError:  # pragma: no cover
        return None


def machine():
    info = {"model_name": platform.processor() or platform.machine(), "cpus": os.cpu_count()}
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
        keys = {"Model name": "model_name", "CPU(s)": "cpus", "Core(s) per socket": "cores_per_socket",
                "Thread(s) per core": "threads_per_core", "Socket(s)": "sockets"}
        for line in out.splitlines():
            k, _, v = line.partition(":")
            if k.strip() in keys:
                v = v.strip()
                info[keys[k.strip()]] = int(v) if v.isdigit() else v
    except Exception:  # pragma: no cover - lscpu missing
        pass
    try:
        import numba
        info["numba_threads"] = numba.get_num_threads()
    except Exception:  # pragma: no cover
        pass
    return info


def machine_line(m):
    cores = m.get("cores_per_socket")
    cores = cores * m.get("sockets", 1) if isinstance(cores, int) else "?"
    return (f"{m.get('model_name')}, {m.get('cpus')} CPUs ({cores} cores, {m.get('threads_per_core', '?')} "
            f"thread/core), numba threads {m.get('numba_threads', '?')}")


def versions():
    v = {"python": platform.python_version(), "numpy": np.__version__}
    for mod in ("numba", "llvmlite", "scipy", "heyoka", "h5py", "matplotlib"):
        try:
            v[mod] = __import__(mod).__version__
        except Exception:
            v[mod] = "not installed"
    try:
        from importlib.metadata import version
        v["explorer"] = version("explorer")
    except Exception:  # pragma: no cover
        v["explorer"] = "?"
    try:
        rev = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--", "src"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        v["explorer_git"] = rev + (" (+ uncommitted changes in src/)" if dirty else "")
    except Exception:  # pragma: no cover
        pass
    return v


def have(module):
    try:
        __import__(module)
        return True
    except Exception:
        return False


def command_line(script_name, argv=None):
    """The command as a reader reruns it from the repository root (no path of this machine)."""
    argv = sys.argv[1:] if argv is None else argv
    return " ".join(["python", f"benchmarks/{script_name}"] + [shlex.quote(a) for a in argv])


def header(title, command, started, seconds, load_start, extra=(), stored=None, numba_threads=None):
    """The common head of a RESULTS.md section.  ``stored``: a run's JSON document (machine,
    versions, load_end) when a section is re-rendered from it rather than written by the run;
    ``numba_threads``: the threads the measured processes ran with, when not this process's."""
    m = stored["machine"] if stored else machine()
    if numba_threads is not None:
        m = dict(m, numba_threads=numba_threads)
    v = stored["versions"] if stored else versions()
    load_end = stored["load_end"] if stored else loadavg()
    lines = [f"## {title}", "",
             f"- Date: {started.isoformat(timespec='seconds')}; run time {seconds:.0f} s",
             f"- Command (from the repository root): `{command}`",
             f"- Machine: {machine_line(m)}; load average at start {load_start}, at end {load_end} "
             "(other jobs may have run at the same time)",
             "- Versions: " + ", ".join(f"{k} {val}" for k, val in v.items())]
    lines += [f"- {e}" for e in extra]
    return lines, dict(machine=m, versions=v)


class Emitter:
    """Print lines as they come and keep them for RESULTS.md: ``emit = Emitter(); emit("| a |")``;
    ``emit.lines`` is what was printed, split into lines."""

    def __init__(self):
        self.lines = []

    def __call__(self, text=""):
        print(text, flush=True)
        self.lines.extend(str(text).split("\n"))


def report(section, lines, record, written=()):
    """Print a benchmark's table (and the files it wrote); with ``record``, put the table into
    RESULTS.md's section ``section``.  Returns 0 (the exit status)."""
    print("\n".join(lines))
    if written:
        print("wrote " + " and ".join(str(w) for w in written))
    if record:
        update_section(section, lines)
        print(f"updated {RESULTS_MD}")
    return 0


def update_section(name, body_lines):
    """Replace (or append) the block <!-- BEGIN name --> ... <!-- END name --> of RESULTS.md."""
    begin, end = f"<!-- BEGIN {name}: generated by benchmarks/, do not edit by hand -->", f"<!-- END {name} -->"
    block = "\n".join([begin] + list(body_lines) + ["", end])
    text = RESULTS_MD.read_text() if RESULTS_MD.exists() else "# Benchmark results\n"
    pat = re.compile(re.escape(f"<!-- BEGIN {name}") + r"[^\n]*-->.*?" + re.escape(end), re.S)
    if pat.search(text):
        text = pat.sub(lambda _m: block, text)
    else:
        text = text.rstrip("\n") + "\n\n" + block + "\n"
    RESULTS_MD.write_text(text)


def _json_default(o):
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def write_json(path, obj):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(obj, indent=1, default=_json_default) + "\n")
    return path


def best_of(fn, repeats=3, budget=60.0):
    """Run fn() (returns a result) up to ``repeats`` times while the cumulative time stays within
    ``budget`` (at least once).  Returns (best seconds, all times, result of the best run)."""
    times, best, res, spent = [], math.inf, None, 0.0
    for _ in range(repeats):
        if times and spent + best > budget:
            break
        t0 = time.perf_counter()
        r = fn()
        sec = time.perf_counter() - t0
        spent += sec
        times.append(sec)
        if sec < best:
            best, res = sec, r
    return best, times, res


def fmt_e(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if not math.isfinite(x):
        return "inf"
    return f"{x:.1e}"


def section_seeds(prm, h, n, span=0.95):
    """n start points on phi = pi across the allowed ellipse at p2 = c2 (as W4)."""
    from explorer import model
    c1, c2, r1, r2 = model.allowed_ellipse(prm, h)
    p1 = c1 + r1 * np.linspace(-span, span, n)
    return model.section_state(prm, p1, np.full(n, c2), h)


def savefig(fig, path, title=None, rect=(0, 0, 1, 1)):
    """Title, lay out (within ``rect``), save (120 dpi) and close a benchmark's figure; returns its
    path."""
    import matplotlib.pyplot as plt

    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=rect)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def round_robin(jobs, max_runs, budget):
    """Timing runs interleaved over rows, so that a burst of load from other processes spreads
    over rows instead of spoiling one row.  jobs[i]() returns (seconds, cost, result); round r
    runs every job that still has max_runs - r runs left and whose cumulative cost plus its best
    time stays within budget (every job runs at least once).  Returns, per job, a dict with all
    times, the best time and the result of the best run."""
    state = [dict(times=[], best=math.inf, cost=0.0, res=None) for _ in jobs]
    for rnd in range(max_runs):
        for fn, st in zip(jobs, state):
            if rnd > 0 and st["cost"] + st["best"] > budget:
                continue
            sec, cost, res = fn()
            st["times"].append(sec)
            st["cost"] += cost
            if sec < st["best"]:
                st["best"], st["res"] = sec, res
    return state


def runs_note(times):
    n = len(times)
    if n == 1:
        return "1 run"
    return f"best of {n} (runs {min(times):.2f}-{max(times):.2f} s)"


class Recorder:
    """Crossings recorded by heyoka's event callbacks: ts (N, K), ys (N, K, dim), count (N); ``lane``
    the orbit of each batch lane (-1: none), ``orbit`` the orbit of the scalar integrator."""

    def __init__(self, dim):
        self.dim = dim
        self.lane = np.full(1, -1, np.int64)
        self.orbit = -1
        self.reset(0, 1)

    def reset(self, N, K):
        self.K = K
        self.ts = np.full((N, K), np.nan)
        self.ys = np.full((N, K, self.dim), np.nan)
        self.count = np.zeros(N, np.int64)

    def record(self, o, t, y):
        """Record a crossing of orbit o; False (stop the lane) once it has K."""
        k = self.count[o]
        self.ts[o, k] = t
        self.ys[o, k] = y
        self.count[o] = k + 1
        return k + 1 < self.K


def heyoka_lanes(ta, rec, Y0, tmax, status, steps):
    """The rows of Y0 through the lanes of the ``taylor_adaptive_batch`` ``ta`` whose terminal event
    records into ``rec`` and stops a lane after rec.K crossings: a lane that stops is refilled with the
    next orbit (state, time 0, cooldowns reset) and the propagation resumes; lanes without work get a
    time limit equal to their time (no step).  status[o]: 0 done, 1 time limit, 2 non-finite; steps[o]
    the steps taken."""
    S = int(ta.batch_size)
    N = Y0.shape[0]
    nxt = 0
    rec.lane = np.full(S, -1, np.int64)
    limit = np.zeros(S)

    def refill(lanes):
        nonlocal nxt
        tt = np.array(ta.time, dtype=np.float64)
        st = ta.state
        for i in lanes:
            if nxt < N:
                rec.lane[i] = nxt
                st[:, i] = Y0[nxt]
                tt[i] = 0.0
                limit[i] = tmax
                nxt += 1
            else:
                rec.lane[i] = -1
                limit[i] = tt[i]
        ta.set_time(tt)
        for i in lanes:
            ta.reset_cooldowns(i)

    refill(range(S))
    while np.any(rec.lane >= 0):
        ta.propagate_until(limit)
        res = ta.propagate_res
        tt = ta.time
        done = []
        for i in range(S):
            o = rec.lane[i]
            if o < 0:
                continue
            steps[o] += int(res[i][3])
            if rec.count[o] >= rec.K:
                done.append(i)
            elif not np.all(np.isfinite(ta.state[:, i])):
                status[o] = 2
                done.append(i)
            elif tt[i] >= limit[i]:
                status[o] = 1
                done.append(i)
        if done:
            refill(done)


def spawned(target, args_per_process):
    """Run ``target(*args, barrier, queue, tag)`` in one spawned process per entry of args_per_process
    (tag: its index); each puts a dict with ``tag``, ``start`` and ``end`` (time.monotonic() around its
    timed work, started after the barrier) on the queue.  Returns (the dicts in tag order, the wall time
    of the timed work: latest end - earliest start, the total wall time with process starts)."""
    ctx = mp.get_context("spawn")
    n = len(args_per_process)
    barrier, queue = ctx.Barrier(n), ctx.Queue()
    T0 = time.monotonic()
    procs = [ctx.Process(target=target, args=(*a, barrier, queue, r)) for r, a in enumerate(args_per_process)]
    for p in procs:
        p.start()
    outs = sorted((queue.get() for _ in procs), key=lambda o: o["tag"])
    for p in procs:
        p.join()
    return outs, max(o["end"] for o in outs) - min(o["start"] for o in outs), time.monotonic() - T0
