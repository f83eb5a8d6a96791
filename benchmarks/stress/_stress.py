"""Helpers of the stress scripts: every script checks numbers against thresholds, prints them,
writes benchmarks/stress/results/<name>.json (quick: <name>_quick.json) and exits with status 1
if any check failed (0 otherwise)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))          # benchmarks/_common.py

import _common as C  # noqa: E402

RESULTS = HERE / "results"


class Checks:
    """Collects named checks: value, threshold (text), pass/fail, details."""

    def __init__(self, name, quick, argv=None):
        self.name = name
        self.quick = quick
        self.items = []
        self.notes = []
        self.started = C.now()
        self.t0 = time.perf_counter()
        self.command = " ".join([sys.executable.replace(str(C.ROOT) + "/", ""), f"benchmarks/stress/{name}.py"]
                                + list(sys.argv[1:] if argv is None else argv))

    def check(self, label, ok, value, threshold, **details):
        ok = bool(ok)
        self.items.append(dict(check=label, ok=ok, value=value, threshold=threshold, **details))
        print(f"[{'PASS' if ok else 'FAIL'}] {label}: {value} (threshold: {threshold})", flush=True)
        return ok

    def note(self, text):
        self.notes.append(text)
        print(f"  note: {text}", flush=True)

    def finish(self, summary=""):
        seconds = time.perf_counter() - self.t0
        failed = [c for c in self.items if not c["ok"]]
        doc = dict(script=self.name, quick=self.quick, command=self.command,
                   date=self.started.isoformat(timespec="seconds"), seconds=seconds, passed=not failed,
                   n_checks=len(self.items), n_failed=len(failed), summary=summary, checks=self.items,
                   notes=self.notes, machine=C.machine(), versions=C.versions(), load_end=C.loadavg())
        path = C.write_json(RESULTS / f"{self.name}{'_quick' if self.quick else ''}.json", doc)
        print(f"{self.name}: {len(self.items) - len(failed)}/{len(self.items)} checks passed in {seconds:.0f} s; "
              f"wrote {path.relative_to(C.ROOT)}", flush=True)
        if summary:
            print(summary)
        return 1 if failed else 0
