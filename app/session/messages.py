"""What the window has to say: the reader's invalid views, scenes that failed to open, the
scene's warnings, the frame's own message and a failed render, and the one problem shown at
the top of the status.

:class:`Messages` is the ``messages`` part of :class:`app.session.state.ViewerState`, which
holds the fields.
"""

from __future__ import annotations


class Messages:
    """The messages to show, and the problem at the top of the status (``state.messages``)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    @property
    def invalid(self) -> list[str]:
        """The reader's message for each invalid view (the window's collapsed strip)."""
        return [f"invalid view: {m}" for m in self.state.scene.view_messages]

    @property
    def notices(self) -> list[str]:
        """Everything else to read: failed opens, this frame's message, a failed render."""
        s = self.state
        found = list(s.open_messages) + [f"warning: {m}" for m in s.scene.messages]
        message = getattr(s.frame, "message", None)
        if message:
            found.append(message)
        if s.render_error:
            found.append(s.render_error)
        return found

    @property
    def all(self) -> list[str]:
        """Every message: the invalid views first, then :attr:`notices`."""
        return self.invalid + self.notices

    def open_failed(self, message: str, details: list[str] = ()) -> bool:
        """Say that a scene did not open (``details`` below it); returns False, the open's
        answer."""
        s = self.state
        s.open_messages.append(message)
        s.open_messages.extend(details)
        s.failed_open, s._clear_failed_open = message, False
        return False

    @property
    def problem(self) -> str:
        """The last error or refusal, for the top of the status line: a render that failed,
        the frame's own message (a renderer's refusal, an invalid view), a scene that did not
        open, a refused setting or volume edit; "" when all is well."""
        s = self.state
        for text in (s.render_error, getattr(s.frame, "message", None), s.failed_open,
                     s.option_message, s.volume_message):
            if text:
                return text
        return ""

    def clear(self) -> None:
        self.state.open_messages.clear()
        self.state.failed_open = ""
