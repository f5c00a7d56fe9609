"""The window's volume controls as plain functions over a scene's volumes (no GL, no window).

- the transfer function's points, edited one at a time (:func:`moved_transfer`), checked as
  the scene reader checks them, over the data's histogram (:func:`histogram`);
- the iso value of an isosurface volume: a new one is checked at once (:func:`checked_iso`)
  and the surface re-extracted by marching cubes on the render worker's thread, just before
  the frame that shows it (:func:`reextract`);
- slices through a volume along one of its axes (:func:`slice_values`, the array slice itself,
  and :func:`slice_picture`, that slice as a grey picture for the buffer views).

The volume's axes are those of ``values[i, j, k]``: ``i`` along x, ``j`` along y, ``k`` along
z. An **axial** slice holds ``k`` fixed (the x-y plane), a **coronal** one ``j`` (x-z), a
**sagittal** one ``i`` (y-z), as for a patient lying along z.
"""

from __future__ import annotations

import weakref

import numpy as np

from core.volume.data import VolumeError, check_iso, checked_transfer, volumes_of

SLICES = ("axial", "coronal", "sagittal")
SLICE_AXIS = {"axial": 2, "coronal": 1, "sagittal": 0}
HISTOGRAM_BINS = 64

_histograms: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def scene_volumes(scene) -> list:
    return list(volumes_of(scene))


def histogram(volume, bins: int = HISTOGRAM_BINS) -> tuple[np.ndarray, np.ndarray]:
    """``(counts, edges)`` of the volume's samples over its range (kept with the volume: the
    samples never change)."""
    held = _histograms.get(volume)
    if held is None or len(held[0]) != bins:
        lo, hi = volume.value_range
        if hi <= lo:
            hi = lo + 1.0
        held = np.histogram(volume.values, bins=bins, range=(lo, hi))
        _histograms[volume] = held
    return held


def moved_transfer(transfer: np.ndarray, index: int, value: float, alpha: float) -> np.ndarray:
    """The transfer function with point ``index`` moved to ``value`` and extinction ``alpha``
    (its colour kept); a new array, checked: raises :class:`VolumeError` with the reader's
    message (alpha < 0, values out of order) and leaves ``transfer`` as it was."""
    if transfer is None or not 0 <= index < len(transfer):
        raise VolumeError(f"transfer: there is no point {index}")
    rows = np.array(transfer, dtype=np.float64)
    rows[index, 0], rows[index, 4] = float(value), float(alpha)
    return checked_transfer(rows, "transfer")


def checked_iso(volume, iso: float) -> float:
    """``iso`` when it lies strictly inside the data's range, else :class:`VolumeError`."""
    return check_iso(float(iso), volume.values, "iso")


def isosurface_index(scene, volume) -> int | None:
    """The position in ``scene.meshes`` of the volume's isosurface (its own material)."""
    for k, mesh in enumerate(scene.meshes):
        if mesh.material is volume.material and mesh.name == volume.name:
            return k
    return None


def reextract(scene, volume, iso: float) -> int:
    """Marching cubes at ``iso`` (already checked); the mesh replaces the volume's isosurface
    in ``scene`` (appended when it had none) and ``volume.iso`` becomes ``iso``. Returns the
    new triangle count. Runs on the render worker's thread, before the frame that shows it."""
    from core.volume.marching import isosurface
    old = volume.iso
    volume.iso = float(iso)
    try:
        mesh = isosurface(volume)
    except Exception:
        volume.iso = old
        raise
    k = isosurface_index(scene, volume)
    from core.scene.generators import MAX_TRIANGLES
    total = scene.triangle_count - (0 if k is None else len(scene.meshes[k].triangles))
    if total + len(mesh.triangles) > MAX_TRIANGLES:
        volume.iso = old
        raise VolumeError(f"iso {iso:g}: the isosurface takes the scene to "
                          f"{total + len(mesh.triangles)} triangles; the limit is {MAX_TRIANGLES}")
    if k is None:
        scene.meshes.append(mesh)
    else:
        scene.meshes[k] = mesh
    return len(mesh.triangles)


def slice_values(volume, name: str, index: int) -> np.ndarray:
    """The samples of slice ``index`` along ``name``'s axis: exactly ``values[:, :, k]``
    (axial), ``values[:, j, :]`` (coronal) or ``values[i, :, :]`` (sagittal)."""
    if name not in SLICE_AXIS:
        raise ValueError(f"slice must be one of {', '.join(SLICES)}, not {name!r}")
    axis = SLICE_AXIS[name]
    n = volume.values.shape[axis]
    if not 0 <= index < n:
        raise ValueError(f"{name} slice index must be in 0..{n - 1}, not {index}")
    return np.take(volume.values, index, axis=axis)


def slice_picture(volume, name: str, index: int, size: tuple[int, int]) -> np.ndarray:
    """The slice as grey over the data's range, ``(H, W, 4)`` uint8 for ``size = (W, H)``:
    the slice's first axis across, its second up (as the world's x then y, or z), each sample
    a square of whole pixels, centred, the rest black."""
    width, height = size
    values = slice_values(volume, name, index)
    lo, hi = volume.value_range
    grey = np.floor(np.clip((values - lo) / max(hi - lo, 1e-30), 0, 1) * 255 + 0.5)
    image = grey.astype(np.uint8).T[::-1]                 # rows: second axis, top = largest
    side = max(1, min(width // image.shape[1], height // image.shape[0]))
    image = np.repeat(np.repeat(image, side, axis=0), side, axis=1)[:height, :width]
    out = np.zeros((height, width, 4), np.uint8)
    top, left = (height - image.shape[0]) // 2, (width - image.shape[1]) // 2
    out[top:top + image.shape[0], left:left + image.shape[1], :3] = image[..., None]
    return out
