"""The web server of ``explorer serve``: Panel on Bokeh's Tornado server, a page (page.SectionPage) per browser
session; safe by default (docs/commands/serve.md, "Safe by default": loopback unless told otherwise, a token
elsewhere, signed sessions, no file named by the page)."""
from __future__ import annotations

import asyncio
import contextlib
import gc
import hmac
import ipaddress
import os
import secrets
import signal
import socket
import sys
import threading
from dataclasses import replace

from explorer.app.serve.settings import TOKEN_ARG, Settings

#: where the page is served unless told otherwise (loopback only: docs/commands/serve.md)
DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 5006
#: a request's headers at most (bytes): above any address a browser sends, so the page refuses a long link
MAX_HEADER_BYTES = 4 << 20
#: what a page shows when its connection to the server is lost
DISCONNECT_NOTICE = "connection to the server lost: nothing on this page is computed any more; reload when it is back"


def is_loopback(host: str) -> bool:
    """``host`` is only reachable from this machine (127.0.0.0/8, ::1, localhost)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def free_port(host: str) -> int:
    """A port that is free on ``host`` now (for ``--port 0``)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def token_matches(expected: str, arguments) -> bool:
    """A request's ``arguments`` (Tornado's, {name: [bytes]}) carry the token ``expected`` (constant-time
    comparison)."""
    given = (arguments or {}).get(TOKEN_ARG) or [b""]
    return hmac.compare_digest(expected.encode("utf-8"), given[0])


def url_of(host: str, port: int, token: str | None) -> str:
    shown = f"[{host}]" if ":" in host else host
    if host in ("0.0.0.0", "::"):
        shown = socket.gethostname()
    return f"http://{shown}:{port}/" + (f"?{TOKEN_ARG}={token}" if token else "")


def make_server(base: Settings, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, token: str | None = None,
                export_dir=None, label: str = "", **page_options):
    """The Bokeh server (not started) and its URL; a token is made on a host other than loopback.
    ``page_options``: of every session's SectionPage."""
    import panel as pn

    from explorer.app.serve.page import session_app

    if token is None and not is_loopback(host):
        token = secrets.token_urlsafe(24)
    if port == 0:
        port = free_port(host)
    kw: dict = {}
    if token:
        # (Panel's authorize_callback: the page request's token argument must match)
        pn.config.authorize_callback = lambda _user_info, _path: token_matches(token, pn.state.session_args)
        kw.update(sign_sessions=True, secret_key=secrets.token_urlsafe(48), websocket_origin="*")
    else:
        hosts = dict.fromkeys(("127.0.0.1", "localhost", host))
        kw["websocket_origin"] = [f"{h}:{port}" for h in hosts if ":" not in h]   # (Bokeh takes no IPv6 here)
    pn.config.disconnect_notification = DISCONNECT_NOTICE
    app = session_app(base, export_dir=export_dir, label=label, **page_options)
    server = pn.serve(app, port=port, address=host, show=False, start=False, verbose=False, title="explorer",
                      liveness=True, http_server_kwargs={"max_header_size": MAX_HEADER_BYTES}, **kw)
    return server, url_of(host, port, token)


def web_browser():
    """The user's web browser, or None (on Linux/BSD without a display nor BROWSER: no text browser)."""
    import webbrowser

    if (os.name == "posix" and sys.platform != "darwin" and not os.environ.get("DISPLAY")
            and not os.environ.get("WAYLAND_DISPLAY") and not os.environ.get("BROWSER")):
        return None
    try:
        return webbrowser.get()
    except webbrowser.Error:
        return None


def open_in_browser(url: str) -> None:
    """Open ``url`` in :func:`web_browser` in a thread; without one, say so on stderr."""
    browser = web_browser()
    if browser is None:
        print("explorer: no web browser here: open the URL above (or forward the port: ssh -L)", file=sys.stderr,
              flush=True)
    else:
        threading.Thread(target=browser.open, args=(url,), name="explorer-open-browser", daemon=True).start()


def warm_up_and_freeze(base: Settings) -> None:
    """Load (or compile) the crossing kernels of ``base``'s method, one crossing from the region's centre, then
    ``gc.freeze`` every object alive (docs/commands/serve.md, *Latency*)."""
    from explorer.app.serve.orbits import OrbitRun

    if base.region is not None:
        with contextlib.suppress(Exception):    # a click reports the same error with its orbit
            OrbitRun(0, base.region[0], base.region[1], replace(base, crossings=1)).advance()
    gc.collect()
    gc.freeze()


def run(base: Settings, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, token: str | None = None,
        export_dir=None, label: str = "", open_browser: bool = False, **page_options) -> None:
    """Serve until interrupted, printing the URL first (then opening it with ``open_browser``)."""
    server, url = make_server(base, host=host, port=port, token=token, export_dir=export_dir, label=label,
                              **page_options)
    print(url, flush=True)
    threading.Thread(target=warm_up_and_freeze, args=(base,), name="explorer-serve-warm-up", daemon=True).start()
    server.start()
    if open_browser:
        open_in_browser(url)
    server.io_loop.add_callback(lambda: asyncio.get_running_loop().set_exception_handler(_quiet_about_clients_gone))
    before = _end_on_signals()
    try:
        server.io_loop.start()
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)
        server.stop()


def _quiet_about_clients_gone(loop, context) -> None:
    """The loop's exception handler: a client gone while Bokeh wrote to it is no error of the server."""
    from tornado.iostream import StreamClosedError
    from tornado.websocket import WebSocketClosedError

    if isinstance(context.get("exception"), (WebSocketClosedError, StreamClosedError)):
        return
    loop.default_exception_handler(context)


def _end_on_signals() -> dict:
    """SIGINT and SIGTERM end the process at once, streams flushed (docs/commands/serve.md, "Faults");
    returns their handlers before.  Off the main thread nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        return {}

    def handler(_signum, _frame):
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError, RuntimeError):   # closed, or interrupted inside a write
                stream.flush()
        os._exit(0)

    return {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
