"""Interactive explorer: click on the section phi = phi0, watch the orbit appear.

``python -m explorer explore [SCENE]`` opens a matplotlib window with the
allowed region of the section (MODEL.md R9: white inside the ellipse
M^2 >= 0 of :func:`explorer.model.allowed_ellipse`, light gray outside, as in
:mod:`explorer.figures`).  A click inside starts an orbit there
(:func:`explorer.model.section_state`, M > 0) and its crossings are drawn as
they are computed, in a new colour.

How the window stays responsive
-------------------------------
Nothing runs in a thread.  A matplotlib timer (``fig.canvas.new_timer``)
calls :meth:`Explorer.step`, which advances every running orbit by one chunk
of ``chunk`` crossings with :func:`explorer.sections.crossings` (all running
orbits in one batch, parallel over Numba threads) and redraws.  Each chunk
restarts the integrator from the state where the previous chunk stopped;
``sections.crossings`` counts time from 0 and measures the energy error from
the chunk's start, so the explorer keeps each orbit's absolute time and its
energy reference H0 = H(y0) itself: a stored row is
``(t_start + t, p1, p2, M, dH + (H(chunk start) - H0))``.  With the Taylor
method the step size is a function of the state alone, so the chunked states
are those of one long run (only the time sum is split), and so are those of
the fixed-step splitting methods; the adaptive DOP853 controller restarts at
each chunk, which changes the steps by round-off-sized amounts.  Each chunk has
the time budget ``100 * chunk`` (the default of
``sections.crossings``); an orbit whose chunk ends early (it no longer turns
over, or any other status) stops with that status.

Chaos indicator ('x')
---------------------
Each orbit also gets the chaos indicators of :func:`explorer.lyapunov.indicators`
over its first ``INDICATOR_TIME`` time units (variational equations of the
same method and tolerance), computed once, in the tick after the click:
the mean MEGNO <Y> (Cincotta & Simó 2000: <Y> -> 2 for quasi-periodic
orbits, -> 0 for stable periodic ones, grows like chi t / 2 for chaotic ones)
colours the orbit with 'x', and the finite-time maximal Lyapunov exponent
chi is shown in the status line.  It is a finite-time value from one
deviation vector: an orbit that is chaotic only over longer times (thin
layers, stickiness near islands) can look regular at T = 1000; the label
"chaotic-like" in the status line means <Y> > ``CHAOTIC_MEGNO``.

Separatrices ('p')
------------------
'p' looks for fixed points of the section map by Newton's
method from p = 0, from the centre of the region and from half-way to its
edge along both axes, marks them (o elliptic,
x hyperbolic) and draws the stable and unstable manifolds of the hyperbolic
ones (:mod:`explorer.analysis.fixedpoints`).

API
---
``Explorer(params, h, *, method, tol, dt, chunk, max_crossings, fig=None)``
    the whole tool; its handlers ``on_click(event)``, ``on_key(event)``,
    ``set_param(name, value)``, ``step()``, ``save_png(path)``,
    ``save_h5(path)`` work headless (Agg) and are what the tests drive;
    ``run()`` shows the window.
``display_problem()``
    why no window can be opened (None if one can).
"""
from __future__ import annotations

import datetime as _dt
import math
import os
import secrets
import sys
import time
from dataclasses import dataclass

import numpy as np

from explorer import model
from explorer.model import PARAM_NAMES, ParameterError, validation

#: time over which the chaos indicators (MEGNO, finite-time mLCE) of an orbit are computed
INDICATOR_TIME = 1000.0
#: mean MEGNO above this is called "chaotic-like" in the status line (quasi-periodic: 2)
CHAOTIC_MEGNO = 3.0
#: top of the colour scale of the MEGNO (larger values get the top colour)
MEGNO_COLOR_MAX = 10.0
#: characters per line of the status text (longer lines are cut)
STATUS_WIDTH = 140
#: separatrix polylines are broken where two points are farther apart than this x the larger semi-axis
SEPARATRIX_GAP = 0.1
#: after a parameter change, separatrices are recomputed when the parameters rest this long (ms)
SEPARATRIX_DELAY_MS = 400
#: colour of separatrices and fixed-point markers
SEPARATRIX_COLOR = "k"
#: milliseconds between timer ticks
TIMER_INTERVAL_MS = 15
#: at most this many orbits are advanced per tick (round robin beyond)
MAX_BATCH = 32
#: status code stored for an orbit written while it was still running (not a kernel status)
STATUS_RUNNING = -1
RUNNING_NAME = "running (written before it finished)"
#: status code of orbits stopped because the integration raised an exception
STATUS_FAILED = -2
FAILED_NAME = "integration failed (exception)"
#: keys of the explorer (taken away from matplotlib's default key map while it runs)
KEYS = {"c": "clear orbits and seeds", "r": "re-run the seeds at the current parameters",
        "s": "save the section as PNG", "w": "write the orbits as HDF5 (store format)",
        "x": "colour by the chaos indicator (MEGNO)", "p": "toggle separatrices"}
DISPLAY_ERROR = "explore needs a display (set DISPLAY or use a GUI backend)"

_NO_DISPLAY_BACKENDS = ("webagg", "nbagg", "notebook", "ipympl", "widget", "macosx")
_COLORS = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
           "#bcbd22", "#393b79", "#637939", "#843c39", "#7b4173", "#3182bd", "#e6550d", "#31a354")
_FIGSIZE = (11.0, 7.6)


