"""Shared fixtures.  ``tests/`` is put on sys.path so that tests can
``import reference`` (the independent numpy/scipy implementation of R3)."""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))

#: The tests write the bytecode of the modules they import, whatever PYTHONDONTWRITEBYTECODE says,
#: and so does every process they start (xdist's workers, the generic-CPU rerun, servers, commands):
#: each module is compiled by its first importer and read by the others, where without bytecode
#: every process compiled numpy, scipy, numba, Bokeh and Panel from source.  README's install
#: therefore compiles none (uv's --compile-bytecode compiled every installed module, most of them
#: never imported: benchmarks/RESULTS.md, "README's test command").
sys.dont_write_bytecode = False
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)

#: The thread tests compare 1 and 2 Numba threads.  Numba launches at most NUMBA_NUM_THREADS
#: (default: the number of cores), so on a one-core machine a request for 2 could not be met;
#: ask for at least 2 before numba is imported (2 threads on one core are time-sliced, and
#: tests/test_stress.py::test_two_numba_threads_really_run asserts that both ran).
if int(os.environ.get("NUMBA_NUM_THREADS", "0") or 0) < 2:
    os.environ["NUMBA_NUM_THREADS"] = str(max(2, os.cpu_count() or 1))

#: Numba's parallel regions run on GNU OpenMP here (numba.threading_layer() == "omp"), whose idle
#: threads spin after each region unless told to wait passively: with two xdist workers on two
#: cores, one worker's spinning threads took the CPU the other's tests wanted (the quick periodic
#: figure: 12-13 CPU-s spinning, 9 passive).  Results do not depend on it; every process the tests
#: start (servers, commands, the generic-CPU rerun) inherits it.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from explorer import model  # noqa: E402

#: the browser modules' shared Chromium and default server (tests/app/browser_session.py), and the
#: generic-CPU rerun that README's test command runs beside the suite (tests/generic_cpu.py, --rerun-cpu-dependent)
pytest_plugins = ("app.browser_session", "generic_cpu")


def pytest_configure(config):
    """A test run started as a background job of a non-interactive shell (``cmd &``) inherits
    SIGINT ignored, and so would every process it starts: the Ctrl-C tests (tests/app/
    test_interrupt.py, the servers') would then test the launcher, not the program.  Python's own
    SIGINT handler is put back in every pytest process (controller and xdist workers); the
    programs the tests start inherit the default action."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)

#: Figure-4 scene (docs/model.md R9) and asymmetric sets (chi, zeta, xi, eta != 0, lam < 0).
PARAM_SETS = {
    "figure4_mu0.5": model.FIGURE4.with_(mu=0.5),
    "asym_lam_neg": model.Params(a1=1.3, a2=0.6, b=1.7, lam=-0.8, chi=0.2, zeta=-0.15, mu=0.7, xi=0.3, eta=-0.25),
    "asym_lam_pos": model.Params(a1=0.8, a2=1.4, b=2.5, lam=1.6, chi=-0.3, zeta=0.25, mu=1.2, xi=-0.2, eta=0.4),
}


@pytest.fixture(params=sorted(PARAM_SETS))
def param_set(request):
    return request.param, PARAM_SETS[request.param]


def random_states(params, n, seed=0, scale=1.0):
    """Random physical states (p1, p2, M, sin phi, cos phi)."""
    rng = np.random.default_rng(seed)
    y = np.empty((n, 5))
    y[:, :3] = scale * rng.normal(size=(n, 3))
    phi = rng.uniform(0, 2 * np.pi, n)
    y[:, 3] = np.sin(phi)
    y[:, 4] = np.cos(phi)
    return y


def assert_threads_and_order_keep_the_bits(run, n, seed=0):
    """``run(perm)`` runs the lane driver on the orbits in the order ``perm`` (an index array of n)
    and returns its output arrays: on 1 and 2 threads, in the given and in a permuted order, every
    array equals that of one thread in the given order bit for bit (np.array_equal on the bytes,
    rows put back in order)."""
    from explorer._jit import get_num_threads, set_num_threads

    ident = np.arange(n)
    perm = np.random.default_rng(seed).permutation(n)
    old = get_num_threads()
    try:
        set_num_threads(1)
        ref = run(ident)
        for threads, order in ((1, perm), (2, ident), (2, perm)):
            set_num_threads(threads)
            got = run(order)
            for a, b in zip(ref, got):
                assert np.array_equal(a.view(np.uint8), b[np.argsort(order)].view(np.uint8)), threads
    finally:
        set_num_threads(old)


def pytest_sessionstart(session):
    """Compile the kernels of the package's default paths once, before any test starts
    subprocesses or joblib workers: they then load the kernels from numba's on-disk cache instead
    of compiling the same functions concurrently (concurrent writers of one cache entry are a
    known numba hazard, and a cold cache is what CI starts with).  Under pytest-xdist (README's
    `-n 2`) this runs in the controller before it starts the workers (xdist starts them in its
    own `pytest_sessionstart`, which runs after this one), and the workers load from the cache.

    Two processes at once (this one and a second), each running its jobs of :data:`WARM_PLAN`,
    so that neither core waits."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    import subprocess
    import time

    t0 = time.perf_counter()
    _drop_a_stale_kernel_cache()
    first, here, there = WARM_PLAN["taylor" if session.config.option.markexpr.strip() == "cpu_dependent" else "all"]
    warm_kernels(*first)
    other = subprocess.Popen([sys.executable, "-c", f"import conftest; conftest.warm_kernels(*{there!r})"],
                             cwd=os.path.dirname(__file__), stdin=subprocess.DEVNULL)
    try:
        warm_kernels(*here)
    finally:
        if other.wait() != 0:
            raise RuntimeError(f"compiling the kernels {there} before the tests failed (see above)")
    _PHASES["kernels loaded or compiled before the tests"] = time.perf_counter() - t0


