"""The rerun of the tests marked ``cpu_dependent`` beside the suite (README's test command).

The tests marked ``cpu_dependent`` (tests/conftest.py) are run a second time with Numba compiling
for a generic x86-64 CPU, in a kernel cache of its own, so that the suite proves their searches,
thresholds and classifications on a CPU without AVX or FMA too (docs/tests.md, "Across
machines").  README's command asks for it with the rerun's environment::

    python -m pytest -q -n 2 --dist loadscope \
        --rerun-cpu-dependent "NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic"

which runs, beside the suite, what was run after it before (the same command, alone)::

    NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic python -m pytest -q -n 2 --dist loadscope -m cpu_dependent

The suite starts it itself, at its own start, as a child process at the lowest CPU priority
(niceness :data:`NICENESS`): it then runs on the CPU time the suite leaves idle (about a tenth
of both cores: tests that wait for a browser, a throttled socket, a server's start or a killed
process), and the suite's processes, the servers and the browser the timing tests measure
included, are served first whenever they want a core.  At the suite's end its controller waits
for the rerun, fails the session if the rerun failed, and prints the rerun's output under a
header of its own after the suite's last line (benchmarks/RESULTS.md: what it adds to README's
command).

A test marked ``cpu_dependent`` therefore runs starved of CPU for minutes at a time: none may
assert on wall-clock time (a budget of seconds, a speed).  Its outcome rests on the numbers only.
"""
from __future__ import annotations

import fnmatch
import functools
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

#: the option that asks for the rerun; its value: the rerun's environment, ``NAME=VALUE`` assignments
#: separated by spaces (README: Numba's target CPU and an on-disk cache of its own; a relative path
#: is the rootdir's, where the rerun runs)
OPTION = "--rerun-cpu-dependent"
#: the rerun's niceness (POSIX: 19 is the lowest priority): it takes only the CPU the suite leaves idle
NICENESS = 19
#: the marker of the tests it runs
MARKER = "cpu_dependent"
#: the longest the suite's end waits for the rerun (s): a bound on a hang, not a speed goal
TIMEOUT = 3600.0
#: pytest's exit code when no test was selected: the paths given hold no cpu_dependent test
NO_TESTS = 5

_RERUN: dict = {}


def pytest_addoption(parser):
    parser.addoption(OPTION, metavar="ASSIGNMENTS", default=None,
                     help=f"also run the tests marked {MARKER}, beside the suite at the lowest CPU priority, with "
                          'these environment variables, e.g. "NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic" '
                          "(tests/generic_cpu.py)")


def _environment(value: str) -> dict:
    """The rerun's environment variables from the option's value; a clear error for anything but
    NAME=VALUE assignments."""
    words = shlex.split(value)
    bad = [w for w in words if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=.*", w)]
    if not words or bad:
        raise pytest.UsageError(f"{OPTION} takes NAME=VALUE environment assignments separated by spaces, "
                                f'e.g. "NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic"; got {value!r}')
    return dict(w.split("=", 1) for w in words)


@functools.cache
def _names_the_marker(path: Path) -> bool:
    return MARKER in path.read_text(encoding="utf-8", errors="replace")


def _marked_files(config) -> list:
    """This run's paths, narrowed to the test files that name MARKER: the rerun collects only these
    (collecting all the suite's modules, to deselect all but 93 of 3310 tests, took about 5
    CPU-s in each of its workers).  A test is marked in its own file, by a decorator or
    ``pytestmark``; :func:`pytest_collection_modifyitems` holds every run to that."""
    patterns = config.getini("python_files")
    out = []
    for arg in config.args:
        path = Path(str(arg).split("::")[0])
        if path.is_file():
            files = [path]
        else:
            files = sorted(f for f in path.rglob("*.py") if any(fnmatch.fnmatch(f.name, p) for p in patterns))
        out += [str(arg) if f == path else str(f) for f in files if _names_the_marker(f)]   # (a node id kept)
    return out


def _argv(config, files) -> list:
    """The rerun's command line: the files given, this run's workers, the tests marked MARKER only."""
    mark = config.option.markexpr.strip()
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
            "-m", f"{MARKER} and ({mark})" if mark else MARKER]
    workers = getattr(config.option, "numprocesses", None)
    if workers:
        argv += ["-n", str(workers), "--dist", config.option.dist]
    return argv + files


