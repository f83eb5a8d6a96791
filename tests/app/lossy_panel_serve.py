"""``python -m explorer`` whose Panel loses the messages it writes itself (for
tests/app/test_serve.py): a change of a Panel component made in a callback of the page goes to
the browser through Panel's own writer (``panel.io.document.unlocked``: ``write_events`` now, or
``schedule_write_events`` when the socket is busy), and panel 1.9's queue for the latter can end
its write task before it sends a message queued meanwhile (the message then waits for Panel's
next write, which may never come).  Here both drop every message, so a change that reaches the
browser only through them never does; Bokeh's own dispatch (the page's Bokeh models, its link
among them: explorer.app.serve.page) is untouched.  Test scaffolding only."""
import sys

import panel.io.document as panel_document

from explorer.app.cli import main


def _lost(*_args, **_kwargs):
    return None


panel_document.write_events = _lost
panel_document.schedule_write_events = _lost

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
