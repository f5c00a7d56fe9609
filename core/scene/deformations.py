"""Barr's structure-deforming transformations: taper, twist and bend (Barr 1984, "Global and
local deformations of solid primitives"; the course notes: "Structure-deforming
transformations may be obtained through non-uniform scaling. Barr, at Caltech, was first to
do this").

Each is a non-uniform transformation whose factors vary with the position along an axis
``h`` (the other two coordinates ``p, q`` taken cyclically after it, so that ``p × q`` is the
axis):

- **taper**: ``p' = r p, q' = r q`` with ``r = 1 + k h`` (``rate`` = k, per unit length);
- **twist**: a rotation about the axis by ``θ = k h`` (``rate`` in degrees per unit length,
  counter-clockwise seen from the axis' tip);
- **bend** (Barr's bend of the y axis toward z): inside ``range = [h_min, h_max]`` the axis is
  wound onto a circle of radius ``1/k`` about a centre at ``toward = 1/k``, at ``center`` h0,
  angle ``θ = k (h − h0)``; beyond the range the two ends go on straight along the circle's
  tangents (``rate`` in degrees per unit length).

Each also gives its Jacobian J, and a vertex normal becomes ``J⁻ᵀ n`` (Barr's rule for the
normals of a deformed surface), so a smooth mesh stays smoothly shaded. They act on a mesh in
its object frame: after a geometry's ``scale`` and ``shear``, before its rotations and
translation (so a twist turns the object about its own axis wherever it is placed).

Scene file, a key of a ``[[geometry]]``: a list applied in order::

    deform = [{ taper = { axis = "y", rate = -0.2 } },
              { twist = { axis = "y", rate = 60 } },
              { bend = { axis = "y", toward = "z", rate = 30, center = 0, range = [-1, 1] } }]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

AXES = ("x", "y", "z")
MAX_DEFORMATIONS = 16


@dataclass(frozen=True)
class Deformation:
    kind: str                     # a name in DEFORMATIONS
    axis: int                     # h: 0, 1, 2
    rate: float                   # taper: per unit length; twist, bend: radians per unit
    toward: int = -1              # bend: the coordinate the axis bends toward
    center: float = 0.0           # bend: h0
    lo: float = -np.inf           # bend: the bent range of h
    hi: float = np.inf

    def frame(self) -> list[int]:
        """The coordinates as (p, q, h): h the axis, p × q = h (cyclic); a bend's
        (third, axis, toward) as Barr's (x, y, z)."""
        if self.kind == "bend":
            third = 3 - self.axis - self.toward
            return [third, self.axis, self.toward]
        return [(self.axis + 1) % 3, (self.axis + 2) % 3, self.axis]


def taper(d: Deformation, p, q, h):
    """``r = 1 + k h`` scales p and q."""
    r = 1.0 + d.rate * h
    jac = _zeros(len(h))
    jac[:, 0, 0] = jac[:, 1, 1] = r
    jac[:, 0, 2], jac[:, 1, 2], jac[:, 2, 2] = d.rate * p, d.rate * q, 1.0
    return (r * p, r * q, h), jac


def twist(d: Deformation, p, q, h):
    """A rotation by ``θ = k h`` about the axis."""
    c, s = np.cos(d.rate * h), np.sin(d.rate * h)
    jac = _zeros(len(h))
    jac[:, 0, 0], jac[:, 0, 1], jac[:, 0, 2] = c, -s, -d.rate * (p * s + q * c)
    jac[:, 1, 0], jac[:, 1, 1], jac[:, 1, 2] = s, c, d.rate * (p * c - q * s)
    jac[:, 2, 2] = 1.0
    return (p * c - q * s, p * s + q * c, h), jac


def bend(d: Deformation, x, y, z):
    """Barr's bend of y toward z (``x, y, z`` here: the third coordinate, the axis, toward)."""
    k, y0 = d.rate, d.center
    clamped = np.clip(y, d.lo, d.hi)
    c, s = np.cos(k * (clamped - y0)), np.sin(k * (clamped - y0))
    beyond = y - clamped                         # 0 inside the range: the straight ends
    inside = beyond == 0.0
    Y = -s * (z - 1.0 / k) + y0 + c * beyond
    Z = c * (z - 1.0 / k) + 1.0 / k + s * beyond
    jac = _zeros(len(y))
    jac[:, 0, 0] = 1.0
    stretch = np.where(inside, 1.0 - k * z, 1.0)   # d(Y, Z)/dy: the fibre's length factor
    jac[:, 1, 1], jac[:, 1, 2] = c * stretch, -s
    jac[:, 2, 1], jac[:, 2, 2] = s * stretch, c
    return (x, Y, Z), jac


DEFORMATIONS: dict[str, Callable] = {"taper": taper, "twist": twist, "bend": bend}


