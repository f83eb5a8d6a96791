"""The fields of the page's values (the model parameters, h, method, tol, dt, crossings per click,
φ0): their widgets, the text they show, and the settings an edit gives
(:func:`explorer.app.serve.settings.parse_fields`, the command line's checks).  A component of
:class:`~explorer.app.serve.page.SectionPage`."""
from __future__ import annotations

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


class Fields:
    """One widget per field (``inputs``); an edit calls ``on_edit(name)`` on the session's loop."""

    def __init__(self, loop, settings: Settings, on_edit):
        from explorer.analysis.sections import METHODS

        self._quiet = False
        s = settings.fields()
        self.inputs: dict = {}
        for name in FIELDS:
            if name == "method":
                w = pn.widgets.Select(label=LABELS[name], options=list(METHODS), value=s[name], width=FIELD_WIDTH)
            else:
                w = pn.widgets.TextInput(label=LABELS[name], value=s[name], width=FIELD_WIDTH)
            w.param.watch(lambda _e, name=name: self._quiet or loop.soon(lambda: on_edit(name)), "value")
            self.inputs[name] = w
        lo, hi, step = MU_SLIDER
        self.mu_slider = pn.widgets.FloatSlider(name=f"{LABELS['mu']} (slider)", start=lo, end=hi, step=step,
                                                value=min(max(settings.params.mu, lo), hi), width=220)
        # on release (value_throttled): one new value per drag, written into the field, which applies it
        self.mu_slider.param.watch(self._slid, "value_throttled")
        self.grid = pn.Column(self.mu_slider, pn.GridBox(*self.inputs.values(), ncols=2))

    def _slid(self, event) -> None:
        if not self._quiet and event.new is not None:
            self.inputs["mu"].value = repr(float(event.new))

    def show(self, settings: Settings) -> None:
        """The fields and the slider show ``settings`` (not an edit: nothing is called)."""
        lo, hi, _step = MU_SLIDER
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
