"""The explorer's state and logic, without a window: parameters, energy level, integration
settings, the clicked seeds and the orbits computed chunk after chunk, their chaos indicators,
the fixed points and separatrices, the status text and what every key does to the state.

Pure Python and numpy (no matplotlib: ``tests/app/test_explore_state.py`` checks it), so it is
driven directly by tests and notebooks; :mod:`explorer.app.explore.view` draws it and
:mod:`explorer.app.explore.controller` connects the two to the window's events.

Chunks: :meth:`ExplorerState.step` advances every running orbit by ``chunk`` crossings with
:func:`explorer.analysis.sections.crossings` (all running orbits in one batch, parallel over Numba
threads). Each chunk restarts the integrator from the state where the previous one stopped;
``sections.crossings`` counts time from 0 and measures the energy error from the chunk's start,
so the state keeps each orbit's absolute time and its energy reference H0 = H(y0): a stored row
is ``(t_start + t, p1, p2, M, dH + (H(chunk start) - H0))``.  With the Taylor method the step
size is a function of the state alone and the splitting methods have a fixed step, so the
chunked states are those of one long run (only the time sum is split); DOP853 restarts its
controller at each chunk (round-off-sized changes).  Each chunk has the time budget
``100 * chunk`` (the default of ``sections.crossings``); an orbit whose chunk ends early stops
with that status.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.analysis import sections
from explorer.model import PARAM_NAMES, ParameterError, validation

#: time over which the chaos indicators (MEGNO, finite-time mLCE) of an orbit are computed
INDICATOR_TIME = 1000.0
#: mean MEGNO above this is called "chaotic-like" in the status line (quasi-periodic: 2)
CHAOTIC_MEGNO = 3.0
#: characters per line of the status text (longer lines are cut)
STATUS_WIDTH = 140
#: at most this many orbits are advanced per tick (round robin beyond)
MAX_BATCH = 32
#: status code stored for an orbit written while it was still running (not a kernel status)
STATUS_RUNNING = -1
RUNNING_NAME = "running (written before it finished)"
#: status code of orbits stopped because the integration raised an exception
STATUS_FAILED = -2
FAILED_NAME = "integration failed (exception)"
#: keys of the explorer and what they do
KEYS = {"c": "clear orbits and seeds", "r": "re-run the seeds at the current parameters",
        "s": "save the section as PNG", "w": "write the orbits as HDF5 (store format)",
        "x": "colour by the chaos indicator (MEGNO)", "p": "toggle separatrices",
        "o": "toggle the periodic orbits of periods 1..PERIODIC_MAX (o elliptic, x hyperbolic)"}
#: key o marks the periodic orbits of periods 1..PERIODIC_MAX (analysis/periodic.py)
PERIODIC_MAX = 4
#: one colour per orbit, in turn
COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
          "#bcbd22", "#393b79", "#637939", "#843c39", "#7b4173", "#3182bd", "#e6550d", "#31a354")


def _num(x) -> str:
    """Short form of a coordinate: 4 digits, round-off-sized values as 0."""
    x = float(x)
    return "0" if abs(x) < 1e-12 else f"{x:.4g}"


def clip(line: str, width: int = STATUS_WIDTH) -> str:
    """``line`` cut to ``width`` characters (with "...")."""
    return line if len(line) <= width else line[:width - 3] + "..."


def _finite(name, v) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a real number, got {v!r}") from None
    if not math.isfinite(x):
        raise ParameterError(f"{name} must be finite, got {v!r}")
    return x


# ---------------------------------------------------------------- orbits
@dataclass
class _Track:
    """The integration state of one orbit, continued chunk after chunk."""

    y0: np.ndarray                 # (5,) initial state
    rows: np.ndarray               # (capacity, 5): t, p1, p2, M, dH (absolute t, dH from H(y0)); grows
    H0: float                      # energy reference H(y0)
    state: np.ndarray = None       # (5,) where the next chunk starts
    H_state: float = 0.0           # H(state): the reference of the next chunk's dH
    t: float = 0.0                 # absolute time of ``state``
    count: int = 0
    steps: int = 0
    casimir: float = 0.0           # Casimir error g1^2 + g2^2 - 1 of ``state``
    status: int | None = None      # None while running, else a kernel status code

    def __post_init__(self):
        self.state = self.y0.copy()
        self.H_state = self.H0

    @property
    def running(self) -> bool:
        return self.status is None

    def append(self, rows, final, info, params, limit):
        """Take one chunk's result (rows relative to the chunk start)."""
        n = min(len(rows), limit - self.count)
        if self.count + n > len(self.rows):  # grow by doubling (capacity is allocated lazily)
            grown = np.zeros((min(limit, max(2 * len(self.rows), self.count + n)), 5))
            grown[:self.count] = self.rows[:self.count]
            self.rows = grown
        if n > 0:
            block = rows[:n].copy()
            block[:, 0] += self.t
            block[:, 4] += self.H_state - self.H0
            self.rows[self.count:self.count + n] = block
            self.count += n
        self.t += float(info[0])
        self.steps += int(info[1])
        self.casimir = float(info[2])
        self.state = np.array(final, dtype=np.float64)
        with np.errstate(all="ignore"):
            self.H_state = float(model.energy(params, self.state))
        return n


