"""The explorer in the browser: ``python -m explorer serve [SCENE]`` (docs/commands/serve.md).

A local web app with HoloViz Panel on Bokeh: the allowed region of the section, a click starts
an orbit whose crossings are streamed onto the page as they are computed (bit for bit those of
``explorer orbit`` for the same start and settings), the parameters as fields, the view in the
URL, the session exported as a scene that ``explorer sweep`` reruns.

One concept per module:

:mod:`~explorer.app.serve.settings`  what the page may set, validated (no web library)
:mod:`~explorer.app.serve.orbits`    the session's orbits, block by block
:mod:`~explorer.app.serve.tasks`     the one task helper of a session's background jobs
:mod:`~explorer.app.serve.overlays`  the fixed point, periodic orbit and rotation searches
:mod:`~explorer.app.serve.raster`    the chaos layer (MEGNO, frequency diffusion), coarse to fine
:mod:`~explorer.app.serve.export`    the session as a scene TOML, its store, its figure files
:mod:`~explorer.app.serve.style`     the page's colours and sizes
:mod:`~explorer.app.serve.image`     the view as PNG/SVG (matplotlib)
:mod:`~explorer.app.serve.page`      the Panel/Bokeh page of one session, made of the
                                      components ``view``, ``page_orbits``, ``page_layers``,
                                      ``page_overlays``, ``page_readout``, ``page_orbit_list``,
                                      ``page_fields``, ``page_message``, ``page_exports``
:mod:`~explorer.app.serve.server`    the server: loopback by default, token, URL
:mod:`~explorer.app.serve.command`   the command's options and entry point
"""
