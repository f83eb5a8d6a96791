"""The page's fields, and the μ slider and stepper that write into them (docs/commands/serve.md)."""
from __future__ import annotations

import math
import time

import panel as pn

from explorer import model
from explorer.app.serve.settings import Settings, room_for
from explorer.app.serve.style import FIELD_WIDTH
from explorer.app.serve.tasks import Timer
from explorer.model import ParameterError

#: the μ slider ends at least here; while dragged its value applies at most every SLIDE_SECONDS
MU_SLIDER_END = 0.1
SLIDE_SECONDS = 0.25
#: labels of the fields, and what each means (its tooltip)
LABELS = {p.name: p.symbol for p in model.PARAMETERS} | {
    "h": "h", "method": "method", "tol": "tol", "dt": "dt", "crossings": "crossings", "phi0": "φ0"}
HELP = {p.name: f"{p.symbol}: {p.help} (docs/model.md)" for p in model.PARAMETERS} | {
    "h": "the energy: the white ellipse is where it allows motion (M² ≥ 0), gray where not",
    "method": "the integrator: taylor and dop853 adapt their step to tol; split2 to split8 take fixed steps dt",
    "tol": "the local error per step of taylor and dop853 (smaller: more accurate, slower)",
    "dt": "the fixed step of split2 to split8 (smaller: more accurate, more steps)",
    "crossings": "how many crossings of the section each click computes",
    "phi0": "the section φ = φ0 (a number, or pi, pi/2, 2pi)"}
#: the stepper's widgets' margins (px): its row fits the fields' 230 px
STEP_MARGIN = (5, 3)


def default_step(value: float) -> float:
    """The stepper's step for a field's value: the power of ten near 1 % of it (0.01 for 0)."""
    value = abs(float(value))
    if not (math.isfinite(value) and value > 0.0):
        return 0.01
    return 10.0 ** (math.floor(math.log10(value)) - 2)


def stepped(name: str, text: str, step: float, k: int) -> str:
    """Field ``name``'s ``text`` moved by ``k`` steps of ``step`` (15 significant digits: 0.03 + 0.0001 is 0.0301)."""
    if name == "crossings":
        return str(int(text) + k * max(1, round(step)))
    return repr(float(f"{float(text) + k * step:.15g}"))


def slider_range(mu: float) -> tuple:
    """(end, step) of the μ slider at ``mu`` (docs/commands/serve.md, "μ slider")."""
    want = max(2.0 * abs(mu), MU_SLIDER_END) if math.isfinite(2.0 * mu) else MU_SLIDER_END
    decade = 10.0 ** math.floor(math.log10(want))
    end = next(m * decade for m in (1, 2, 5, 10) if m * decade >= want * (1 - 1e-12))
    return end, 10.0 ** (math.floor(math.log10(end * (1 + 1e-12))) - 3)


