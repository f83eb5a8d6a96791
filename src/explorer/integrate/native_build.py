"""Build the native library of :mod:`explorer.integrate.native`: the Taylor lane worker
(:func:`explorer.integrate.lanes.run_worker`) and the first block's carry
(:func:`explorer.integrate.drivers.start_carry`) compiled ahead of time into a shared library
that a process loads with ``ctypes``, without importing numba.

How (run as ``python -m explorer.integrate.native_build DEST``, in a process of its own):

1. numba compiles C-callable wrappers (``numba.cfunc``) of the two kernels and of
   :func:`~explorer.integrate.lanes.workspace_sizes`.  :func:`explorer.integrate.native.build`
   runs this with a numba cache of its own: the build goes on while the command that started
   it runs on numba, and two processes must not write one numba cache at once.
2. The optimised IR modules of the three wrappers are linked into one.  Every function the IR
   declares but does not define must be a C math or memory function (``ALLOWED_EXTERNALS``)
   or belong to numba's run time or the Python C API, reached only when a kernel raises or
   allocates: the kernels allocate nothing (the worker's buffers come from the caller) and
   raise nothing (status codes), so those are given bodies that call ``abort()``, and the
   library needs nothing but libc and libm.
3. The module is compiled for this CPU (numba's CPU name and features: the same machine code
   as numba's own), position-independent, and linked with the system C compiler
   (``$CC``, ``cc``, ``gcc`` or ``clang``).
4. Before it is installed the library proves itself: a lone orbit and a batch of orbits are
   integrated by the library and by numba in this process, and every output must be equal
   bit for bit.

The library and its description (``.json``: the key, the exported symbols, the build's
self-test) are written atomically; a failed build writes only the description, with the
reason, so that later runs do not try again until the key changes.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

#: functions the library may take from libc / libm (LLVM lowers its intrinsics to these)
ALLOWED_EXTERNALS = frozenset({
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "exp2", "expm1", "log",
    "log2", "log10", "log1p", "pow", "sqrt", "cbrt", "hypot", "fabs", "floor", "ceil", "trunc", "round", "fmod",
    "copysign", "fmin", "fmax", "ldexp", "frexp", "memset", "memcpy", "memmove", "abort"})
#: the exported functions: name in the description -> the Python function it wraps
SYMBOLS = ("lane_worker", "start_carry", "workspace_sizes")


def _wrappers():
    """The three C-callable wrappers (numba cfuncs)."""
    from numba import carray, cfunc, types

    from explorer.integrate import drivers, lanes
    from explorer.integrate._lanes_generated import LANES, NVAR
    from explorer.integrate.lanes import _N_NORMS as N_NORMS
    from explorer.kernels.events import ISOLATE_STACK, MAX_STEP_ROOTS

    i64 = types.int64
    i64p, f64p, bp = types.CPointer(types.int64), types.CPointer(types.float64), types.CPointer(types.boolean)

    # ia = (n, width, nlanes, direction, order, max_steps, npar, workspace sizes (8));
    # da = (cphi, sphi, tmax)
    @cfunc(i64(i64p, f64p, f64p, f64p, f64p, i64p, f64p, i64p, i64p, f64p, f64p, f64p, f64p, f64p, f64p, f64p,
               f64p, i64p, bp, i64p), error_model="numpy")
    def lane_worker(ia, da, y0p, pp, carryp, limp, crossp, countp, statusp, finalp, infop, xp, normsp, ynewp,
                    bracketsp, stackp, wfp, wip, wbp, nextp):
        n = ia[0]
        width = ia[1]
        order = ia[4]
        s = 7
        return lanes.run_worker(
            ia[2], carray(nextp, (1,)), carray(y0p, (n, NVAR)), carray(pp, (ia[6],)), da[0], da[1], ia[3], da[2],
            order, ia[5], carray(carryp, (n, drivers.N_CARRY)), carray(limp, (n, 2)),
            carray(crossp, (n, width, 5)), carray(countp, (n,)), carray(statusp, (n,)), carray(finalp, (n, NVAR)),
            carray(infop, (n, 3)), carray(xp, (order + 1, NVAR, LANES)), carray(normsp, (N_NORMS, LANES)),
            carray(ynewp, (NVAR, LANES)), carray(bracketsp, (MAX_STEP_ROOTS, 4)),
            carray(stackp, (ISOLATE_STACK, 5)), carray(wfp, (ia[s + 5],)), carray(wip, (ia[s + 6],)),
            carray(wbp, (ia[s + 7],)))

    @cfunc(i64(i64, f64p, f64p, i64, types.float64, types.float64, f64p), error_model="numpy")
    def start_carry(n, y0p, pp, npar, cphi, sphi, carryp):
        drivers.start_carry(carray(y0p, (n, NVAR)), carray(pp, (npar,)), cphi, sphi,
                            carray(carryp, (n, drivers.N_CARRY)))
        return 0

    @cfunc(i64(i64, i64p), error_model="numpy")
    def workspace_sizes(order, outp):
        lanes.workspace_sizes(order, carray(outp, (lanes.N_WORKSPACE,)))
        return 0

    return {"lane_worker": lane_worker, "start_carry": start_carry, "workspace_sizes": workspace_sizes}


_DECLARE = re.compile(r"^declare\s.*?@(\"[^\"]+\"|[\w.$]+)\(")
_GLOBAL_DECL = re.compile(r"^@(\"[^\"]+\"|[\w.$]+) = external (?:dso_local )?(global|constant) (.+?)(, align \d+)?$")


def _closed_ir(text: str) -> tuple[str, list[str]]:
    """The module's IR with every declaration outside ALLOWED_EXTERNALS given a body that calls
    abort() (functions) or a zero value (variables); returns (IR, names closed)."""
    out, closed = [], []
    need_abort = False
    for line in text.splitlines():
        m = _DECLARE.match(line)
        if m:
            name = m.group(1).strip('"')
            if name.startswith("llvm.") or name in ALLOWED_EXTERNALS:
                out.append(line)
                continue
            closed.append(name)
            need_abort = True
            sig = line[len("declare"):]
            sig = re.sub(r"\s#\d+\s*$", "", sig)            # attribute group of the declaration
            out.append("define internal" + re.sub(r"^\s*(?:dso_local\s+)?", " ", sig)
                       + " {\n  call void @abort()\n  unreachable\n}")
            continue
        g = _GLOBAL_DECL.match(line)
        if g:
            closed.append(g.group(1).strip('"'))
            out.append(f"@{g.group(1)} = internal {g.group(2)} {g.group(3)} zeroinitializer")
            continue
        out.append(line)
    if need_abort and not any(_DECLARE.match(x) and "@abort(" in x for x in out):
        out.append("declare void @abort()")
    return "\n".join(out) + "\n", closed


def _compiler() -> str | None:
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and shutil.which(cand.split()[0]):
            return cand
    return None


def _self_test(lib_path: str, symbols: dict) -> dict:
    """Run the library and numba side by side (a lone orbit, and 11 orbits on 3 lanes, in
    blocks, through two-root steps) and compare every output bit for bit."""
    from explorer import model
    from explorer.integrate import drivers, lanes, native
    from explorer.kernels.taylor_order import order_for_tolerance

    lib = native.Library(lib_path, symbols)
    prm = model.FIGURE4.with_(mu=0.5)
    P = np.ascontiguousarray(prm.as_array())
    rng = np.random.default_rng(7)
    cases = []
    y1 = model.section_state(prm, [0.5], [0.0], 2.0)
    cases.append((y1, 400, 1, 1e-12))
    ys = model.section_state(prm, rng.uniform(-0.6, 0.6, 11), rng.uniform(-0.3, 0.3, 11), 2.0)
    cases.append((ys, 37, 3, 1e-9))
    cphi, sphi = -1.0, 0.0
    checked = 0
    for Y0, K, nlanes, tol in cases:
        order = order_for_tolerance(tol)
        n = Y0.shape[0]
        c_lib = np.empty((n, drivers.N_CARRY))
        c_nb = np.empty((n, drivers.N_CARRY))
        lib.start_carry(Y0, P, cphi, sphi, c_lib)
        drivers.start_carry(Y0, P, cphi, sphi, c_nb)
        if c_lib.tobytes() != c_nb.tobytes():
            raise RuntimeError("self-test: start_carry differs from numba's")
        for block in (K, 7):
            outs = []
            for who in ("lib", "numba"):
                carry = (c_lib if who == "lib" else c_nb).copy()
                Y = Y0.copy()
                rows = []
                for _ in range(-(-K // block)):
                    limits = np.empty((n, 2), np.int64)
                    limits[:, 0] = block
                    limits[:, 1] = block + drivers.MAX_ROOTS_PER_STEP
                    width = block + drivers.MAX_ROOTS_PER_STEP
                    out = (np.full((n, width, 5), np.nan), np.zeros(n, np.int64), np.zeros(n, np.int64),
                           np.zeros((n, 5)), np.zeros((n, 3)))
                    args = (nlanes, np.zeros(1, np.int64), Y, P, cphi, sphi, 1, 100.0 * K, order, 10**9, carry,
                            limits) + out
                    if who == "lib":
                        lib.lane_worker(*args)
                    else:
                        lanes._run_worker(*args)
                    rows.append(b"".join(a.tobytes() for a in out))
                    Y = out[3].copy()
                outs.append(b"".join(rows) + carry.tobytes())
            if outs[0] != outs[1]:
                raise RuntimeError(f"self-test: the lane worker differs from numba's ({n} orbits, block {block})")
            checked += 1
    return {"cases": checked, "identical": True}


def build(dest_dir: str, key: str, identity: dict) -> dict:
    """Build the library for ``key`` into ``dest_dir``; returns its description (also written
    next to it).  Raises RuntimeError with the reason when it cannot be built."""
    import llvmlite.binding as llvm

    t0 = time.perf_counter()
    wrappers = _wrappers()
    names = {k: w.native_name for k, w in wrappers.items()}
    mods = [llvm.parse_assembly(str(w._library._final_module)) for w in wrappers.values()]
    mod = mods[0]
    for m in mods[1:]:
        mod.link_in(m)
    text, closed = _closed_ir(str(mod))
    mod = llvm.parse_assembly(text)
    mod.verify()
    undefined = sorted(f.name for f in mod.functions if f.is_declaration and not f.name.startswith("llvm.")
                       and f.name not in ALLOWED_EXTERNALS)
    if undefined:
        raise RuntimeError(f"the kernels call functions outside libc/libm: {', '.join(undefined)}")
    codegen = wrappers["lane_worker"]._library.codegen
    target = llvm.Target.from_triple(llvm.get_process_triple())
    from numba.core import config

    tm = target.create_target_machine(cpu=codegen._get_host_cpu_name(), features=codegen._tm_features,
                                      opt=config.OPT, reloc="pic", codemodel="default")
    obj = tm.emit_object(mod)
    cc = _compiler()
    if cc is None:
        raise RuntimeError("no C compiler to link it (set CC, or install cc, gcc or clang)")
    os.makedirs(dest_dir, exist_ok=True)
    base = os.path.join(dest_dir, f"explorer-native-{key[:16]}")
    with tempfile.TemporaryDirectory(dir=dest_dir) as tmp:
        o_path = os.path.join(tmp, "kernels.o")
        so_tmp = os.path.join(tmp, "kernels.so")
        with open(o_path, "wb") as f:
            f.write(obj)
        cmd = cc.split() + ["-shared", "-o", so_tmp, o_path, "-lm", "-Wl,-z,defs"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"linking failed ({' '.join(cmd)}): {r.stderr.strip()[-500:]}")
        test = _self_test(so_tmp, names)
        desc = {"key": key, "identity": identity, "symbols": names, "closed": closed, "self_test": test,
                "compiler": cc, "build_seconds": round(time.perf_counter() - t0, 2),
                "built": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "library": os.path.basename(base) + ".so"}
        os.replace(so_tmp, base + ".so")
    _write_json(base + ".json", desc)
    _prune(dest_dir)
    return desc


#: libraries kept in the directory (the newest; each source, numba or CPU change makes a new one)
KEEP = 8


def _prune(dest_dir: str) -> None:
    """Remove all but the KEEP newest libraries (and their descriptions) from ``dest_dir``."""
    from explorer.integrate.native import _PREFIX

    found = []
    for name in os.listdir(dest_dir):
        if name.startswith(_PREFIX) and name.endswith(".json"):
            path = os.path.join(dest_dir, name)
            found.append((os.path.getmtime(path), path[:-len(".json")]))
    for _mtime, base in sorted(found, reverse=True)[KEEP:]:
        for ext in (".so", ".json"):
            try:
                os.remove(base + ext)
            except OSError:
                pass


def _write_json(path: str, doc: dict) -> None:
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=1, sort_keys=True)
    os.replace(tmp, path)


def main(argv=None) -> int:
    from explorer.integrate import native

    argv = sys.argv[1:] if argv is None else argv
    dest = argv[0] if argv else native.library_dir()
    key, identity = native.key()
    try:
        desc = build(dest, key, identity)
    except Exception as exc:  # noqa: BLE001 - any failure is recorded, and the numba path stays
        desc = {"key": key, "identity": identity, "error": f"{type(exc).__name__}: {exc}",
                "built": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        os.makedirs(dest, exist_ok=True)
        _write_json(os.path.join(dest, f"explorer-native-{key[:16]}.json"), desc)
    finally:
        _clean_up()
    print(json.dumps(desc))
    return 0 if "error" not in desc else 1


def _clean_up() -> None:
    """Remove the lock and the numba cache that :func:`explorer.integrate.native.build` made for
    this build."""
    lock = os.environ.get("EXPLORER_NATIVE_LOCK")
    if lock:
        try:
            os.remove(lock)
        except OSError:
            pass
    if os.environ.get("EXPLORER_NATIVE_OWN_CACHE") == "1" and os.environ.get("NUMBA_CACHE_DIR"):
        shutil.rmtree(os.environ["NUMBA_CACHE_DIR"], ignore_errors=True)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
