"""Sampled 3D data and how it is drawn: a :class:`Volume`, its memory budget, its checks.

A volume is a grid of samples ``values[i, j, k]`` (float32, ``(nx, ny, nz)``: ``i`` runs along
x, ``j`` along y, ``k`` along z) at the points of *volume coordinates*

    x_vol = spacing · (i, j, k) − spacing · (n − 1) / 2        (the grid centred on the origin)

placed in the world by ``transform`` (4 x 4, translation in the rightmost column, the scene's
S → R_x → R_y → R_z → T as for geometry). :meth:`Volume.world_from_index` composes both, so
that index space, where the kernels work, is one matrix from the world.

Between samples the data is trilinear (FvDFH 20.6's reconstruction for volume rendering); it is
zero outside the grid's box. How it is drawn (``mode``):

- ``"isosurface"``: the surface ``value = iso`` by marching cubes, an ordinary mesh;
- ``"emission-absorption"``: the transfer function maps a value to an emitted colour
  ``(r, g, b)`` and an extinction ``σ`` (opacity per unit length, world units); the ray
  marcher integrates ``I = ∫ c σ e^{−∫σ} dt`` front to back;
- ``"mip"``: each ray shows the largest sample along it (maximum intensity projection), grey
  over ``window`` (default: the data's range).

Memory: every reader and generator checks the number of voxels against :data:`MAX_VOXELS`
before it allocates anything (a header that claims 2^40 voxels is refused from its numbers),
so a volume never takes more than ``MAX_VOXELS × 4`` bytes of samples plus the reader's own
copy of the file's type.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from core.scene.model import Material
from core.transforms import scale, translate

MODES = ("isosurface", "emission-absorption", "mip")
LIGHTINGS = ("gradient", "none")
# The budget: 2^26 voxels (four 256³ volumes), 256 MiB as float32.
MAX_VOXELS = 1 << 26
MIN_SIDE = 2                 # a trilinear cell needs two samples along each axis


class VolumeError(ValueError):
    """Malformed volume input; the message says what and where."""


@dataclass(eq=False)                  # identity: a volume keys the render caches
class Volume:
    values: np.ndarray                                    # (nx, ny, nz) float32
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    mode: str = "emission-absorption"
    iso: float | None = None
    transfer: np.ndarray | None = None                    # (K, 5): value, r, g, b, σ
    lighting: str = "gradient"
    material: Material = field(default_factory=Material)
    window: tuple[float, float] | None = None             # MIP's grey ramp
    name: str = "volume"

    def __post_init__(self):
        # the readers check this on a file's header; a volume made in code is held to it
        # too (the marcher's cells are indexed unsigned and need two samples a side)
        check_dims(np.shape(self.values), self.name)

    @property
    def dims(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.values.shape)

    @property
    def value_range(self) -> tuple[float, float]:
        return float(self.values.min()), float(self.values.max())

    def world_from_index(self) -> np.ndarray:
        """4 x 4: index (i, j, k) → world point."""
        s = np.asarray(self.spacing, dtype=np.float64)
        centre = s * (np.asarray(self.dims) - 1) / 2.0
        return np.asarray(self.transform) @ translate(*(-centre)) @ scale(*s)

    def mip_window(self) -> tuple[float, float]:
        return self.window if self.window is not None else self.value_range


def check_dims(dims, where: str) -> tuple[int, int, int]:
    """Three whole numbers ≥ 2 whose product is within the budget, or a :class:`VolumeError`
    (checked on the header's numbers, before anything is allocated)."""
    dims = tuple(dims)
    if len(dims) != 3:
        raise VolumeError(f"{where}: a volume has 3 dimensions, this one {len(dims)} "
                          f"({' x '.join(str(d) for d in dims)})")
    for axis, n in zip("xyz", dims):
        if isinstance(n, bool) or not float(n).is_integer() or n < MIN_SIDE:
            raise VolumeError(f"{where}: dims along {axis} must be a whole number of at least "
                              f"{MIN_SIDE} samples, not {n!r}")
    dims = tuple(int(n) for n in dims)
    count = math.prod(dims)
    if count > MAX_VOXELS:
        raise VolumeError(f"{where}: {' x '.join(map(str, dims))} = {count} voxels "
                          f"(2^{math.log2(count):.1f}) is over the budget of {MAX_VOXELS} "
                          f"(2^{int(math.log2(MAX_VOXELS))}, {MAX_VOXELS * 4 >> 20} MiB as float32)")
    return dims


def check_spacing(spacing, where: str) -> tuple[float, float, float]:
    spacing = tuple(float(s) for s in spacing)
    if len(spacing) != 3 or not all(math.isfinite(s) and s > 0 for s in spacing):
        raise VolumeError(f"{where}: spacing must be three finite numbers > 0, "
                          f"not {list(spacing)}")
    return spacing


def checked_samples(values, where: str) -> np.ndarray:
    """``values`` as contiguous float32 ``(nx, ny, nz)``; refuses NaN or infinite samples
    (saying how many and the first voxel) and any value beyond float32."""
    values = np.asarray(values)
    check_dims(values.shape, where)
    if values.dtype.kind not in "biuf":
        raise VolumeError(f"{where}: samples of type {values.dtype} are not numbers")
    if values.dtype.kind == "f":
        with np.errstate(over="ignore", invalid="ignore"):
            bad = ~np.isfinite(values.astype(np.float32))
        if bad.any():
            first = tuple(int(c) for c in np.argwhere(bad)[0])
            raise VolumeError(f"{where}: {int(bad.sum())} samples are NaN or infinite "
                              f"(or beyond float32), the first at voxel (i, j, k) = {first}")
    return np.ascontiguousarray(values, dtype=np.float32)


def checked_transfer(points, where: str) -> np.ndarray:
    """``(K, 5)`` rows ``value, r, g, b, σ``: values strictly increasing, colours in [0, 1],
    ``σ ≥ 0``; at least one point."""
    rows = np.asarray(points, dtype=np.float64)
    if rows.size == 0:
        raise VolumeError(f"{where}: the transfer function is empty; it needs at least one "
                          f"[value, r, g, b, alpha] point")
    if rows.ndim != 2 or rows.shape[1] != 5:
        raise VolumeError(f"{where}: each transfer point is [value, r, g, b, alpha]")
    if not np.all(np.isfinite(rows)):
        raise VolumeError(f"{where}: transfer points must be finite numbers")
    if np.any(np.diff(rows[:, 0]) <= 0):
        raise VolumeError(f"{where}: the transfer points' values must increase strictly")
    if np.any(rows[:, 1:4] < 0) or np.any(rows[:, 1:4] > 1):
        raise VolumeError(f"{where}: transfer colours must lie in [0, 1]")
    if np.any(rows[:, 4] < 0):
        raise VolumeError(f"{where}: transfer alpha (extinction per unit length) must be >= 0")
    return np.ascontiguousarray(rows)


def check_iso(iso: float, values: np.ndarray, where: str) -> float:
    lo, hi = float(values.min()), float(values.max())
    if not lo < iso < hi:
        raise VolumeError(f"{where}: iso {iso:g} is outside the data's range ({lo:g}, {hi:g}): "
                          f"no surface")
    return float(iso)


def transfer_at(transfer: np.ndarray, value) -> np.ndarray:
    """The transfer function (piecewise linear, constant beyond its ends) at ``value`` (...):
    ``(..., 4)`` rows ``r, g, b, σ`` (numpy; the kernels' :func:`core.volume.raymarch.classify`
    is the same rule)."""
    v = np.asarray(value, dtype=np.float64)
    return np.stack([np.interp(v, transfer[:, 0], transfer[:, c]) for c in range(1, 5)], -1)


def volumes_of(scene) -> list[Volume]:
    """The scene's volumes (``Scene.systems``): the ``[[volume]]`` reader attaches them, the
    renderer and the inspector read them, and a copy of the scene has them too."""
    return scene.systems.get("volumes", [])


def attach_volumes(scene, volumes) -> None:
    scene.systems = {**scene.systems, "volumes": list(volumes)}
