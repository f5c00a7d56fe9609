"""The class of a view in the taxonomy of planar geometric projections (FvDFH 6.1, the notes'
tree of January 22 and quiz 1), found from the view's numbers alone.

- **Perspective**: the number of principal axes (world x, y, z) the projection plane cuts, i.e.
  the non-zero components of VPN: one, two or three vanishing points (one-, two-,
  three-point perspective). An axis parallel to the plane has no vanishing point.
- **Parallel**: the direction of projection DOP = CW − PRP (VRC; CW the window's centre)
  against VPN.
  - DOP along VPN: **orthographic**. VPN along a principal axis: a multiview elevation (front,
    top/plan, side). Otherwise **axonometric**, by the foreshortening of the three axes,
    ``sqrt(1 − n_i²)`` for the unit VPN n: all equal **isometric** (the DOP makes equal angles
    with each axis), two equal **dimetric**, none **trimetric**.
  - DOP oblique to VPN: **oblique**, by the length ``|DOP_uv| / |DOP_n|`` at which a line
    perpendicular to the plane is drawn: 1 **cavalier** (projectors at 45° to the plane),
    1/2 **cabinet** (at arctan 2 = 63.4°). Any other ratio is an oblique projection of none of
    the named classes, and :func:`classify` says so.

Numbers count as equal (and components as zero) within ``TOLERANCE`` relative to their
vector's length: the view files hold decimals (20√2 as 28.2843).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from core.camera.view import View

TOLERANCE = 1e-6
CLASSES = ("orthographic (front elevation)", "orthographic (top view, plan)",
           "orthographic (side elevation)", "isometric", "dimetric", "trimetric", "cavalier",
           "cabinet", "one-point perspective", "two-point perspective",
           "three-point perspective")
AXES = "xyz"


class NoClass(ValueError):
    """The view is none of the taxonomy's named classes; the message says what it is."""


@dataclass(frozen=True)
class ProjectionClass:
    name: str                  # one of CLASSES
    family: str                # "perspective", "parallel: orthographic", ... the tree's path
    why: str                   # the numbers that decide it
    numbers: dict = field(default_factory=dict)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _zero(x: float) -> bool:
    return abs(x) <= TOLERANCE


def classify(view: View, projection: str) -> ProjectionClass:
    """The class of ``view`` drawn in ``projection``; raises :class:`NoClass` for an oblique
    view that is neither cavalier nor cabinet (and ValueError for a zero VPN)."""
    if not np.linalg.norm(view.vpn) > 0.0:
        raise ValueError(f"{view.label}: VPN is zero: no projection plane to classify")
    n = _unit(view.vpn)
    if projection == "perspective":
        return _perspective(n)
    if projection != "parallel":
        raise ValueError(f"projection must be perspective or parallel, not {projection!r}")
    u_min, u_max, v_min, v_max = view.window
    cw = np.array([(u_min + u_max) / 2, (v_min + v_max) / 2, 0.0])
    dop = cw - np.asarray(view.prp, dtype=np.float64)
    if not np.linalg.norm(dop) > 0.0:
        raise ValueError(f"{view.label}: PRP is the window's centre: no direction of projection")
    across, along = math.hypot(dop[0], dop[1]), abs(dop[2])
    if along == 0.0:
        raise ValueError(f"{view.label}: DOP lies in the view plane: nothing is projected")
    if _zero(across / np.linalg.norm(dop)):
        return _orthographic(n, dop)
    return _oblique(view, n, dop, across / along)


def _perspective(n) -> ProjectionClass:
    cut = [AXES[i] for i in range(3) if not _zero(n[i])]
    name = ("one-point perspective", "two-point perspective",
            "three-point perspective")[len(cut) - 1]
    return ProjectionClass(name, "perspective", f"the projection plane cuts {len(cut)} principal "
                           f"ax{'is' if len(cut) == 1 else 'es'} ({', '.join(cut)}): VPN "
                           f"{_v(n)} has {len(cut)} non-zero component"
                           f"{'' if len(cut) == 1 else 's'}, one vanishing point each",
                           {"VPN": n.tolist(), "axes cut": cut})


def _orthographic(n, dop) -> ProjectionClass:
    cut = [i for i in range(3) if not _zero(n[i])]
    numbers = {"VPN": n.tolist(), "DOP (VRC)": dop.tolist()}
    if len(cut) == 1:
        name = ("orthographic (side elevation)", "orthographic (top view, plan)",
                "orthographic (front elevation)")[cut[0]]
        return ProjectionClass(name, "parallel: orthographic (multiview)",
                               f"DOP along VPN, and VPN along the {AXES[cut[0]]} axis",
                               numbers)
    shorten = np.sqrt(np.maximum(0.0, 1.0 - n * n))    # each axis' length on the plane
    pairs = sum(abs(shorten[i] - shorten[j]) <= TOLERANCE for i, j in ((0, 1), (0, 2), (1, 2)))
    name = "isometric" if pairs == 3 else "dimetric" if pairs >= 1 else "trimetric"
    numbers["foreshortening"] = shorten.tolist()
    equal = {3: "all three equal", 2: "two equal", 1: "two equal", 0: "no two equal"}[pairs]
    return ProjectionClass(name, "parallel: orthographic: axonometric",
                           f"DOP along VPN, VPN {_v(n)} along no principal axis; the axes are "
                           f"foreshortened to {_v(shorten)}: {equal}", numbers)


def _oblique(view, n, dop, ratio) -> ProjectionClass:
    angle = math.degrees(math.atan2(abs(dop[2]), math.hypot(dop[0], dop[1])))
    numbers = {"VPN": n.tolist(), "DOP (VRC)": dop.tolist(),
               "perpendicular lines drawn at": ratio, "projectors to the plane (degrees)": angle}
    why = (f"DOP {_v(dop)} is oblique to VPN: lines perpendicular to the view plane are drawn "
           f"at {ratio:.4g} of their length (projectors at {angle:.4g} degrees to the plane)")
    if abs(ratio - 1.0) <= TOLERANCE:
        return ProjectionClass("cavalier", "parallel: oblique", why, numbers)
    if abs(ratio - 0.5) <= TOLERANCE:
        return ProjectionClass("cabinet", "parallel: oblique", why, numbers)
    raise NoClass(f"{view.label}: an oblique parallel projection of none of the named classes: "
                  f"{why}; cavalier draws them at 1 (45 degrees), cabinet at 1/2 (63.43 degrees)")


def _v(values) -> str:
    return "(" + ", ".join(f"{float(x):.4g}" for x in values) + ")"


def describe(view: View, projection: str) -> dict:
    """The class as ``matrices`` prints it: ``{"class", "family", "why"}``, or the message
    of a view that is none of the classes (``"class": None``)."""
    try:
        found = classify(view, projection)
    except ValueError as error:
        return {"class": None, "family": None, "why": str(error)}
    return {"class": found.name, "family": found.family, "why": found.why,
            "numbers": found.numbers}