@dataclass
class Orbit:
    """One clicked orbit at the current parameters: its crossings and its chaos indicators."""

    seed: tuple                    # (p1, p2) where it was started
    color: str
    main: _Track
    megno: float | None = None     # mean MEGNO <Y>(INDICATOR_TIME) (None: not known)
    mlce: float | None = None      # finite-time maximal Lyapunov exponent at INDICATOR_TIME
    indicator_pending: bool = True
    indicator_note: str = ""       # why the indicator is missing
    wall_time: float = 0.0
    number: int = 0

    @property
    def running(self) -> bool:
        return self.main.running

    @property
    def crossings(self) -> np.ndarray:
        return self.main.rows[:self.main.count]

    @property
    def max_energy_error(self) -> float:
        c = self.main.count
        return float(np.max(np.abs(self.main.rows[:c, 4]))) if c else 0.0


# ---------------------------------------------------------------- the state
class ExplorerState:
    """Parameters, settings, seeds and orbits of the explorer, and every action on them.

    Parameters
    ----------
    params : model.Params
        Model parameters (docs/model.md R3).
    h : float
        Energy level; the section is phi = ``phi0`` (default pi, docs/model.md R9).
    method, tol, dt :
        Integration settings of :func:`explorer.analysis.sections.crossings`.
    chunk : int
        Crossings computed per orbit and step (default 50).
    max_crossings : int
        Crossings per orbit (default 2000).
    phi0, direction :
        Section angle and crossing direction (+1: dphi/dt > 0, -1, 0: both).
    label : str
        A name shown in the title and stored with the orbits (e.g. the scene name).
    indicators : bool
        Compute the chaos indicators of each orbit (MEGNO, mLCE; default True).

    Bad parameters raise :class:`explorer.model.ParameterError`. ``message`` is the last
    message for the user; actions set it.
    """

    def __init__(self, params, h, *, method="taylor", tol=None, dt=None, chunk=50, max_crossings=2000,
                 phi0=math.pi, direction=1, label="", indicators=True):
        if not isinstance(params, model.Params):
            params = model.Params(**params) if isinstance(params, dict) else model.Params.from_array(params)
        if method not in sections.METHODS:
            raise ParameterError(f"method must be one of {', '.join(sections.METHODS)}; got {method!r}")
        self.params = params
        self.h = validation.magnitude("h", h)
        self.phi0 = _finite("phi0", phi0)
        if direction not in (-1, 0, 1):
            raise ParameterError(f"direction must be +1, -1 or 0 (both), got {direction!r}")
        self.direction = int(direction)
        self.method = method
        self.tol = sections.DEFAULT_TOL if tol is None else float(tol)
        self.dt = sections.DEFAULT_DT if dt is None else float(dt)
        # both settings are validated, the one the method does not use too (a NaN is a mistake)
        validation.real("tol", self.tol, sections.MIN_TOL, sections.MAX_TOL)
        validation.real("dt", self.dt, 0.0, lo_open=True)
        for name, v in (("crossings-per-chunk", chunk), ("max-crossings", max_crossings)):
            validation.fits_in_memory(name, v, sections.ROW_BYTES, "a crossing row per orbit", lo=1)
        self.chunk = int(chunk)
        self.max_crossings = int(max_crossings)
        self.label = str(label)
        self.indicators = bool(indicators)

        self.seeds: list[tuple] = []        # every clicked (p1, p2), kept across parameter changes
        self.seed_colors: list[str] = []
        self.orbits: list[Orbit] = []       # orbits at the current parameters
        self.color_by_indicator = False
        self.show_separatrices = False
        self.show_periodic = False
        self.message = ""
        self._next_color = 0
        self._orbit_number = 0
        self._rr = 0                         # round-robin offset when more than MAX_BATCH run

    # ------------------------------------------------------------ queries
    def integration_kwargs(self) -> dict:
        """Keywords of :func:`explorer.analysis.sections.crossings` for these settings."""
        kw = {"method": self.method, "phi0": self.phi0, "direction": self.direction}
        if self.method in sections.ADAPTIVE_METHODS:
            kw["tol"] = self.tol
        else:
            kw["dt"] = self.dt
        return kw

    @property
    def region(self):
        """(c1, c2, r1, r2) of the allowed region, or None if it is empty."""
        e = model.allowed_ellipse(self.params, self.h, self.phi0)
        if e is None or not (e[2] > 0.0 and e[3] > 0.0):
            return None
        return e

    @property
    def running(self) -> bool:
        """True while some orbit runs or waits for its chaos indicator."""
        return any(o.running or (o.indicator_pending and self.indicators) for o in self.orbits)

    def admissible(self, p1, p2) -> bool:
        """(p1, p2) lies in the allowed region (M^2 >= 0, docs/model.md R9)."""
        with np.errstate(all="ignore"):
            return bool(model.section_M2(self.params, p1, p2, self.h, self.phi0) >= 0.0)

    def energy_minimum(self):
        """Minimum of the energy on the section (the region is a point there), or None."""
        big = abs(self.h) + 1e3
        e = model.allowed_ellipse(self.params, big, self.phi0)
        if e is None:
            return None
        _c1, _c2, r1, _r2 = e
        return big - r1 * r1 / (2.0 * self.params.a1)

    def title_parts(self) -> list[str]:
        """``mu = ..., h = ...`` and every parameter that differs from Figure 4's."""
        parts = [f"mu = {self.params.mu:g}", f"h = {self.h:g}"]
        for n in PARAM_NAMES:
            v = getattr(self.params, n)
            if n != "mu" and v != getattr(model.FIGURE4, n):
                parts.append(f"{n} = {v:g}")
        return parts

    def seeds_split(self):
        """(admissible, not admissible) seeds as (n, 2) arrays."""
        ok, bad = [], []
        for s in self.seeds:
            (ok if self.admissible(*s) else bad).append(s)
        return np.array(ok).reshape(-1, 2), np.array(bad).reshape(-1, 2)

    @staticmethod
    def status_names() -> dict:
        """{code: name} of the kernels' status codes plus the explorer's own (running, failed)."""
        from explorer.kernels import STATUS_NAMES

        names = dict(STATUS_NAMES)
        names.update({STATUS_RUNNING: RUNNING_NAME, STATUS_FAILED: FAILED_NAME})
        return names

    def status_name(self, code) -> str:
        return self.status_names().get(int(code), f"status {code}")

    def status_lines(self) -> tuple[str, str]:
        """(last orbit line, message line) of the status text."""
        if not self.orbits:
            first = "no orbit yet"
        else:
            o = self.orbits[-1]
            if o.running:
                state = "running"
            else:
                state = "done" if o.main.status == 0 else self.status_name(o.main.status)
            if o.megno is not None:
                kind = "chaotic-like" if o.megno > CHAOTIC_MEGNO else "regular-like"
                ind = f"<Y> = {o.megno:.3g}, mLCE = {o.mlce:.3g} ({kind})"
            elif o.indicator_pending and self.indicators:
                ind = "<Y> = pending"
            else:
                ind = f"<Y> = n/a{(' (' + o.indicator_note + ')') if o.indicator_note else ''}"
            first = (f"orbit {o.number} ({o.seed[0]:.4g}, {o.seed[1]:.4g}): {o.main.count}/{self.max_crossings} "
                     f"crossings, {state}, t = {o.main.t:.1f}, max|dH| = {o.max_energy_error:.1e}, {ind}")
        return first, self.message

    def status_report(self) -> str:
        first, msg = self.status_lines()
        return "\n".join(clip(line) for line in [first] + msg.splitlines())

    # ------------------------------------------------------------ orbits
    def take_color(self) -> str:
        c = COLORS[self._next_color % len(COLORS)]
        self._next_color += 1
        return c

    def launch(self, p1, p2, color=None) -> Orbit:
        """Start an orbit at (p1, p2) on the section (M from the energy, sign from the direction);
        raises ParameterError if the point is outside the allowed region."""
        p1, p2 = float(p1), float(p2)
        y0 = model.section_state(self.params, p1, p2, self.h, self.phi0, self.direction or 1)[0]
        H0 = float(model.energy(self.params, y0))
        main = _Track(y0=y0, rows=np.zeros((min(self.max_crossings, 4 * self.chunk), 5)), H0=H0)
        self._orbit_number += 1
        orbit = Orbit(seed=(p1, p2), color=color or self.take_color(), main=main,
                      indicator_pending=self.indicators, number=self._orbit_number)
        self.orbits.append(orbit)
        return orbit

    def click(self, p1, p2) -> Orbit | None:
        """What a click at (p1, p2) does: a new seed and its orbit, or a message saying why not."""
        p1, p2 = float(p1), float(p2)
        if self.region is None:
            self.message = (f"nothing to do: the region is empty at h = {self.h:g} "
                            f"(h is below the minimum of the energy on the section)")
            return None
        with np.errstate(all="ignore"):
            m2 = float(model.section_M2(self.params, p1, p2, self.h, self.phi0))
        if not m2 >= 0.0:
            self.message = (f"({p1:.4g}, {p2:.4g}) is outside the allowed region: M^2 = {m2:.3g} < 0 there "
                            f"(no real M at energy h = {self.h:g}); click in the white ellipse")
            return None
        color = self.take_color()
        self.seeds.append((p1, p2))
        self.seed_colors.append(color)
        orbit = self.launch(p1, p2, color=color)
        self.message = f"orbit {orbit.number} started at ({p1:.4g}, {p2:.4g}), M = {orbit.main.y0[2]:.4g}"
        return orbit

    def step(self) -> list[Orbit]:
        """Advance every running orbit by one chunk of crossings (one batch; at most MAX_BATCH
        orbits, round robin) and compute the chaos indicators of new orbits. Returns the orbits
        that changed (empty: nothing runs)."""
        jobs = [o for o in self.orbits if o.running]
        pending = [o for o in self.orbits if o.indicator_pending and self.indicators]
        if not jobs and not pending:
            return []
        if len(jobs) > MAX_BATCH:  # round robin over the running orbits
            start = self._rr % len(jobs)
            jobs = (jobs[start:] + jobs[:start])[:MAX_BATCH]
            self._rr += MAX_BATCH
        groups: dict[int, list[Orbit]] = {}
        for o in jobs:
            groups.setdefault(min(self.chunk, self.max_crossings - o.main.count), []).append(o)
        kw = self.integration_kwargs()
        tmax = 100.0 * self.chunk  # the default budget of sections.crossings for one chunk
        for k, group in groups.items():
            Y = np.array([o.main.state for o in group])
            t0 = time.perf_counter()
            res = sections.crossings(self.params, Y, k, tmax=tmax, **kw)
            share = (time.perf_counter() - t0) / len(group)
            for i, o in enumerate(group):
                tr = o.main
                tr.append(res.orbit(i), res.final[i], res.info[i], self.params, self.max_crossings)
                o.wall_time += share
                if tr.count >= self.max_crossings:
                    tr.status = 0  # done
                elif int(res.count[i]) < k:  # the chunk ended early: the orbit stops with that status
                    tr.status = int(res.status[i]) or 1
        if pending:
            self._compute_indicators(pending[:MAX_BATCH])
        return list({id(o): o for o in jobs + pending}.values())

    def fail_running(self, exc):
        """An exception stopped the integration: every running orbit gets STATUS_FAILED."""
        for o in self.orbits:
            if o.running:
                o.main.status = STATUS_FAILED
            o.indicator_pending = False
        self.message = f"integration failed: {type(exc).__name__}: {' '.join(str(exc).split())}"

    def _compute_indicators(self, orbits):
        """MEGNO and finite-time mLCE of ``orbits`` over INDICATOR_TIME (analysis.lyapunov)."""
        from explorer.analysis import lyapunov

        kw = {"method": self.method}
        if self.method in sections.ADAPTIVE_METHODS:
            kw["tol"] = self.tol
        else:
            kw["dt"] = self.dt
        try:
            res = lyapunov.indicators(self.params, np.array([o.main.y0 for o in orbits]), INDICATOR_TIME, **kw)
        except Exception as exc:  # noqa: BLE001 - the indicator failed: the orbits still run
            note = f"indicator unavailable: {type(exc).__name__}: {' '.join(str(exc).split())}"
            for o in orbits:
                o.indicator_pending, o.indicator_note = False, note
            return
        for i, o in enumerate(orbits):
            o.indicator_pending = False
            megno, mlce = float(res.megno[i]), float(res.mlce[i])
            if int(res.status[i]) == 0 and math.isfinite(megno) and math.isfinite(mlce):
                o.megno, o.mlce = megno, mlce
            else:
                o.indicator_note = f"indicator run stopped: {res.status_name(i)}"

    def run_until_done(self, max_steps=10**6) -> int:
        """Call :meth:`step` until nothing runs; returns the number of steps."""
        n = 0
        while n < max_steps and self.step():
            n += 1
        return n

    def clear(self) -> int:
        """Remove every orbit and every seed; returns how many orbits were removed."""
        n = len(self.orbits)
        self.orbits = []
        self.seeds, self.seed_colors = [], []
        self.message = f"cleared ({n} orbits)"
        return n

    def rerun(self) -> list[Orbit]:
        """Start the kept seeds again at the current parameters; inadmissible ones are reported."""
        self.orbits = []
        if not self.seeds:
            self.message = "no seeds to re-run: click in the region first"
            return []
        started, skipped = [], []
        for s, c in zip(self.seeds, self.seed_colors):
            if self.region is not None and self.admissible(*s):
                started.append(self.launch(*s, color=c))
            else:
                skipped.append(s)
        msg = f"re-running {len(started)} seeds"
        if skipped:
            pts = ", ".join(f"({a:.3g}, {b:.3g})" for a, b in skipped[:4]) + (" ..." if len(skipped) > 4 else "")
            msg += f"; {len(skipped)} outside the allowed region at these parameters (x): {pts}"
        self.message = msg
        return started

    def toggle_indicator(self):
        """Colour by the MEGNO or one colour per orbit."""
        self.color_by_indicator = not self.color_by_indicator
        if self.color_by_indicator:
            self.message = (f"colour = MEGNO <Y> over t <= {INDICATOR_TIME:g} (2: quasi-periodic, 0: stable "
                            f"periodic, larger: chaotic; gray: not known)")
        else:
            self.message = "colour = one per orbit"

    # ------------------------------------------------------------ parameters
    def set_params(self, changes: dict) -> bool:
        """Set model parameters and/or h at once, e.g. ``{"mu": 0.03, "h": 2.5}``: removes the
        orbits, keeps the seeds (``rerun`` starts them again). Returns False when nothing changed.
        Raises ParameterError, with nothing changed, for a bad name or value."""
        names = PARAM_NAMES + ("h",)
        new = {}
        for name, value in dict(changes).items():
            name = str(name).strip()
            if name not in names:
                raise ParameterError(f"unknown parameter {name!r}; one of {', '.join(names)}")
            new[name] = _finite(name, value)
        h = new.pop("h", self.h)
        params = self.params.with_(**new) if new else self.params  # validated: raises ParameterError
        if params == self.params and h == self.h:
            return False
        changed = [f"{k} = {v:g}" for k, v in new.items() if v != getattr(self.params, k)]
        if h != self.h:
            changed.append(f"h = {h:g}")
        self.params, self.h = params, h
        n = len(self.orbits)
        self.orbits = []
        ok = sum(self.admissible(*s) for s in self.seeds) if self.region is not None else 0
        msg = ", ".join(changed) + ": region redrawn"
        if n:
            msg += f", {n} orbit{'s' if n != 1 else ''} removed"
        if self.seeds:
            msg += f"; {len(self.seeds)} seeds kept ({ok} inside the region): press r to re-run them"
        self.message = msg
        return True

    @staticmethod
    def parse_assignments(text: str) -> dict:
        """``name=value[, name=value ...]`` (also ``;``-separated) -> {name: value text}."""
        changes = {}
        for piece in text.replace(";", ",").split(","):
            piece = piece.strip()
            if not piece:
                continue
            if "=" not in piece:
                raise ParameterError(f"write name=value (e.g. a1=1.2), got {piece!r}")
            k, v = piece.split("=", 1)
            changes[k.strip()] = v.strip()
        return changes

    # ------------------------------------------------------------ separatrices
    def periodic_orbits(self, max_period=None):
        """(orbits, message): :func:`periodic_orbits` of this state."""
        return periodic_orbits(self, max_period)

    def fixed_points_and_curves(self):
        """(fixed points, curves, message): :func:`fixed_points_and_curves` of this state."""
        return fixed_points_and_curves(self)

    # ------------------------------------------------------------ output
    def settings(self) -> dict:
        """Everything that determines the orbits' numbers (stored with 'w')."""
        integ = {"method": self.method, "crossings": self.max_crossings, "chunk": self.chunk,
                 "tmax_per_chunk": 100.0 * self.chunk, "phi0": self.phi0, "direction": self.direction}
        if self.method in sections.ADAPTIVE_METHODS:
            integ["tol"] = self.tol
        else:
            integ["dt"] = self.dt
        return {"source": "explore", "params": self.params.as_dict(), "h": self.h,
                "seeds": {"kind": "points", "points": [list(o.seed) for o in self.orbits]},
                "integration": integ}

    def panel_arrays(self) -> dict:
        """The orbits at the current parameters as the arrays of one store panel."""
        n = len(self.orbits)
        count = np.array([o.main.count for o in self.orbits], dtype=np.int64)
        offsets = np.zeros(n + 1, np.int64)
        np.cumsum(count, out=offsets[1:])
        crossings = (np.concatenate([o.crossings for o in self.orbits]) if n else np.zeros((0, 5)))
        return {
            "seeds": np.array([o.seed for o in self.orbits], dtype=np.float64).reshape(n, 2),
            "y0": np.array([o.main.y0 for o in self.orbits], dtype=np.float64).reshape(n, 5),
            "count": count,
            "status": np.array([STATUS_RUNNING if o.running else o.main.status for o in self.orbits],
                               dtype=np.int8),
            "final": np.array([o.main.state for o in self.orbits], dtype=np.float64).reshape(n, 5),
            "info": np.array([[o.main.t, o.main.steps, o.main.casimir] for o in self.orbits],
                             dtype=np.float64).reshape(n, 3),
            "offsets": offsets,
            "crossings": np.ascontiguousarray(crossings, dtype=np.float64),
        }

    def panel_attrs(self) -> dict:
        """The attributes of that panel (settings, indicators, provenance of the numbers)."""
        nan = float("nan")
        return {
            "label": f"explore: mu = {self.params.mu:g}, h = {self.h:g}", "parameter": "",
            "value": float("nan"), "h": self.h, "params": self.params.as_dict(), "settings": self.settings(),
            "method": self.method, "tol": float(self.tol), "dt": float(self.dt), "phi0": self.phi0,
            "direction": self.direction, "crossings_requested": self.max_crossings, "chunk": self.chunk,
            "wall_time": float(sum(o.wall_time for o in self.orbits)),
            "megno": np.array([nan if o.megno is None else o.megno for o in self.orbits], dtype=np.float64),
            "mlce": np.array([nan if o.mlce is None else o.mlce for o in self.orbits], dtype=np.float64),
            "indicator_time": INDICATOR_TIME,
            "indicator_note": ("megno, mlce: explorer.analysis.lyapunov.indicators over t <= indicator_time "
                               "from y0 (mean MEGNO <Y>, finite-time maximal Lyapunov exponent); NaN: not computed"),
        }

    def warm_up(self):
        """Load (or compile) the integrator before the first click."""
        if self.region is not None:
            c1, c2 = self.region[:2]
            y = model.section_state(self.params, c1, c2, self.h, self.phi0, self.direction or 1)
            sections.crossings(self.params, y, 1, tmax=1.0, **self.integration_kwargs())


