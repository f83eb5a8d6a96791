"""The native library of lone Taylor orbits (explorer.integrate.native): built once here into a
directory of its own, it must give numba's results bit for bit, be used only where it should,
never be loaded when it was built for something else, and leave numba's path working whenever
it is missing, broken or switched off."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from explorer import model
from explorer.integrate import drivers, lanes, native, native_build
from explorer.kernels.taylor_order import order_for_tolerance

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the native path is Linux only")


@pytest.fixture(scope="module")
def native_dir(tmp_path_factory):
    """A library built by the command line into a fresh directory (the build's own self-test
    runs too: it refuses to install a library that differs from numba)."""
    if native_build._compiler() is None:
        pytest.skip("no C compiler to link the native library (orbits run on numba)")
    d = tmp_path_factory.mktemp("native")
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(d))
    r = subprocess.run([sys.executable, "-m", "explorer", "native", "--build", "--json"], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    doc = json.loads(r.stdout)
    assert doc["built"] and doc["description"]["self_test"]["identical"]
    return d, doc


@pytest.fixture(scope="module")
def library(native_dir):
    d, doc = native_dir
    return native.Library(doc["library"], doc["description"]["symbols"])


def _outputs(n, width):
    return (np.full((n, width, 5), np.nan), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros((n, 5)),
            np.zeros((n, 3)))


@pytest.mark.parametrize("nlanes, tol, block", [(1, 1e-12, 500), (3, 1e-9, 13), (8, 1e-15, 64)])
def test_lane_worker_is_numbas_bit_for_bit(library, nlanes, tol, block):
    """Blocks of crossings, final states, statuses, times, step counts and carries of the native
    worker equal numba's, for one lane and for several orbits sharing lanes, across blocks."""
    prm = model.FIGURE4.with_(mu=0.7)
    P = np.ascontiguousarray(prm.as_array())
    rng = np.random.default_rng(3)
    n = 1 if nlanes == 1 else 2 * nlanes + 1
    Y0 = model.section_state(prm, rng.uniform(-0.6, 0.6, n), rng.uniform(-0.3, 0.3, n), 2.0)
    order = order_for_tolerance(tol)
    cphi, sphi = -1.0, 0.0
    runs = {}
    for who, worker, start in (("native", library.lane_worker, library.start_carry),
                               ("numba", lanes._run_worker, drivers.start_carry)):
        carry = np.empty((n, drivers.N_CARRY))
        start(Y0, P, cphi, sphi, carry)
        Y = Y0.copy()
        got = [carry.copy()]
        for _ in range(4):
            limits = np.empty((n, 2), np.int64)
            limits[:, 0] = block
            limits[:, 1] = block + drivers.MAX_ROOTS_PER_STEP
            out = _outputs(n, block + drivers.MAX_ROOTS_PER_STEP)
            worker(nlanes, np.zeros(1, np.int64), Y, P, cphi, sphi, 0, 1e6, order, 10**9, carry, limits, *out)
            got += list(out) + [carry.copy()]
            Y = out[3].copy()
        runs[who] = got
    assert runs["native"][-5].min() > 0           # every orbit crossed the section in the last block
    for a, b in zip(runs["native"], runs["numba"]):
        assert a.tobytes() == b.tobytes()


def test_stops_and_budgets_match_numba(library):
    """The orbit's budgets end it the same way on both (time budget, step budget)."""
    prm = model.FIGURE4.with_(mu=0.5)
    P = np.ascontiguousarray(prm.as_array())
    Y0 = model.section_state(prm, [0.5], [0.0], 2.0)
    for tmax, max_steps, status in ((30.0, 10**9, drivers.STATUS_TMAX), (1e6, 77, drivers.STATUS_MAX_STEPS)):
        res = []
        for worker, start in ((library.lane_worker, library.start_carry), (lanes._run_worker, drivers.start_carry)):
            carry = np.empty((1, drivers.N_CARRY))
            start(Y0, P, -1.0, 0.0, carry)
            out = _outputs(1, 100)
            limits = np.array([[90, 100]], np.int64)
            worker(1, np.zeros(1, np.int64), Y0, P, -1.0, 0.0, 1, tmax, 15, max_steps, carry, limits, *out)
            res.append(b"".join(a.tobytes() for a in out) + carry.tobytes())
            assert out[2][0] == status
        assert res[0] == res[1]


