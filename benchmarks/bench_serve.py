"""SERVE: latency of `explorer serve` in a real browser (issue 22).

Starts `python -m explorer serve --mu 0.03 --crossings 10000` on a free loopback port, opens it in
Debian's headless chromium (Playwright, no `playwright install`), clicks once to load the kernels
(a warm process, as the issue asks), clears, then clicks REPEATS times at different points of the
section and measures, in the page (polled every animation frame):

- click -> first crossings of the orbit in the page's data source (seen at an animation frame);
- click -> those first crossings painted: two animation frames later (the frame that draws them
  has ended: Bokeh repaints on the frame after a change), the time the issue's 100 ms is about;
- click -> 10,000 crossings of the orbit in the data source, and painted.

Times include Playwright's round trips (a few ms each; the painted times two of them, so they
err on the slow side).  Usage: python benchmarks/bench_serve.py [REPEATS]
[--breakdown] [--empty] [--megno]

``--megno`` measures the MEGNO layer instead (docs/commands/serve.md, "Chaos layer"): per repeat, a
page opened with the layer on, adaptive (``megno=1``) and exact (``megno=exact``) in turn, waits for
its raster of the whole window, then zooms in with the wheel at a point of the section and
measures the time from the wheel to the final (128^2) raster of the new window in the page, and
the server process's CPU seconds meanwhile; both modes zoom at the same points, so their windows
are the same.  It reports the medians and the exact / adaptive ratios, and the share of the final
rasters' cells of the same class (<Y> > 4).

``--empty`` clears the page before each click: every orbit is clicked on an empty section
(the latency of a first click), instead of beside the 0 to 40,000 crossings of the clicks before.

``--breakdown`` also runs the server through ``benchmarks/_serve_trace.py`` and prints where each
click's time goes (medians), from the click's pointerdown in the page: to the server's Tap
callback, to the worker's block, to the block streamed into the document, to the rows in the
page's data source (the browser's side: the message, and the redraws it is busy with), and to the
first crossings painted (two animation frames after they are seen, as above).  Server and
page times are both wall-clock times of this machine (a few ms apart at most).
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
N = 10_000
READY = ("() => window.Bokeh && Bokeh.documents.length > 0 && "
         "Bokeh.index.all_views().some(v => v.model.name === 'section')")
TO_SCREEN = """([x, y]) => { const v = Bokeh.index.all_views().find(v => v.model.name === 'section');
  const r = v.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)]; }"""
#: resolves when two animation frames have begun: the frame painting the last change has ended
FRAMES = "() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(0))))"
#: rows of the page: in ``crossings``, and the newest in ``live`` (drawn on the overlay canvas)
COUNT = ("() => { const d = Bokeh.documents[0];"
        " return d.get_model_by_name('crossings').data.p1.length + d.get_model_by_name('live').data.p1.length; }")
#: --breakdown: the page notes its pointerdowns and, every animation frame, when the rows arrive
CLICKS = ("window.__clicks = []; document.addEventListener('pointerdown', "
          "() => window.__clicks.push(performance.timeOrigin + performance.now()), true);")
WATCH = """([before, n]) => { const rows = %s; window.__seen = [0, 0, 0];
  const now = () => performance.timeOrigin + performance.now();
  function f() { const c = rows(), t = now();
    if (!__seen[0] && c > before) {
      __seen[0] = t;      // painted: the start of the second frame after (the frame drawing them has ended)
      requestAnimationFrame(() => requestAnimationFrame(() => { __seen[2] = now(); }));
    }
    if (c >= before + n) { __seen[1] = t; return; }
    requestAnimationFrame(f); }
  requestAnimationFrame(f); }""" % COUNT


def main(repeats: int = 5, breakdown: bool = False, empty: bool = False) -> None:
    from playwright.sync_api import sync_playwright

    from explorer import model

    c1, c2, r1, r2 = model.allowed_ellipse(model.FIGURE4.with_(mu=0.03), 2.0)
    command, env = [sys.executable, "-m", "explorer", "serve"], None
    if breakdown:
        trace = tempfile.mktemp(suffix=".log")
        command, env = [sys.executable, str(Path(__file__).with_name("_serve_trace.py"))], dict(os.environ,
                                                                                              SERVE_TRACE=trace)
    proc = subprocess.Popen([*command, "--port", "0", "--mu", "0.03", "--crossings", str(N)], stdout=subprocess.PIPE,
                            text=True, env=env)
    clicks, seen = [], []
    url = proc.stdout.readline().strip()
    try:
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM, args=ARGS,
                                                       headless=True, viewport={"width": 1100, "height": 800})
            page = ctx.new_page()
            if breakdown:
                page.add_init_script(CLICKS)
            page.goto(url)
            page.wait_for_function(READY, timeout=120_000)
            page.mouse.click(*page.evaluate(TO_SCREEN, [c1, c2 + 0.5 * r2]))        # warm up
            page.wait_for_function(f"() => ({COUNT})() >= {N}", timeout=600_000)
            first, full, first_drawn, full_drawn = [], [], [], []
            for i in range(repeats):
                if i == 0 or empty:                   # (after the warm-up: always)
                    page.get_by_role("button", name="Clear").click()
                    page.wait_for_function(f"() => ({COUNT})() === 0", timeout=60_000)
                    page.wait_for_timeout(400)        # (the click is not a double tap)
                u = -0.8 + 1.6 * i / max(repeats - 1, 1)
                xy = page.evaluate(TO_SCREEN, [c1 + u * r1, c2 + 0.1 * r2])
                before = page.evaluate(COUNT)
                if breakdown:
                    page.evaluate(WATCH, [before, N])
                t0 = time.perf_counter()
                page.mouse.click(*xy)
                page.wait_for_function(f"() => ({COUNT})() > {before}", polling="raf", timeout=120_000)
                first.append(time.perf_counter() - t0)
                page.evaluate(FRAMES)
                first_drawn.append(time.perf_counter() - t0)
                page.wait_for_function(f"() => ({COUNT})() >= {before + N}", polling="raf", timeout=600_000)
                full.append(time.perf_counter() - t0)
                page.evaluate(FRAMES)
                full_drawn.append(time.perf_counter() - t0)
                if breakdown:
                    page.wait_for_function("() => window.__seen[1] > 0 && window.__seen[2] > 0", timeout=60_000)
                    clicks.append(page.evaluate("() => window.__clicks[window.__clicks.length - 1]") / 1e3)
                    seen.append([t / 1e3 for t in page.evaluate("() => window.__seen")])
                page.wait_for_timeout(400)           # the next click is not a double tap
            ctx.close()
    finally:
        proc.terminate()
        proc.wait()
    print(f"SERVE ({repeats} clicks, mu = 0.03, taylor tol 1e-13, warm server"
          + (", each on an empty section)" if empty else ", each beside the orbits of the clicks before)"))
    print(f"  click -> first crossings in the page: median {1e3 * statistics.median(first):.0f} ms "
          f"(min {1e3 * min(first):.0f}, max {1e3 * max(first):.0f})")
    print(f"  click -> first crossings painted:    median {1e3 * statistics.median(first_drawn):.0f} ms "
          f"(min {1e3 * min(first_drawn):.0f}, max {1e3 * max(first_drawn):.0f})")
    print(f"  click -> {N} crossings in the page: median {statistics.median(full):.2f} s "
          f"(min {min(full):.2f}, max {max(full):.2f})")
    print(f"  click -> {N} crossings painted:     median {statistics.median(full_drawn):.2f} s "
          f"(min {min(full_drawn):.2f}, max {max(full_drawn):.2f})")
    if breakdown:
        print_breakdown(trace, clicks, seen)


#: the MEGNO layer's raster: its data, and the figure's ranges
RASTER = "Bokeh.documents[0].get_model_by_name('raster').data"
RANGES = ("() => { const f = Bokeh.documents[0].get_model_by_name('section');"
          " return [f.x_range.start, f.x_range.end, f.y_range.start, f.y_range.end]; }")
#: the final raster of the figure's window is in the page
FINAL = (f"([n]) => {{ const r = ({RANGES})(); const d = {RASTER}; return d.n.length > 0 && d.n[0] === n && "
         "d.complete[0] && d.x[0] === r[0] && Math.abs(d.x[0] + d.dw[0] - r[1]) < 1e-12 && d.y[0] === r[2]; }")
#: the first raster of the figure's window is complete (or a finer one is on)
FIRST = (f"() => {{ const r = ({RANGES})(); const d = {RASTER}; return d.n.length > 0 && (d.n[0] > 16 || "
         "d.complete[0]) && d.x[0] === r[0] && Math.abs(d.x[0] + d.dw[0] - r[1]) < 1e-12 && d.y[0] === r[2]; }")
#: points of the section (in units of the region's half axes) the wheel zooms in at
ZOOMS = ((0.0, 0.0), (0.55, 0.05), (-0.3, 0.45), (0.2, -0.5), (-0.6, -0.1))


def _cpu(pid: int) -> float:
    """CPU seconds (user + system) of process ``pid`` so far, all its threads."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def megno_zoom(repeats: int = 3, n: int = 128) -> None:
    """--megno: the MEGNO layer's final raster after a zoom, adaptive and exact in one run."""
    import numpy as np
    from playwright.sync_api import sync_playwright

    from explorer import model

    c1, c2, r1, r2 = model.allowed_ellipse(model.FIGURE4.with_(mu=0.03), 2.0)
    proc = subprocess.Popen([sys.executable, "-m", "explorer", "serve", "--port", "0", "--mu", "0.03"],
                            stdout=subprocess.PIPE, text=True)
    url = proc.stdout.readline().strip()
    sep = "&" if "?" in url else "?"
    times: dict = {"adaptive": [], "exact": []}
    cpus: dict = {"adaptive": [], "exact": []}
    same, firsts = [], []
    try:
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM, args=ARGS,
                                                       headless=True, viewport={"width": 1100, "height": 800})
            for i in range(repeats + 1):                      # (the first: warm-up, not counted)
                u, v = ZOOMS[(i - 1) % len(ZOOMS)]
                modes = ("adaptive", "exact") if i % 2 else ("exact", "adaptive")
                finals = []
                for mode in modes:
                    page = ctx.new_page()
                    page.goto(f"{url}{sep}megno={'exact' if mode == 'exact' else '1'}")
                    page.wait_for_function(READY, timeout=120_000)
                    page.wait_for_function(FINAL, arg=[n], timeout=600_000)       # the whole window's raster
                    page.mouse.move(*page.evaluate(TO_SCREEN, [c1 + u * r1, c2 + v * r2]))
                    before = page.evaluate(RANGES)
                    cpu0, t0 = _cpu(proc.pid), time.perf_counter()
                    page.mouse.wheel(0, -400)
                    page.wait_for_function(f"() => ({RANGES})()[0] !== {before[0]!r}", timeout=60_000)
                    page.wait_for_function(FIRST, polling="raf", timeout=600_000)
                    first = time.perf_counter() - t0
                    page.wait_for_function(FINAL, arg=[n], timeout=600_000)
                    wall, cpu = time.perf_counter() - t0, _cpu(proc.pid) - cpu0
                    finals.append((page.evaluate(RANGES), np.array(page.evaluate(f"() => Array.from({RASTER}"
                                                                                ".image[0])"), float)))
                    page.close()
                    if i:
                        times[mode].append(wall)
                        cpus[mode].append(cpu)
                        firsts.append(first)
                assert finals[0][0] == finals[1][0], (finals[0][0], finals[1][0])     # the same window
                x0, x1, y0, y1 = finals[0][0]
                print(f"  zoom {i}{'' if i else ' (warm-up)'} at ({u:+.2f}, {v:+.2f}) of the half axes: window "
                      f"p1 {x0:.4f}..{x1:.4f}, p2 {y0:.4f}..{y1:.4f}" + (f"; exact {times['exact'][-1]:.2f} s, "
                      f"{cpus['exact'][-1]:.2f} CPU-s; adaptive {times['adaptive'][-1]:.2f} s, "
                      f"{cpus['adaptive'][-1]:.2f} CPU-s" if i else ""), flush=True)
                inside = np.isfinite(finals[1][1])
                if i:
                    same.append(float(np.mean((finals[0][1][inside] > 4) == (finals[1][1][inside] > 4))))
            ctx.close()
    finally:
        proc.terminate()
        proc.wait()
    med = {m: (statistics.median(times[m]), statistics.median(cpus[m])) for m in times}
    print(f"SERVE MEGNO layer ({repeats} zooms, mu = 0.03, {n}^2, T = 200, warm server, load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    for m in ("exact", "adaptive"):
        print(f"  wheel -> final raster, {m:<8}: median {med[m][0]:.2f} s wall (min {min(times[m]):.2f}, max "
              f"{max(times[m]):.2f}), {med[m][1]:.2f} CPU-s of the server (min {min(cpus[m]):.2f}, max "
              f"{max(cpus[m]):.2f})")
    print(f"  exact / adaptive: {med['exact'][0] / med['adaptive'][0]:.2f}x wall, "
          f"{med['exact'][1] / med['adaptive'][1]:.2f}x CPU (medians); per zoom: "
          + ", ".join(f"{e / a:.2f}x" for e, a in zip(cpus["exact"], cpus["adaptive"])) + " CPU")
    print(f"  wheel -> the new window's first (16^2) raster, both modes: median {statistics.median(firsts):.2f} s "
          f"(min {min(firsts):.2f}, max {max(firsts):.2f}): the part of the wall time the modes share")
    print(f"  cells of the same class (<Y> > 4): {', '.join(f'{100 * x:.2f} %' for x in same)}")


def print_breakdown(trace: str, clicks: list, seen: list) -> None:
    """Medians (ms) of the steps of each click, from the server's trace and the page's times."""
    events = []
    for line in Path(trace).read_text().splitlines():
        t, *what = line.split()
        events.append((float(t), what))
    steps: dict = {}

    def note(name, value):
        steps.setdefault(name, []).append(1e3 * value)

    for i, (down, (first, full, painted)) in enumerate(zip(clicks, seen)):
        end = clicks[i + 1] if i + 1 < len(clicks) else float("inf")
        mine = [(t, w) for t, w in events if down <= t < end]
        tap = next(t for t, w in mine if w[0] == "tap")
        block = next(t for t, w in mine if w[0] == "block" and t >= tap)
        flush = next(t for t, w in mine if w[0] == "flush" and t >= block)
        last = next(t for t, w in mine if w[0] == "block" and w[3] != "running" and t >= tap)
        last_flush = next(t for t, w in mine if w[0] == "flush" and t >= last)
        note("first: pointerdown -> server's Tap callback", tap - down)
        note("first: Tap callback -> first block handed in", block - tap)
        note("first: -> streamed into the document", flush - block)
        note("first: -> in the page's data source", first - flush)
        note("first: total (in the page)", first - down)
        note("first: total (painted, in the page's clock)", painted - down)
        note(f"{N}: pointerdown -> last block handed in", last - down)
        note(f"{N}: -> streamed into the document", last_flush - last)
        note(f"{N}: -> in the page's data source", full - last_flush)
        note(f"{N}: total (in the page)", full - down)
        steps.setdefault(f"{N}: messages with crossings (count)", []).append(
            sum(1 for t, w in mine if w[0] == "flush" and tap <= t <= last_flush))
    print(f"  breakdown (medians of {len(clicks)} clicks, ms; load average {os.getloadavg()[0]:.1f}):")
    for name, values in steps.items():
        print(f"    {name:<52} {statistics.median(values):7.1f}  ({min(values):.1f}-{max(values):.1f})")


if __name__ == "__main__":
    numbers = [a for a in sys.argv[1:] if not a.startswith("--")]
    if "--megno" in sys.argv[1:]:
        megno_zoom(int(numbers[0]) if numbers else 3)
        sys.exit(0)
    main(int(numbers[0]) if numbers else 5, breakdown="--breakdown" in sys.argv[1:], empty="--empty" in sys.argv[1:])
