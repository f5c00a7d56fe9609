"""The volume controls' state on the viewer's state: which volume they act on, the iso values
asked for (each re-extracted by the next frame's job, on the worker's thread), the transfer
edits (checked; a bad one keeps the last good function with a message) and the slice shown
among the buffer views. The checks themselves are :mod:`app.session.volume_controls`, imported
when first used (a scene without volumes never loads them).

:class:`VolumeChoices` is the ``volumes`` part of :class:`app.session.state.ViewerState`, which
holds the fields.
"""

from __future__ import annotations

import logging

log = logging.getLogger("fvd")


class VolumeChoices:
    """Which volume, its iso and transfer function, and the slice shown (``state.volumes``)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    @property
    def all(self) -> list:
        """The scene's volumes (``[[volume]]`` tables), in file order."""
        from app.session.volume_controls import scene_volumes
        return scene_volumes(self.state.scene)

    @property
    def current(self):
        """The volume the controls act on, or None."""
        found = self.all
        return found[min(self.state.volume_index, len(found) - 1)] if found else None

    def select(self, index: int) -> None:
        count = len(self.all)
        if not 0 <= index < max(count, 1):
            raise ValueError(f"volume index must be in 0..{count - 1}, not {index}")
        self.state.volume_index, self.state.slice_index = int(index), None

    @property
    def extracting(self) -> bool:
        """Is an isosurface asked for that the worker has not extracted yet?"""
        return any(v.iso != iso for v, iso in self.state.iso_wanted.items())

    def iso_shown(self, volume) -> float | None:
        """The iso value the slider shows: the one asked for, else the volume's."""
        return self.state.iso_wanted.get(volume, volume.iso)

    def set_iso(self, iso: float) -> bool:
        """Ask for the current volume's isosurface at ``iso`` (marching cubes runs in the next
        frame's job). Outside the data's range: a message, and the last good surface stays."""
        from app.session.volume_controls import checked_iso
        from core.volume.data import VolumeError
        s, volume = self.state, self.current
        if volume is None or volume.mode != "isosurface":
            s.volume_message = "iso: this volume is not drawn as an isosurface"
            return False
        try:
            iso = checked_iso(volume, iso)
        except VolumeError as error:
            s.volume_message = f"{error}; the surface stays at iso {self.iso_shown(volume):g}"
            return False
        s.volume_message = ""
        if iso != self.iso_shown(volume):
            s.iso_wanted[volume] = iso
            s.dirty = True
        return True

    def extract(self, scene, isos: dict, control=None) -> None:
        """On the worker's thread: marching cubes for each iso asked for, then the scene's
        caches are dropped (its meshes changed in place)."""
        from app.session.volume_controls import reextract
        for volume, iso in isos.items():
            if control is not None:
                control.check()
                control.report(0.0, f"extracting {volume.name} at iso {iso:g}…")
            count = reextract(scene, volume, iso)
            log.info("volume: %s re-extracted at iso %r: %d triangles", volume.name, iso, count)
        self.state.context.forget(scene)
        self.state.scene_edits += 1        # other contexts (the inspector's) drop theirs too

    def move_transfer_point(self, index: int, value: float, alpha: float) -> bool:
        """Move the current volume's transfer point ``index`` to ``value`` with extinction
        ``alpha``; a bad point (alpha < 0, values out of order) gets a message and the last
        good transfer function stays."""
        import numpy as np
        from app.session.volume_controls import moved_transfer
        from core.volume.data import VolumeError
        s, volume = self.state, self.current
        if volume is None or volume.transfer is None:
            s.volume_message = "transfer: this volume has no transfer function"
            return False
        try:
            transfer = moved_transfer(volume.transfer, index, value, alpha)
        except VolumeError as error:
            s.volume_message = f"{error}; the last good transfer function stays"
            return False
        s.volume_message = ""
        if not np.array_equal(transfer, volume.transfer):
            volume.transfer = transfer       # a new array: a frame being drawn keeps the old
            s.dirty = True
        return True

    def set_slice(self, name: str, index: int | None = None) -> None:
        """The slice the buffer view shows: ``name`` (axial, coronal, sagittal) and its index
        (None: the middle); an index past the end is refused."""
        from app.session.volume_controls import SLICE_AXIS, SLICES
        if name not in SLICE_AXIS:
            raise ValueError(f"slice must be one of {', '.join(SLICES)}, not {name!r}")
        volume = self.current
        if index is not None and volume is not None:
            n = volume.values.shape[SLICE_AXIS[name]]
            if not 0 <= index < n:
                raise ValueError(f"{name} slice index must be in 0..{n - 1}, not {index}")
        self.state.slice_name, self.state.slice_index = name, index

    def slice_shown(self) -> int:
        """The index of the slice shown (the middle one when none was chosen)."""
        from app.session.volume_controls import SLICE_AXIS
        s = self.state
        n = self.current.values.shape[SLICE_AXIS[s.slice_name]]
        return n // 2 if s.slice_index is None else min(s.slice_index, n - 1)
