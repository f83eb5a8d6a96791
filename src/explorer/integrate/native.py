"""A lone Taylor orbit without numba: the lane worker compiled ahead of time, loaded with ctypes.

A process that follows one orbit (``python -m explorer orbit ...``) spends more time starting
numba than integrating: importing numba and loading its cached kernels take about 0.4 s
(benchmarks/bench_long_orbit.py, section C).  This module runs the same machine code without
numba: :mod:`explorer.integrate.native_build` compiles the Taylor lane worker
(:func:`explorer.integrate.lanes.run_worker`) and the first block's carry
(:func:`explorer.integrate.drivers.start_carry`) into a shared library, once per machine and
source, and proves it bit for bit against numba before installing it.  Loading it takes a
millisecond.

When it is used (:func:`active`): for a Taylor batch of one orbit (the lane worker without the
parallel layer, as numba runs it) in a process that has not imported numba, on Linux, when
the library for the current key exists and ``EXPLORER_NATIVE`` is not ``0``.  Everything
else (several orbits on numba's threads, the other methods, chaos indicators, processes that
have numba loaded anyway) runs on numba.  The results are the same bit for bit either way
(the build's self-test; tests/integrate/test_native.py).

The key (:func:`key`) covers what the machine code depends on: the source of the compiled
packages (``explorer/integrate``, ``kernels``, ``model`` and ``_jit.py``), the installed numba
and llvmlite, the Python version and the CPU (model and feature flags): a library built
elsewhere, or for other sources, is never loaded.

Where: ``$EXPLORER_NATIVE_DIR``, else ``$NUMBA_CACHE_DIR/explorer-native``, else
``$XDG_CACHE_HOME/explorer/native`` (default ``~/.cache/explorer/native``).  Build it with
``python -m explorer native --build`` (``explorer orbit`` builds it when it is missing).

This module imports neither numba nor any compiled kernel.
"""
from __future__ import annotations

import ctypes
import hashlib
import json
import os
import platform
import sys
import time

import numpy as np

#: source trees compiled into the library (their bytes are in the key)
_SOURCES = ("integrate", "kernels", "model")
_PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_PREFIX = "explorer-native-"
#: entries of the lane worker's workspace sizes (lanes.N_WORKSPACE; the library checks it)
N_WORKSPACE = 8
#: alignment (bytes) of the work arrays: one cache line
ALIGN = 64

_c_void_p = ctypes.c_void_p
_c_int64 = ctypes.c_int64
_c_double = ctypes.c_double


def library_dir() -> str:
    """Where the library and its description are kept."""
    d = os.environ.get("EXPLORER_NATIVE_DIR")
    if d:
        return d
    d = os.environ.get("NUMBA_CACHE_DIR")
    if d:
        return os.path.join(d, "explorer-native")
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "explorer", "native")


def _cpu() -> str:
    """The CPU's vendor, model and feature flags (Linux: /proc/cpuinfo); '' when unknown."""
    try:
        with open("/proc/cpuinfo") as f:
            text = f.read(65536)
    except OSError:
        return ""
    first = text.split("\n\n", 1)[0]
    keep = [ln for ln in first.splitlines() if ln.split(":", 1)[0].strip() in
            ("vendor_id", "cpu family", "model", "model name", "flags", "Features", "CPU implementer", "CPU part")]
    return "\n".join(keep)


def _package_stamp(name: str) -> str:
    """path, size and mtime of an installed package's __init__.py (found without importing it)."""
    import importlib.util

    spec = importlib.util.find_spec(name)
    if spec is None or not spec.origin:
        return f"{name}: missing"
    st = os.stat(spec.origin)
    return f"{name}: {spec.origin} {st.st_size} {st.st_mtime_ns}"


