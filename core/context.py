"""What outlives a frame: the z-buffer's memory and the per-mesh, per-scene caches.

Whoever draws frames in a row (the viewer, the bench, an animation) keeps one
:class:`RenderContext` and passes it to :func:`core.render.render`; calls without one share
:data:`DEFAULT_CONTEXT`. Nothing else in the core keeps state between frames.
"""

from __future__ import annotations

import math
import weakref

import numpy as np


class RenderContext:
    """Memory and caches that outlive one frame, kept by whoever draws frames in a row.

    ``buffer(key, make)`` keeps one object per key (e.g. the visibility buffer of a size; a
    new size replaces it); ``cache(owner)`` is a dict that lives as long as ``owner`` (a mesh
    or a scene) and is dropped with it.
    """

    def __init__(self) -> None:
        self._buffers: dict = {}
        self._caches: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()

    def buffer(self, kind: str, key, make):
        held = self._buffers.get(kind)
        if held is None or held[0] != key:
            self._buffers[kind] = held = (key, make())
        return held[1]

    def remembered(self, kind: str, key, compute):
        """``compute()``, kept for the last ``key`` asked under ``kind``: a viewer asks for the
        same view's matrices every frame. A key that cannot be compared (a View built from
        arrays) is computed each time."""
        held = self._buffers.get(kind)
        try:
            same = held is not None and bool(held[0] == key)
        except (TypeError, ValueError):     # numpy arrays in the key: no single answer
            return compute()
        if not same:
            self._buffers[kind] = held = (key, compute())
        return held[1]

    def normalizing_transform(self, view, projection: str):
        """``core.camera.view.normalizing_transform``, kept for the last view asked (0.13 ms
        saved a frame). N is read-only."""
        def compute():
            from core.camera.view import normalizing_transform
            n, z_min = normalizing_transform(view, projection)
            n.flags.writeable = False
            return n, z_min
        return self.remembered("normalizing transform", (view, projection), compute)

    def eye(self, view, projection: str):
        """``core.camera.view.eye_from_view``, kept for the last view asked (its arrays
        read-only)."""
        def compute():
            from core.camera.view import eye_from_view
            eye = eye_from_view(view, projection)
            for a in eye:
                if a is not None:
                    a.flags.writeable = False
            return eye
        return self.remembered("eye", (view, projection), compute)

    def scratch(self, kind: str, shape: tuple, dtype=np.float64, zero: bool = False) -> np.ndarray:
        """A ``shape`` array kept from frame to frame for ``kind`` (grown as needed), so a frame
        allocates no big array: fresh memory costs a page fault per 4 KB on first write (on
        this project's VMs ~20 ms for the 12 MB of a million-vertex array), reused memory none.
        Valid until the next request for the same ``kind``; ``zero`` clears it first."""
        need = math.prod(int(n) for n in shape)        # np.prod of a tuple: ~4 µs
        held = self._buffers.get(("scratch", kind))
        if held is None or held[1].dtype != np.dtype(dtype) or held[1].size < need:
            held = (None, np.empty(max(need, 1) + need // 2, dtype=dtype))
            self._buffers[("scratch", kind)] = held
        view = held[1][:need].reshape(shape)
        if zero:
            view.fill(0)
        return view

    def forget(self, owner) -> None:
        """Drop what is kept for ``owner`` (a scene whose meshes were replaced in place)."""
        self._caches.pop(owner, None)

    def cache(self, owner) -> dict:
        entry = self._caches.get(owner)
        if entry is None:
            entry = self._caches[owner] = {}
        return entry


DEFAULT_CONTEXT = RenderContext()
