"""Cameras the readers make: the ``.tri`` pinhole as a VRC view, and views that frame a mesh.

- :func:`tri_view` turns the course's pixel-grid camera (viewpoint, top-left, right and down
  pixel displacements, image size) into an FvDFH view (VRP, VPN, VUP, window, PRP, F, B), so that
  the ``.tri`` scenes go through the same N_per as everything else (FvDFH 6.5, pipeline.md).
- :func:`framing_views` gives a mesh file without views three views of its bounding box
  (front, three-quarter, top); :func:`default_lights` lights it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.scene.model import Light
from core.camera.view import View, unit3

# The front plane is kept at least this fraction of the depth range in front of the eye, so
# that z_min (and with it the z-buffer's precision) stays reasonable when geometry crosses it.
FRONT_GAP = 0.01
# Relative tolerance for "the right and down displacements are perpendicular".
PERPENDICULAR_TOLERANCE = 1e-6


@dataclass(frozen=True)
class TriCamera:
    """A ``.tri`` camera converted: the view, and whether the world had to be mirrored.

    ``mirror`` is None, or the 4 x 4 reflection across the screen plane that was applied to the
    geometry and the light because the viewpoint lay behind the screen (see :func:`tri_view`).
    """

    view: View
    mirror: np.ndarray | None


def screen_basis(right: np.ndarray, down: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``u`` along the right displacement, ``v`` against the down one, ``n = u x v``.

    Raises ValueError with the reason when the two displacements cannot span a pixel grid.
    """
    u, len_r = unit3(right)            # scaled: a displacement of 1e-300 is not zero
    unit_down, len_d = unit3(down)
    if not len_r > 0.0:
        raise ValueError("the right displacement is zero")
    if not len_d > 0.0:
        raise ValueError("the down displacement is zero")
    cosine = float(np.dot(u, unit_down))
    if abs(cosine) > PERPENDICULAR_TOLERANCE:
        raise ValueError(f"the right and down displacements are not perpendicular (the angle "
                         f"between them is {np.degrees(np.arccos(np.clip(cosine, -1, 1))):.6g} "
                         f"degrees); a VRC window needs a rectangular pixel grid")
    v = unit3(-(unit_down - np.dot(unit_down, u) * u))[0]   # drop the rounding-sized slant
    return u + 0.0, v + 0.0, np.cross(u, v) + 0.0      # + 0.0: no -0.0 in messages


def front_back(depths: np.ndarray, prp_n: float) -> tuple[float, float]:
    """F and B along n for geometry at VRC depths ``depths``, seen from an eye at ``prp_n`` > 0.

    B lies just behind the farthest geometry (and behind the view plane); F just in front of the
    nearest geometry but never nearer the eye than FRONT_GAP of the depth range, so that
    geometry reaching past the eye is cut by the front plane instead of crossing the eye.
    """
    far = min(float(depths.min()), 0.0) if len(depths) else 0.0
    near = float(depths.max()) if len(depths) else 0.0
    pad = 0.01 * (prp_n - far)
    back = far - pad
    front = min(near + pad, prp_n - FRONT_GAP * (prp_n - back))
    return front, back