def key() -> tuple[str, dict]:
    """(sha256 hex, what went into it) of the library this process would load."""
    h = hashlib.sha256()
    files = [os.path.join(_PKG, "_jit.py")]
    for sub in _SOURCES:
        d = os.path.join(_PKG, sub)
        files += sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(".py"))
    for path in files:
        h.update(os.path.relpath(path, _PKG).encode())
        with open(path, "rb") as f:
            h.update(f.read())
    source = h.hexdigest()
    identity = {"source": source, "numba": _package_stamp("numba"), "llvmlite": _package_stamp("llvmlite"),
                "python": sys.version.split()[0], "platform": f"{sys.platform} {platform.machine()}",
                "cpu": hashlib.sha256(_cpu().encode()).hexdigest()}
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest(), identity


def paths(k: str | None = None) -> tuple[str, str]:
    """(library, description) paths for key ``k`` (default: this process's key)."""
    k = _key()[0] if k is None else k
    base = os.path.join(library_dir(), _PREFIX + k[:16])
    return base + ".so", base + ".json"


def _ptr(a) -> int:
    return a.ctypes.data


class Library:
    """The loaded library: ``lane_worker`` and ``start_carry`` with the arguments of their
    numba twins (``lanes._run_worker``, ``drivers.start_carry``)."""

    def __init__(self, path: str, symbols: dict):
        self.path = path
        self._dll = ctypes.CDLL(path)
        self._worker = self._dll[symbols["lane_worker"]]
        self._worker.restype = _c_int64
        self._worker.argtypes = [_c_void_p] * 20
        self._start = self._dll[symbols["start_carry"]]
        self._start.restype = _c_int64
        self._start.argtypes = [_c_int64, _c_void_p, _c_void_p, _c_int64, _c_double, _c_double, _c_void_p]
        self._sizes = self._dll[symbols["workspace_sizes"]]
        self._sizes.restype = _c_int64
        self._sizes.argtypes = [_c_int64, _c_void_p]

    def workspace(self, order: int):
        """(sizes, zeroed work arrays) of the lane worker for ``order``: the five of
        ``lanes.WORKSPACE_ND`` and the flat float64, int64 and bool buffers."""
        n = np.zeros(N_WORKSPACE, np.int64)
        self._sizes(int(order), _ptr(n))
        arrays = [_aligned_zeros(int(k), np.float64) for k in n[:6]]
        arrays += [_aligned_zeros(int(n[6]), np.int64), _aligned_zeros(int(n[7]), np.bool_)]
        return n, arrays

    def start_carry(self, Y0, P, cphi, sphi, carry):
        _check(Y0=(Y0, np.float64), P=(P, np.float64), carry=(carry, np.float64))
        self._start(Y0.shape[0], _ptr(Y0), _ptr(P), P.shape[0], float(cphi), float(sphi), _ptr(carry))

    def lane_worker(self, nlanes, next_orbit, Y0, P, cphi, sphi, direction, tmax, order, max_steps, carry, limits,
                    out_cross, out_count, out_status, out_final, out_info):
        _check(next_orbit=(next_orbit, np.int64), Y0=(Y0, np.float64), P=(P, np.float64),
               carry=(carry, np.float64), limits=(limits, np.int64), out_cross=(out_cross, np.float64),
               out_count=(out_count, np.int64), out_status=(out_status, np.int64),
               out_final=(out_final, np.float64), out_info=(out_info, np.float64))
        sizes, work = self.workspace(order)
        n = Y0.shape[0]
        ia = np.concatenate([np.array([n, out_cross.shape[1], nlanes, direction, order, max_steps, P.shape[0]],
                                      np.int64), sizes])
        da = np.array([cphi, sphi, tmax], np.float64)
        return self._worker(_ptr(ia), _ptr(da), _ptr(Y0), _ptr(P), _ptr(carry), _ptr(limits), _ptr(out_cross),
                            _ptr(out_count), _ptr(out_status), _ptr(out_final), _ptr(out_info),
                            *(_ptr(a) for a in work), _ptr(next_orbit))


def _aligned_zeros(n: int, dtype) -> np.ndarray:
    """n zeros whose first element lies on a cache line (ALIGN bytes): the lanes load and store
    whole vectors of LANES doubles (64 bytes), which must not straddle two lines."""
    itemsize = np.dtype(dtype).itemsize
    raw = np.zeros(n * itemsize + ALIGN, np.uint8)
    skip = (-raw.ctypes.data) % ALIGN
    return raw[skip:skip + n * itemsize].view(dtype)