def fixed_points_and_curves(view):
    """(fixed points, curves, message) from :mod:`explorer.analysis.fixedpoints`: Newton's method
    from p = 0, from the centre of the region and half-way to its edge along both axes; the
    separatrices of the hyperbolic points.  ``view``: anything with ``params``, ``h``, ``phi0``,
    ``region`` (c1, c2, r1, r2 or None) and ``admissible(p1, p2)`` (this module's state, the
    settings of ``explorer serve``)."""
    from explorer.analysis.fixedpoints import find_fixed_point, separatrices

    if view.region is None:
        return [], [], "separatrices: the region is empty"
    c1, c2, r1, r2 = view.region
    guesses = [(0.0, 0.0), (c1, c2), (c1 - 0.5 * r1, c2), (c1 + 0.5 * r1, c2), (c1, c2 - 0.5 * r2),
               (c1, c2 + 0.5 * r2)]
    points = []
    for g in guesses:
        if not view.admissible(*g):
            continue
        try:
            fp = find_fixed_point(view.params, view.h, g, phi0=view.phi0)
        except Exception:  # noqa: BLE001 - no convergence from this guess
            continue
        if all(np.max(np.abs(np.asarray(fp.point) - np.asarray(q.point))) > 1e-7 for q in points):
            points.append(fp)
    if not points:
        return [], [], ("separatrices: Newton's method found no fixed point from p = 0, the region's centre "
                        "or half-way to its edge")
    curves = []
    try:
        for fp in points:
            if not fp.stable:
                for c in separatrices(fp, phi0=view.phi0):
                    a = np.asarray(c, dtype=np.float64)
                    if a.ndim == 2 and a.shape[1] == 2 and len(a):
                        curves.append(a)
    except Exception as exc:  # noqa: BLE001 - reported in the status line
        return points, [], f"separatrices: failed ({type(exc).__name__}: {' '.join(str(exc).split())})"
    desc = ", ".join(f"({_num(fp.point[0])}, {_num(fp.point[1])}) {'elliptic' if fp.stable else 'hyperbolic'}"
                     for fp in points)
    return points, curves, f"fixed points {desc}; {len(curves)} separatrix branches"


def periodic_orbits(view, max_period=None):
    """(orbits, message): the periodic orbits of minimal periods 1..``max_period`` (default
    PERIODIC_MAX) found by :func:`explorer.analysis.periodic.search_periodic_orbits` (a coarse
    grid, 8 x 8, and the symmetry lines), each once.  ``view``: as for :func:`fixed_points_and_curves`."""
    from explorer.analysis.periodic import search_periodic_orbits

    K = PERIODIC_MAX if max_period is None else int(max_period)
    if view.region is None:
        return [], "periodic orbits: the region is empty"
    orbits = []
    for k in range(1, K + 1):
        try:
            orbits += search_periodic_orbits(view.params, view.h, k, grid=8, max_guesses=30, phi0=view.phi0)
        except Exception:  # noqa: BLE001 - a failed search marks nothing for this period
            continue
    counts = ", ".join(f"K={k}: {sum(o.period == k for o in orbits)} "
                       f"({sum(o.period == k and o.stable for o in orbits)} stable)" for k in range(1, K + 1))
    return orbits, f"periodic orbits {counts}"