class Fields:
    """One widget per field of ``settings()`` (``inputs``); an edit calls ``on_edit(name)`` on the session's loop."""

    def __init__(self, session, settings, on_edit):
        from explorer.analysis.sections import METHODS

        self._quiet = False
        self.settings = settings
        self._typed: dict = {}                  # each text field's value_input when last read
        s = settings().fields()
        self.inputs: dict = {}
        for name in settings().field_names:
            shown = dict(label=LABELS.get(name, name), value=s[name], width=FIELD_WIDTH, description=HELP.get(name))
            if name == "method":
                w = pn.widgets.Select(options=list(METHODS), **shown)
            else:
                w = pn.widgets.TextInput(**shown)
            w.param.watch(lambda _e, name=name: self._edited(session, on_edit, name), "value")
            self.inputs[name] = w
        self.mu_slider = pn.widgets.FloatSlider(label=f"{LABELS['mu']} (slider)", start=0.0, width=220,
                                                visible="mu" in s)
        self._slider_at(float(s.get("mu", 0.0)))
        self._dragging = False                  # from a drag's first move to its release: the range stays
        self._slide_timer = Timer(session, lambda: self._slid(self.mu_slider.value))
        self.mu_slider.param.watch(self._drag, "value")
        self.mu_slider.param.watch(self._released, "value_throttled")
        steps = [n for n in settings().field_names if n != "method"]
        self.step_field = pn.widgets.Select(label="step", options={LABELS.get(n, n): n for n in steps},
                                            value=steps[0], width=62, margin=STEP_MARGIN)
        self.step_size = pn.widgets.FloatInput(label="by", width=82, margin=STEP_MARGIN)
        self._reset_step(steps[0])
        self.step_field.param.watch(lambda e: self._reset_step(e.new), "value")
        self.step_buttons = tuple(pn.widgets.Button(label=label, width=28, align="end", margin=STEP_MARGIN)
                                  for label in ("−", "+"))
        for b, k in zip(self.step_buttons, (-1, 1)):
            b.on_click(lambda _e, k=k: session.soon(lambda: self.step(k)))
        self.grid = pn.Column(self.mu_slider, pn.GridBox(*self.inputs.values(), ncols=2),
                              pn.Row(self.step_field, self.step_size, *self.step_buttons))

    def _edited(self, session, on_edit, name: str) -> None:
        if self._quiet:
            return
        if name != "method":
            self.step_field.value = name
        session.soon(lambda: on_edit(name))

    def _reset_step(self, name: str) -> None:
        self.step_size.value = default_step(float(self.settings().fields()[name]))

    def step(self, k: int, name: str | None = None) -> None:
        """Move field ``name`` (None: the stepper's) ``k`` steps from the value that applies, as if typed."""
        name = name or self.step_field.value
        size = self.step_size.value
        if size is None or not (math.isfinite(size) and size > 0.0):
            return self._reset_step(name)
        text = stepped(name, self.settings().fields()[name], float(size), k)
        if self.inputs[name].value == text:       # the same refused text again: said again
            self.inputs[name].param.trigger("value")
        else:
            self.inputs[name].value = text

    # Panel's slider gives ``value`` at every move and ``value_throttled`` at the release only, a value that
    # is a browser's sum of steps, and one fixed range: the hold, the rounding and the range are the page's.
    def _drag(self, _event) -> None:
        if not self._quiet:
            self._dragging = True
            self._slide_timer.at(time.monotonic() + SLIDE_SECONDS)

    def _released(self, event) -> None:
        if not self._quiet:
            self._slide_timer.cancel()
            self._dragging = False
            self._slider_at(self._slid(event.new))      # the range follows the released value

    def _slid(self, value) -> float:
        """The slider's ``value`` into the μ field, rounded to the slider's step (no float noise)."""
        text = repr(round(float(value), max(0, -math.floor(math.log10(self.mu_slider.step)))))
        self.inputs["mu"].value = text
        return float(text)

    def _slider_at(self, mu: float) -> None:
        """The slider at ``mu``, over slider_range(mu), in one update (the browser takes them together)."""
        end, step = slider_range(mu)
        self._quiet = True
        try:
            self.mu_slider.param.update(value=min(max(mu, 0.0), end), end=end, step=step)
        finally:
            self._quiet = False

    def show(self) -> None:
        """The fields and the slider show the page's settings (not an edit: nothing is called)."""
        self._quiet = True
        try:
            for name, text in self.settings().fields().items():
                w = self.inputs[name]
                if getattr(w, "value_input", None) not in (None, self._typed.get(name, "")):
                    continue            # typed into since its last apply: the text is the user's
                w.value = text          # (param calls no watcher and sends nothing for an unchanged value)
        finally:
            self._quiet = False
        mu = self.settings().fields().get("mu")
        if mu is not None and not self._dragging:
            self._slider_at(float(mu))

    def read(self, base: Settings, n_orbits: int, name: str | None = None) -> Settings:
        """``base`` with the page's settings and the text of field ``name`` (None: every field's), validated, with
        room for ``n_orbits`` orbits (ParameterError otherwise)."""
        fields = self.settings().fields()
        for n in self.inputs if name is None else (name,):
            fields[n] = self.inputs[n].value
            if getattr(self.inputs[n], "value_input", None) == fields[n]:
                self._typed[n] = fields[n]          # this text applies now (or is refused): no longer typing
        new = base.with_fields(fields)
        full = room_for(n_orbits, new.crossings)
        if full:
            raise ParameterError(f"crossings: {full}")
        return new
