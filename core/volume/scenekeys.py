"""The scene file's ``[[volume]]`` tables (registered with the scene reader; every message names
the table, the key and its line)::

    [[volume]]
    name = "head"
    generator = "shepp-logan"            # or "sphere", "metaballs", "torus"
    params = { size = 96 }               # the generator's own (core.volume.generators)
    # file = "ct.nrrd"                   # or .nii / .nii.gz, a folder of DICOM slices, or
    #                                    # .raw with a header table:
    # raw = { dims = [64, 64, 32], dtype = "uint16", byte_order = "little", offset = 0 }
    spacing = [0.02, 0.02, 0.02]         # world units between samples (default: the file's)
    transform = { scale = 1.0, rotate = [0, 0, 0], translate = [0, 0, 0] }
    mode = "emission-absorption"         # "isosurface" | "emission-absorption" | "mip"
    iso = 0.5                            # isosurface: the surface value = iso
    transfer = [[0.0, 0, 0, 0, 0], [1.0, 1, 0.9, 0.8, 4.0]]   # value, r, g, b, alpha
    lighting = "gradient"                # or "none": emission only
    material = { ka = 0.3, kd = 0.7, ks = 0.2, n = 10 }       # the Phong terms it is lit by
    window = [0.0, 1.0]                  # MIP: the values shown black and white

``alpha`` is the extinction σ per unit length (world units), so a sample's opacity depends on
the step, not on the grid; the transfer function is piecewise linear in the value. An
isosurface becomes an ordinary mesh of the scene (drawn by every renderer), named after the
volume; the other modes are drawn by ``--renderer volume``.
"""

from __future__ import annotations

import inspect

import numpy as np

from core.scene import generators as mesh_generators
from core.scene.formats.keys import register_scene_contents, register_scene_keys
from core.scene.model import Material
from core.transforms import rotate_x, rotate_y, rotate_z, scale, translate
from core.volume import generators, readers
from core.volume.data import (LIGHTINGS, MAX_VOXELS, MODES, Volume, VolumeError,
                              attach_volumes, check_iso, check_spacing, checked_transfer,
                              volumes_of)
from core.volume.marching import isosurface

VOLUME_KEYS = ("name", "file", "generator", "params", "raw", "spacing", "transform", "mode",
               "iso", "transfer", "lighting", "material", "window")
RAW_KEYS = ("dims", "dtype", "byte_order", "offset")
TRANSFORM_KEYS = ("scale", "rotate", "translate")


def read_scene_keys(reader, doc: dict, scene) -> None:
    if "volume" not in doc:
        return
    volumes, voxels = [], 0
    for i, table in enumerate(reader.tables(doc["volume"], ("volume",))):
        path = ("volume", i + 1)
        volume = read_volume(reader, table, path, f"volume {i + 1}")
        voxels += volume.values.size
        if voxels > MAX_VOXELS:
            raise reader.fail(path, f"the scene's volumes hold {voxels} voxels by here; the "
                                    f"budget is {MAX_VOXELS}")
        if volume.mode == "isosurface":
            scene.meshes.append(isosurface(volume))
            if scene.triangle_count > mesh_generators.MAX_TRIANGLES:
                raise reader.fail(path + ("iso",), f"the isosurface takes the scene to "
                                  f"{scene.triangle_count} triangles; the limit is "
                                  f"{mesh_generators.MAX_TRIANGLES}")
        volumes.append(volume)
    attach_volumes(scene, volumes)


def read_volume(reader, table, path, default_name: str) -> Volume:
    t = reader.table(table, path, VOLUME_KEYS)
    if ("file" in t) == ("generator" in t):
        raise reader.fail(path, "give exactly one of 'file' or 'generator'")
    try:
        values, spacing = (read_file(reader, t, path) if "file" in t
                           else generate(reader, t, path))
    except VolumeError as error:
        key = "file" if "file" in t else "params"
        raise reader.fail(path + (key,), str(error)) from None
    if "spacing" in t:
        spacing = reader.vector(t["spacing"], path + ("spacing",))
        try:
            spacing = check_spacing(spacing, "spacing")
        except VolumeError as error:
            raise reader.fail(path + ("spacing",), str(error).removeprefix("spacing: "))
    mode = reader.choice(t.get("mode", "emission-absorption"), path + ("mode",), MODES)
    volume = Volume(values=values, spacing=spacing, mode=mode,
                    name=reader.string(t.get("name", default_name), path + ("name",)),
                    lighting=reader.choice(t.get("lighting", "gradient"),
                                           path + ("lighting",), LIGHTINGS))
    if "transform" in t:
        volume.transform = placement(reader, t["transform"], path + ("transform",))
    if "material" in t:
        volume.material = reader.material(t["material"], path + ("material",), Material())
    read_drawing(reader, t, path, volume)
    return volume


