"""Chaos benchmark (issue 10): the explorer's tangent SIMD lanes against heyoka's batch mode.

Rows (RESULTS.md section CHAOS):

- the 400-orbit chaos map: mu = 1, h = 2, section phi = pi, T = 1000, tol 1e-12, MEGNO; the
  explorer (``lyapunov.indicators``, Taylor on tangent lanes, 2 Numba threads) against heyoka's
  ``taylor_adaptive_batch`` with the variational equations of one deviation vector in 2
  spawned processes (batch size ``heyoka.recommended_simd_size()``), renormalising the
  deviation vector every time unit and accumulating MEGNO with the explorer's accumulator
  formulas (kernels/tangent.py) over those unit intervals; same start states, same start
  deviation vectors (``lyapunov.deviation_vector``), chaotic fractions compared (<Y> > 4, the
  scene default ``[lyapunov] threshold``), wall-time ratio;
- the grid: a 20 x 20 raster over the bounding box of the allowed ellipse has only 316 cells
  inside the allowed region, so the 400 orbits are a 20 x 20 polar grid *on* the ellipse
  (20 equal-area radii sqrt((i + 1/2) / 20) x 0.98 of the semi-axes, 20 angles); the 316-cell
  raster is timed too (explorer only);
- MEGNO orbits per second at mu = 0.03 and mu = 1 (32 x 32 raster, 812 orbits);
- time against T (250, 500, 1000, 2000) on the 400-orbit map (explorer);
- the 512 x 512 map: ``python -m explorer sweep megno_map`` run in a subprocess and timed
  (``--skip-512`` reuses the last recorded number, and says so).

    python benchmarks/bench_chaos.py [--write] [--skip-512] [--quick]
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _common as C  # noqa: E402

SECTION = "CHAOS"
H_LEVEL = 2.0
TOL = 1e-12
THRESHOLD = 4.0                 # ScanSettings / [lyapunov] threshold default
JSON_OUT = C.OUT_DIR / "chaos.json"


# ----------------------------------------------------------------------------- workload
def polar_seeds(prm, n_r=20, n_a=20, span=0.98):
    """n_r x n_a start states on phi = pi inside the allowed ellipse (equal-area radii)."""
    from explorer import model
    c1, c2, r1, r2 = model.allowed_ellipse(prm, H_LEVEL)
    rho = span * np.sqrt((np.arange(n_r) + 0.5) / n_r)
    ang = 2 * np.pi * (np.arange(n_a) + 0.5) / n_a
    R, A = np.meshgrid(rho, ang, indexing="ij")
    p1 = (c1 + r1 * R * np.cos(A)).ravel()
    p2 = (c2 + r2 * R * np.sin(A)).ravel()
    return model.section_state(prm, p1, p2, H_LEVEL)


def raster_seeds(prm, resolution):
    from explorer import model
    from explorer.analysis.sweep import map_seeds
    p1, p2, _grid = map_seeds(prm, H_LEVEL, np.pi, resolution)
    return model.section_state(prm, p1, p2, H_LEVEL)


def explorer_run(prm, Y0, T, threads=2, repeats=3):
    from explorer.analysis import lyapunov
    lyapunov.indicators(prm, states=Y0[:8], tmax=1.0, tol=TOL, threads=threads)      # compile / load the cache
    best, _times, r = C.best_of(lambda: lyapunov.indicators(prm, states=Y0, tmax=T, tol=TOL, threads=threads), repeats,
                                budget=120.0)
    return best, r.megno, r.steps


# ----------------------------------------------------------------------------- heyoka
def _hy_tangent_system(P):
    """docs/model.md R3 and its variational equations d' = Df(y) d (one deviation vector) in heyoka
    expressions (the Jacobian by heyoka's symbolic differentiation)."""
    import heyoka as hy
    y = hy.make_vars("p1", "p2", "M", "g1", "g2")
    d = hy.make_vars("d1", "d2", "d3", "d4", "d5")
    p1, p2, M, g1, g2 = y
    a1, a2, b, lam, chi, zeta, mu, xi, eta = (float(v) for v in P)
    w = M / b
    f = [w * (p2 - zeta) - mu * g1 - lam * p2 / a2,
         -w * (p1 - chi) - mu * g2 + lam * p1 / a1,
         (p1 - chi) * p2 / a2 - (p2 - zeta) * p1 / a1 - mu * (xi * g2 - eta * g1),
         w * g2,
         -w * g1]
    eqs = [(y[i], f[i]) for i in range(5)]
    for i in range(5):
        terms = [hy.diff(f[i], y[j]) * d[j] for j in range(5)]
        eqs.append((d[i], hy.sum(terms)))
    return eqs


def _hy_accumulate(acc, t0, t1, dlog):
    """kernels.tangent.accumulate on arrays of lanes (acc: (6, S))."""
    acc[0] += dlog
    acc[1] += 0.5 * (t0 + t1) * dlog
    y1 = 2.0 * acc[1] / t1
    acc[2] += 0.5 * (acc[4] + y1) * (t1 - t0)
    acc[4] = y1
    acc[5] = t1
    np.maximum(acc[3], acc[0], out=acc[3])


def heyoka_build(P, tol, simd):
    """The heyoka integrator (JIT-compiled here, once per process)."""
    import heyoka as hy
    init = np.zeros((10, simd))
    init[4] = -1.0
    init[5] = 1.0
    return hy.taylor_adaptive_batch(_hy_tangent_system(P), init, tol=tol)


def heyoka_megno(ta, Y0, V0, T):
    """<Y> of every orbit of Y0 with deviation vectors V0: batches of ``simd`` orbits, all lanes
    propagated to t = 1, 2, ..., T, the deviation renormalised after each time unit."""
    simd = int(ta.batch_size)
    N = Y0.shape[0]
    megno = np.full(N, np.nan)
    steps = np.zeros(N, np.int64)       # not counted (a Python loop per time unit would slow heyoka down)
    n_units = int(round(T))
    in_prop = 0.0
    t0 = time.perf_counter()
    for a in range(0, N, simd):
        b = min(a + simd, N)
        st = ta.state
        st[:5, :] = Y0[a][:, None]       # pad a short last batch with copies of its first orbit
        st[5:, :] = V0[a][:, None]
        st[:5, :b - a] = Y0[a:b].T
        st[5:, :b - a] = V0[a:b].T
        ta.set_time(np.zeros(simd))
        acc = np.zeros((6, simd))
        for k in range(1, n_units + 1):
            tp = time.perf_counter()
            ta.propagate_until(float(k))
            in_prop += time.perf_counter() - tp
            st = ta.state
            norm = np.sqrt(np.sum(st[5:] ** 2, axis=0))
            st[5:] /= norm
            _hy_accumulate(acc, float(k - 1), float(k), np.log(norm))
        megno[a:b] = (acc[2] / acc[5])[:b - a]
    return dict(megno=megno, steps=steps, elapsed=time.perf_counter() - t0, order=int(ta.order),
                in_propagate=in_prop)


def _hy_worker(P, Y0, V0, T, tol, simd, barrier, queue, tag):
    import heyoka as hy
    simd = simd or hy.recommended_simd_size()
    t0 = time.perf_counter()
    ta = heyoka_build(P, tol, simd)             # JIT build before the barrier (not timed)
    build = time.perf_counter() - t0
    barrier.wait()
    start = time.monotonic()
    out = heyoka_megno(ta, Y0, V0, T)
    end = time.monotonic()
    queue.put(dict(tag=tag, megno=out["megno"], steps=out["steps"], start=start, end=end,
                   build=build, order=out["order"], simd=simd, elapsed=out["elapsed"],
                   in_propagate=out["in_propagate"]))


def heyoka_processes(P, Y0, V0, T, tol, nproc=2, simd=None):
    """Y0 split over nproc spawned processes (orbit j to process j % nproc); the wall time is the
    latest end - the earliest start after a barrier (no process start, no JIT build)."""
    ctx = mp.get_context("spawn")
    barrier = ctx.Barrier(nproc)
    queue = ctx.Queue()
    parts = [np.arange(r, Y0.shape[0], nproc) for r in range(nproc)]
    T0 = time.monotonic()
    procs = [ctx.Process(target=_hy_worker, args=(np.asarray(P), Y0[idx], V0[idx], T, tol, simd, barrier,
                                                   queue, r)) for r, idx in enumerate(parts)]
    for p in procs:
        p.start()
    outs = [queue.get(timeout=3600) for _ in procs]
    for p in procs:
        p.join()
    total = time.monotonic() - T0
    megno = np.full(Y0.shape[0], np.nan)
    steps = np.zeros(Y0.shape[0], np.int64)
    for o in outs:
        megno[parts[o["tag"]]] = o["megno"]
        steps[parts[o["tag"]]] = o["steps"]
    wall = max(o["end"] for o in outs) - min(o["start"] for o in outs)
    share = sum(o["in_propagate"] for o in outs) / sum(o["elapsed"] for o in outs)
    return dict(megno=megno, steps=steps, wall=wall, total=total, build=max(o["build"] for o in outs),
                propagate_share=share,
                order=outs[0]["order"], simd=outs[0]["simd"])


# ----------------------------------------------------------------------------- 512 x 512
def run_megno_map_preset():
    """Time ``python -m explorer sweep megno_map`` (fresh store in a temporary directory)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "megno_map.h5"
        cmd = [sys.executable, "-m", "explorer", "sweep", "megno_map", "--out", str(out), "--figure",
               str(Path(tmp) / "megno_map"), "--quiet"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, cwd=str(C.ROOT), env=dict(os.environ))
        wall = time.perf_counter() - t0
    return dict(wall=wall)


def previous_512():
    if JSON_OUT.exists():
        try:
            return json.loads(JSON_OUT.read_text()).get("map512")
        except Exception:
            return None
    return None


# ----------------------------------------------------------------------------- main
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="update the CHAOS section of benchmarks/RESULTS.md")
    ap.add_argument("--skip-512", action="store_true", help="do not run the 512 x 512 preset (reuse the last number)")
    ap.add_argument("--quick", action="store_true", help="T = 100 and fewer repeats (a smoke test; not recorded)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--heyoka-batch", type=int, nargs="+", default=None, metavar="N",
                    help="heyoka batch sizes to time (default: heyoka.recommended_simd_size()); the ratio takes "
                         "the fastest")
    args = ap.parse_args(argv)
    from explorer import model
    from explorer.analysis import lyapunov
    started, load0, t_start = C.now(), C.loadavg(), time.perf_counter()
    T = 100.0 if args.quick else 1000.0
    repeats = 1 if args.quick else 3
    prm = model.FIGURE4.with_(mu=1.0)
    Y0 = polar_seeds(prm)
    V0 = lyapunov.deviation_vector(prm, Y0)
    doc: dict = {"T": T, "tol": TOL, "threshold": THRESHOLD}

    # 400-orbit map: explorer vs heyoka
    te, me, se = explorer_run(prm, Y0, T, args.threads, repeats)
    fe = float(np.mean(me > THRESHOLD))
    hy_runs = []
    batches = args.heyoka_batch or (None,)     # None: heyoka.recommended_simd_size()
    if C.have("heyoka"):
        for _ in range(1 if args.quick else 2):
            for b in batches:
                hy_runs.append(heyoka_processes(prm.as_array(), Y0, V0, T, TOL, nproc=2, simd=b))
        hy = min(hy_runs, key=lambda r: r["wall"])
        hy_runs = [r for r in hy_runs if r["simd"] == hy["simd"]]
        fh = float(np.mean(hy["megno"] > THRESHOLD))
        agree = float(np.mean((me > THRESHOLD) == (hy["megno"] > THRESHOLD)))
        doc["heyoka"] = dict(wall=[r["wall"] for r in hy_runs], fraction=fh, batches=[b for b in batches if b], agree=agree, order=hy["order"],
                             simd=hy["simd"],
                             propagate_share=hy["propagate_share"])
    doc["explorer400"] = dict(n=len(Y0), wall=te, fraction=fe, steps_mean=float(np.mean(se)))
    print(f"400-orbit map: explorer {te:.2f} s, chaotic {fe:.4f}", flush=True)
    if hy_runs:
        print(f"heyoka 2 processes: {[round(r['wall'], 2) for r in hy_runs]} s, chaotic {fh:.4f}, "
              f"ratio {hy['wall'] / te:.2f}, per-orbit agreement {agree:.4f}", flush=True)

    # the same comparison on a mixed phase space (mu = 0.03: islands and a stochastic layer), where
    # the chaotic fractions are a real test (at mu = 1 nearly every orbit is chaotic)
    if C.have("heyoka"):
        p3 = model.FIGURE4.with_(mu=0.03)
        Y3 = polar_seeds(p3)
        V3 = lyapunov.deviation_vector(p3, Y3)
        t3, m3, _ = explorer_run(p3, Y3, T, args.threads, repeats)
        h3 = min((heyoka_processes(p3.as_array(), Y3, V3, T, TOL, nproc=2, simd=b)
                  for _ in range(1 if args.quick else 2) for b in batches), key=lambda r: r["wall"])
        doc["compare003"] = dict(n=len(Y3), wall=t3, fraction=float(np.mean(m3 > THRESHOLD)), hy_wall=h3["wall"],
                                 hy_fraction=float(np.mean(h3["megno"] > THRESHOLD)),
                                 agree=float(np.mean((m3 > THRESHOLD) == (h3["megno"] > THRESHOLD))))
        print(f"mu = 0.03: {doc['compare003']}", flush=True)

    # the 316-cell raster of the same scene
    Yr = raster_seeds(prm, 20)
    tr, mr, _ = explorer_run(prm, Yr, T, args.threads, repeats)
    doc["raster316"] = dict(n=len(Yr), wall=tr, fraction=float(np.mean(mr > THRESHOLD)))

    # MEGNO orbits per second
    doc["rate"] = {}
    for mu in (0.03, 1.0):
        p = model.FIGURE4.with_(mu=mu)
        Ys = raster_seeds(p, 32)
        t, m, _ = explorer_run(p, Ys, T, args.threads, repeats)
        doc["rate"][f"{mu:g}"] = dict(n=len(Ys), wall=t, rate=len(Ys) / t, fraction=float(np.mean(m > THRESHOLD)))
        print(f"MEGNO mu = {mu:g}: {len(Ys) / t:.0f} orbits/s", flush=True)

    # time against T
    doc["vs_T"] = []
    for TT in ((25.0, 50.0, 100.0) if args.quick else (250.0, 500.0, 1000.0, 2000.0)):
        t, m, _ = explorer_run(prm, Y0, TT, args.threads, repeats)
        doc["vs_T"].append(dict(T=TT, wall=t, fraction=float(np.mean(m > THRESHOLD))))
        print(f"T = {TT:g}: {t:.3f} s", flush=True)

    # 512 x 512
    if args.skip_512 or args.quick:
        prev = previous_512()
        doc["map512"] = dict(prev, reused=True) if prev else None
    else:
        doc["map512"] = dict(run_megno_map_preset(), reused=False)
        print(f"512x512 megno_map: {doc['map512']['wall']:.1f} s", flush=True)

    seconds = time.perf_counter() - t_start
    lines = render(doc, started, seconds, load0, argv)
    print("\n".join(lines))
    if args.write and not args.quick:
        C.write_json(JSON_OUT, doc)
        C.update_section(SECTION, lines)
    return 0


def render(doc, started, seconds, load0, argv):
    head, _ = C.header("Chaos maps: tangent SIMD lanes against heyoka (issue 10)",
                       C.command_line("bench_chaos.py", argv), started, seconds, load0,
                       extra=["400-orbit map: mu = 1, h = 2, phi = pi, T = 1000, tol 1e-12, MEGNO, chaotic = <Y> > 4 "
                              "(scene default). A 20 x 20 raster over the bounding box of the allowed ellipse has "
                              "only 316 cells inside the allowed region, so the 400 orbits are a 20 x 20 polar grid "
                              "on the ellipse (equal-area radii, 0.98 of the semi-axes); the 316-cell raster is "
                              "timed too.",
                              "heyoka: taylor_adaptive_batch of state + one deviation vector (Jacobian by hy.diff), "
                              "batch = recommended SIMD size (or the fastest of the sizes --heyoka-batch names), "
                              "2 spawned processes (orbit j to process j % 2), "
                              "deviation renormalised every time unit and MEGNO accumulated with the explorer's "
                              "formulas over those units; wall = latest end - earliest start after a barrier "
                              "(no JIT build). Explorer: lyapunov.indicators, 2 Numba threads, renormalised and "
                              "accumulated every step; best of 3."])
    e = doc["explorer400"]
    lines = head + ["", "| run | orbits | wall time | rate | chaotic fraction |", "|---|---|---|---|---|",
                    f"| explorer, 400-orbit map, 2 threads | {e['n']} | {e['wall']:.2f} s | "
                    f"{e['n'] / e['wall']:.0f} orbits/s | {e['fraction']:.4f} |"]
    if doc.get("heyoka"):
        h = doc["heyoka"]
        w = min(h["wall"])
        tried = f" (fastest of batch sizes {', '.join(map(str, h['batches']))})" if h.get("batches") else ""
        lines.append(f"| heyoka batch (simd {h['simd']}, order {h['order']}){tried}, 2 processes | {e['n']} | {w:.2f} s "
                     f"(runs {', '.join(f'{x:.2f}' for x in h['wall'])}) | {e['n'] / w:.0f} orbits/s | "
                     f"{h['fraction']:.4f} |")
    c3 = doc.get("compare003")
    if c3:
        lines.append(f"| explorer, 400-orbit polar grid at mu = 0.03, 2 threads | {c3['n']} | {c3['wall']:.2f} s | "
                     f"{c3['n'] / c3['wall']:.0f} orbits/s | {c3['fraction']:.4f} |")
        lines.append(f"| heyoka batch, same grid at mu = 0.03, 2 processes | {c3['n']} | {c3['hy_wall']:.2f} s | "
                     f"{c3['n'] / c3['hy_wall']:.0f} orbits/s | {c3['hy_fraction']:.4f} |")
    r = doc["raster316"]
    lines.append(f"| explorer, 20x20 raster (cells inside the allowed region), 2 threads | {r['n']} | "
                 f"{r['wall']:.2f} s | {r['n'] / r['wall']:.0f} orbits/s | {r['fraction']:.4f} |")
    for mu, d in doc["rate"].items():
        lines.append(f"| explorer MEGNO, mu = {mu}, 32x32 raster, T = 1000 | {d['n']} | {d['wall']:.2f} s | "
                     f"{d['rate']:.0f} orbits/s | {d['fraction']:.4f} |")
    m5 = doc.get("map512")
    if m5:
        note = " (recorded by an earlier run: this run skipped it)" if m5.get("reused") else ""
        lines.append(f"| `python -m explorer sweep megno_map` (512x512, mu = 0.03, T = 1000, 205892 orbits, "
                     f"separatrices and figure){note} | 205892 | {m5['wall']:.1f} s | "
                     f"{205892 / m5['wall']:.0f} orbits/s | - |")
    if doc.get("heyoka"):
        h = doc["heyoka"]
        lines += ["", f"**Ratio heyoka / explorer on the 400-orbit map: {min(h['wall']) / e['wall']:.2f}x** "
                  f"(goal >= 3x); chaotic fractions {e['fraction']:.4f} (explorer) and {h['fraction']:.4f} "
                  f"(heyoka), difference {abs(e['fraction'] - h['fraction']):.4f} (goal <= 0.02); the same "
                  f"class per orbit for {h['agree']:.4f} of the orbits; mean Taylor steps per orbit of the "
                  f"explorer {e['steps_mean']:.0f}; heyoka spent "
                  f"{100 * h['propagate_share']:.0f} % of its time inside propagate_until (the rest: the Python "
                  "loop over time units, renormalisation and accumulation)."]
    if c3:
        lines += ["", f"At mu = 0.03 (same grid on the allowed ellipse, a mixed phase space): ratio "
                  f"{c3['hy_wall'] / c3['wall']:.2f}x, chaotic fractions {c3['fraction']:.4f} (explorer) and "
                  f"{c3['hy_fraction']:.4f} (heyoka), difference {abs(c3['fraction'] - c3['hy_fraction']):.4f}; "
                  f"the same class per orbit for {c3['agree']:.4f} of the orbits."]
    lines += ["", "Time against T (explorer, 400-orbit map, 2 threads):", "", "| T | wall time | chaotic fraction |",
              "|---|---|---|"]
    lines += [f"| {d['T']:g} | {d['wall']:.3f} s | {d['fraction']:.4f} |" for d in doc["vs_T"]]
    return lines


if __name__ == "__main__":
    sys.exit(main())