# ---------------------------------------------------------------- display check
def display_problem() -> str | None:
    """None if an interactive matplotlib window can be opened, else the reason.

    Resolves matplotlib's backend (this may import pyplot: with no backend
    configured, matplotlib picks a GUI backend if a display is reachable, else
    Agg).  A non-interactive backend (agg, pdf, ...) cannot show a window; a
    GUI backend on Linux needs DISPLAY or WAYLAND_DISPLAY.  Browser backends
    (webagg) and custom ``module://`` backends are let through.
    """
    import matplotlib

    backend = str(matplotlib.get_backend()).lower()
    try:
        from matplotlib.backends import BackendFilter, backend_registry

        interactive = set(backend_registry.list_builtin(BackendFilter.INTERACTIVE))
    except ImportError:  # matplotlib < 3.9
        from matplotlib import rcsetup

        interactive = {b.lower() for b in rcsetup.interactive_bk}
    if backend.startswith("module://"):
        return None
    if backend not in interactive:
        return DISPLAY_ERROR
    if (sys.platform.startswith("linux") and backend not in _NO_DISPLAY_BACKENDS
            and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY")):
        return DISPLAY_ERROR
    return None


def _free_keys():
    """Remove the explorer's keys from matplotlib's default key map (e.g. 's' would open
    a save dialog, 'p' pan, 'r' home, 'c' back) for this process."""
    import matplotlib as mpl

    for name in [k for k in mpl.rcParams if k.startswith("keymap.")]:
        keys = list(mpl.rcParams[name])
        kept = [k for k in keys if k not in KEYS]
        if kept != keys:
            mpl.rcParams[name] = kept


def _stamp() -> str:
    return _dt.datetime.now().strftime("%Y%m%d-%H%M%S")


def _num(x) -> str:
    """Short form of a coordinate: 4 digits, round-off-sized values as 0."""
    x = float(x)
    return "0" if abs(x) < 1e-12 else f"{x:.4g}"


def _break_jumps(curve, gap):
    """A polyline with NaN rows inserted where consecutive points are more than ``gap`` apart
    (unresolved pieces of a manifold are not drawn as straight chords)."""
    c = np.asarray(curve, dtype=np.float64)
    if len(c) < 2:
        return c
    jumps = np.flatnonzero(np.hypot(*np.diff(c, axis=0).T) > gap)
    return np.insert(c, jumps + 1, np.nan, axis=0) if len(jumps) else c


def _clip(line: str, width: int = STATUS_WIDTH) -> str:
    return line if len(line) <= width else line[:width - 3] + "..."


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
    """One clicked orbit at the current parameters: its crossings, its chaos indicators and
    its artist."""

    seed: tuple                    # (p1, p2) where it was started
    color: str
    main: _Track
    line: object = None            # matplotlib Line2D of the crossings
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


# ---------------------------------------------------------------- the explorer
class Explorer:
    """Click on the section, watch the orbit appear.

    Parameters
    ----------
    params : model.Params
        model parameters (MODEL.md R3).
    h : float
        energy level; the section is phi = ``phi0`` (default pi, MODEL.md R9).
    method, tol, dt :
        integration settings of :func:`explorer.sections.crossings`.
    chunk : int
        crossings computed per orbit and timer tick (default 50).
    max_crossings : int
        crossings per orbit (default 2000).
    fig : matplotlib Figure or None
        draw into this figure (it must have a canvas); None creates one with pyplot.
    phi0, direction :
        section angle and crossing direction (+1: dphi/dt > 0, -1, 0: both).
    out_dir : str
        where 's' and 'w' write their files (default: the current directory).
    label : str
        a name shown in the title and stored with 'w' (e.g. the scene name).
    indicators : bool
        compute the chaos indicators of each orbit (MEGNO, mLCE; default True).

    Headless use (tests): build it on a ``Figure`` with an Agg canvas, call
    :meth:`on_click` / :meth:`on_key` with matplotlib events (or process them
    through ``fig.canvas.callbacks``), and call :meth:`step` until it returns
    False.  Bad parameters raise :class:`model.ParameterError`.
    """

    def __init__(self, params, h, *, method="taylor", tol=None, dt=None, chunk=50, max_crossings=2000,
                 fig=None, phi0=math.pi, direction=1, out_dir=".", label="", indicators=True):
        from explorer.analysis import sections

        if not isinstance(params, model.Params):
            params = model.Params(**params) if isinstance(params, dict) else model.Params.from_array(params)
        if method not in sections.METHODS:
            raise ParameterError(f"method must be one of {', '.join(sections.METHODS)}; got {method!r}")
        self._sections = sections
        self.params = params
        self.h = self._finite("h", h)
        self.phi0 = self._finite("phi0", phi0)
        if direction not in (-1, 0, 1):
            raise ParameterError(f"direction must be +1, -1 or 0 (both), got {direction!r}")
        self.direction = int(direction)
        self.method = method
        self.tol = sections.DEFAULT_TOL if tol is None else float(tol)
        self.dt = sections.DEFAULT_DT if dt is None else float(dt)
        if method in sections.ADAPTIVE_METHODS:
            validation.real("tol", self.tol, sections.MIN_TOL, sections.MAX_TOL)
        else:
            validation.real("dt", self.dt, 0.0, lo_open=True)
        for name, v in (("crossings-per-chunk", chunk), ("max-crossings", max_crossings)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ParameterError(f"{name} must be an integer >= 1, got {v!r}")
        self.chunk = int(chunk)
        self.max_crossings = int(max_crossings)
        self.out_dir = os.fspath(out_dir)
        self.label = str(label)
        self.indicators = bool(indicators)

        self.seeds: list[tuple] = []        # every clicked (p1, p2), kept across parameter changes
        self.seed_colors: list[str] = []
        self.orbits: list[Orbit] = []       # orbits at the current parameters
        self.color_by_indicator = False
        self.show_separatrices = False
        self.message = ""
        self._next_color = 0
        self._orbit_number = 0
        self._rr = 0                         # round-robin offset when more than MAX_BATCH run
        self._syncing = False
        self._timer = None
        self._sep_artists = []

        self._build_figure(fig)
        self._draw_region(reset_limits=True)
        self._set_message(f"click inside the white region to start an orbit ({self.method}, "
                          f"{self.max_crossings} crossings in chunks of {self.chunk})")

    # ------------------------------------------------------------ small helpers
    @staticmethod
    def _finite(name, v) -> float:
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise ParameterError(f"{name} must be a real number, got {v!r}") from None
        if not math.isfinite(x):
            raise ParameterError(f"{name} must be finite, got {v!r}")
        return x

    def _integration_kwargs(self) -> dict:
        kw = {"method": self.method, "phi0": self.phi0, "direction": self.direction}
        if self.method in self._sections.ADAPTIVE_METHODS:
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
        return any(o.running or (o.indicator_pending and self.indicators) for o in self.orbits)

    def _title(self) -> str:
        from explorer.app.figures import mathtext_label

        parts = [f"mu = {self.params.mu:g}", f"h = {self.h:g}"]
        for n in PARAM_NAMES:
            v = getattr(self.params, n)
            if n != "mu" and v != getattr(model.FIGURE4, n):
                parts.append(f"{n} = {v:g}")
        text = mathtext_label(", ".join(parts))
        return f"{self.label}: {text}" if self.label else text

    # ------------------------------------------------------------ figure
    def _build_figure(self, fig):
        import matplotlib as mpl
        from matplotlib.patches import Ellipse
        from matplotlib.widgets import Button, Slider, TextBox

        from explorer.app.figures import BOUNDARY_COLOR, BOUNDARY_WIDTH, FORBIDDEN_COLOR

        if fig is None:
            import matplotlib.pyplot as plt

            try:
                fig = plt.figure(figsize=_FIGSIZE)
            except Exception as exc:  # e.g. TclError: the display cannot be opened
                raise ParameterError(f"{DISPLAY_ERROR}: {type(exc).__name__}: {exc}") from None
            try:
                fig.canvas.manager.set_window_title("explorer explore")
            except Exception:  # some backends have no window title
                pass
        self.fig = fig
        ax = self.ax = fig.add_axes([0.07, 0.27, 0.56, 0.65])
        ax.set_facecolor(FORBIDDEN_COLOR)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("$p_1$")
        ax.set_ylabel("$p_2$")
        ax.tick_params(direction="in", top=True, right=True)
        self.region_patch = Ellipse((0, 0), 1, 1, facecolor="white", edgecolor="none", zorder=0.5)
        self.boundary_patch = Ellipse((0, 0), 1, 1, facecolor="none", edgecolor=BOUNDARY_COLOR,
                                      linewidth=BOUNDARY_WIDTH, zorder=3)
        ax.add_patch(self.region_patch)
        ax.add_patch(self.boundary_patch)
        self.region_note = ax.text(0.03, 0.03, "", transform=ax.transAxes, fontsize=9, zorder=5,
                                   bbox=dict(boxstyle="round,pad=0.25", facecolor="white", edgecolor="none",
                                             alpha=0.85))
        (self.seed_ok_line,) = ax.plot([], [], linestyle="none", marker="+", markersize=7, color="k",
                                       markeredgewidth=1.0, zorder=4)
        (self.seed_bad_line,) = ax.plot([], [], linestyle="none", marker="x", markersize=6, color="#b2182b",
                                        markeredgewidth=1.0, zorder=4)

        # colour bar of the MEGNO (shown with 'x'); turbo: every colour is visible on white
        self.cmap = mpl.colormaps["turbo"]
        self.norm = mpl.colors.Normalize(vmin=0.0, vmax=MEGNO_COLOR_MAX, clip=True)
        self.cax = fig.add_axes([0.645, 0.27, 0.013, 0.65])
        sm = mpl.cm.ScalarMappable(norm=self.norm, cmap=self.cmap)
        self.colorbar = fig.colorbar(sm, cax=self.cax, extend="max")
        self.colorbar.set_label(f"MEGNO $\\langle Y\\rangle$ at t = {INDICATOR_TIME:g} (2: regular, larger: chaotic)",
                                fontsize=8)
        self.cax.tick_params(labelsize=7)
        self.cax.set_visible(False)

        # sliders and the parameter text box
        mu_max = max(10.0, 2.0 * self.params.mu)
        emin = self._energy_minimum()
        h_lo = min(self.h, emin) if emin is not None else min(self.h, 0.0)
        h_hi = max(self.h + 1.0, (emin if emin is not None else 0.0) + 3.0 * max(self.h - (emin or 0.0), 1.0))
        self.mu_slider = Slider(fig.add_axes([0.12, 0.175, 0.46, 0.025]), "$\\mu$", 0.0, mu_max,
                                valinit=self.params.mu, valfmt="%.4g")
        self.h_slider = Slider(fig.add_axes([0.12, 0.138, 0.46, 0.025]), "$h$", h_lo, h_hi,
                               valinit=self.h, valfmt="%.4g")
        self.mu_slider.on_changed(lambda v: self._slider_changed("mu", v))
        self.h_slider.on_changed(lambda v: self._slider_changed("h", v))
        self.textbox = TextBox(fig.add_axes([0.12, 0.088, 0.30, 0.034]), "set ", initial="")
        self.textbox.on_submit(self._text_submitted)
        fig.text(0.43, 0.105, "e.g. a1=1.2  or  mu=0.03, h=2.5  (Enter)", fontsize=8, va="center", color="0.3")

        # buttons (same actions as the keys)
        self.buttons = {}
        labels = (("c", "clear  [c]"), ("r", "re-run seeds  [r]"), ("s", "save PNG  [s]"),
                  ("w", "write HDF5  [w]"), ("x", "colour by MEGNO  [x]"), ("p", "separatrices  [p]"))
        for i, (key, text) in enumerate(labels):
            b = Button(fig.add_axes([0.73, 0.86 - i * 0.058, 0.22, 0.046]), text)
            b.label.set_fontsize(9)
            b.on_clicked(lambda _ev, k=key: self.do(k))
            self.buttons[key] = b
        help_text = ("click in the white region: start an orbit\n"
                     "there (M > 0 from the energy)\n\n"
                     "sliders / text: change a parameter;\n"
                     "the seeds (+) are kept, press r\n"
                     "to run them again\n\n"
                     f"x: colour by the MEGNO <Y> over\n"
                     f"t <= {INDICATOR_TIME:g} (2: quasi-periodic,\n"
                     f"0: stable periodic, > {CHAOTIC_MEGNO:g}: chaotic-like)\n\n"
                     "p: fixed points (o elliptic, x hyperbolic)\n"
                     "and separatrices\n\n"
                     "toolbar zoom/pan: clicks do not start orbits")
        fig.text(0.73, 0.47, help_text, fontsize=8, va="top", color="0.2", linespacing=1.3)
        self.status_text = fig.text(0.01, 0.006, "", fontsize=9, va="bottom", ha="left", family="monospace")

        fig.canvas.mpl_connect("button_press_event", self.on_click)
        fig.canvas.mpl_connect("key_press_event", self.on_key)
        self._timer = fig.canvas.new_timer(interval=TIMER_INTERVAL_MS)
        self._timer.add_callback(self._tick)
        self._sep_timer = fig.canvas.new_timer(interval=SEPARATRIX_DELAY_MS)
        self._sep_timer.single_shot = True
        self._sep_timer.add_callback(self.refresh_separatrices)

    def _energy_minimum(self):
        """Minimum of the energy on the section (the region is a point there), or None."""
        big = abs(self.h) + 1e3
        e = model.allowed_ellipse(self.params, big, self.phi0)
        if e is None:
            return None
        c1, c2, r1, r2 = e
        P = self.params
        return big - r1 * r1 / (2.0 * P.a1)

    def _draw_region(self, reset_limits=False):
        """Region, title, seeds and (if shown) separatrices at the current parameters; returns
        the separatrices' message (None if they are hidden)."""
        from explorer.app.figures import region_limits

        e = self.region
        if e is None:
            self.region_patch.set_visible(False)
            self.boundary_patch.set_visible(False)
            emin = self._energy_minimum()
            extra = f" (h must exceed {emin:.6g})" if emin is not None else ""
            self.region_note.set_text(f"no allowed region at h = {self.h:g}{extra}")
            self.region_note.set_visible(True)
        else:
            c1, c2, r1, r2 = e
            for p in (self.region_patch, self.boundary_patch):
                p.set_center((c1, c2))
                p.set_width(2 * r1)
                p.set_height(2 * r2)
                p.set_visible(True)
            self.region_note.set_visible(False)
            if reset_limits:
                (x0, x1), (y0, y1) = region_limits(self.params, self.h, self.phi0)
                self.ax.set_xlim(x0, x1)
                self.ax.set_ylim(y0, y1)
        self.ax.set_title(self._title(), fontsize=10)
        self._draw_seeds()
        if not self.show_separatrices:
            return None
        # recomputed when the parameters rest (a slider drag would otherwise recompute them at
        # every motion event); headless, call refresh_separatrices()
        self._clear_separatrices()
        self._sep_timer.stop()
        self._sep_timer.start()
        return "separatrices: recomputing at the new parameters ..."

    def refresh_separatrices(self):
        """Recompute the fixed points and separatrices shown (after a parameter change)."""
        if self.show_separatrices:
            self._set_message(self._draw_separatrices())
            self._redraw()

    def _draw_seeds(self):
        ok, bad = [], []
        for s in self.seeds:
            (ok if self._admissible(*s) else bad).append(s)
        ok = np.array(ok).reshape(-1, 2)
        bad = np.array(bad).reshape(-1, 2)
        self.seed_ok_line.set_data(ok[:, 0], ok[:, 1])
        self.seed_bad_line.set_data(bad[:, 0], bad[:, 1])

    def _admissible(self, p1, p2) -> bool:
        with np.errstate(all="ignore"):
            return bool(model.section_M2(self.params, p1, p2, self.h, self.phi0) >= 0.0)

    def _redraw(self):
        self.fig.canvas.draw_idle()

    def _set_message(self, text):
        self.message = str(text)
        self._update_status()

    def status_lines(self) -> tuple[str, str]:
        """(last orbit line, message line) of the status text."""
        if not self.orbits:
            first = "no orbit yet"
        else:
            o = self.orbits[-1]
            if o.running:
                state = "running"
            else:
                state = "done" if o.main.status == 0 else self._status_name(o.main.status)
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

    @staticmethod
    def status_names() -> dict:
        """{code: name} of the kernels' status codes plus the explorer's own (running, failed)."""
        from explorer.kernels import STATUS_NAMES

        names = dict(STATUS_NAMES)
        names.update({STATUS_RUNNING: RUNNING_NAME, STATUS_FAILED: FAILED_NAME})
        return names

    def _status_name(self, code) -> str:
        return self.status_names().get(int(code), f"status {code}")

    def _update_status(self):
        first, msg = self.status_lines()
        self.status_text.set_text("\n".join(_clip(line) for line in [first] + msg.splitlines()))

    # ------------------------------------------------------------ orbits
    def _take_color(self) -> str:
        c = _COLORS[self._next_color % len(_COLORS)]
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
        orbit = Orbit(seed=(p1, p2), color=color or self._take_color(), main=main,
                      indicator_pending=self.indicators, number=self._orbit_number)
        (orbit.line,) = self.ax.plot([], [], linestyle="none", marker="o", markersize=1.8, markeredgewidth=0,
                                     color=orbit.color, zorder=2)
        self.orbits.append(orbit)
        self._start_timer()
        return orbit

    def _start_timer(self):
        if self._timer is not None:
            self._timer.start()

    def _stop_timer(self):
        if self._timer is not None:
            self._timer.stop()

    def _tick(self):
        """Timer callback: one step; stop the timer when nothing runs."""
        try:
            more = self.step()
        except Exception as exc:  # never let an exception kill the GUI loop
            self._stop_timer()
            for o in self.orbits:
                if o.running:
                    o.main.status = STATUS_FAILED
                o.indicator_pending = False
            self._set_message(f"integration failed: {type(exc).__name__}: {' '.join(str(exc).split())}")
            self._redraw()
            return
        if not more:
            self._stop_timer()

    def step(self) -> bool:
        """One timer tick: advance every running orbit by one chunk of crossings (one batch),
        compute the chaos indicators of new orbits, update the drawing.  Returns True while
        some orbit still runs."""
        jobs = [o for o in self.orbits if o.running]
        pending = [o for o in self.orbits if o.indicator_pending and self.indicators]
        if not jobs and not pending:
            return False
        if len(jobs) > MAX_BATCH:  # round robin over the running orbits
            start = self._rr % len(jobs)
            jobs = (jobs[start:] + jobs[:start])[:MAX_BATCH]
            self._rr += MAX_BATCH
        groups = {}
        for o in jobs:
            groups.setdefault(min(self.chunk, self.max_crossings - o.main.count), []).append(o)
        kw = self._integration_kwargs()
        tmax = 100.0 * self.chunk  # the default budget of sections.crossings for one chunk
        for k, group in groups.items():
            Y = np.array([o.main.state for o in group])
            t0 = time.perf_counter()
            res = self._sections.crossings(self.params, Y, k, tmax=tmax, **kw)
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
        for o in {id(o): o for o in jobs + pending}.values():
            self._update_orbit_artist(o)
        self._update_status()
        self._redraw()
        return self.running

    def _compute_indicators(self, orbits):
        """MEGNO and finite-time mLCE of ``orbits`` over INDICATOR_TIME (explorer.lyapunov)."""
        kw = {"method": self.method}
        if self.method in self._sections.ADAPTIVE_METHODS:
            kw["tol"] = self.tol
        else:
            kw["dt"] = self.dt
        try:
            from explorer.analysis import lyapunov

            res = lyapunov.indicators(self.params, np.array([o.main.y0 for o in orbits]), INDICATOR_TIME, **kw)
        except Exception as exc:  # no indicator module, or it failed: the orbits still run
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

    def run_until_done(self, max_ticks=10**6) -> int:
        """Call :meth:`step` until nothing runs (headless use); returns the number of ticks."""
        n = 0
        while n < max_ticks and self.step():
            n += 1
        return n

    def _orbit_color(self, o):
        if not self.color_by_indicator:
            return o.color
        return "0.55" if o.megno is None else self.cmap(self.norm(o.megno))

    def _update_orbit_artist(self, o):
        pts = o.crossings
        o.line.set_data(pts[:, 1], pts[:, 2])
        o.line.set_color(self._orbit_color(o))

    def _remove_orbits(self):
        for o in self.orbits:
            try:
                o.line.remove()
            except (ValueError, AttributeError, NotImplementedError):
                pass
        self.orbits = []

    # ------------------------------------------------------------ events
    def on_click(self, event):
        """Mouse button 1 in the section axes: start an orbit there, or say why not."""
        if event is None or getattr(event, "inaxes", None) is not self.ax:
            return
        if getattr(event, "button", 1) != 1:
            return
        toolbar = getattr(self.fig.canvas, "toolbar", None)
        if toolbar is not None and getattr(toolbar, "mode", ""):
            return  # zoom / pan in progress
        if event.xdata is None or event.ydata is None:
            return
        self.click(event.xdata, event.ydata)

    def click(self, p1, p2):
        """What a click at (p1, p2) does (also usable without an event)."""
        p1, p2 = float(p1), float(p2)
        if self.region is None:
            self._set_message(f"nothing to do: the region is empty at h = {self.h:g} "
                              f"(h is below the minimum of the energy on the section)")
            self._redraw()
            return None
        with np.errstate(all="ignore"):
            m2 = float(model.section_M2(self.params, p1, p2, self.h, self.phi0))
        if not m2 >= 0.0:
            self._set_message(f"({p1:.4g}, {p2:.4g}) is outside the allowed region: M^2 = {m2:.3g} < 0 there "
                              f"(no real M at energy h = {self.h:g}); click in the white ellipse")
            self._redraw()
            return None
        color = self._take_color()
        self.seeds.append((p1, p2))
        self.seed_colors.append(color)
        orbit = self.launch(p1, p2, color=color)
        self._draw_seeds()
        self._set_message(f"orbit {orbit.number} started at ({p1:.4g}, {p2:.4g}), M = {orbit.main.y0[2]:.4g}")
        self._redraw()
        return orbit

    def on_key(self, event):
        """Keys c, r, s, w, x, p (ignored while the text box is being typed into)."""
        if event is None or getattr(self, "textbox", None) is not None and self.textbox.capturekeystrokes:
            return
        key = getattr(event, "key", None)
        if key in KEYS:
            self.do(key)

    def do(self, key):
        """The action of a key / button: c clear, r re-run, s save PNG, w write HDF5,
        x colour by the chaos indicator (MEGNO), p separatrices."""
        try:
            if key == "c":
                self.clear()
            elif key == "r":
                self.rerun()
            elif key == "s":
                path = self.save_png(self._default_path(".png"))
                self._set_message(f"saved {path}")
            elif key == "w":
                if not self.orbits:
                    self._set_message("no orbit to write: click in the region first")
                else:
                    path = self.save_h5(self._default_path(".h5"))
                    n = len(self.orbits)
                    self._set_message(f"wrote {n} orbit{'s' if n != 1 else ''} to {path}")
            elif key == "x":
                self.toggle_indicator()
            elif key == "p":
                self.toggle_separatrices()
        except (OSError, ValueError) as exc:
            self._set_message(f"{key}: failed: {' '.join(str(exc).split())}")
        self._redraw()

    def _default_path(self, ext):
        base = os.path.join(self.out_dir, f"explore-{_stamp()}")
        path, n = base + ext, 1
        while os.path.exists(path):
            path, n = f"{base}-{n}{ext}", n + 1
        return path

    def clear(self):
        """Remove every orbit and every seed."""
        n = len(self.orbits)
        self._remove_orbits()
        self.seeds, self.seed_colors = [], []
        self._draw_seeds()
        self._stop_timer()
        self._set_message(f"cleared ({n} orbits)")

    def rerun(self):
        """Start the kept seeds again at the current parameters; inadmissible ones are reported."""
        self._remove_orbits()
        if not self.seeds:
            self._set_message("no seeds to re-run: click in the region first")
            return []
        started, skipped = [], []
        for s, c in zip(self.seeds, self.seed_colors):
            if self.region is not None and self._admissible(*s):
                started.append(self.launch(*s, color=c))
            else:
                skipped.append(s)
        msg = f"re-running {len(started)} seeds"
        if skipped:
            pts = ", ".join(f"({a:.3g}, {b:.3g})" for a, b in skipped[:4]) + (" ..." if len(skipped) > 4 else "")
            msg += f"; {len(skipped)} outside the allowed region at these parameters (x): {pts}"
        self._set_message(msg)
        return started

    def toggle_indicator(self):
        self.color_by_indicator = not self.color_by_indicator
        self.cax.set_visible(self.color_by_indicator)
        for o in self.orbits:
            self._update_orbit_artist(o)
        if self.color_by_indicator:
            self._set_message(f"colour = MEGNO <Y> over t <= {INDICATOR_TIME:g} (2: quasi-periodic, 0: stable "
                              f"periodic, larger: chaotic; gray: not known)")
        else:
            self._set_message("colour = one per orbit")

    # ------------------------------------------------------------ separatrices
    def _fixed_points_and_curves(self):
        """(fixed points, curves, message) from :mod:`explorer.analysis.fixedpoints`: Newton's method
        from p = 0 and from the centre of the region; the separatrices of the hyperbolic points."""
        from explorer.analysis.fixedpoints import find_fixed_point as find
        from explorer.analysis.fixedpoints import separatrices as sep

        if self.region is None:
            return [], [], "separatrices: the region is empty"
        c1, c2, r1, r2 = self.region
        guesses = [(0.0, 0.0), (c1, c2), (c1 - 0.5 * r1, c2), (c1 + 0.5 * r1, c2), (c1, c2 - 0.5 * r2),
                   (c1, c2 + 0.5 * r2)]
        points = []
        for g in guesses:
            if not self._admissible(*g):
                continue
            try:
                fp = find(self.params, self.h, g, phi0=self.phi0)
            except Exception:  # no convergence from this guess
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
                    for c in sep(fp, phi0=self.phi0):
                        a = np.asarray(c, dtype=np.float64)
                        if a.ndim == 2 and a.shape[1] == 2 and len(a):
                            curves.append(a)
        except Exception as exc:
            return points, [], f"separatrices: failed ({type(exc).__name__}: {' '.join(str(exc).split())})"
        desc = ", ".join(f"({_num(fp.point[0])}, {_num(fp.point[1])}) {'elliptic' if fp.stable else 'hyperbolic'}"
                         for fp in points)
        return points, curves, f"fixed points {desc}; {len(curves)} separatrix branches"

    def _clear_separatrices(self):
        for a in self._sep_artists:
            a.remove()
        self._sep_artists = []

    def _draw_separatrices(self):
        from explorer.app.figures import CURVE_STYLE

        self._clear_separatrices()
        if not self.show_separatrices:
            return None
        points, curves, msg = self._fixed_points_and_curves()
        style = dict(CURVE_STYLE, color=SEPARATRIX_COLOR, linewidth=0.9)  # black: visible over any orbit colour
        gap = SEPARATRIX_GAP * max(self.region[2], self.region[3]) if self.region else math.inf
        for c in curves or ():
            c = _break_jumps(c, gap)
            (ln,) = self.ax.plot(c[:, 0], c[:, 1], zorder=3.5, **style)
            self._sep_artists.append(ln)
        for fp in points or ():
            (mk,) = self.ax.plot([fp.point[0]], [fp.point[1]], linestyle="none", zorder=4.5,
                                 marker="o" if fp.stable else "x", markersize=8, markeredgewidth=1.8,
                                 markerfacecolor="none", color=SEPARATRIX_COLOR)
            self._sep_artists.append(mk)
        if points is None:
            self.show_separatrices = False
        return msg

    def toggle_separatrices(self):
        """Show / hide the fixed points and separatrices (if explorer.fixedpoints exists)."""
        if self.show_separatrices:
            self.show_separatrices = False
            self._draw_separatrices()
            self._set_message("separatrices hidden")
            return
        self.show_separatrices = True
        self._set_message(self._draw_separatrices())

    # ------------------------------------------------------------ parameters
    def set_param(self, name, value):
        """Set a model parameter (a1 a2 b lam chi zeta mu xi eta) or h: see :meth:`set_params`."""
        self.set_params({name: value})

    def set_params(self, changes: dict):
        """Set model parameters and/or h at once, e.g. ``{"mu": 0.03, "h": 2.5}``.  Stops and
        removes the orbits, redraws the region, keeps the seeds (press r to re-run them).
        Raises ParameterError, with nothing changed, for a bad name or value."""
        names = PARAM_NAMES + ("h",)
        new = {}
        for name, value in dict(changes).items():
            name = str(name).strip()
            if name not in names:
                raise ParameterError(f"unknown parameter {name!r}; one of {', '.join(names)}")
            new[name] = self._finite(name, value)
        h = new.pop("h", self.h)
        params = self.params.with_(**new) if new else self.params  # validated: raises ParameterError
        if params == self.params and h == self.h:
            return
        changed = [f"{k} = {v:g}" for k, v in new.items() if v != getattr(self.params, k)]
        if h != self.h:
            changed.append(f"h = {h:g}")
        self.params, self.h = params, h
        n = len(self.orbits)
        self._remove_orbits()
        self._stop_timer()
        sep_msg = self._draw_region(reset_limits=True)
        self._sync_sliders()
        ok = sum(self._admissible(*s) for s in self.seeds) if self.region is not None else 0
        msg = ", ".join(changed) + ": region redrawn"
        if n:
            msg += f", {n} orbit{'s' if n != 1 else ''} removed"
        if self.seeds:
            msg += f"; {len(self.seeds)} seeds kept ({ok} inside the region): press r to re-run them"
        if sep_msg:
            msg += f"\n{sep_msg}"
        self._set_message(msg)
        self._redraw()

    def _sync_sliders(self):
        self._syncing = True
        try:
            for slider, v in ((self.mu_slider, self.params.mu), (self.h_slider, self.h)):
                if v < slider.valmin or v > slider.valmax:
                    lo, hi = min(slider.valmin, v), max(slider.valmax, v)
                    slider.valmin, slider.valmax = lo, hi
                    slider.ax.set_xlim(lo, hi)
                if slider.val != v:
                    slider.set_val(v)
        finally:
            self._syncing = False

    def _slider_changed(self, name, value):
        if self._syncing:
            return
        try:
            self.set_param(name, value)
        except ParameterError as exc:
            self._set_message(str(exc))
            self._redraw()

    def _text_submitted(self, text):
        """``name=value[, name=value ...]`` from the text box (Enter)."""
        text = text.strip()
        if not text:
            return
        try:
            changes = {}
            for piece in text.replace(";", ",").split(","):
                piece = piece.strip()
                if not piece:
                    continue
                if "=" not in piece:
                    raise ParameterError(f"write name=value (e.g. a1=1.2), got {piece!r}")
                k, v = piece.split("=", 1)
                changes[k.strip()] = v.strip()
            self.set_params(changes)
        except ParameterError as exc:
            self._set_message(" ".join(str(exc).split()))
            self._redraw()
            return
        # hand the keyboard back to the figure (keys c, r, s, ... would go to the text box)
        stop = getattr(self.textbox, "stop_typing", None)
        if stop is not None and self.textbox.capturekeystrokes:
            stop()

    # ------------------------------------------------------------ output
    def _section_bbox(self):
        """The part of the figure holding the section (title, labels, colour bar if shown), in inches."""
        from matplotlib.transforms import Bbox

        renderer = self.fig.canvas.get_renderer()
        boxes = [self.ax.get_tightbbox(renderer)]
        if self.cax.get_visible():
            boxes.append(self.cax.get_tightbbox(renderer))
        return Bbox.union(boxes).transformed(self.fig.dpi_scale_trans.inverted()).padded(0.08)

    def save_png(self, path) -> str:
        """Write the section (axes with its orbits, not the widgets) as a PNG, atomically."""
        from explorer.io.store import atomic_path

        path = os.fspath(path)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.fig.canvas.draw()
        bbox = self._section_bbox()
        with atomic_path(path) as tmp:
            self.fig.savefig(tmp, format="png", dpi=200, bbox_inches=bbox, facecolor="white")
        return path

    def settings(self) -> dict:
        """Everything that determines the orbits' numbers (stored with 'w')."""
        integ = {"method": self.method, "crossings": self.max_crossings, "chunk": self.chunk,
                 "tmax_per_chunk": 100.0 * self.chunk, "phi0": self.phi0, "direction": self.direction}
        if self.method in self._sections.ADAPTIVE_METHODS:
            integ["tol"] = self.tol
        else:
            integ["dt"] = self.dt
        return {"source": "explore", "params": self.params.as_dict(), "h": self.h,
                "seeds": {"kind": "points", "points": [list(o.seed) for o in self.orbits]},
                "integration": integ}

    def _scene_text(self) -> str:
        """A scene file with these parameters and seeds (``python -m explorer sweep`` can rerun
        it; its time budget is per orbit, the explorer's per chunk)."""
        from explorer.io import scene as scene_mod

        try:
            sc = scene_mod.Scene(
                name="explore", params=self.params, h=self.h,
                seeds=scene_mod.SeedSpec(kind="points", points=tuple(o.seed for o in self.orbits)),
                integration=scene_mod.IntegrationSpec(method=self.method, tol=self.tol, dt=self.dt,
                                                      crossings=self.max_crossings, phi0=self.phi0,
                                                      direction=self.direction),
                description="written by python -m explorer explore")
            return sc.to_toml()
        except ParameterError:
            return ""

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

    def save_h5(self, path) -> str:
        """Write the orbits at the current parameters as one panel (index 0) of a new store
        file (:mod:`explorer.store` format), replacing ``path`` atomically."""
        from explorer.io import store

        path = os.fspath(path)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        arrays = self.panel_arrays()
        nan = float("nan")
        attrs = {
            "label": f"explore: mu = {self.params.mu:g}, h = {self.h:g}", "parameter": "",
            "value": float("nan"), "h": self.h, "params": self.params.as_dict(), "settings": self.settings(),
            "method": self.method, "tol": float(self.tol), "dt": float(self.dt), "phi0": self.phi0,
            "direction": self.direction, "crossings_requested": self.max_crossings, "chunk": self.chunk,
            "wall_time": float(sum(o.wall_time for o in self.orbits)),
            "megno": np.array([nan if o.megno is None else o.megno for o in self.orbits], dtype=np.float64),
            "mlce": np.array([nan if o.mlce is None else o.mlce for o in self.orbits], dtype=np.float64),
            "indicator_time": INDICATOR_TIME,
            "indicator_note": ("megno, mlce: explorer.lyapunov.indicators over t <= indicator_time from y0 "
                               "(mean MEGNO <Y>, finite-time maximal Lyapunov exponent); NaN: not computed"),
        }
        names = self.status_names()
        file_attrs = {"scene_name": "explore", "scene": self._scene_text()}
        tmp = f"{path}.tmp-{os.getpid()}-{secrets.token_hex(4)}"
        try:
            store.commit_panel(tmp, 0, arrays, attrs, file_attrs, status_names=names)
            os.replace(tmp, path)
        except BaseException:
            for p in (tmp,):
                try:
                    os.remove(p)
                except FileNotFoundError:
                    pass
            raise
        return path

    # ------------------------------------------------------------ GUI
    def warm_up(self):
        """Load (or compile) the integrator before the first click."""
        if self.region is not None:
            c1, c2 = self.region[:2]
            y = model.section_state(self.params, c1, c2, self.h, self.phi0, self.direction or 1)
            self._sections.crossings(self.params, y, 1, tmax=1.0, **self._integration_kwargs())

    def run(self):
        """Show the window and run until it is closed."""
        import matplotlib.pyplot as plt

        _free_keys()
        self._set_message("loading the integrator ...")
        try:
            self.warm_up()
        except ParameterError:
            pass
        self._set_message("click inside the white region to start an orbit (keys: see the buttons)")
        plt.show()


def from_args(args, fig=None) -> Explorer:
    """An :class:`Explorer` from the ``explore`` command's arguments: the scene's panel (if a
    SCENE is given; else Figure 4 with mu = 0, h = 2), then the explicit options on top."""
    from explorer.analysis import sections
    from explorer.io import scene as scene_mod

    base = model.FIGURE4
    h = model.FIGURE4_H
    method, tol, dt, phi0, direction = "taylor", sections.DEFAULT_TOL, sections.DEFAULT_DT, math.pi, 1
    label = ""
    if args.scene is not None:
        sc = scene_mod.load_scene(args.scene)
        i = args.panel
        if isinstance(i, bool) or not 0 <= i < sc.n_panels:
            raise ParameterError(f"--panel must be in [0, {sc.n_panels - 1}] for scene '{sc.name}', got {i}")
        base, h, plabel = sc.panel(i)
        integ = sc.integration
        method, tol, dt, phi0, direction = integ.method, integ.tol, integ.dt, integ.phi0, integ.direction
        label = sc.name if not plabel else f"{sc.name}[{i}]"
    elif args.panel != 0:
        raise ParameterError("--panel needs a SCENE")
    overrides = {n: getattr(args, n) for n in PARAM_NAMES if getattr(args, n, None) is not None}
    params = base.with_(**overrides) if overrides else base
    if args.h is not None:
        h = args.h
    method = args.method or method
    tol = args.tol if args.tol is not None else tol
    dt = args.dt if args.dt is not None else dt
    return Explorer(params, h, method=method, tol=tol, dt=dt, chunk=args.crossings_per_chunk,
                    max_crossings=args.max_crossings, phi0=phi0, direction=direction,
                    out_dir=args.out_dir, label=label, fig=fig)
