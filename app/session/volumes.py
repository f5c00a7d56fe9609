"""The volume controls' state on the viewer's state: which volume they act on, the iso values
asked for (each re-extracted by the next frame's job, on the worker's thread), the transfer
edits (checked; a bad one keeps the last good function with a message) and the slice shown
among the buffer views. The checks themselves are :mod:`app.session.volume_controls`, imported
when first used (a scene without volumes never loads them).

A part of :class:`app.session.state.ViewerState`, which holds the fields.
"""

from __future__ import annotations

import logging

log = logging.getLogger("fvd")


class VolumeChoices:
    """Which volume, its iso and transfer function, and the slice shown."""

    @property
    def volumes(self) -> list:
        """The scene's volumes (``[[volume]]`` tables), in file order."""
        from app.session.volume_controls import scene_volumes
        return scene_volumes(self.scene)

    @property
    def volume(self):
        """The volume the controls act on, or None."""
        found = self.volumes
        return found[min(self.volume_index, len(found) - 1)] if found else None

    def select_volume(self, index: int) -> None:
        if not 0 <= index < max(len(self.volumes), 1):
            raise ValueError(f"volume index must be in 0..{len(self.volumes) - 1}, not {index}")
        self.volume_index, self.slice_index = int(index), None

    @property
    def extracting(self) -> bool:
        """Is an isosurface asked for that the worker has not extracted yet?"""
        return any(v.iso != iso for v, iso in self.iso_wanted.items())

    def iso_shown(self, volume) -> float | None:
        """The iso value the slider shows: the one asked for, else the volume's."""
        return self.iso_wanted.get(volume, volume.iso)

    def set_iso(self, iso: float) -> bool:
        """Ask for the current volume's isosurface at ``iso`` (marching cubes runs in the next
        frame's job). Outside the data's range: a message, and the last good surface stays."""
        from app.session.volume_controls import checked_iso
        from core.volume.data import VolumeError
        volume = self.volume
        if volume is None or volume.mode != "isosurface":
            self.volume_message = "iso: this volume is not drawn as an isosurface"
            return False
        try:
            iso = checked_iso(volume, iso)
        except VolumeError as error:
            self.volume_message = f"{error}; the surface stays at iso {self.iso_shown(volume):g}"
            return False
        self.volume_message = ""
        if iso != self.iso_shown(volume):
            self.iso_wanted[volume] = iso
            self.dirty = True
        return True

    def _extract(self, scene, isos: dict, control=None) -> None:
        """On the worker's thread: marching cubes for each iso asked for, then the scene's
        caches are dropped (its meshes changed in place)."""
        from app.session.volume_controls import reextract
        for volume, iso in isos.items():
            if control is not None:
                control.check()
                control.report(0.0, f"extracting {volume.name} at iso {iso:g}…")
            count = reextract(scene, volume, iso)
            log.info("volume: %s re-extracted at iso %r: %d triangles", volume.name, iso, count)
        self.context.forget(scene)
        self.scene_edits += 1              # other contexts (the inspector's) drop theirs too

    def move_transfer_point(self, index: int, value: float, alpha: float) -> bool:
        """Move the current volume's transfer point ``index`` to ``value`` with extinction
        ``alpha``; a bad point (alpha < 0, values out of order) gets a message and the last
        good transfer function stays."""
        import numpy as np
        from app.session.volume_controls import moved_transfer
        from core.volume.data import VolumeError
        volume = self.volume
        if volume is None or volume.transfer is None:
            self.volume_message = "transfer: this volume has no transfer function"
            return False
        try:
            transfer = moved_transfer(volume.transfer, index, value, alpha)
        except VolumeError as error:
            self.volume_message = f"{error}; the last good transfer function stays"
            return False
        self.volume_message = ""
        if not np.array_equal(transfer, volume.transfer):
            volume.transfer = transfer       # a new array: a frame being drawn keeps the old
            self.dirty = True
        return True

    def set_slice(self, name: str, index: int | None = None) -> None:
        """The slice the buffer view shows: ``name`` (axial, coronal, sagittal) and its index
        (None: the middle); an index past the end is refused."""
        from app.session.volume_controls import SLICE_AXIS, SLICES
        if name not in SLICE_AXIS:
            raise ValueError(f"slice must be one of {', '.join(SLICES)}, not {name!r}")
        if index is not None and self.volume is not None:
            n = self.volume.values.shape[SLICE_AXIS[name]]
            if not 0 <= index < n:
                raise ValueError(f"{name} slice index must be in 0..{n - 1}, not {index}")
        self.slice_name, self.slice_index = name, index

    def slice_shown(self) -> int:
        """The index of the slice shown (the middle one when none was chosen)."""
        from app.session.volume_controls import SLICE_AXIS
        n = self.volume.values.shape[SLICE_AXIS[self.slice_name]]
        return n // 2 if self.slice_index is None else min(self.slice_index, n - 1)
