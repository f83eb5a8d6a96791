"""Interactive explorer: click on the section phi = phi0, watch the orbit appear.

``python -m explorer explore [SCENE]`` opens a matplotlib window with the
allowed region of the section (docs/model.md R9: white inside the ellipse
M^2 >= 0 of :func:`explorer.model.allowed_ellipse`, light gray outside, as in
:mod:`explorer.app.figures`).  A click inside starts an orbit there
(:func:`explorer.model.section_state`, M > 0) and its crossings are drawn as
they are computed, in a new colour.

How the window stays responsive
-------------------------------
Nothing runs in a thread.  A matplotlib timer (``fig.canvas.new_timer``)
calls :meth:`Explorer.step`, which advances every running orbit by one chunk
of ``chunk`` crossings with :func:`explorer.analysis.sections.crossings` (all running
orbits in one batch, parallel over Numba threads) and redraws.  Each chunk
restarts the integrator from the state where the previous chunk stopped;
``sections.crossings`` counts time from 0 and measures the energy error from
the chunk's start, so the explorer keeps each orbit's absolute time and its
energy reference H0 = H(y0) itself: a stored row is
``(t_start + t, p1, p2, M, dH + (H(chunk start) - H0))``.  With the Taylor
method the step size is a function of the state alone, so the chunked states
are those of one long run (only the time sum is split), and so are those of
the fixed-step splitting methods; the adaptive DOP853 controller restarts at
each chunk, which changes the steps by round-off-sized amounts.  Each chunk has
the time budget ``100 * chunk`` (the default of
``sections.crossings``); an orbit whose chunk ends early (it no longer turns
over, or any other status) stops with that status.

Chaos indicator ('x')
---------------------
Each orbit also gets the chaos indicators of :func:`explorer.analysis.lyapunov.indicators`
over its first ``INDICATOR_TIME`` time units (variational equations of the
same method and tolerance), computed once, in the tick after the click:
the mean MEGNO <Y> (Cincotta & Simó 2000: <Y> -> 2 for quasi-periodic
orbits, -> 0 for stable periodic ones, grows like chi t / 2 for chaotic ones)
colours the orbit with 'x', and the finite-time maximal Lyapunov exponent
chi is shown in the status line.  It is a finite-time value from one
deviation vector: an orbit that is chaotic only over longer times (thin
layers, stickiness near islands) can look regular at T = 1000; the label
"chaotic-like" in the status line means <Y> > ``CHAOTIC_MEGNO``.

Separatrices ('p')
------------------
'p' looks for fixed points of the section map by Newton's
method from p = 0, from the centre of the region and from half-way to its
edge along both axes, marks them (o elliptic,
x hyperbolic) and draws the stable and unstable manifolds of the hyperbolic
ones (:mod:`explorer.analysis.fixedpoints`).

Layout
------
:mod:`~explorer.app.explore.state` (``ExplorerState``: parameters, seeds, orbits, indicators,
separatrices, status; no matplotlib), :mod:`~explorer.app.explore.view` (``ExplorerView``: the
artists and widgets) and :mod:`~explorer.app.explore.controller` (``Explorer``: events, timers,
files; ``from_args`` for the command; ``display_problem``).

API
---
``Explorer(params, h, *, method, tol, dt, chunk, max_crossings, fig=None)``
    the whole tool; its handlers ``on_click(event)``, ``on_key(event)``,
    ``set_param(name, value)``, ``step()``, ``save_png(path)``,
    ``save_h5(path)`` work headless (Agg) and are what the tests drive;
    ``run()`` shows the window.
``ExplorerState(params, h, ...)``
    the same without a window: ``click``, ``step``, ``rerun``, ``set_params``, ...
``display_problem()``
    why no window can be opened (None if one can).
"""
from explorer.app.explore.controller import Explorer, check_args, display_problem, from_args
from explorer.app.explore.state import (
                                        CHAOTIC_MEGNO,
                                        FAILED_NAME,
                                        INDICATOR_TIME,
                                        KEYS,
                                        MAX_BATCH,
                                        RUNNING_NAME,
                                        STATUS_FAILED,
                                        STATUS_RUNNING,
                                        ExplorerState,
                                        Orbit,
)
from explorer.app.explore.view import DISPLAY_ERROR, FIGSIZE, ExplorerView, break_jumps

__all__ = ["CHAOTIC_MEGNO", "DISPLAY_ERROR", "FAILED_NAME", "FIGSIZE", "INDICATOR_TIME", "KEYS", "MAX_BATCH",
           "RUNNING_NAME", "STATUS_FAILED", "STATUS_RUNNING", "Explorer", "ExplorerState", "ExplorerView", "Orbit",
           "break_jumps", "check_args", "display_problem", "from_args"]