#: more orbits than one lane group of either worker holds: the batch then runs the parallel lane
#: driver with the CPU's default lane groups (lanes.worker_lanes), as every sweep does
WARM_BATCH = 40

#: The warm-up's plan: (the jobs run first, alone; then the jobs of this process, while a second
#: process runs the last ones), each job one call of a default path on a tiny problem
#: (:func:`warm_kernels`).  ``taylor orbit`` compiles the callees that every Taylor kernel shares
#: (the field's Taylor coefficients, the event roots, the clock), so the other Taylor jobs come
#: after it in either process; the DOP853 and splitting paths share little with it.  Compile
#: times measured one by one on 2 cores (AMD EPYC, cold cache): taylor orbit 9-13 s, taylor
#: batch 9, fixed point 3, taylor indicators 22, other methods (DOP853 and split4, crossings and
#: indicators, one orbit each) 20.
#:
#: - the whole suite (``all``): the taylor orbit here while the other methods compile there
#:   (20 s, so the orbit's callees are in the cache before the second process reaches its Taylor
#:   batch; were they not, it would compile them once more, which costs time, not correctness),
#:   then the Taylor indicators here: 34-35 s in all, where the orbit alone first and then two
#:   processes took 40-42 s (cold, on an idle machine).
#: - the generic-CPU rerun (``-m cpu_dependent``, tests/generic_cpu.py): its tests run only
#:   Taylor paths (a run of them with no warm-up compiled no DOP853 or splitting kernel), so the
#:   taylor orbit alone first, then the rest in two processes: 24-27 s against 32.
WARM_PLAN = {
    "all": ((), ("taylor orbit", "taylor indicators"), ("other methods", "taylor batch", "fixed point")),
    "taylor": (("taylor orbit",), ("taylor batch", "fixed point"), ("taylor indicators",)),
}


def warm_kernels(*jobs: str) -> None:
    """Run the default paths once on tiny problems, compiling (or loading) their kernels: each of
    ``jobs`` a name of WARM_PLAN's jobs."""
    from explorer.analysis import fixedpoints, lyapunov, sections

    prm = model.FIGURE4.with_(mu=0.1)
    one = model.section_state(prm, [0.2], [0.1], 2.0)
    batch = model.section_state(prm, np.linspace(-0.3, 0.3, WARM_BATCH), np.zeros(WARM_BATCH), 2.0)

    def crossings(*runs):
        for y0, method in runs:
            sections.crossings(prm, states=y0, n_crossings=1, method=method, tol=1e-10, dt=0.05)

    def indicators(*runs):
        for y0, method in runs:
            lyapunov.indicators(prm, states=y0, tmax=1.0, method=method, tol=1e-10, dt=0.05)

    table = {
        "taylor orbit": lambda: crossings((one, "taylor")),
        "taylor batch": lambda: crossings((batch, "taylor")),
        "fixed point": lambda: fixedpoints.find_fixed_point(model.FIGURE4, 2.0),
        "taylor indicators": lambda: indicators((one, "taylor"), (batch, "taylor")),
        "other methods": lambda: (crossings((one, "dop853"), (one, "split4")),
                                  indicators((one, "dop853"), (one, "split4"))),
    }
    for job in jobs:
        if job not in table:
            raise ValueError(f"warm-up job must be one of {tuple(table)}, got {job!r}")
        table[job]()


