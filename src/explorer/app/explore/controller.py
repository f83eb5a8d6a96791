"""The explorer's controller: the window's events (clicks, keys, sliders, text box, buttons,
timers) turned into actions on the :class:`~explorer.app.explore.state.ExplorerState` and
redraws of the :class:`~explorer.app.explore.view.ExplorerView`; writing the orbits (HDF5 store,
PNG); the ``explore`` command (:func:`from_args`).

Nothing runs in a thread: a matplotlib timer (``fig.canvas.new_timer``) calls
:meth:`Explorer.step`, which advances every running orbit by one chunk and redraws.
"""
from __future__ import annotations

import datetime as _dt
import math
import os
import sys

from explorer import model
from explorer.app.explore.state import KEYS, ExplorerState
from explorer.app.explore.view import DISPLAY_ERROR, ExplorerView
from explorer.model import PARAM_NAMES, ParameterError

#: milliseconds between timer ticks
TIMER_INTERVAL_MS = 15
#: after a parameter change, separatrices are recomputed when the parameters rest this long (ms)
SEPARATRIX_DELAY_MS = 400
_NO_DISPLAY_BACKENDS = ("webagg", "nbagg", "notebook", "ipympl", "widget", "macosx")


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


class Explorer:
    """Click on the section, watch the orbit appear.

    ``Explorer(params, h, *, method, tol, dt, chunk, max_crossings, fig=None, phi0, direction,
    out_dir, label, indicators)``: the arguments of
    :class:`~explorer.app.explore.state.ExplorerState` plus ``fig`` (draw into this figure, which
    must have a canvas; None creates one with pyplot) and ``out_dir`` (where 's' and 'w' write).

    Headless use (tests, notebooks): build it on a ``Figure`` with an Agg canvas, call
    :meth:`click` / :meth:`do` (or send matplotlib events through ``fig.canvas.callbacks``) and
    :meth:`run_until_done`. ``state`` and ``view`` are the two halves; attribute reads that this
    class does not define go to the state, then to the view (``ex.orbits``, ``ex.ax``).
    """

    def __init__(self, params, h, *, fig=None, out_dir=".", **settings):
        self.state = ExplorerState(params, h, **settings)
        self.out_dir = os.fspath(out_dir)
        self.view = ExplorerView(self.state, fig)
        self._syncing = False
        v = self.view
        v.mu_slider.on_changed(lambda val: self._slider_changed("mu", val))
        v.h_slider.on_changed(lambda val: self._slider_changed("h", val))
        v.textbox.on_submit(self._text_submitted)
        for key, b in v.buttons.items():
            b.on_clicked(lambda _ev, k=key: self.do(k))
        canvas = v.fig.canvas
        canvas.mpl_connect("button_press_event", self.on_click)
        canvas.mpl_connect("key_press_event", self.on_key)
        self._timer = canvas.new_timer(interval=TIMER_INTERVAL_MS)
        self._timer.add_callback(self._tick)
        self._sep_timer = canvas.new_timer(interval=SEPARATRIX_DELAY_MS)
        self._sep_timer.single_shot = True
        self._sep_timer.add_callback(self.refresh_separatrices)
        v.draw_region(reset_limits=True)
        st = self.state
        self._say(f"click inside the white region to start an orbit ({st.method}, "
                  f"{st.max_crossings} crossings in chunks of {st.chunk})")

    def __getattr__(self, name):
        # only called for names not found on the controller itself
        if name in ("state", "view"):
            raise AttributeError(name)
        for part in (self.state, self.view):
            if hasattr(part, name):
                return getattr(part, name)
        raise AttributeError(f"'Explorer' object has no attribute {name!r}")

    @property
    def _sep_artists(self):
        return self.view.sep_artists

    # ------------------------------------------------------------ helpers
    def _say(self, text):
        self.state.message = str(text)
        self.view.update_status()

    def _refresh(self, reset_limits=False):
        """Redraw everything that depends on the state."""
        self.view.draw_region(reset_limits=reset_limits)
        self.view.sync_orbits()
        self.view.update_status()
        self.view.redraw()

    # ------------------------------------------------------------ orbits and the timer
    def launch(self, p1, p2, color=None):
        orbit = self.state.launch(p1, p2, color=color)
        self.view.update_orbit(orbit)
        self._timer.start()
        return orbit

    def _tick(self):
        """Timer callback: one step; stop the timer when nothing runs."""
        try:
            more = self.step()
        except Exception as exc:  # noqa: BLE001 - never let an exception kill the GUI loop
            self._timer.stop()
            self.state.fail_running(exc)
            self.view.update_status()
            self.view.redraw()
            return
        if not more:
            self._timer.stop()

    def step(self) -> bool:
        """One timer tick: advance every running orbit by one chunk, compute the chaos indicators
        of new orbits, update the drawing. Returns True while some orbit still runs."""
        changed = self.state.step()
        if not changed:
            return False
        for o in changed:
            self.view.update_orbit(o)
        self.view.update_status()
        self.view.redraw()
        return self.state.running

    def run_until_done(self, max_ticks=10**6) -> int:
        """Call :meth:`step` until nothing runs (headless use); returns the number of ticks."""
        n = 0
        while n < max_ticks and self.step():
            n += 1
        return n

    # ------------------------------------------------------------ events
    def on_click(self, event):
        """Mouse button 1 in the section axes: start an orbit there, or say why not."""
        if event is None or getattr(event, "inaxes", None) is not self.view.ax:
            return
        if getattr(event, "button", 1) != 1:
            return
        toolbar = getattr(self.view.fig.canvas, "toolbar", None)
        if toolbar is not None and getattr(toolbar, "mode", ""):
            return  # zoom / pan in progress
        if event.xdata is None or event.ydata is None:
            return
        self.click(event.xdata, event.ydata)

    def click(self, p1, p2):
        """What a click at (p1, p2) does (also usable without an event)."""
        orbit = self.state.click(p1, p2)
        if orbit is not None:
            self.view.update_orbit(orbit)
            self.view.draw_seeds()
            self._timer.start()
        self.view.update_status()
        self.view.redraw()
        return orbit

    def on_key(self, event):
        """Keys c, r, s, w, x, p, o (ignored while the text box is being typed into)."""
        if event is None or self.view.textbox.capturekeystrokes:
            return
        key = getattr(event, "key", None)
        if key in KEYS:
            self.do(key)

    def do(self, key):
        """The action of a key / button: c clear, r re-run, s save PNG, w write HDF5,
        x colour by the chaos indicator (MEGNO), p separatrices, o periodic orbits."""
        st = self.state
        try:
            if key == "c":
                self.clear()
            elif key == "r":
                self.rerun()
            elif key == "s":
                path = self.save_png(self._default_path(".png"))
                self._say(f"saved {path}")
            elif key == "w":
                if not st.orbits:
                    self._say("no orbit to write: click in the region first")
                else:
                    path = self.save_h5(self._default_path(".h5"))
                    n = len(st.orbits)
                    self._say(f"wrote {n} orbit{'s' if n != 1 else ''} to {path}")
            elif key == "x":
                self.toggle_indicator()
            elif key == "p":
                self.toggle_separatrices()
            elif key == "o":
                self.toggle_periodic()
        except (OSError, ValueError) as exc:
            self._say(f"{key}: failed: {' '.join(str(exc).split())}")
        self.view.redraw()

    def _default_path(self, ext):
        base = os.path.join(self.out_dir, f"explore-{_stamp()}")
        path, n = base + ext, 1
        while os.path.exists(path):
            path, n = f"{base}-{n}{ext}", n + 1
        return path

    def clear(self):
        """Remove every orbit and every seed."""
        self.state.clear()
        self._timer.stop()
        self._refresh()

    def rerun(self):
        """Start the kept seeds again at the current parameters; inadmissible ones are reported."""
        started = self.state.rerun()
        if started:
            self._timer.start()
        self._refresh()
        return started

    def toggle_indicator(self):
        self.state.toggle_indicator()
        self._refresh()

    # ------------------------------------------------------------ separatrices
    def _draw_separatrices(self):
        points, curves, msg = self.state.fixed_points_and_curves()
        self.view.draw_separatrices(points, curves)
        return msg

    def refresh_separatrices(self):
        """Recompute the fixed points and separatrices shown (after a parameter change)."""
        if self.state.show_separatrices:
            self._say(self._draw_separatrices())
            self.view.redraw()

    def toggle_separatrices(self):
        """Show / hide the fixed points and separatrices."""
        st = self.state
        st.show_separatrices = not st.show_separatrices
        if not st.show_separatrices:
            self.view.clear_separatrices()
            self._say("separatrices hidden")
            return
        self._say(self._draw_separatrices())

    # ------------------------------------------------------------ periodic orbits
    def toggle_periodic(self):
        """Show / hide the periodic orbits of periods 1..PERIODIC_MAX with their stability."""
        st = self.state
        st.show_periodic = not st.show_periodic
        if not st.show_periodic:
            self.view.clear_periodic()
            self._say("periodic orbits hidden")
            return
        orbits, msg = st.periodic_orbits()
        self.view.draw_periodic(orbits)
        self._say(msg)

    # ------------------------------------------------------------ parameters
    def set_param(self, name, value):
        """Set a model parameter (a1 a2 b lam chi zeta mu xi eta) or h: see :meth:`set_params`."""
        self.set_params({name: value})

    def set_params(self, changes: dict):
        """Set model parameters and/or h at once, e.g. ``{"mu": 0.03, "h": 2.5}``.  Stops and
        removes the orbits, redraws the region, keeps the seeds (press r to re-run them).
        Raises ParameterError, with nothing changed, for a bad name or value."""
        if not self.state.set_params(changes):
            return
        self._timer.stop()
        self._syncing = True
        try:
            self.view.sync_sliders()
        finally:
            self._syncing = False
        if self.state.show_separatrices:
            # recomputed when the parameters rest (a slider drag would otherwise recompute them at
            # every motion event); headless, call refresh_separatrices()
            self.view.clear_separatrices()
            self._sep_timer.stop()
            self._sep_timer.start()
            self.state.message += "\nseparatrices: recomputing at the new parameters ..."
        if self.state.show_periodic:   # stale at the new parameters: hidden (press o again)
            self.view.clear_periodic()
            self.state.show_periodic = False
            self.state.message += "\nperiodic orbits hidden (parameters changed; press o)"
        self._refresh(reset_limits=True)

    def _slider_changed(self, name, value):
        if self._syncing:
            return
        try:
            self.set_param(name, value)
        except ParameterError as exc:
            self._say(str(exc))
            self.view.redraw()

    def _text_submitted(self, text):
        """``name=value[, name=value ...]`` from the text box (Enter)."""
        text = text.strip()
        if not text:
            return
        try:
            self.set_params(self.state.parse_assignments(text))
        except ParameterError as exc:
            self._say(" ".join(str(exc).split()))
            self.view.redraw()
            return
        # hand the keyboard back to the figure (keys c, r, s, ... would go to the text box)
        stop = getattr(self.view.textbox, "stop_typing", None)
        if stop is not None and self.view.textbox.capturekeystrokes:
            stop()

    # ------------------------------------------------------------ output
    def save_png(self, path) -> str:
        """Write the section (axes with its orbits, not the widgets) as a PNG, atomically."""
        return self.view.save_png(path)

    def scene_text(self) -> str:
        """A scene file with these parameters and seeds (``python -m explorer sweep`` can rerun
        it; its time budget is per orbit, the explorer's per chunk)."""
        from explorer.io import scene as scene_mod

        st = self.state
        try:
            sc = scene_mod.Scene(
                name="explore", params=st.params, h=st.h,
                seeds=scene_mod.SeedSpec(kind="points", points=tuple(o.seed for o in st.orbits)),
                integration=scene_mod.IntegrationSpec(method=st.method, tol=st.tol, dt=st.dt,
                                                      crossings=st.max_crossings, phi0=st.phi0,
                                                      direction=st.direction),
                description="written by python -m explorer explore")
            return sc.to_toml()
        except ParameterError:
            return ""

    def save_h5(self, path) -> str:
        """Write the orbits at the current parameters as one panel (index 0) of a new store
        file (:mod:`explorer.io.store` format), replacing ``path`` atomically."""
        from explorer.io import store

        path = os.fspath(path)
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        file_attrs = {"scene_name": "explore", "scene": self.scene_text()}
        store.commit_panel(path, 0, self.state.panel_arrays(), self.state.panel_attrs(), file_attrs,
                           status_names=self.state.status_names(), fresh=True)
        return path

    # ------------------------------------------------------------ GUI
    def run(self):
        """Show the window and run until it is closed."""
        import matplotlib.pyplot as plt

        _free_keys()
        self._say("loading the integrator ...")
        try:
            self.state.warm_up()
        except ParameterError:
            pass
        self._say("click inside the white region to start an orbit (keys: see the buttons)")
        plt.show()


def from_args(args, fig=None) -> Explorer:
    """An :class:`Explorer` from the ``explore`` command's arguments: the scene's panel (if a
    SCENE is given; else Figure 4 with mu = 0, h = 2), then the explicit options on top."""
    params, h, settings = _settings(args)
    return Explorer(params, h, fig=fig, **settings)


def check_args(args) -> None:
    """Validate the ``explore`` command's arguments without opening a window (ParameterError
    naming the option otherwise), so that bad input is reported even where no display is."""
    params, h, settings = _settings(args)
    ExplorerState(params, h, **{k: v for k, v in settings.items() if k != "out_dir"})


def _settings(args):
    """(params, h, keywords of :class:`Explorer`) of the ``explore`` command's arguments."""
    from explorer.analysis import sections
    from explorer.io import scene as scene_mod
    from explorer.model import validation

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
    return params, h, dict(method=method, tol=tol, dt=dt, chunk=args.crossings_per_chunk,
                           max_crossings=args.max_crossings, phi0=phi0, direction=direction,
                           out_dir=validation.output_path("--out-dir", args.out_dir, directory=True), label=label)