def tri_view(viewpoint: np.ndarray, top_left: np.ndarray, right: np.ndarray, down: np.ndarray,
             size: tuple[int, int], positions: np.ndarray, label: str) -> TriCamera:
    """The ``.tri`` camera as a View: VRP = top-left, u = right, v = -down, n = u x v.

    Pixel (i, j) (column i, row j from the top) of the course's camera is sampled at the world
    point ``top_left + i right + j down``: the startup code's scan lines run through integer
    screen coordinates and its screen is ``0 <= x < xdim``. That point is the pixel's centre,
    so the window reaches half a pixel beyond it: u from -|r|/2 to (W - 1/2)|r|, v from
    -(H - 1/2)|d| to |d|/2. With our viewport (pixel centres at half-integers) the world point
    then lands exactly on the centre of pixel (i, j).

    A viewpoint behind the screen (on the -n side) looks at the grid from behind, which a
    right-handed VRC cannot express; the image it defines is the same as that of the world
    mirrored across the screen plane seen from the mirrored viewpoint (the plane is fixed, so
    every projected point and every distance is unchanged). The caller applies ``mirror`` to the
    geometry and the light.
    """
    u, v, n = screen_basis(right, down)
    width, height = size
    len_r, len_d = unit3(right)[1], unit3(down)[1]
    eye = viewpoint - top_left
    if min(len_r, len_d) < 1e-12 * unit3(eye)[1]:
        raise ValueError("the pixel displacements are too small next to the viewpoint's "
                         "distance from the screen (less than 1e-12 of it): the image would "
                         "be one point")
    prp = np.array([eye @ u, eye @ v, eye @ n])
    mirror = None
    if prp[2] == 0.0:
        raise ValueError("the viewpoint lies on the screen plane (PRP_n = 0)")
    if prp[2] < 0.0:
        reflect = np.eye(4)
        reflect[:3, :3] -= 2.0 * np.outer(n, n)
        reflect[:3, 3] = 2.0 * np.dot(top_left, n) * n
        mirror = reflect
        prp[2] = -prp[2]
    depths = (positions - top_left) @ n
    if mirror is not None:
        depths = -depths
    front, back = front_back(depths, float(prp[2]))
    window = (-0.5 * len_r, (width - 0.5) * len_r, -(height - 0.5) * len_d, 0.5 * len_d)
    view = View(vrp=tuple(float(c) for c in top_left), vpn=tuple(float(c) for c in n),
                vup=tuple(float(c) for c in v), window=tuple(float(c) for c in window),
                prp=tuple(float(c) for c in prp), front=front, back=back,
                label=label + (" (viewpoint behind the screen: world mirrored)" if mirror is not None else ""))
    return TriCamera(view=view, mirror=mirror)


def tri_light(viewpoint: np.ndarray, right: np.ndarray, down: np.ndarray) -> np.ndarray:
    """The startup code's light: ``(viewpoint_x + 40 rx, viewpoint_y + 40 dy, viewpoint_z)``."""
    return np.array([viewpoint[0] + 40.0 * right[0], viewpoint[1] + 40.0 * down[1], viewpoint[2]])


def bounds(points: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre of the bounding box and the radius of the sphere about it that holds the points."""
    if len(points) == 0:
        return np.zeros(3), 1.0
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.sqrt(((points - centre) ** 2).sum(axis=1).max()))
    # A point, or a speck too small for float64 views around it: frame a sensible size.
    floor = 1e-9 * (1.0 + float(np.abs(centre).max()))
    if not radius > floor:
        radius = max(1.0, float(np.abs(centre).max()) * 1e-3) if radius == 0.0 else floor
    return centre, radius


# Where the framing views look from (VPN, towards the eye) and which way is up.
_FRAMINGS = (
    ("front", (0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    ("three-quarter", (1.0, 0.8, 1.2), (0.0, 1.0, 0.0)),
    ("top", (0.0, 1.0, 0.0), (0.0, 0.0, -1.0)),
)
# Eye distance in bounding-sphere radii; the window's half size is chosen so the sphere fits.
_EYE_DISTANCE = 3.0


def framing_views(points: np.ndarray, label: str) -> list[View]:
    """Front, three-quarter and top views of the bounding sphere of ``points``.

    VRP is the sphere's centre and the view plane passes through it; the eye sits 3 radii away
    on n (PRP = (0, 0, 3r)), where the sphere subtends a half angle whose tangent is 1/sqrt(8),
    so a window of half size 1.15 r (> 3r / sqrt(8) = 1.06 r) frames it with a margin, in
    perspective and in parallel projection alike. F and B enclose the sphere.
    """
    centre, radius = bounds(points)
    half = 1.15 * radius
    views = []
    for name, vpn, vup in _FRAMINGS:
        views.append(View(vrp=tuple(float(c) for c in centre), vpn=vpn, vup=vup,
                          window=(-half, half, -half, half), prp=(0.0, 0.0, _EYE_DISTANCE * radius),
                          front=1.05 * radius, back=-1.05 * radius, label=f"{label}: {name} view"))
    return views


def default_lights(points: np.ndarray) -> list[Light]:
    """A white key light above, right and in front of the bounding sphere, and a dim fill light."""
    centre, radius = bounds(points)
    key = centre + radius * np.array([2.0, 3.0, 4.0])
    return [Light(intensity=(0.9, 0.9, 0.9), position=tuple(float(c) for c in key)),
            Light(intensity=(0.3, 0.3, 0.35), direction=(-1.0, 0.3, 0.5))]
