"""The explorer in a notebook cell (docs/commands/serve.md): the page's work runs on the kernel's event loop,
and a periodic callback pushes what reached the page (``panel.io.push_notebook``)."""
from __future__ import annotations

import asyncio
import contextlib
import sys

import panel as pn

from explorer.app.serve.page import SectionPage

#: how often the notebook is pushed (ms)
POLL_MS = 50


class Explorer(pn.viewable.Viewer):
    """The displayable explorer of a notebook cell; ``page`` is its :class:`SectionPage`."""

    def __init__(self, page: SectionPage, **params):
        super().__init__(**params)
        self.page = page
        self._poller = None

    def _poll(self):
        with contextlib.suppress(Exception):    # not rendered in a notebook (yet): nothing to push
            pn.io.push_notebook(self.page.layout)

    def __panel__(self):
        if self._poller is None:
            self._poller = pn.state.add_periodic_callback(self._poll, period=POLL_MS)
        return self.page.layout

    def close(self) -> None:
        """Stop the polling and the page's work."""
        if self._poller is not None:
            self._poller.stop()
        self.page.close()


def explore(scene=None, *, panel: int = 0, export_dir=None, h: float | None = None, method: str | None = None,
            tol: float | None = None, dt: float | None = None, n_crossings: int | None = None,
            a1: float | None = None, a2: float | None = None, b: float | None = None, lam: float | None = None,
            chi: float | None = None, zeta: float | None = None, mu: float | None = None, xi: float | None = None,
            eta: float | None = None) -> Explorer:
    """The explorer as a Panel object for a notebook cell::

        import panel as pn, explorer as ex
        pn.extension()
        ex.explore("figure4", panel=2)            # or ex.explore(mu=0.03, n_crossings=5000)

    ``scene`` (a scene, None: Figure 4) and its ``panel``, with each value given on top (validated);
    ``export_dir``: where *Export scene* writes.  ``scene`` a System's section map or scene: its page,
    ``h`` its energy (docs/commands/serve.md, "Your own system").
    """
    from explorer.app.serve.settings import page_settings

    base, label, seeds = page_settings(scene, None, panel, a1=a1, a2=a2, b=b, lam=lam, chi=chi, zeta=zeta, mu=mu,
                                       xi=xi, eta=eta, h=h, method=method, tol=tol, dt=dt, crossings=n_crossings)
    return Explorer(SectionPage(base, {}, export_dir=export_dir, label=label, seeds=seeds, loop=_kernel_loop()))


def _kernel_loop():
    """The event loop of the Jupyter kernel this runs in (None elsewhere: the page gets a loop of its own)."""
    ipython = sys.modules.get("IPython")
    if getattr(ipython and ipython.get_ipython(), "kernel", None) is None:
        return None
    return asyncio.get_running_loop()
