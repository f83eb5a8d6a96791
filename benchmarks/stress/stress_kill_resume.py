#!/usr/bin/env python
"""A sweep killed with SIGKILL twenty times at random moments resumes to the same file as an
uninterrupted run (tests/test_sweep.py kills 6 times).

Scene: 6 panels (mu = 0.1 .. 1.5) x a grid of ~100 seeds x 600 crossings (taylor), sections and
chaos indicators (T = 1500): ~10 s uninterrupted on 2 cores, so that kills land in every phase.  The uninterrupted run gives the reference file and its wall time T.  Then,
in rounds (the output file removed at the start of each round), `python -m explorer sweep` is
started and SIGKILLed at a uniformly random moment in (0.1 s, T), again and again, until the
round's kill count is reached; then it runs to completion.  One round uses --jobs 2 (the whole
process group is killed).

Checks: 20 kills that hit a running process; after every kill the file (if any) opens with
store.read_store and every panel it holds is identical to the reference panel; at the end of
every round every dataset equals the reference (nothing lost, nothing duplicated) and no
temporary file is left.

    python benchmarks/stress/stress_kill_resume.py            # 20 kills, ~4 min
    python benchmarks/stress/stress_kill_resume.py --quick    # 5 kills
"""
from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _stress import Checks

SCENE = """name = "killme"
[model]
mu = 0.0
[energy]
h = 2.0
[sweep]
parameter = "mu"
values = [0.1, 0.3, 0.6, 0.9, 1.2, 1.5]
[seeds]
kind = "grid"
n = 100
[integration]
method = "taylor"
tol = 1e-12
crossings = 600
tmax = 6000.0
[compute]
sections = true
lyapunov = true
[lyapunov]
time = 1500.0
"""


def datasets(path):
    import h5py
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
        f.visititems(visit)
    return out


def same(a, b, prefix=""):
    keys = [k for k in a if k.startswith(prefix)]
    if sorted(keys) != sorted(k for k in b if k.startswith(prefix)):
        return False
    return all(np.array_equal(a[k], b[k]) for k in keys)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="5 kills instead of 20")
    ap.add_argument("--kills", type=int, default=None)
    ap.add_argument("--seed", type=int, default=2024)
    args = ap.parse_args(argv)
    n_kills = args.kills or (5 if args.quick else 20)
    rounds = [(n_kills - n_kills // 4 * 3, 1)] + [(n_kills // 4, 1)] * 2 + [(n_kills // 4, 2)]
    rounds = [r for r in rounds if r[0] > 0]
    ck = Checks("stress_kill_resume", args.quick, argv)
    from explorer.io import store
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        scene = tmp / "killme.toml"
        scene.write_text(SCENE)
        cmd = [sys.executable, "-m", "explorer", "sweep", str(scene), "--no-figure", "--quiet"]
        ref_path = tmp / "ref.h5"
        t0 = time.perf_counter()
        subprocess.run(cmd + ["--out", str(ref_path)], check=True, capture_output=True, timeout=3600)
        T = time.perf_counter() - t0
        ref = datasets(ref_path)
        ck.note(f"uninterrupted run {T:.1f} s; kills at uniform random moments in (0.1, {T:.1f}) s")
        kills, partial_ok, partial_checked, rounds_ok = 0, True, 0, 0
        log = []
        for r, (target, jobs) in enumerate(rounds):
            out = tmp / f"killed{r}.h5"
            got, attempts = 0, 0
            while got < target and attempts < 20 * target:
                attempts += 1
                proc = subprocess.Popen(cmd + ["--out", str(out), "--jobs", str(jobs)], stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL, start_new_session=True)
                delay = rng.uniform(0.1, T)
                time.sleep(delay)
                killed = proc.poll() is None
                if killed:
                    if jobs > 1:
                        os.killpg(proc.pid, signal.SIGKILL)
                    else:
                        os.kill(proc.pid, signal.SIGKILL)
                    got += 1
                    kills += 1
                proc.wait()
                what = f"killed after {delay:.2f} s" if killed else f"finished before {delay:.2f} s"
                if out.exists():
                    data = store.read_store(out)          # opens whatever the moment of the kill
                    cur = datasets(out)
                    for i in data.panels:
                        partial_checked += 1
                        if not same(cur, ref, f"panels/{i:03d}/"):
                            partial_ok = False
                    log.append(f"round {r} (--jobs {jobs}) {what}: panels stored {sorted(data.panels)}")
                else:
                    log.append(f"round {r} (--jobs {jobs}) {what}: no file yet")
                if proc.returncode == 0 and got < target:
                    out.unlink()                          # finished before the kill: start the round again
            subprocess.run(cmd + ["--out", str(out), "--jobs", str(jobs)], check=True, capture_output=True,
                           timeout=3600)
            ok = same(datasets(out), ref) and not list(tmp.glob(f"killed{r}.h5.tmp-*"))
            rounds_ok += ok
            ck.check(f"round {r} (--jobs {jobs}, {got} kills): resumed file identical to the uninterrupted run, "
                     "no temporary left", ok, ok, "identical datasets")
        for line in log:
            print("  " + line)
        ck.check("kills that hit a running sweep", kills >= n_kills, kills, f">= {n_kills}")
        ck.check("every panel present after a kill equals the reference panel", partial_ok,
                 f"{partial_checked} panel checks", "all identical")
    return ck.finish(f"{kills} SIGKILLs over {len(rounds)} rounds; {rounds_ok}/{len(rounds)} rounds identical")


if __name__ == "__main__":
    sys.exit(main())