def test_library_rejects_arrays_it_cannot_read(library):
    Y0 = np.zeros((1, 5), np.float32)
    with pytest.raises(TypeError, match="Y0 must be a C-contiguous float64"):
        library.start_carry(Y0, np.zeros(9), -1.0, 0.0, np.zeros((1, 6)))


def test_work_arrays_are_cache_line_aligned(library):
    _sizes, work = library.workspace(15)
    assert all(a.ctypes.data % native.ALIGN == 0 for a in work)
    assert native.N_WORKSPACE == lanes.N_WORKSPACE and native.ALIGN == lanes.ALIGN
    for n in (1, 7, 64):
        assert lanes.aligned_zeros(n).ctypes.data % lanes.ALIGN == 0


def test_workspace_views_tile_the_buffers():
    """The 1-D work arrays cut from the flat buffers neither overlap nor leave a gap."""
    for order in (4, 15, 40):
        n = np.zeros(lanes.N_WORKSPACE, np.int64)
        lanes.workspace_sizes(order, n)
        wf, wi, wb = np.zeros(n[5]), np.zeros(n[6], np.int64), np.zeros(n[7], np.bool_)
        views = lanes.workspace_views(order, wf, wi, wb)
        assert len(views) == len(lanes.WORKSPACE_F) + len(lanes.WORKSPACE_I) + len(lanes.WORKSPACE_B)
        for buf in (wf, wi, wb):
            mine = [v for v in views if v.base is buf or np.shares_memory(v, buf)]
            assert sum(v.size for v in mine) == buf.size
            cover = np.zeros(buf.size, int)
            for v in mine:
                start = (v.ctypes.data - buf.ctypes.data) // buf.itemsize
                cover[start:start + v.size] += 1
            assert np.all(cover == 1)


def _orbit(env, *extra):
    cmd = [sys.executable, "-m", "explorer", "orbit", "--p1", "0.5", "--p2", "0", "--mu", "0.5", "--tol", "1e-12",
           "--crossings", "700", "--block", "300", "--json", *extra]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)


_PROBE = r"""
import sys
from explorer import model
from explorer.analysis import sections
from explorer.integrate import native
prm = model.FIGURE4.with_(mu=0.5)
c = sections.section_crossings(prm, [0.5], [0.0], 2.0, 50, tol=1e-12)
print(native.active() is not None, "numba" in sys.modules, repr(c.data[0, -1].tolist()))
"""


def test_orbit_command_uses_it_without_numba_and_prints_numbas_rows(native_dir):
    d, _doc = native_dir
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(d))
    fast = _orbit(env)
    slow = _orbit(dict(env, EXPLORER_NATIVE="0"))
    assert fast.returncode == 0 and slow.returncode == 0, fast.stderr + slow.stderr
    assert fast.stdout == slow.stdout
    assert len(json.loads(fast.stdout)["crossings"]) == 700
    used = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=600)
    off = subprocess.run([sys.executable, "-c", _PROBE], env=dict(env, EXPLORER_NATIVE="0"), capture_output=True,
                         text=True, timeout=600)
    assert used.stdout.split()[:2] == ["True", "False"], used.stdout + used.stderr    # no numba at all
    assert off.stdout.split()[:2] == ["False", "True"], off.stdout + off.stderr
    assert used.stdout.split(" ", 2)[2] == off.stdout.split(" ", 2)[2]


def test_streamed_store_is_the_same_with_and_without_it(native_dir, tmp_path):
    from explorer.io import store

    d, _doc = native_dir
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(d))
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    assert _orbit(env, "--out", str(a)).returncode == 0
    assert _orbit(dict(env, EXPLORER_NATIVE="0"), "--out", str(b)).returncode == 0
    pa, pb = store.read_store(str(a)).panels[0], store.read_store(str(b)).panels[0]
    assert pa.crossings.tobytes() == pb.crossings.tobytes() and pa.count[0] == 700