def _drop_a_stale_kernel_cache() -> None:
    """Numba invalidates a cached kernel only when its own source file changes: a kernel that
    inlines or calls one from another file keeps the old callee (a developer's warm cache failed
    19 tests of tests/integrate/test_lanes.py after kernels/taylor.py changed, while a fresh cache
    passed).  So the tests start from a cache written by this tree's sources: a stamp (a hash of
    every .py that may shape a kernel, :func:`_may_shape_a_kernel`) is kept beside the cached
    kernels, and when it differs they are removed first.  Only the package's own entries go:
    numba's files beside the sources (__pycache__/*.nbi, *.nbc) or, with NUMBA_CACHE_DIR, its
    per-directory subfolders there (named ``<dir>_<sha1 of the directory's path>`` by numba).  CI
    and a fresh install start with an empty cache and lose nothing."""
    import hashlib
    import shutil
    from pathlib import Path

    import explorer

    pkg = Path(os.path.abspath(explorer.__file__)).parent
    dirs = sorted({p.parent for p in pkg.rglob("*.py")})
    digest = hashlib.sha256()
    for p in sorted(pkg.rglob("*.py")):
        if _may_shape_a_kernel(pkg, p):
            digest.update(p.relative_to(pkg).as_posix().encode() + b"\0" + p.read_bytes())
    key = digest.hexdigest()
    cache = os.environ.get("NUMBA_CACHE_DIR")
    stamp = Path(cache) / "explorer-sources.sha256" if cache else pkg / "__pycache__" / "explorer-sources.sha256"
    if stamp.is_file() and stamp.read_text() == key:
        return
    for d in dirs:
        if cache:
            shutil.rmtree(Path(cache) / f"{d.name}_{hashlib.sha1(os.path.abspath(d).encode()).hexdigest()}",
                          ignore_errors=True)
        else:
            for f in (d / "__pycache__").glob("*.nb[ic]"):
                f.unlink(missing_ok=True)
    stamp.parent.mkdir(parents=True, exist_ok=True)
    stamp.write_text(key)


#: the folders whose every module may be compiled into a kernel or read by one (a global's value is
#: frozen into the kernel that reads it): the layers below analysis
KERNEL_LAYERS = ("kernels", "model", "integrate")


def _may_shape_a_kernel(pkg, path) -> bool:
    """``path`` may change what a cached kernel computes: it is in :data:`KERNEL_LAYERS` or it
    compiles kernels itself.  The stamp covers these files only, so that editing the page or the
    docs of an analysis does not throw away every compiled kernel."""
    rel = path.relative_to(pkg).parts
    return rel[0] in KERNEL_LAYERS or rel[0] == "_jit.py" or b"njit" in path.read_bytes()


#: seconds of the phases of a run that no test's duration shows (printed at the end, docs/tests.md)
_PHASES: dict = {}


def pytest_terminal_summary(terminalreporter):
    for what, seconds in _PHASES.items():
        terminalreporter.write_line(f"{what}: {seconds:.1f} s")


#: The tests whose outcome rests on a search, a threshold or a classification (periodic orbits,
#: fixed points and continuation, rotation numbers, early stop, chaotic fractions, the atlas,
#: homoclinic points and turnstiles, the figures' classifications) are marked
#: ``@pytest.mark.cpu_dependent`` one by one: results may move in the last bits between CPUs,
#: so the suite asserts properties and tolerances, and README's test command runs these tests a
#: second time with Numba compiling for NUMBA_CPU_NAME=generic (docs/tests.md, "Across machines").
