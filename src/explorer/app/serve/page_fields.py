"""The fields of the page's values, the μ slider and the stepper: slider and stepper write into a
field, which applies the value as typed (:func:`explorer.app.serve.settings.parse_fields`).
"""
from __future__ import annotations

import math

import panel as pn

from explorer import model
from explorer.app.serve import settings as settings_mod
from explorer.app.serve.settings import FIELDS, Settings, parse_fields
from explorer.app.serve.style import FIELD_WIDTH
from explorer.model import ParameterError

#: the slider beside the field of mu (the circulation, the parameter most often changed): its range
#: and step (the field takes any value the command line does; the slider then stops at its end)
MU_SLIDER = (0.0, 2.0, 0.001)
#: labels of the fields
LABELS = {p.name: p.symbol for p in model.PARAMETERS} | {
    "h": "h", "method": "method", "tol": "tol (taylor, dop853)", "dt": "dt (split*)",
    "crossings": "crossings per click", "phi0": "φ0 (section φ = φ0)"}
#: the fields the stepper steps: every numeric one (the method is a choice)
STEP_FIELDS = tuple(n for n in FIELDS if n != "method")
#: the stepper's widgets' margins (px: top and bottom, left and right): its row fits the fields' 230 px
STEP_MARGIN = (5, 3)


def default_step(value: float) -> float:
    """The stepper's step for a field's value: the power of ten near 1 % of it (0.01 for 0)."""
    value = abs(float(value))
    if not (math.isfinite(value) and value > 0.0):
        return 0.01
    return 10.0 ** (math.floor(math.log10(value)) - 2)


def stepped(name: str, text: str, step: float, k: int) -> str:
    """The text of field ``name`` (now ``text``) moved by ``k`` steps of ``step`` (a whole number of
    crossings, at least 1; a float written to 15 significant digits, so 0.03 + 0.0001 is 0.0301)."""
    if name == "crossings":
        return str(int(text) + k * max(1, round(step)))
    return repr(float(f"{float(text) + k * step:.15g}"))


class Fields:
    """One widget per field (``inputs``); an edit calls ``on_edit(name)`` on the session's loop."""

    def __init__(self, session, settings: Settings, on_edit):
        from explorer.analysis.sections import METHODS

        self._quiet = False
        self.applied = settings
        s = settings.fields()
        self.inputs: dict = {}
        for name in FIELDS:
            if name == "method":
                w = pn.widgets.Select(label=LABELS[name], options=list(METHODS), value=s[name], width=FIELD_WIDTH)
            else:
                w = pn.widgets.TextInput(label=LABELS[name], value=s[name], width=FIELD_WIDTH)
            w.param.watch(lambda _e, name=name: self._edited(session, on_edit, name), "value")
            self.inputs[name] = w
        lo, hi, step = MU_SLIDER
        self.mu_slider = pn.widgets.FloatSlider(label=f"{LABELS['mu']} (slider)", start=lo, end=hi, step=step,
                                                value=min(max(settings.params.mu, lo), hi), width=220)
        # on release (value_throttled): one new value per drag, written into the field, which applies it
        self.mu_slider.param.watch(self._slid, "value_throttled")
        # the stepper: which field (the last one edited), by how much (1 % of its value when chosen)
        self.step_field = pn.widgets.Select(label="step", options={LABELS[n]: n for n in STEP_FIELDS}, value="mu",
                                            width=62, margin=STEP_MARGIN)
        self.step_size = pn.widgets.FloatInput(label="by", value=default_step(settings.params.mu), width=82,
                                            margin=STEP_MARGIN)
        self.step_field.param.watch(lambda e: self._retarget(e.new), "value")
        buttons = []
        for label, k in (("−", -1), ("+", 1)):
            b = pn.widgets.Button(label=label, width=28, align="end", margin=STEP_MARGIN)
            b.on_click(lambda _e, k=k: session.soon(lambda: self.step(k)))
            buttons.append(b)
        self.step_buttons = tuple(buttons)
        self.grid = pn.Column(self.mu_slider, pn.GridBox(*self.inputs.values(), ncols=2),
                              pn.Row(self.step_field, self.step_size, *buttons))

    def _edited(self, session, on_edit, name: str) -> None:
        if self._quiet:
            return
        if name in STEP_FIELDS and self.step_field.value != name:
            self.step_field.value = name          # (the stepper steps the field edited last)
        session.soon(lambda: on_edit(name))

    def _retarget(self, name: str) -> None:
        self.step_size.value = default_step(float(self.applied.fields()[name]))

    def step(self, k: int, name: str | None = None) -> None:
        """Move field ``name`` (None: the stepper's) ``k`` steps of the stepper's size from the value
        that applies: its new text goes into the field, which applies it as a typed value (refused
        with the field's message when the command line would refuse it)."""
        name = name or self.step_field.value
        size = self.step_size.value
        if size is None or not (math.isfinite(size) and size > 0.0):
            self.step_size.value = default_step(float(self.applied.fields()[name]))
            return
        text = stepped(name, self.applied.fields()[name], float(size), k)
        if self.inputs[name].value == text:       # (the same refused text again: said again)
            self.inputs[name].param.trigger("value")
        else:
            self.inputs[name].value = text

    def _slid(self, event) -> None:
        if not self._quiet and event.new is not None:
            # (rounded to the slider's step: the browser's sums of steps carry float noise, 0.49800000000000005)
            digits = max(0, -math.floor(math.log10(MU_SLIDER[2])))
            self.inputs["mu"].value = repr(round(float(event.new), digits))

    def show(self, settings: Settings) -> None:
        """The fields and the slider show ``settings`` (not an edit: nothing is called)."""
        lo, hi, _step = MU_SLIDER
        self.applied = settings
        self._quiet = True
        try:
            for name, text in settings.fields().items():
                if self.inputs[name].value != text:
                    self.inputs[name].value = text
            mu = min(max(float(settings.params.mu), lo), hi)
            if self.mu_slider.value != mu:
                self.mu_slider.value = mu
        finally:
            self._quiet = False

    def read(self, base: Settings, applied: Settings, n_orbits: int, name: str | None = None) -> Settings:
        """The settings the fields give: ``applied`` with the text of field ``name`` (every field's
        text when None) on top of ``base``, validated as the command line's values are, and room
        on the page for ``n_orbits`` orbits of its crossings (ParameterError otherwise)."""
        if name is None:
            fields = {n: w.value for n, w in self.inputs.items()}
        else:
            fields = {**applied.fields(), name: self.inputs[name].value}
        new = parse_fields(base, fields)
        full = settings_mod.room_for(n_orbits, new.crossings)
        if full:
            raise ParameterError(f"crossings: {full}")
        return new
