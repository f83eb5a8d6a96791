"""The explorer in the browser: ``python -m explorer serve [SCENE]`` (docs/commands/serve.md).

A local web app with HoloViz Panel on Bokeh: the allowed region of the section, a click starts
an orbit whose crossings are streamed onto the page as they are computed (bit for bit those of
``explorer orbit`` for the same start and settings), the parameters as fields, the view in the
URL, the session exported as a scene that ``explorer sweep`` reruns.

One concept per module:

:mod:`~explorer.app.serve.settings`  what the page may set, validated (no web library)
:mod:`~explorer.app.serve.orbits`    the session's orbits, block by block in a worker thread
:mod:`~explorer.app.serve.export`    the session as a scene TOML
:mod:`~explorer.app.serve.page`      the Panel/Bokeh page of one session
:mod:`~explorer.app.serve.server`    the server: loopback by default, token, URL
:mod:`~explorer.app.serve.command`   the command's options and entry point
"""
