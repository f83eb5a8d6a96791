"""CPU time per test: a pytest plugin, and the summary of what it wrote (docs/tests.md, "Time").

Run README's test command with it::

    PYTHONPATH=tools CPU_PER_TEST=/tmp/cpu python -m pytest -q -n 2 --dist loadscope -p pytest_cpu
    python tools/pytest_cpu.py /tmp/cpu          # CPU per module, largest first

Each process (the xdist controller and each worker) writes ``<CPU_PER_TEST>/<worker>.json``:
{test id: [own CPU s, children's CPU s, wall s]} and ``__total__``.  Children's CPU is what
``getrusage(RUSAGE_CHILDREN)`` gained during the test: a child's CPU counts once it is reaped,
so a server or browser started by a fixture shows on the test during which it ended (or on the
next test that starts a process: ``subprocess`` reaps finished children then).  CPU seconds,
unlike wall seconds, stay meaningful on a loaded machine (they grow some under contention).
"""
from __future__ import annotations

import collections
import glob
import json
import os
import resource
import sys
import time

import pytest

_RECORDS: dict = {}


def _cpu() -> tuple[float, float]:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime, kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    (own0, kids0), t0 = _cpu(), time.perf_counter()
    yield
    own1, kids1 = _cpu()
    _RECORDS[item.nodeid] = (own1 - own0, kids1 - kids0, time.perf_counter() - t0)


def pytest_sessionfinish(session):
    out = os.environ.get("CPU_PER_TEST")
    if not out:
        return
    os.makedirs(out, exist_ok=True)
    own, kids = _cpu()
    records = dict(_RECORDS, __total__=(own, kids, 0.0))
    with open(os.path.join(out, os.environ.get("PYTEST_XDIST_WORKER", "main") + ".json"), "w") as f:
        json.dump(records, f)


def summary(where: str, top: int = 40) -> str:
    """CPU per test module from the files of ``where``, largest first."""
    records, totals = {}, {}
    for path in sorted(glob.glob(os.path.join(where, "*.json"))):
        with open(path) as f:
            d = json.load(f)
        totals[os.path.basename(path)] = d.pop("__total__")
        records.update(d)
    mod = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0])
    for test, (own, kids, wall) in records.items():
        m = mod[test.split("::")[0]]
        m[0] += own
        m[1] += kids
        m[2] += wall
        m[3] += 1
    lines = [f"{len(records)} tests: own CPU {sum(m[0] for m in mod.values()):.0f} s, children's "
             f"{sum(m[1] for m in mod.values()):.0f} s"]
    lines += [f"  {name}: own {t[0]:.0f} s, children's {t[1]:.0f} s" for name, t in totals.items()]
    lines.append(f"{'own':>7} {'child':>7} {'wall':>7} {'tests':>5}  module")
    for name, m in sorted(mod.items(), key=lambda kv: -(kv[1][0] + kv[1][1]))[:top]:
        lines.append(f"{m[0]:7.1f} {m[1]:7.1f} {m[2]:7.1f} {m[3]:5d}  {name}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(summary(sys.argv[1], *(int(a) for a in sys.argv[2:3])))