def pytest_collection_modifyitems(config, items):
    """Every test marked MARKER is in a file that names it, where the rerun looks for it (a mark
    given by a hook elsewhere would be missed by the rerun without a word)."""
    missed = sorted({str(item.path) for item in items
                     if item.get_closest_marker(MARKER) is not None and not _names_the_marker(Path(item.path))})
    if missed:
        raise pytest.UsageError(f"tests marked {MARKER} outside a file that names the marker (the rerun of "
                                f"{OPTION}, tests/generic_cpu.py, would not run them): {missed}")


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """Start the rerun before the suite's own warm-up, so that it compiles its kernels on whatever
    CPU that warm-up leaves (not on xdist's workers: only the controller, or a run without -n)."""
    config = session.config
    value = config.getoption(OPTION)
    if value is None or os.environ.get("PYTEST_XDIST_WORKER"):
        return
    assignments = _environment(value)
    _RERUN["title"] = f"rerun of the {MARKER} tests with {' '.join(f'{k}={v}' for k, v in assignments.items())}"
    files = _marked_files(config)
    if not files:
        _RERUN["status"] = "not run: no file under the paths given names the marker"
        return
    out = tempfile.TemporaryFile("w+", encoding="utf-8", errors="replace")
    # a process group of its own, so that its end ends every process it started, but not a session
    # of its own: Linux's autogroup scheduling weighs each session as one, and a niceness counts
    # only against the processes of its session (in a session of its own, the rerun took half the
    # CPU: the suite's warm-up 80 s against 35)
    group = ({} if not hasattr(os, "setpgrp") else {"process_group": 0} if sys.version_info >= (3, 11)
             else {"preexec_fn": os.setpgrp})
    proc = subprocess.Popen(_argv(config, files), cwd=config.rootpath, env=dict(os.environ, **assignments),
                            stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, **group)
    # (set from here, right after it starts: the child spends its first fraction of a second
    # importing pytest, before it starts any process of its own, which inherit the niceness)
    if hasattr(os, "setpriority"):
        os.setpriority(os.PRIO_PROCESS, proc.pid, NICENESS)
    _RERUN.update(proc=proc, out=out, started=time.perf_counter(), files=len(files))


def _stop(proc) -> None:
    """End the rerun and every process it started (its own process group)."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (AttributeError, ProcessLookupError, PermissionError):    # (no process groups off POSIX)
            proc.kill()
        proc.wait()


@pytest.hookimpl(tryfirst=True)
def pytest_sessionfinish(session, exitstatus):
    """Wait for the rerun (stop it if the suite was interrupted) and fail the session if it failed."""
    proc = _RERUN.get("proc")
    if proc is None:
        return
    if exitstatus == pytest.ExitCode.INTERRUPTED:
        _stop(proc)
        _RERUN["status"] = "stopped: the suite was interrupted"
        return
    waited = time.perf_counter()
    try:
        proc.wait(TIMEOUT)
    except subprocess.TimeoutExpired:
        _stop(proc)
        _RERUN["status"] = f"stopped after {TIMEOUT:.0f} s"
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
        return
    now = time.perf_counter()
    _RERUN["status"] = (f"exit code {proc.returncode}, {now - _RERUN['started']:.1f} s from the suite's start, "
                        f"{now - waited:.1f} s of them after the suite's end")
    if proc.returncode not in (0, NO_TESTS) and session.exitstatus == pytest.ExitCode.OK:
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


@pytest.hookimpl(tryfirst=True)
def pytest_unconfigure(config):
    """Report the rerun after the suite's own last line (so that a run's last lines say how it
    ended): its output under a header, then its status.  An internal error or a crash of the
    session still ends it."""
    if "title" not in _RERUN:
        return
    proc, out = _RERUN.get("proc"), _RERUN.get("out")
    if proc is not None:
        _stop(proc)
    status = _RERUN.get("status", "stopped: the session ended before it")
    tr = config.pluginmanager.get_plugin("terminalreporter")
    if tr is not None:
        if out is not None:
            tr.write_sep("=", f"{_RERUN['title']} ({_RERUN['files']} test files)")
            out.seek(0)
            tr.write(out.read())
        tr.write_line(f"{_RERUN['title']}: {status}")
    if out is not None:
        out.close()
    _RERUN.clear()
