#!/usr/bin/env python
"""Results bit-identical for 1 and 2 numba threads (and for --jobs 1 and 2), at a larger scale
than the tests: every method of sections.crossings (all splitting schemes), chaos indicators
of lyapunov.indicators for every kind of tangent dynamics, the fixed-point routines.

- sections: 96 orbits x 150 crossings, Figure-4 scene at mu = 0.5 and an asymmetric set;
- lyapunov: 48 orbits, T = 500, history 8 (taylor, dop853, split4, split8);
- fixedpoints: find_fixed_point, continue_branch (mu 0 .. 1, with the bisection of a stability
  change being outside this range: 0 .. 3.2 in the full run), separatrices (manifold);
- sweep: a 3-panel scene with sections and chaos indicators, --jobs 1 and --jobs 2.

Check: every array equal bit for bit (numpy.array_equal, NaN padding compared as equal).

    python benchmarks/stress/stress_threads.py            # ~2 min
    python benchmarks/stress/stress_threads.py --quick
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from _stress import Checks

SCENE = """name = "threads"
[sweep]
parameter = "mu"
values = [0.1, 0.5, 2.0]
[seeds]
kind = "grid"
n = 40
[integration]
crossings = 50
tmax = 500.0
[compute]
sections = true
lyapunov = true
[lyapunov]
time = 200.0
"""


def equal(a, b):
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    quick = args.quick
    ck = Checks("stress_threads", quick, argv)
    from explorer import model
    from explorer._jit import get_num_threads, set_num_threads
    from explorer.analysis import fixedpoints, lyapunov, sections
    from explorer.kernels import splitting
    nmax = max(2, get_num_threads())
    if get_num_threads() < 2:
        ck.note("numba has one thread only: the comparison is 1 thread vs 1 thread")
    N, K = (24, 40) if quick else (96, 150)
    sets = {"figure4_mu0.5": model.FIGURE4.with_(mu=0.5),
            "asym": model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25)}
    methods = [("taylor", dict(tol=1e-13)), ("taylor", dict(tol=1e-9)), ("dop853", dict(tol=1e-12))]
    methods += [(m, dict(dt=0.05)) for m in splitting.SCHEMES]
    for name, prm in sets.items():
        c1, c2, r1, r2 = model.allowed_ellipse(prm, 2.0)
        rng = np.random.default_rng(11)
        ang, rad = rng.uniform(0, 2 * np.pi, N), np.sqrt(rng.uniform(0, 0.9, N))
        y0 = model.section_state(prm, c1 + r1 * rad * np.cos(ang), c2 + r2 * rad * np.sin(ang), 2.0)
        for method, kw in methods:
            a = sections.crossings(prm, states=y0, n_crossings=K, method=method, threads=1, **kw)
            b = sections.crossings(prm, states=y0, n_crossings=K, method=method, threads=nmax, **kw)
            ok = all(equal(getattr(a, f), getattr(b, f)) for f in ("data", "count", "status", "final", "info"))
            ck.check(f"sections {name} {method} {kw}: {N} orbits x {K} crossings, 1 vs {nmax} threads", ok, ok,
                     "bit-identical")
        for method, kw in (("taylor", dict(tol=1e-12)), ("dop853", dict(tol=1e-12)), ("split4", dict(dt=0.02)),
                           ("split8", dict(dt=0.05))):
            T = 100.0 if quick else 500.0
            a = lyapunov.indicators(prm, states=y0[: N // 2], tmax=T, method=method, history=8, threads=1, **kw)
            b = lyapunov.indicators(prm, states=y0[: N // 2], tmax=T, method=method, history=8, threads=nmax, **kw)
            ok = all(equal(getattr(a, f), getattr(b, f)) for f in ("time", "mlce", "megno", "Y", "fli", "status",
                                                                 "steps", "final", "history"))
            ck.check(f"lyapunov {name} {method} {kw}: {N // 2} orbits, T = {T:g}, 1 vs {nmax} threads", ok, ok,
                     "bit-identical")
    old = get_num_threads()
    outs = []
    try:
        for n in (1, nmax):
            set_num_threads(min(n, old))
            fp = fixedpoints.find_fixed_point(model.FIGURE4.with_(mu=0.5), 2.0, (-0.2, 0.0))
            br = fixedpoints.continue_branch(model.FIGURE4, 2.0, "mu", 0.0, 1.0 if quick else 3.2, 0.2)
            seps = fixedpoints.separatrices(fp.params, fp.h, fp, iterations=2 if quick else 4, max_points=400)
            outs.append([fp.point, fp.jacobian, np.array([p.point for p in br.orbits]),
                         np.array([b["value"] for b in br.bifurcations])] + seps)
    finally:
        set_num_threads(old)
    ok = len(outs[0]) == len(outs[1]) and all(equal(x, y) for x, y in zip(outs[0], outs[1]))
    ck.check(f"fixedpoints: fixed point, continuation, 4 separatrix branches, 1 vs {nmax} threads", ok, ok,
             "bit-identical")
    if not quick:
        import h5py
        with tempfile.TemporaryDirectory() as tmp:
            scene = Path(tmp) / "threads.toml"
            scene.write_text(SCENE)
            files = []
            for jobs in (1, 2):
                out = Path(tmp) / f"j{jobs}.h5"
                subprocess.run([sys.executable, "-m", "explorer", "sweep", str(scene), "--out", str(out),
                                "--no-figure", "--quiet", "--jobs", str(jobs)], check=True, capture_output=True,
                               timeout=3600)
                d = {}
                with h5py.File(out, "r") as f:
                    f.visititems(lambda k, o: d.__setitem__(k, o[()]) if isinstance(o, h5py.Dataset) else None)
                files.append(d)
            ok = sorted(files[0]) == sorted(files[1]) and all(equal(files[0][k], files[1][k]) for k in files[0])
            ck.check("sweep with chaos indicators: --jobs 1 vs --jobs 2, every dataset", ok, ok, "bit-identical")
    n_ok = sum(c["ok"] for c in ck.items)
    return ck.finish(f"{n_ok}/{len(ck.items)} comparisons bit-identical (sections: {len(methods)} method settings x "
                     f"{len(sets)} parameter sets; lyapunov: 4 x {len(sets)}; fixedpoints; "
                     f"{'no sweep (quick)' if quick else 'sweep --jobs 1 vs 2'})")


if __name__ == "__main__":
    sys.exit(main())