def _check(**arrays):
    """The C side reads raw memory: every array must be C-contiguous of the expected dtype."""
    for name, (a, dtype) in arrays.items():
        if not (isinstance(a, np.ndarray) and a.dtype == dtype and a.flags.c_contiguous):
            raise TypeError(f"native: {name} must be a C-contiguous {np.dtype(dtype).name} array")


_state: dict = {}
#: a build lock older than this (seconds) is left over from a killed build
LOCK_STALE = 600.0


def _key() -> tuple[str, dict]:
    """:func:`key`, computed once per process."""
    if "key" not in _state:
        _state["key"] = key()
    return _state["key"]


def describe() -> dict:
    """What :func:`active` sees: key, paths, the description of a built library (or the reason
    of a failed build), and whether the native path is enabled here."""
    k, identity = _key()
    so, js = paths(k)
    desc = None
    if os.path.exists(js):
        with open(js) as f:
            desc = json.load(f)
    return {"key": k, "identity": identity, "library": so, "built": os.path.exists(so), "description": desc,
            "enabled": enabled(), "directory": library_dir()}


def enabled() -> bool:
    """The native path may be used in this process at all (Linux, not switched off)."""
    return os.environ.get("EXPLORER_NATIVE", "1") != "0" and sys.platform.startswith("linux")


def active() -> Library | None:
    """The loaded library if this process uses it (decided once, at the first call): numba is
    not imported, the native path is enabled, and the library for the current key exists."""
    if "lib" in _state:
        return _state["lib"]
    lib = None
    if enabled() and "numba" not in sys.modules:
        try:
            so, js = paths(_key()[0])
            if os.path.exists(so):
                with open(js) as f:
                    desc = json.load(f)
                lib = Library(so, desc["symbols"])
        except (OSError, ValueError, KeyError, AttributeError, TypeError):
            lib = None       # a missing, partial or foreign file: numba's path instead
    _state["lib"] = lib
    return lib


def missing() -> bool:
    """The native path is enabled but has no library for the current key, no earlier build for
    it failed, and no other process is building it: :func:`build` should be run."""
    if not enabled():
        return False
    so, js = paths(_key()[0])
    if os.path.exists(so) or os.path.exists(js):
        return False
    lock = _lock_path()
    try:
        return time.time() - os.path.getmtime(lock) > LOCK_STALE
    except OSError:
        return True


def _lock_path() -> str:
    return paths(_key()[0])[0] + ".lock"


def build(wait: bool = True):
    """Build the library in a process of its own, with a numba cache of its own (every kernel
    compiled from source: about 10 s; no two processes write one numba cache at once).  Returns
    the running build (``wait=False``: pass it to :func:`finish_build`) or its exit status
    (0: built; 1: failed, the reason is in the description)."""
    import subprocess
    import tempfile

    os.makedirs(library_dir(), exist_ok=True)
    lock = _lock_path()
    with open(lock, "w") as f:
        f.write(str(os.getpid()))
    tmp = tempfile.mkdtemp(prefix="explorer-native-numba-")
    # the build removes its numba cache and the lock itself, even when the command that started
    # it is killed meanwhile
    env = dict(os.environ, NUMBA_CACHE_DIR=tmp, EXPLORER_NATIVE_DIR=library_dir(), EXPLORER_NATIVE_LOCK=lock,
               EXPLORER_NATIVE_OWN_CACHE="1")
    proc = subprocess.Popen([sys.executable, "-m", "explorer.integrate.native_build", library_dir()], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc.explorer_cleanup = (tmp, lock)
    if not wait:
        return proc
    return finish_build(proc)


def finish_build(proc) -> int:
    """Wait for a build started by :func:`build`; remove its numba cache and its lock."""
    import shutil

    proc.communicate()
    tmp, lock = proc.explorer_cleanup
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        os.remove(lock)
    except OSError:
        pass
    _state.pop("lib", None)
    return proc.returncode
