"""``explorer serve`` with the times (time.time) of its click path written to the file named by
SERVE_TRACE, one event a line, for ``bench_serve.py --breakdown`` (not a benchmark itself):

- ``tap``: the page's Tap callback starts (SectionPage._on_tap);
- ``block ROWS DONE STATUS``: a block the worker computed reaches the page's event loop
  (OrbitsLayer._on_block; the worker's job posts it there as soon as it is computed);
- ``flush N``: the page has streamed queued blocks into the document (N crossings now); the
  message to the browser is written right after.

Usage: python benchmarks/_serve_trace.py SERVE-ARGUMENTS (with SERVE_TRACE set).
"""
from __future__ import annotations

import functools
import os
import sys
import threading
import time

from explorer.app.cli import main
from explorer.app.serve import page as page_mod
from explorer.app.serve import page_orbits

_LOG = open(os.environ["SERVE_TRACE"], "a", buffering=1)   # noqa: SIM115 - open for the process
_LOCK = threading.Lock()


def _log(text: str) -> None:
    with _LOCK:
        _LOG.write(f"{time.time():.6f} {text}\n")


def _traced(name, before=None, after=None, cls=page_mod.SectionPage):
    f = getattr(cls, name)

    @functools.wraps(f)
    def g(self, *args, **kwargs):
        if before:
            _log(before(self, *args))
        out = f(self, *args, **kwargs)
        if after:
            _log(after(self, *args))
        return out
    setattr(cls, name, g)


_traced("_on_tap", before=lambda self, _e: "tap")
_traced("_on_block", before=lambda self, _i, rows, done, status: f"block {len(rows)} {done} {status}",
        cls=page_orbits.OrbitsLayer)
_traced("_flush", after=lambda self: f"flush {len(self.columns(keys=('orbit',))['orbit'])}", cls=page_orbits.OrbitsLayer)

if __name__ == "__main__":
    sys.exit(main(["serve", *sys.argv[1:]]))
