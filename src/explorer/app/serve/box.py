"""The page's check box: a boolean ``value`` drawn as Panel's ``CheckBoxGroup`` of one option
(Bokeh's ``CheckboxGroup``), whose input is inside a ``<label>``: a click on the label's text
toggles it (Panel's ``Checkbox`` puts its label in a ``<div>`` beside the input).  Public API
only: a :class:`panel.viewable.Viewer` whose ``value`` two watchers keep equal to the group's."""
from __future__ import annotations

import panel as pn
import param


class Box(pn.viewable.Viewer):
    """A check box with a clickable label (module docstring): ``value`` is a bool, watched and set
    like a widget's (``box.param.watch(fn, "value")``, ``box.value = True``); ``widget`` is the
    ``CheckBoxGroup`` drawn."""

    value = param.Boolean(default=False, doc="ticked")
    label = param.String(default="", constant=True, doc="the text beside the box (a click on it ticks it)")

    def __init__(self, **params):
        super().__init__(**params)
        self.widget = pn.widgets.CheckBoxGroup(options=[self.label], value=self._group_value(self.value))
        self.widget.param.watch(lambda e: setattr(self, "value", self.label in e.new), "value")
        self.param.watch(lambda e: self._show(e.new), "value")

    def _group_value(self, ticked: bool) -> list:
        return [self.label] if ticked else []

    def _show(self, ticked: bool) -> None:
        want = self._group_value(ticked)
        if self.widget.value != want:
            self.widget.value = want

    def __panel__(self):
        return self.widget
