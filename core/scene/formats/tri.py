"""The course's triangle file (``.tri``, Assignments #2 and #3) read into a Scene.

Takes the text of a ``.tri`` file and returns a :class:`Scene` with one open mesh (a soup of
arbitrary winding: ``closed=False``, lit from both sides), the file's camera as the first view
(``camera.tri_view``), framing views after it, and the startup code's light::

    vx vy vz          the viewpoint (centre of projection), world coordinates
    tx ty tz          the top-left of the screen: where pixel (0, 0) lies
    rx ry rz          displacement from one pixel to the next, to the right
    dx dy dz          displacement from one pixel to the next, downward
    N                 number of triangles
    x0 y0 z0 x1 y1 z1 x2 y2 z2      N times

Numbers may be split across lines in any way (the startup code reads them with ``>>``);
``#`` starts a comment. The count N is never used to allocate: the numbers present are read
first, then held against N, and a disagreement is an error naming the line. Equal vertices
become one mesh vertex by hashing, numbered in order of first appearance like the startup
code's ``v_table`` (which finds them with an O(N^2) scan).
"""

from __future__ import annotations

import numpy as np

from core.scene.formats.camera import default_lights, framing_views, tri_light, tri_view
from core.scene.formats.errors import (MAX_COORDINATE, ReaderError, decode_text, file_stem, short,
                                 tolerant_of_underflow, whole_number)
from core.scene.formats.mesh import drop_repeated_triangles, merge_vertices
from core.scene.formats.numbers import Numbers
from core.camera.view import problems
from core.scene.model import Light, Material, Mesh, Scene
from core.transforms import apply

DEFAULT_SIZE = (500, 500)
_HEADER = ("the viewpoint", "the top-left corner", "the right displacement",
           "the down displacement")


@tolerant_of_underflow
def read_tri(data: bytes | str, file: str, size: tuple[int, int] | None = None) -> Scene:
    """The scene of a ``.tri`` file; ``size`` (width, height) is the image, 500 x 500 by default."""
    size = tuple(size) if size is not None else DEFAULT_SIZE
    values, positions, triangles, numbers = _parse(data, file)
    viewpoint, top_left, right, down = (values[3 * k:3 * k + 3].copy() for k in range(4))
    try:
        camera = tri_view(viewpoint, top_left, right, down, size, positions,
                          label=f"{file}: the file's camera")
    except ValueError as error:
        at = 0 if str(error).startswith("the viewpoint") else 6     # else: the displacements
        raise ReaderError(file, str(error), numbers.line(at)) from None
    # the renderer's own rules: a camera that loads can be drawn, in both projections
    found = list(dict.fromkeys(problems(camera.view, "perspective")
                               + problems(camera.view, "parallel")))
    if found:
        raise ReaderError(file, "the camera cannot be drawn: " + "; ".join(found),
                          numbers.line(0))
    light = tri_light(viewpoint, right, down)
    if camera.mirror is not None:
        positions = apply(camera.mirror, positions)[:, :3]
        light = apply(camera.mirror, light[None])[0, :3]

    mesh = Mesh(positions=positions, triangles=triangles, closed=False, material=Material(),
                name=file_stem(file))
    views = [camera.view] + framing_views(positions, f"{file}")
    lights = [Light(intensity=(1.0, 1.0, 1.0), position=tuple(float(c) for c in light))]
    if len(positions) == 0:
        lights = default_lights(positions)
    return Scene(name=file_stem(file), meshes=[mesh], views=views, lights=lights,
                 shading="flat", projection="perspective", size=size, source=str(file))


def read_tri_mesh(data: bytes | str, file: str, budget: int | None = None) -> Mesh:
    """Only the triangles of a ``.tri`` file, as they are in the file (a scene file's mesh):
    its camera is neither needed nor checked, and nothing is mirrored for it."""
    _, positions, triangles, _ = _parse(data, file, budget)
    return Mesh(positions=positions, triangles=triangles, closed=False, material=Material(),
                name=file_stem(file))


def _parse(data: bytes | str, file: str, budget: int | None = None):
    """``(header values, positions, triangles, numbers)``; every error names its line."""
    from core.scene.generators import MAX_TRIANGLES
    budget = MAX_TRIANGLES if budget is None else budget
    text = decode_text(data, file) if isinstance(data, bytes) else data
    numbers = Numbers(text, file, keep=13)
    values = numbers.values

    if len(values) < 12:
        what = _HEADER[len(values) // 3]
        raise ReaderError(file, f"the file ends before the header is complete: {what} needs 3 "
                                f"numbers (the header is 12 numbers and the triangle count; "
                                f"found {len(values)})", numbers.line(len(values)))
    for k, what in enumerate(_HEADER):
        _check_finite(values[3 * k:3 * k + 3], what, numbers, 3 * k, file)
    if len(values) < 13:
        raise ReaderError(file, "the file ends before the triangle count N",
                          numbers.line(len(values)))
    count_line = numbers.line(12)
    count = whole_number(numbers.tokens[12], file, count_line, "the triangle count")

    body = values[13:]                      # what the file holds, whatever N says
    if len(body) < 9 * count:
        k = len(body) // 9                  # triangles complete
        got = len(body) - 9 * k
        if got:
            raise ReaderError(file, f"expected 9 numbers for triangle {k + 1}, got {got} (the "
                                    f"file ends; the count on line {count_line} is {count})",
                              numbers.line(13 + 9 * k))
        raise ReaderError(file, f"the file ends after {_triangles(k)}, but the count on line "
                                f"{count_line} says {count}", numbers.line(len(values)))
    if len(body) > 9 * count:
        extra = 13 + 9 * count
        raise ReaderError(file, f"more numbers than the count on line {count_line} says "
                                f"({_triangles(count)}): {short(numbers_text(values[extra]))} would "
                                f"start triangle {count + 1}", numbers.line(extra))
    if count > budget:          # (after the checks above: a count the data lacks says so)
        raise ReaderError(file, f"the count says {count} triangles; the limit is {budget} (the "
                                f"triangle budget of a scene)", count_line)
    _check_finite(body, "a triangle", numbers, 13, file)

    corners = body.reshape(-1, 3)           # three rows per triangle
    positions, inverse = merge_vertices(corners)
    return values, positions, drop_repeated_triangles(inverse.reshape(-1, 3)), numbers


def numbers_text(value: float) -> str:
    return f"{value:g}"


def _triangles(k: int) -> str:
    return f"{k} triangle" + ("" if k == 1 else "s")


def _check_finite(values: np.ndarray, what: str, numbers: Numbers, first: int, file: str) -> None:
    """Refuse NaN, infinities and coordinates too large to compute with, naming the line."""
    bad = ~np.isfinite(values) | (np.abs(np.nan_to_num(values)) > MAX_COORDINATE)
    if np.any(bad):
        k = int(np.argmax(bad))
        value = values[k]
        reason = ("NaN" if np.isnan(value) else "infinite" if np.isinf(value) else
                  f"too large (|x| > {MAX_COORDINATE:g})")
        if what == "a triangle":
            what = f"triangle {k // 9 + 1}, vertex {k % 9 // 3 + 1}"
        raise ReaderError(file, f"{what} has a coordinate that is {reason} "
                                f"({numbers_text(value)})", numbers.line(first + k))

