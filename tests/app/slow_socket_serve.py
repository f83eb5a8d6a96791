"""``python -m explorer`` on a slow connection (for tests/app/test_serve.py): every websocket frame
the server writes completes SLOW_FRAME_SECONDS after tornado took it, as when the browser reads
slowly or the machine is loaded, so writes overlap the next callbacks of the page.  Test
scaffolding only: it changes no result, only when the server learns that a write is done."""
import asyncio
import sys

from tornado.websocket import WebSocketHandler

from explorer.app.cli import main

SLOW_FRAME_SECONDS = 0.03
_write = WebSocketHandler.write_message


def _slow_write(self, message, binary=False):
    written = _write(self, message, binary)
    loop = asyncio.get_event_loop()
    later = loop.create_future()

    def done(_f):
        loop.call_later(SLOW_FRAME_SECONDS, lambda: later.done() or later.set_result(None))
    written.add_done_callback(done)
    return later


WebSocketHandler.write_message = _slow_write

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
