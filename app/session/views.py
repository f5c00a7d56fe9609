"""The views a scene offers and the camera shown: a file's view, an animation's keyed camera or
one the user moved (app.viewer.hands), stepped through in file order, and the camera's history
(Ctrl+Z / Ctrl+Shift+Z).

A part of :class:`app.session.state.ViewerState`, which holds the fields (``scene``,
``view_index``, ``hand_view``, ``keyed_view``, ``playback``, the history's lists).
"""

from __future__ import annotations

from core.scene import view_numbers

CAMERA_HISTORY = 100          # camera changes Ctrl+Z can go back through


class CameraViews:
    """Which view is shown, and the camera's undo and redo."""

    def current_view(self):
        """The view shown now (None when the scene has no valid view)."""
        return self.view

    @property
    def view_count(self) -> int:
        """How many views can be shown (the valid ones)."""
        return len(self.scene.views)

    @property
    def view_number(self) -> int:
        """The current view's position in its file (from 1), 0 when there is none (or when
        the animation's keyed camera is shown)."""
        if self.keyed_view:
            return 0
        return view_numbers.file_number(self.scene, self.view_index) if self.view_count else 0

    @property
    def view_label(self) -> str:
        """``"view 7 of 20 (6 invalid)"``: positions in the file, or why there is nothing;
        ``"the keyed view"`` for an animation's moving camera."""
        if self.hand_view is not None and self.playback is not None:
            return "your camera (Enter: the scene's)"
        if self.keyed_view:
            return f"the keyed view (then the file's {self.view_count})"
        return view_numbers.label(self.scene, self.view_index)

    @property
    def view(self):
        if self.hand_view is not None:          # the user's camera, over a keyed one too
            return self.hand_view
        if self.keyed_view:
            return self.playback.animation.view_at(self.playback.time)
        return self.scene.views[self.view_index] if self.view_count else None

    @property
    def file_view(self):
        """The file's view at the current index (what Reset returns to), or None."""
        return self.scene.views[self.view_index] if self.view_count else None

    def set_hand_view(self, view) -> None:
        """Show ``view`` (a moved camera, already checked) in place of the file's."""
        if view != self.hand_view:
            self._remember_camera()
            self.hand_view, self.dirty = view, True

    def reset_view(self) -> bool:
        """Back to the file's view, bit for bit; returns whether the camera had moved."""
        if self.hand_view is None:
            return False
        self.camera_gesture = None
        self._remember_camera()
        self.hand_view, self.dirty = None, True
        return True

    def _camera(self) -> tuple:
        return self.view_index, self.hand_view, self.keyed_view

    def _remember_camera(self) -> None:
        """Before the camera changes: keep it to go back to (one step per gesture)."""
        gesture = self.camera_gesture
        if gesture is not None and gesture is self._remembered_gesture:
            return
        self._remembered_gesture = gesture
        self._camera_undo.append(self._camera())
        del self._camera_undo[:-CAMERA_HISTORY]
        self._camera_redo.clear()

    def undo_camera(self) -> bool:
        """The camera before the last change (a drag, a wheel spin, a fit, another view);
        whether there was one."""
        return self._swap_camera(self._camera_undo, self._camera_redo)

    def redo_camera(self) -> bool:
        """The camera change undone last, again; whether there was one."""
        return self._swap_camera(self._camera_redo, self._camera_undo)

    def _swap_camera(self, source: list, other: list) -> bool:
        if not source:
            return False
        other.append(self._camera())
        self.view_index, self.hand_view, self.keyed_view = source.pop()
        self.camera_gesture = self._remembered_gesture = None
        self.dirty = True
        return True

    @property
    def camera_history(self) -> tuple[int, int]:
        """(steps that can be undone, steps that can be redone)."""
        return len(self._camera_undo), len(self._camera_redo)

    def next_view(self) -> None:
        self._step_view(+1)

    def prev_view(self) -> None:
        self._step_view(-1)

    def _step_view(self, step: int) -> None:
        """Next / previous view; an animation with a keyed camera has it before the file's
        views (keyed, 1, 2, …, keyed)."""
        keyed = self.playback is not None and self.playback.animation.view is not None
        positions = ([-1] if keyed else []) + list(range(self.view_count))
        if not positions:
            return
        here = positions.index(-1 if self.keyed_view else self.view_index)
        there = positions[(here + step) % len(positions)]
        self.camera_gesture = None
        self._remember_camera()
        self.keyed_view = there < 0
        if there >= 0:
            self.view_index = there
        self.hand_view = None
        self.dirty = True

    def set_view(self, index: int) -> None:
        if not 0 <= index < max(self.view_count, 1):
            raise ValueError(f"view index must be in 0..{self.view_count - 1}, not {index}")
        if index != self.view_index or self.keyed_view or self.hand_view is not None:
            self.camera_gesture = None
            self._remember_camera()
            self.view_index, self.keyed_view, self.hand_view = index, False, None
            self.dirty = True
