"""The angle increments of orbits of Chaplygin's section map around a point, lifted through the
flow on sub-sections phi0 + 2 pi k/m (docs/commands/rotation.md, "The lift"):
:func:`lifted_increments`, what :meth:`explorer.SectionMap.lifted_increments` gives the rotation
numbers."""
from __future__ import annotations

import math

import numpy as np

from explorer import model
from explorer.analysis.crossings_run import run
from explorer.model import ParameterError

__all__ = ["MAX_SUBSECTIONS", "MAX_SUBSTEP", "SUBSECTIONS", "TMAX_PER_RETURN", "WRAP_SAFE", "lifted_increments"]

#: sub-sections per return at the first try
SUBSECTIONS = 4
#: most sub-sections per return: an orbit still under-sampled there is "unresolved"
MAX_SUBSECTIONS = 256
#: largest change of the angle between two consecutive samples accepted as resolved
MAX_SUBSTEP = 0.5 * math.pi
#: the fast path: when every return's increment, wrapped to (-pi, pi], stays within this bound, the
#: wrapped increments are the lifted ones less one constant 2 pi j (docs/commands/rotation.md)
WRAP_SAFE = 0.75 * math.pi
#: time budget of an orbit per return
TMAX_PER_RETURN = 1e3


class _Samples:

    def __init__(self, params, h, starts, center, n_returns, phi0, tol, threads):
        self.args = (params, n_returns, phi0, tol, threads)
        self.center = center
        self.starts = starts
        self.Y0 = model.section_state(params, np.concatenate([[center[0]], starts[:, 0]]),
                                      np.concatenate([[center[1]], starts[:, 1]]), h, phi0, 1)
        self.runs: dict = {}

    def at(self, f: float, rows):
        """Crossings of phi0 + 2 pi f, 0 <= f < 1 (f = 0: the returns to the section), of the centre and
        at least the orbits ``rows`` (sorted): (the orbits run, sorted; the crossings, the centre's in
        row 0, then those orbits').  A sub-section is integrated once for the orbits asked when it is
        first needed; refinement asks fewer (an orbit's crossings do not depend on the others in its
        run), so an orbit still unresolved does not make the resolved ones run again."""
        have = self.runs.get(f)
        if have is None or not np.all(np.isin(rows, have[0])):
            params, n_returns, phi0, tol, threads = self.args
            c = run(params, self.Y0[np.concatenate([[0], 1 + rows])], n_crossings=n_returns,
                    phi0=phi0 + 2.0 * math.pi * f, tol=tol, threads=threads, tmax=TMAX_PER_RETURN * n_returns)
            if c.count[0] < 1:
                raise ParameterError(f"center {tuple(self.center)} must be a point whose orbit crosses the "
                                     f"section; its orbit stopped ({c.status_name(0)})")
            have = self.runs[f] = (rows.copy(), c)
        return have

    def increments(self, rows, m: int):
        """For the orbits ``rows`` (sorted) sampled on m sub-sections: (per-return increments (n, n_returns),
        largest sample-to-sample change (n,), returns reached (n,), status names (n,)); rows of
        orbits that stopped early or turned back are NaN."""
        _, n_returns, _, _, _ = self.args
        n = rows.size
        xs = np.empty((n, n_returns, m, 2))     # x at phi0 + 2 pi (lap + (k + 1)/m), k = 0..m-1
        ts = np.empty((n, n_returns, m))
        ref = np.empty((m, 2))
        count = np.full(n, n_returns)
        status = np.array(["done"] * n, dtype=object)
        for k in range(1, m + 1):
            ran, c = self.at((k % m) / m, rows)
            at = 1 + np.searchsorted(ran, rows)
            ref[k - 1] = self.center if k == m else c.data[0, 0, 1:3]
            xs[:, :, k - 1] = c.data[at, :, 1:3]
            ts[:, :, k - 1] = c.data[at, :, 0]
            for i in np.flatnonzero(c.count[at] < count):
                count[i], status[i] = c.count[at[i]], c.status_name(at[i])
        theta = np.arctan2(xs[..., 1] - ref[:, 1], xs[..., 0] - ref[:, 0]).reshape(n, -1)
        x0 = self.starts[rows]
        theta0 = np.arctan2(x0[:, 1] - self.center[1], x0[:, 0] - self.center[0])
        d = np.diff(np.concatenate([theta0[:, None], theta], axis=1), axis=1)
        d -= 2.0 * np.pi * np.ceil((d - np.pi) / (2.0 * np.pi))
        t = np.concatenate([np.zeros((n, 1)), ts.reshape(n, -1)], axis=1)
        with np.errstate(invalid="ignore"):
            turned = ~np.all(np.diff(t, axis=1) > 0.0, axis=1) & (count == n_returns)
        status[turned] = "turned"
        d[turned] = np.nan
        return d.reshape(n, n_returns, m).sum(axis=2), np.abs(d).max(axis=1, initial=0.0), count, status


def _refined(samples: _Samples, n: int):
    inc = np.full((n, samples.args[1]), np.nan)
    count = np.zeros(n, np.int64)
    status = np.array(["unresolved"] * n, dtype=object)
    todo = np.arange(n)
    m = SUBSECTIONS
    while todo.size and m <= MAX_SUBSECTIONS:
        d, worst, cnt, st = samples.increments(todo, m)
        ok = (worst <= MAX_SUBSTEP) | (st != "done")
        inc[todo[ok]], count[todo[ok]], status[todo[ok]] = d[ok], cnt[ok], st[ok]
        count[todo[~ok]] = cnt[~ok]
        todo, m = todo[~ok], 2 * m
    return inc, count, status


def lifted_increments(params, h, starts, center, n_returns, phi0, tol, threads):
    """(increments (n, n_returns) around ``center``, returns reached, status names, lifted) of the orbits
    from ``starts``: wrapped where every increment is within WRAP_SAFE of 0 and shifted by the first
    return's lift, else sampled on sub-sections until resolved (docs/commands/rotation.md, "The lift")."""
    n = starts.shape[0]
    args = (params, h)
    tail = (phi0, tol, threads)
    # the returns alone (m = 1): the increments wrapped to (-pi, pi]
    inc, worst, count, status = _Samples(*args, starts, center, n_returns, *tail).increments(np.arange(n), 1)
    # a start at the centre itself has no angle around it: unresolved now, not after MAX_SUBSECTIONS
    at_centre = np.all(starts == np.asarray(center, float), axis=1) & (status == "done")
    inc[at_centre], status[at_centre] = np.nan, "unresolved"
    lifted = np.zeros(n, bool)
    safe = np.flatnonzero((status == "done") & (worst <= WRAP_SAFE))
    if safe.size:
        first, _, st = _refined(_Samples(*args, starts[safe], center, 1, *tail), safe.size)
        j = np.round((first[:, 0] - inc[safe, 0]) / (2.0 * np.pi))
        known = (st == "done") & np.isfinite(j)
        inc[safe[known]] += 2.0 * np.pi * j[known, None]
        lifted[safe[known]] = True
    rest = np.flatnonzero((status == "done") & (worst > WRAP_SAFE))
    if rest.size:
        d, cnt, st = _refined(_Samples(*args, starts[rest], center, n_returns, *tail), rest.size)
        inc[rest], count[rest], status[rest] = d, cnt, st
        lifted[rest] = st == "done"
    return inc, count, status, lifted
