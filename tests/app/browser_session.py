"""What the browser modules (tests/app/test_serve*.py) share within one pytest process (a plugin
that tests/conftest.py loads: a second file named conftest.py would take the module name
``conftest`` that the tests' ``from conftest import ...`` means): one
Chromium, and one ``explorer serve --crossings 150 --mu 0.03`` for the tests that need only the
default page (test_serve.SERVED).  Each start costs a process of its own (Chromium: a browser
and its renderers; the server: Python, Panel and Bokeh imported and its kernels loaded), and
under ``-n 2 --dist loadscope`` the CPU that a start takes is taken from the other worker.

Chromium stays open only while the tests of consecutive modules use it: after the last test of
a module that uses ``browser``, if the next test's module does not use it (or no test comes),
it is closed, and the next module that needs it launches it again.  (Playwright's sync API marks
its event loop as running in this thread between calls, so an open browser would make
``asyncio.run`` fail in the tests of another module.)  The server stays until the session ends.
Tests that need a server with other options (a token, another host, a slow connection,
``explore``) or that stop it start their own (``test_serve.Served``).
"""
from __future__ import annotations

import pytest

#: the fixture that a browser test requests (test_serve.browser, which takes it from here)
BROWSER_FIXTURE = "browser"


class _Chromium:
    """The shared Chromium (a persistent context of Playwright's), launched on demand."""

    def __init__(self):
        self.playwright = self.context = None

    def get(self, profile_dir):
        if self.context is None:
            from playwright.sync_api import sync_playwright
            from test_serve import CHROMIUM, CHROMIUM_ARGS

            self.playwright = sync_playwright().start()
            try:
                self.context = self.playwright.chromium.launch_persistent_context(
                    str(profile_dir), executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True,
                    viewport={"width": 1100, "height": 800})
            except BaseException:
                self.close()
                raise
        return self.context

    def close(self):
        context, playwright = self.context, self.playwright
        self.context = self.playwright = None
        try:
            if context is not None:
                context.close()
        finally:
            if playwright is not None:
                playwright.stop()


_CHROMIUM = _Chromium()


@pytest.fixture(scope="session")
def launch_chromium(tmp_path_factory):
    """A function that returns the Chromium context of this pytest process (launched then if it
    is not open): test_serve.browser calls it once per module."""
    return lambda: _CHROMIUM.get(tmp_path_factory.mktemp("chromium-profile"))


def _uses_the_browser(session, path) -> bool:
    """A test of the module at ``path`` (among those this run selected) uses the browser."""
    if not hasattr(session, "_explorer_browser_modules"):
        session._explorer_browser_modules = {item.path for item in session.items
                                             if BROWSER_FIXTURE in getattr(item, "fixturenames", ())}
    return path in session._explorer_browser_modules


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """After the module's fixtures are torn down: close Chromium when the next test's module does
    not use it (or no test comes)."""
    if _CHROMIUM.context is not None and (nextitem is None or not _uses_the_browser(item.session, nextitem.path)):
        _CHROMIUM.close()


def pytest_sessionfinish(session):
    _CHROMIUM.close()


@pytest.fixture(scope="session")
def default_server(tmp_path_factory):
    """``explorer serve --crossings CROSSINGS --mu 0.03 --export-dir DIR`` (test_serve.SERVED), one
    for every module of this process that asks for it; Ctrl-C ends it cleanly at the end."""
    from test_serve import CROSSINGS, Served

    export_dir = tmp_path_factory.mktemp("export")
    s = Served("--crossings", str(CROSSINGS), "--mu", "0.03", "--export-dir", str(export_dir))
    s.export_dir = export_dir
    yield s
    code, err = s.interrupt()
    assert code in (0, 130) and "Traceback" not in err, err[-2000:]