def test_library_for_another_key_is_never_loaded(native_dir, tmp_path, monkeypatch):
    """A library is found by its key: after a source change (a copied tree with one byte more)
    the key differs and nothing is loaded."""
    d, doc = native_dir
    pkg = tmp_path / "explorer"
    pkg_src = os.path.dirname(native.__file__).rsplit(os.sep, 1)[0]
    for sub in ("integrate", "kernels", "model"):
        (pkg / sub).mkdir(parents=True)
        for f in os.listdir(os.path.join(pkg_src, sub)):
            if f.endswith(".py"):
                (pkg / sub / f).write_bytes(open(os.path.join(pkg_src, sub, f), "rb").read())
    (pkg / "_jit.py").write_bytes(open(os.path.join(pkg_src, "_jit.py"), "rb").read())
    monkeypatch.setattr(native, "_PKG", str(pkg))
    assert native.key()[0] == doc["key"]
    (pkg / "kernels" / "taylor.py").write_text((pkg / "kernels" / "taylor.py").read_text() + "\n")
    assert native.key()[0] != doc["key"]


def test_broken_or_failed_library_falls_back_to_numba(tmp_path, monkeypatch):
    """A garbage file where the library should be, or a recorded failed build: not loaded, not
    rebuilt in a loop, and the orbit runs on numba."""
    monkeypatch.setenv("EXPLORER_NATIVE_DIR", str(tmp_path))
    monkeypatch.setattr(native, "_state", {})
    so, js = native.paths()
    assert native.missing()
    with open(js, "w") as f:
        json.dump({"key": "x", "error": "RuntimeError: no C compiler"}, f)
    assert not native.missing()                       # a failed build is not retried by every run
    with open(so, "wb") as f:
        f.write(b"not a shared library")
    monkeypatch.delitem(sys.modules, "numba", raising=False)      # (put back by monkeypatch)
    assert native.active() is None
    monkeypatch.undo()
    assert "numba" in sys.modules
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(tmp_path))
    r = _orbit(env)
    assert r.returncode == 0 and len(json.loads(r.stdout)["crossings"]) == 700, r.stderr
    assert os.path.getsize(so) == len(b"not a shared library")      # left alone, not rebuilt


def test_process_with_numba_keeps_numba(native_dir, monkeypatch):
    """Once numba is loaded, its compiled kernels are as fast: one path per process."""
    d, _doc = native_dir
    monkeypatch.setenv("EXPLORER_NATIVE_DIR", str(d))
    monkeypatch.setattr(native, "_state", {})
    assert "numba" in sys.modules and native.active() is None


def test_closed_ir_gives_runtime_calls_an_aborting_body():
    ir = "\n".join([
        "declare double @llvm.pow.f64(double, double)",
        "declare double @exp(double)",
        "declare ptr @NRT_MemInfo_alloc_aligned(i64, i32) local_unnamed_addr #3",
        "@PyExc_RuntimeError = external global ptr",
        "define double @f(double %x) {",
        "  %y = call double @exp(double %x)",
        "  ret double %y",
        "}",
    ])
    out, closed = native_build._closed_ir(ir)
    assert closed == ["NRT_MemInfo_alloc_aligned", "PyExc_RuntimeError"]
    assert "declare double @llvm.pow.f64" in out and "declare double @exp(double)" in out
    assert "define internal ptr @NRT_MemInfo_alloc_aligned(i64, i32) local_unnamed_addr {" in out
    assert "call void @abort()" in out and "declare void @abort()" in out
    assert "@PyExc_RuntimeError = internal global ptr zeroinitializer" in out
    import llvmlite.binding as llvm

    llvm.parse_assembly(out).verify()


def test_native_command_reports_missing_and_switched_off(tmp_path):
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(tmp_path))
    r = subprocess.run([sys.executable, "-m", "explorer", "native"], env=env, capture_output=True, text=True)
    assert r.returncode == 0 and "not built yet" in r.stdout
    r = subprocess.run([sys.executable, "-m", "explorer", "native", "--build"], env=dict(env, EXPLORER_NATIVE="0"),
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("explorer: error:") and "Traceback" not in r.stderr


def test_unwritable_library_directory_leaves_the_orbit_on_numba(tmp_path):
    """No place to build the library (a file where its directory should be): the orbit runs on
    numba and prints its rows, no traceback."""
    blocker = tmp_path / "not_a_dir"
    blocker.write_text("x")
    env = dict(os.environ, EXPLORER_NATIVE_DIR=str(blocker / "native"))
    r = _orbit(env)
    assert r.returncode == 0 and len(json.loads(r.stdout)["crossings"]) == 700, r.stderr
    assert "Traceback" not in r.stderr