def read_drawing(reader, t, path, volume) -> None:
    """``iso``, ``transfer`` and ``window``: what the mode needs, checked against the data."""
    if "iso" in t or volume.mode == "isosurface":
        if "iso" not in t:
            raise reader.fail(path, "an isosurface needs an 'iso' value")
        iso = reader.number(t["iso"], path + ("iso",))
        try:
            volume.iso = check_iso(iso, volume.values, "iso")
        except VolumeError as error:
            raise reader.fail(path + ("iso",), str(error).removeprefix("iso: ")) from None
    if "transfer" in t or volume.mode == "emission-absorption":
        if "transfer" not in t:
            raise reader.fail(path, "emission-absorption needs a 'transfer' function: "
                                    "[[value, r, g, b, alpha], ...]")
        points = t["transfer"]
        if not isinstance(points, list) or not all(isinstance(p, list) for p in points):
            raise reader.fail(path + ("transfer",), "expected a list of [value, r, g, b, "
                                                    "alpha] points")
        rows = [reader.vector(p, path + ("transfer", k + 1), 5) for k, p in enumerate(points)]
        try:
            volume.transfer = checked_transfer(rows, "transfer")
        except VolumeError as error:
            raise reader.fail(path + ("transfer",),
                              str(error).removeprefix("transfer: ")) from None
    if "window" in t:
        lo, hi = reader.vector(t["window"], path + ("window",), 2)
        if not lo < hi:
            raise reader.fail(path + ("window",), f"the window's low end ({lo:g}) must be "
                                                  f"below its high end ({hi:g})")
        volume.window = (lo, hi)


def read_file(reader, t, path):
    name = reader.string(t["file"], path + ("file",))
    target = reader.folder / name
    kind = readers.kind_of(name, reader.folder)
    if (kind == "raw") != ("raw" in t):
        raise reader.fail(path + ("raw",) if "raw" in t else path + ("file",),
                          "a .raw file needs a raw = { dims, dtype, byte_order } table"
                          if kind == "raw" else "the raw header table is for .raw files")
    if kind == "nrrd":
        return readers.read_nrrd(target, name)
    if kind == "nifti":
        return readers.read_nifti(target, name)
    if kind == "dicom":
        return readers.read_dicom(target, name)
    raw = reader.table(t["raw"], path + ("raw",), RAW_KEYS)
    if "dims" not in raw:
        raise reader.fail(path + ("raw",), "the raw header needs dims = [nx, ny, nz]")
    dims = raw["dims"]
    if not isinstance(dims, list) or not all(isinstance(n, int) and not isinstance(n, bool)
                                             for n in dims):
        raise reader.fail(path + ("raw", "dims"), "expected a list of whole numbers")
    dtype = reader.choice(raw.get("dtype", "uint8"), path + ("raw", "dtype"), readers.DTYPES)
    order = reader.choice(raw.get("byte_order", "little"), path + ("raw", "byte_order"),
                          readers.BYTE_ORDERS)
    offset = reader.number(raw.get("offset", 0), path + ("raw", "offset"), 0, 2 ** 40)
    values = readers.read_raw(target, dims, dtype, order, int(offset), name)
    return values, (1.0, 1.0, 1.0)


def generate(reader, t, path):
    name = reader.choice(t["generator"], path + ("generator",), tuple(generators.GENERATORS))
    make = generators.GENERATORS[name]
    params = reader.table(t.get("params", {}), path + ("params",),
                          tuple(inspect.signature(make).parameters))
    try:
        return make(**params)
    except VolumeError as error:
        raise VolumeError(f"{name}: {error}") from None
    except (TypeError, ValueError, IndexError, KeyError) as error:   # a param of a wrong shape
        raise VolumeError(f"{name}: params {params!r} do not fit the generator "
                          f"({type(error).__name__}: {error})") from None


def placement(reader, value, path) -> np.ndarray:
    """S, then R_x, R_y, R_z (degrees), then T: the geometry's transform, as a matrix."""
    t = reader.table(value, path, TRANSFORM_KEYS)
    factor = t.get("scale", 1.0)
    s = (reader.vector(factor, path + ("scale",), 3, -1e6, 1e6) if isinstance(factor, list)
         else (reader.number(factor, path + ("scale",), -1e6, 1e6),) * 3)
    if any(abs(c) < 1e-6 for c in s):
        raise reader.fail(path + ("scale",), "a scale factor is zero (or below 1e-6 in size)")
    rx, ry, rz = reader.vector(t.get("rotate", [0, 0, 0]), path + ("rotate",), 3, -1e6, 1e6)
    tx, ty, tz = reader.vector(t.get("translate", [0, 0, 0]), path + ("translate",))
    return (translate(tx, ty, tz) @ rotate_z(np.radians(rz)) @ rotate_y(np.radians(ry))
            @ rotate_x(np.radians(rx)) @ scale(*s))


def corners(scene) -> np.ndarray:
    """The world corners of every volume's sample grid (a scene of volumes alone is framed
    and lit by them)."""
    out = []
    for volume in volumes_of(scene):
        last = np.asarray(volume.dims, np.float64) - 1.0
        grid = np.array([[i, j, k, 1.0] for i in (0, last[0]) for j in (0, last[1])
                         for k in (0, last[2])])
        out.append((grid @ volume.world_from_index().T)[:, :3])
    return np.concatenate(out) if out else np.zeros((0, 3))


register_scene_keys("volume", ("volume",), read_scene_keys, arrays=("volume",))
register_scene_contents("volume", corners)
