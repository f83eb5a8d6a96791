"""The explorer in the browser: ``python -m explorer serve [SCENE]`` (docs/commands/serve.md), a
local web app with HoloViz Panel on Bokeh; its modules are listed in docs/architecture.md ("The
page").
"""
