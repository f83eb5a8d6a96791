"""The page's check box: a ``CheckBoxGroup`` of one option, whose label text toggles it (Panel's
``Checkbox`` puts its label beside the input)."""
from __future__ import annotations

import panel as pn
import param


class Box(pn.viewable.Viewer):
    """A check box with a clickable label; ``value`` is watched and set like a widget's."""

    value = param.Boolean(default=False, doc="ticked")
    label = param.String(default="", constant=True, doc="the text beside the box (a click on it ticks it)")

    def __init__(self, **params):
        super().__init__(**params)
        self.widget = pn.widgets.CheckBoxGroup(options=[self.label], value=[self.label] if self.value else [])
        self.widget.param.watch(lambda e: setattr(self, "value", self.label in e.new), "value")
        self.param.watch(lambda e: self.widget.param.update(value=[self.label] if e.new else []), "value")

    def __panel__(self):
        return self.widget