def _zeros(n: int) -> np.ndarray:
    return np.zeros((n, 3, 3))


def deformed(positions: np.ndarray, normals: np.ndarray | None, d: Deformation):
    """``positions`` (and vertex ``normals``, by ``J⁻ᵀ n``) after the deformation ``d``."""
    order = d.frame()
    local = positions[:, order]
    moved, jac = DEFORMATIONS[d.kind](d, local[:, 0], local[:, 1], local[:, 2])
    out = np.empty_like(positions)
    out[:, order] = np.column_stack(moved)
    if normals is None:
        return out, None
    n_local = normals[:, order]
    turned = np.linalg.solve(np.transpose(jac, (0, 2, 1)), n_local[:, :, None])[:, :, 0]
    turned /= np.linalg.norm(turned, axis=1, keepdims=True)
    n_out = np.empty_like(normals)
    n_out[:, order] = turned
    return out, n_out


def folds(positions: np.ndarray, d: Deformation) -> str | None:
    """Why ``d`` would turn part of the mesh inside out (its Jacobian's determinant reaching
    0), or None: a taper's r = 1 + k h at 0 or below, a bend's centre inside the bent part."""
    local = positions[:, d.frame()]
    if d.kind == "taper":
        r = 1.0 + d.rate * local[:, 2]
        if np.any(r <= 0.0):
            at = -1.0 / d.rate
            return (f"the taper's scale 1 + k·{AXES[d.axis]} reaches 0 at {AXES[d.axis]} = "
                    f"{at:.6g}, inside the mesh ({AXES[d.axis]} from {local[:, 2].min():.6g} "
                    f"to {local[:, 2].max():.6g}): it would turn the mesh inside out")
    if d.kind == "bend":
        bent = (local[:, 1] >= d.lo) & (local[:, 1] <= d.hi)
        reach = local[bent, 2] * d.rate
        if reach.size and np.any(reach >= 1.0):
            return (f"the bend's radius 1/k = {1.0 / d.rate:.6g} lies inside the bent part of "
                    f"the mesh ({AXES[d.toward]} reaches {local[bent, 2].max() if d.rate > 0 else local[bent, 2].min():.6g}): "
                    "it would fold the mesh through its centre; bend less or over a range")
    return None


# ---------------------------------------------------------------------- the scene file

KEYS = {"taper": ("axis", "rate"), "twist": ("axis", "rate"),
        "bend": ("axis", "toward", "rate", "center", "range")}


def read_deformations(reader, value, path) -> list[Deformation]:
    """A geometry's ``deform`` list, each entry one ``{ kind = { ... } }`` table."""
    if not isinstance(value, list) or not value:
        raise reader.fail(path, "expected a list of deformations, e.g. "
                                "[{ twist = { axis = \"y\", rate = 45 } }]")
    if len(value) > MAX_DEFORMATIONS:
        raise reader.fail(path, f"{len(value)} deformations; at most {MAX_DEFORMATIONS}")
    out = []
    for i, entry in enumerate(value):
        where = path + (i + 1,)
        t = reader.table(entry, where, tuple(DEFORMATIONS))
        if len(t) != 1:
            raise reader.fail(where, f"each entry is one of {', '.join(DEFORMATIONS)}")
        kind, params = next(iter(t.items()))
        out.append(_one(reader, kind, params, where + (kind,)))
    return out


def _one(reader, kind: str, params, path) -> Deformation:
    t = reader.table(params, path, KEYS[kind])
    if "rate" not in t:
        raise reader.fail(path, f"a {kind} needs a rate")
    axis = AXES.index(reader.choice(t.get("axis", "y"), path + ("axis",), AXES))
    high = 1e6 if kind == "taper" else 1e5
    rate = reader.number(t["rate"], path + ("rate",), -high, high)
    if kind == "taper":
        return Deformation(kind, axis, rate)
    if kind == "twist":
        return Deformation(kind, axis, float(np.radians(rate)))
    if rate == 0.0:
        raise reader.fail(path + ("rate",), "a bend of rate 0 has an endless radius (1/k): "
                                            "leave the bend out")
    toward = AXES.index(reader.choice(t.get("toward", AXES[(axis + 1) % 3]),
                                      path + ("toward",), AXES))
    if toward == axis:
        raise reader.fail(path + ("toward",), "the axis bends toward another axis")
    lo, hi = reader.vector(t["range"], path + ("range",), 2) if "range" in t else (-np.inf, np.inf)
    if lo > hi:
        raise reader.fail(path + ("range",), "the range's low end is above its high end")
    center = reader.number(t.get("center", 0.0), path + ("center",))
    return Deformation(kind, axis, float(np.radians(rate)), toward, center, lo, hi)
