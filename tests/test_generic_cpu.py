"""README's test command runs the tests marked cpu_dependent a second time, for a generic CPU, beside
the suite (tests/generic_cpu.py, ``--rerun-cpu-dependent``): that rerun must run those tests and only them,
with Numba's generic target and a cache of its own, at the lowest priority, and a failure in it
must fail the command.  Proved on a throwaway suite of three tests in a pytest of its own."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import generic_cpu
import pytest

#: README's rerun: Numba's generic CPU, a cache of its own
RERUN = "NUMBA_CPU_NAME=generic NUMBA_CACHE_DIR=.numba-generic"
TITLE = "rerun of the cpu_dependent tests with " + RERUN

TESTS = Path(__file__).resolve().parent
#: the longest a throwaway run may take (s): a bound on a hang.  Its rerun is niced to 19 beside
#: a suite that keeps both cores busy, so its second of work may take a minute or more of wall
THROWAWAY_TIMEOUT = 900.0

SUITE = '''
import os, pytest

def _record(name):
    with open(os.environ["RECORD"], "a") as f:
        f.write(f"{name} {os.environ.get('NUMBA_CPU_NAME', '-')} {os.environ.get('NUMBA_CACHE_DIR', '-')} "
                f"{os.getpriority(os.PRIO_PROCESS, 0)} {os.getsid(0)}\\n")

@pytest.mark.cpu_dependent
def test_marked():
    _record("marked")
    assert not (os.environ.get("FAIL_ON_GENERIC") and os.environ.get("NUMBA_CPU_NAME") == "generic")

def test_not_marked():
    _record("not_marked")
'''


#: a file with no marked test: the rerun must not even import it (it collects the files that name the marker)
UNMARKED = """
import os
with open(os.environ["RECORD"], "a") as f:
    f.write(f"imported {os.environ.get('NUMBA_CPU_NAME', '-')}\\n")

def test_elsewhere():
    pass
"""


def _run(tmp_path, fail_on_generic, conftest='pytest_plugins = ("generic_cpu",)\n', rerun=RERUN):
    (tmp_path / "conftest.py").write_text(conftest)
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n    cpu_dependent: marked\n")
    (tmp_path / "test_throwaway.py").write_text(SUITE)
    (tmp_path / "test_unmarked.py").write_text(UNMARKED)
    record = tmp_path / "record.txt"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST", "NUMBA_CPU", "NUMBA_CACHE"))}
    env.update(PYTHONPATH=str(TESTS), RECORD=str(record), FAIL_ON_GENERIC="1" if fail_on_generic else "")
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", generic_cpu.OPTION, rerun],
                       cwd=tmp_path, env=env, capture_output=True, text=True,
                       timeout=THROWAWAY_TIMEOUT)
    return r, sorted(record.read_text().splitlines()) if record.exists() else []


@pytest.mark.skipif(not hasattr(os, "setpriority"), reason="niceness is POSIX")
def test_the_rerun_runs_the_marked_tests_for_the_generic_cpu_at_the_lowest_priority(tmp_path):
    r, runs = _run(tmp_path, fail_on_generic=False)
    assert r.returncode == 0, r.stdout + r.stderr
    # the rerun in this session (Linux weighs each session as one: a niceness counts only within it)
    own, sid = os.getpriority(os.PRIO_PROCESS, 0), os.getsid(0)
    cache = ".numba-generic"                     # (as given: the rerun runs in the rootdir)
    assert runs == sorted([f"marked - - {own} {sid}", f"not_marked - - {own} {sid}", "imported -",
                           f"marked generic {cache} {max(own, generic_cpu.NICENESS)} {sid}"]), runs
    assert f"= {TITLE} (1 test files)" in r.stdout and f"{TITLE}: exit code 0" in r.stdout


def test_a_marked_test_failing_only_for_the_generic_cpu_fails_the_command(tmp_path):
    r, runs = _run(tmp_path, fail_on_generic=True)
    assert r.returncode == pytest.ExitCode.TESTS_FAILED, r.stdout + r.stderr
    suite, rerun = r.stdout.split(f"= {TITLE} (", 1)
    assert "3 passed" in suite and "1 failed" in rerun and "test_marked" in rerun
    assert f"{TITLE}: exit code 1" in rerun


def test_a_test_marked_from_outside_its_file_is_refused_where_the_rerun_would_miss_it(tmp_path):
    """The rerun collects the files that name the marker; a mark given by a hook elsewhere (here
    conftest.py marking test_unmarked.py's test) would escape it, so every run refuses it."""
    hook = ('import pytest\npytest_plugins = ("generic_cpu",)\n\n'
            '@pytest.hookimpl(tryfirst=True)\ndef pytest_collection_modifyitems(items):\n'
            '    for item in items:\n        if item.name == "test_elsewhere":\n'
            '            item.add_marker("cpu_dependent")\n')
    r, _runs = _run(tmp_path, fail_on_generic=False, conftest=hook)
    assert r.returncode == pytest.ExitCode.USAGE_ERROR, r.stdout + r.stderr
    assert "test_unmarked.py" in r.stderr and generic_cpu.OPTION in r.stderr


@pytest.mark.parametrize("value", ["", "generic", "NUMBA_CPU_NAME", "1X=generic"])
def test_a_rerun_environment_that_is_not_name_value_assignments_is_refused_naming_the_option(tmp_path, value):
    r, runs = _run(tmp_path, fail_on_generic=False, rerun=value)
    assert r.returncode == pytest.ExitCode.USAGE_ERROR and runs == [], r.stdout + r.stderr
    assert generic_cpu.OPTION in r.stderr and "NAME=VALUE" in r.stderr
