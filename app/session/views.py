"""The views a scene offers and the camera shown: a file's view, an animation's keyed camera or
one the user moved (app.viewer.hands), stepped through in file order, and the camera's history
(Ctrl+Z / Ctrl+Shift+Z).

:class:`CameraViews` is the ``views`` part of :class:`app.session.state.ViewerState`; the
fields it reads and changes (``scene``, ``view_index``, ``hand_view``, ``keyed_view``,
``playback``, the history's lists) stay declared on the state.
"""

from __future__ import annotations

from core.scene import view_numbers

CAMERA_HISTORY = 100          # camera changes Ctrl+Z can go back through


class CameraViews:
    """Which view is shown, and the camera's undo and redo (``state.views``)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    @property
    def count(self) -> int:
        """How many views can be shown (the valid ones)."""
        return len(self.state.scene.views)

    @property
    def number(self) -> int:
        """The current view's position in its file (from 1), 0 when there is none (or when
        the animation's keyed camera is shown)."""
        s = self.state
        if s.keyed_view:
            return 0
        return view_numbers.file_number(s.scene, s.view_index) if self.count else 0

    @property
    def label(self) -> str:
        """``"view 7 of 20 (6 invalid)"``: positions in the file, or why there is nothing;
        ``"the keyed view"`` for an animation's moving camera."""
        s = self.state
        if s.hand_view is not None and s.playback is not None:
            return "your camera (Enter: the scene's)"
        if s.keyed_view:
            return f"the keyed view (then the file's {self.count})"
        return view_numbers.label(s.scene, s.view_index)

    @property
    def current(self):
        """The camera shown now (None when the scene has no valid view)."""
        s = self.state
        if s.hand_view is not None:          # the user's camera, over a keyed one too
            return s.hand_view
        if s.keyed_view:
            return s.playback.animation.view_at(s.playback.time)
        return self.file_view

    @property
    def file_view(self):
        """The file's view at the current index (what Reset returns to), or None."""
        return self.state.scene.views[self.state.view_index] if self.count else None

    def set_hand_view(self, view) -> None:
        """Show ``view`` (a moved camera, already checked) in place of the file's."""
        s = self.state
        if view != s.hand_view:
            self._remember()
            s.hand_view, s.dirty = view, True

    def reset(self) -> bool:
        """Back to the file's view, bit for bit; returns whether the camera had moved."""
        s = self.state
        if s.hand_view is None:
            return False
        s.camera_gesture = None
        self._remember()
        s.hand_view, s.dirty = None, True
        return True

    def _camera(self) -> tuple:
        s = self.state
        return s.view_index, s.hand_view, s.keyed_view

    def _remember(self) -> None:
        """Before the camera changes: keep it to go back to (one step per gesture)."""
        s = self.state
        gesture = s.camera_gesture
        if gesture is not None and gesture is s._remembered_gesture:
            return
        s._remembered_gesture = gesture
        s._camera_undo.append(self._camera())
        del s._camera_undo[:-CAMERA_HISTORY]
        s._camera_redo.clear()

    def undo(self) -> bool:
        """The camera before the last change (a drag, a wheel spin, a fit, another view);
        whether there was one."""
        return self._swap(self.state._camera_undo, self.state._camera_redo)

    def redo(self) -> bool:
        """The camera change undone last, again; whether there was one."""
        return self._swap(self.state._camera_redo, self.state._camera_undo)

    def _swap(self, source: list, other: list) -> bool:
        if not source:
            return False
        s = self.state
        other.append(self._camera())
        s.view_index, s.hand_view, s.keyed_view = source.pop()
        s.camera_gesture = s._remembered_gesture = None
        s.dirty = True
        return True

    @property
    def history(self) -> tuple[int, int]:
        """(steps that can be undone, steps that can be redone)."""
        return len(self.state._camera_undo), len(self.state._camera_redo)

    def next_view(self) -> None:
        self._step(+1)

    def prev_view(self) -> None:
        self._step(-1)

    def _step(self, step: int) -> None:
        """Next / previous view; an animation with a keyed camera has it before the file's
        views (keyed, 1, 2, …, keyed)."""
        s = self.state
        keyed = s.playback is not None and s.playback.animation.view is not None
        positions = ([-1] if keyed else []) + list(range(self.count))
        if not positions:
            return
        here = positions.index(-1 if s.keyed_view else s.view_index)
        there = positions[(here + step) % len(positions)]
        s.camera_gesture = None
        self._remember()
        s.keyed_view = there < 0
        if there >= 0:
            s.view_index = there
        s.hand_view = None
        s.dirty = True

    def set_view(self, index: int) -> None:
        s = self.state
        if not 0 <= index < max(self.count, 1):
            raise ValueError(f"view index must be in 0..{self.count - 1}, not {index}")
        if index != s.view_index or s.keyed_view or s.hand_view is not None:
            s.camera_gesture = None
            self._remember()
            s.view_index, s.keyed_view, s.hand_view = index, False, None
            s.dirty = True
