"""SERVE: latency of `explorer serve` in a real browser (issue 22).

Starts `python -m explorer serve --mu 0.03 --crossings 10000` on a free loopback port, opens it in
Debian's headless chromium (Playwright, no `playwright install`), clicks once to load the kernels
(a warm process, as the issue asks), clears, then clicks REPEATS times at different points of the
section and measures, in the page (polled every animation frame):

- click -> first crossings of the orbit in the page's data source (drawn at that frame);
- click -> 10,000 crossings of the orbit in it.

Times include Playwright's round trip (a few ms).  Usage: python benchmarks/bench_serve.py [REPEATS]
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
N = 10_000
READY = ("() => window.Bokeh && Bokeh.documents.length > 0 && "
         "Bokeh.index.all_views().some(v => v.model.name === 'section')")
TO_SCREEN = """([x, y]) => { const v = Bokeh.index.all_views().find(v => v.model.name === 'section');
  const r = v.el.getBoundingClientRect();
  return [r.left + v.frame.x_scale.compute(x), r.top + v.frame.y_scale.compute(y)]; }"""
COUNT = "() => Bokeh.documents[0].get_model_by_name('crossings').data.p1.length"


def main(repeats: int = 5) -> None:
    from playwright.sync_api import sync_playwright

    from explorer import model

    c1, c2, r1, r2 = model.allowed_ellipse(model.FIGURE4.with_(mu=0.03), 2.0)
    proc = subprocess.Popen([sys.executable, "-m", "explorer", "serve", "--port", "0", "--mu", "0.03",
                             "--crossings", str(N)], stdout=subprocess.PIPE, text=True)
    url = proc.stdout.readline().strip()
    try:
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM, args=ARGS,
                                                       headless=True, viewport={"width": 1100, "height": 800})
            page = ctx.new_page()
            page.goto(url)
            page.wait_for_function(READY, timeout=120_000)
            page.mouse.click(*page.evaluate(TO_SCREEN, [c1, c2 + 0.5 * r2]))        # warm up
            page.wait_for_function(f"() => ({COUNT})() >= {N}", timeout=600_000)
            page.get_by_role("button", name="Clear").click()
            page.wait_for_function(f"() => ({COUNT})() === 0", timeout=60_000)
            first, full = [], []
            for i in range(repeats):
                u = -0.8 + 1.6 * i / max(repeats - 1, 1)
                xy = page.evaluate(TO_SCREEN, [c1 + u * r1, c2 + 0.1 * r2])
                before = page.evaluate(COUNT)
                t0 = time.perf_counter()
                page.mouse.click(*xy)
                page.wait_for_function(f"() => ({COUNT})() > {before}", polling="raf", timeout=120_000)
                first.append(time.perf_counter() - t0)
                page.wait_for_function(f"() => ({COUNT})() >= {before + N}", polling="raf", timeout=600_000)
                full.append(time.perf_counter() - t0)
                page.wait_for_timeout(400)           # the next click is not a double tap
            ctx.close()
    finally:
        proc.terminate()
        proc.wait()
    print(f"SERVE ({repeats} clicks, mu = 0.03, taylor tol 1e-13, warm server)")
    print(f"  click -> first crossings on screen: median {1e3 * statistics.median(first):.0f} ms "
          f"(min {1e3 * min(first):.0f}, max {1e3 * max(first):.0f})")
    print(f"  click -> {N} crossings on screen:  median {statistics.median(full):.2f} s "
          f"(min {min(full):.2f}, max {max(full):.2f})")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
