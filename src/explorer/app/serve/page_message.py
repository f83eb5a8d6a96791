"""The message line under the page's figure: text, never HTML (a message may quote a field)."""
from __future__ import annotations

from bokeh.models import Div

from explorer.app.serve.style import MESSAGE_ERROR_COLOR, MESSAGE_OK_COLOR


class Message:
    """The ``message`` Div and whether it says a success (``message_ok``)."""

    def __init__(self):
        self.message = Div(name="message", text="", render_as_text=True,
                           styles={"color": MESSAGE_ERROR_COLOR, "min-height": "1.2em"})
        self.message_ok = False

    def say(self, text: str, ok: bool = False) -> None:
        """``text`` under the figure, in the error colour or (``ok``) the success colour."""
        self.message_ok = bool(ok)
        color = MESSAGE_OK_COLOR if ok else MESSAGE_ERROR_COLOR
        if self.message.styles.get("color") != color:
            self.message.styles = {**self.message.styles, "color": color}
        self.message.text = text

    def tell(self, text: str) -> None:
        """A success under the figure, in the success colour."""
        self.say(text, ok=True)
