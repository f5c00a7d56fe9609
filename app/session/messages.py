"""What the window has to say: the reader's invalid views, scenes that failed to open, the
scene's warnings, the frame's own message and a failed render, and the one problem shown at
the top of the status.

A part of :class:`app.session.state.ViewerState`, which holds the fields.
"""

from __future__ import annotations


class Messages:
    """The messages to show, and the problem at the top of the status."""

    @property
    def invalid_messages(self) -> list[str]:
        """The reader's message for each invalid view (the window's collapsed strip)."""
        return [f"invalid view: {m}" for m in self.scene.view_messages]

    @property
    def notices(self) -> list[str]:
        """Everything else to read: failed opens, this frame's message, a failed render."""
        found = list(self.open_messages) + [f"warning: {m}" for m in self.scene.messages]
        message = getattr(self.frame, "message", None)
        if message:
            found.append(message)
        if self.render_error:
            found.append(self.render_error)
        return found

    @property
    def messages(self) -> list[str]:
        """Every message: the invalid views first, then :attr:`notices`."""
        return self.invalid_messages + self.notices

    def _open_failed(self, message: str, details: list[str] = ()) -> bool:
        self.open_messages.append(message)
        self.open_messages.extend(details)
        self.failed_open, self._clear_failed_open = message, False
        return False

    @property
    def problem(self) -> str:
        """The last error or refusal, for the top of the status line: a render that failed,
        the frame's own message (a renderer's refusal, an invalid view), a scene that did not
        open, a refused setting or volume edit; "" when all is well."""
        for text in (self.render_error, getattr(self.frame, "message", None), self.failed_open,
                     self.option_message, self.volume_message):
            if text:
                return text
        return ""

    def clear_messages(self) -> None:
        self.open_messages.clear()
        self.failed_open = ""
