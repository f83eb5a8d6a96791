"""The page's check box: Panel's ``Checkbox`` (a boolean ``value``) drawn as Bokeh's
``CheckboxGroup`` of one option, whose input is inside a ``<label>``: a click on the label's text
toggles it.  (Bokeh's ``Checkbox`` draws its label as a ``<div>`` beside the input: its text did
nothing, issue 32.)"""
from __future__ import annotations

import panel as pn
from bokeh.models import CheckboxGroup


class Box(pn.widgets.Checkbox):
    """A check box with a clickable label (module docstring); ``value`` is a bool, as Checkbox's."""

    _widget_type = CheckboxGroup
    _rename = {**pn.widgets.Checkbox._rename, "value": "active", "label": "labels"}

    def _process_param_change(self, params):
        props = super()._process_param_change(params)
        if "active" in props:
            props["active"] = [0] if props["active"] else []
        if "labels" in props:
            props["labels"] = [props["labels"]]
        return props

    def _process_property_change(self, props):
        if "active" in props:
            props = {**props, "active": 0 in props["active"]}
        return super()._process_property_change(props)

    def _get_embed_state(self, root, values=None, max_opts=3):
        raise NotImplementedError("a Box is not embedded (the page runs on a server or in a notebook)")
