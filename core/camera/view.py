"""Viewing: the VRC system and the normalizing transformations N_per and N_par (FvDFH 6.5).

Takes a :class:`View` (VRP, VPN, VUP, window, PRP, F, B — the six lines of Assignment #1) and
returns 4 x 4 matrices that carry world coordinates into the canonical view volumes:

- parallel:     ``N_par = S_par · T_par · SH_par · R · T(-VRP)``;
  volume ``-1 <= x <= 1, -1 <= y <= 1, -1 <= z <= 0``.
- perspective:  ``N_per = S_per · SH_par · T(-PRP) · R · T(-VRP)``;
  volume ``z <= x <= -z, z <= y <= -z, -1 <= z <= z_min``.

Every factor is kept by name (:func:`n_par_factors`, :func:`n_per_factors`) so that a learner
can hold each one against a hand calculation (``python -m app matrices``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from core.settings import PROJECTIONS
from core.transforms import rows_as_rotation, scale, shear_xy, translate



class ViewError(ValueError):
    """An invalid or unreasonable view; the message names the view and the reason."""


@dataclass(frozen=True)
class View:
    """One view specification, in the order of Assignment #1.

    ``window`` is ``(u_min, u_max, v_min, v_max)``; ``front`` and ``back`` are the signed
    distances F and B along n from the VRP. ``label`` says where the view came from
    (``"house.views: view 3 (line 13)"``) so that every message can name it.
    """

    vrp: tuple[float, float, float]
    vpn: tuple[float, float, float]
    vup: tuple[float, float, float]
    window: tuple[float, float, float, float]
    prp: tuple[float, float, float]
    front: float
    back: float
    label: str = field(default="view", compare=False)

    @property
    def numbers(self) -> np.ndarray:
        """All 18 numbers of the view, in file order."""
        return np.array([*self.vrp, *self.vpn, *self.vup, *self.window, *self.prp,
                         self.front, self.back], dtype=np.float64)


# Relative tolerance under which two directions count as parallel (|VUP x n| / |VUP|).
PARALLEL_TOLERANCE = 1e-12


def problems(view: View, projection: str | None = None) -> list[str]:
    """Every reason the view is invalid or unreasonable (pipeline.md's list); empty if valid.

    With ``projection=None`` only the checks that hold for both projections are made; with a
    projection, the normalizing transformation is also built and checked for overflow.
    """
    found = _problems(view, projection)
    if not found and projection is not None:
        _factors_or_overflow(view, projection, found)
    return found


def unit3(a) -> tuple[np.ndarray, float]:
    """``(a / |a|, |a|)`` for a 3-vector, scaled first by its largest component so that neither
    a subnormal vector (1e-320, whose square underflows) nor a huge one (1e308, whose square
    overflows) loses its direction; ``|a|`` may be 0.0 or inf, the direction is exact.
    Plain floats: it runs a few times per view, and numpy's per-call cost on 3 numbers
    would be most of a view file's reading time."""
    x, y, z = (float(c) for c in a)
    m = max(abs(x), abs(y), abs(z))
    if not 0.0 < m < math.inf:
        return np.zeros(3), m
    x, y, z = x / m, y / m, z / m             # division, not * (1/m): 1/1e-320 overflows
    s = math.sqrt(x * x + y * y + z * z)
    return np.array([x / s, y / s, z / s]), m * s


# The largest coordinate any reader lets into a scene (core.scene.formats refuses beyond it),
# and how far the normalizing transformation may carry such a point: the clipper and the
# projection then work with numbers far from overflow (products of a few of them stay finite).
MAX_WORLD = 1e30
MAX_REACH = 1e250

# The smallest |CW - PRP| the renderer can turn into a direction: the shading normalises the
# direction of projection with a plain Euclidean norm, whose square must not underflow.
MIN_DOP_LENGTH = float(np.sqrt(np.finfo(np.float64).tiny))


def load_problems(view: View) -> list[str]:
    """Why a reader must refuse ``view``: the reasons it cannot be drawn in either projection
    (the renderer's own rules, matrices included); empty when at least one projection can draw
    it. A view that only one projection refuses (F behind the eye in perspective) loads, and
    the frame drawn that way says why."""
    common = _problems(view, None)
    if common:
        return common
    perspective = _eye_problems(view)
    parallel: list[str] = []
    _factors_or_overflow(view, "parallel", parallel)
    if not parallel:
        return []                              # parallel draws it: it loads
    if not perspective:
        _factors_or_overflow(view, "perspective", perspective)
    return list(dict.fromkeys(perspective + parallel)) if perspective else []


def _problems(view: View, projection: str | None) -> list[str]:
    """The checks of pipeline.md that need no matrix, and those the renderer relies on."""
    if not np.all(np.isfinite(view.numbers)):
        return ["a number is NaN or infinite"]
    with np.errstate(all="ignore"):            # huge or tiny numbers are reported, not raised
        prp = np.array(view.prp, dtype=np.float64)
        u_min, u_max, v_min, v_max = view.window
        found = []
        n, vpn_len = unit3(view.vpn)           # a direction: its length does not matter
        up, vup_len = unit3(view.vup)
        if vpn_len == 0.0:
            found.append("VPN is zero")
        if vup_len == 0.0:
            found.append("VUP is zero")
        elif vpn_len > 0.0:
            across = cross3(up, n)
            if np.sqrt(across @ across) <= PARALLEL_TOLERANCE:
                found.append("VUP is parallel to VPN")
        dop = np.array([(u_min + u_max) / 2, (v_min + v_max) / 2, 0.0]) - prp
        dop_len = float(np.sqrt(dop @ dop))
    if prp[2] == 0.0:
        found.append("PRP lies on the view plane (PRP_n = 0), so the direction of projection "
                     "is parallel to the view plane")
    elif not dop_len >= MIN_DOP_LENGTH:
        found.append(f"the PRP is {unit3(dop)[1]:.3g} from the window's centre: too close to "
                     f"give a direction of projection in float64 (under {MIN_DOP_LENGTH:.3g})")
    if not u_max > u_min:
        found.append(f"the window is degenerate: u_max ({u_max:g}) <= u_min ({u_min:g})")
    if not v_max > v_min:
        found.append(f"the window is degenerate: v_max ({v_max:g}) <= v_min ({v_min:g})")
    if not view.back < view.front:
        found.append(f"B ({view.back:g}) is not behind F ({view.front:g})")
    if projection == "perspective":
        found += _eye_problems(view)
    return found


def _eye_problems(view: View) -> list[str]:
    """The check only perspective makes without a matrix: F in front of the eye."""
    if view.front < view.prp[2]:
        return []
    return [f"the front plane F = {view.front:g} is not in front of the eye "
            f"(PRP_n = {view.prp[2]:g})"]


def _factors_or_overflow(view: View, projection: str, found: list[str]) -> dict | None:
    """The chain's factors, or None after adding the reason they cannot be used to ``found``.

    Besides overflow, perspective needs -1 < z_min < 0 in float64: the perspective-to-parallel
    matrix (FvDFH eq. 6.48) divides by 1 + z_min, and the divide by W = -z needs the front
    plane off the eye. F and B that are equal to the last bits next to the eye's distance round
    z_min to -1 (or a far B rounds it to 0) although F > B.
    """
    build = _n_per if projection == "perspective" else _n_par
    with np.errstate(all="ignore"):            # overflow is detected below, not raised
        factors = build(view)
    n = factors["N_per" if projection == "perspective" else "N_par"]
    # N is the product of every factor: an inf in any of them leaves an inf or a NaN in N
    if not (np.isfinite(n).all() and np.isfinite(factors.get("z_min", 0.0))):
        found.append("the numbers are too large or too small: the normalizing transformation "
                     "overflows")
        return None
    with np.errstate(over="ignore"):
        reach = float(np.max(np.abs(n[:3, :3]).sum(axis=1) * MAX_WORLD + np.abs(n[:3, 3])))
    if not reach <= MAX_REACH:
        found.append(f"the normalizing transformation carries points of the scene's range "
                     f"(|x| <= {MAX_WORLD:g}) as far as {reach:.3g}, beyond {MAX_REACH:g}: the "
                     f"view's numbers are too large or its window too small to compute with")
        return None
    if projection == "perspective":
        z_min = float(factors["z_min"])
        if not -1.0 < z_min < 0.0:
            found.append(f"F ({view.front:.17g}) and B ({view.back:.17g}) are too close together "
                         f"(or too far apart) next to the eye's distance PRP_n = "
                         f"{view.prp[2]:.17g}: z_min = {z_min:.17g} rounds to "
                         f"{'-1' if z_min <= -1.0 else '0'}, and perspective needs -1 < z_min < 0")
            return None
    return factors


def check(view: View, projection: str | None = None) -> None:
    """Raise :class:`ViewError` naming the view and every reason it is invalid."""
    found = problems(view, projection)
    if found:
        raise ViewError(f"{view.label}: " + "; ".join(found))


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (np.cross's generality costs ~20 us a call)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def vrc_basis(view: View) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """u, v, n of the VRC: ``n = VPN/|VPN|``, ``u = VUP x n / |VUP x n|``, ``v = n x u``."""
    n = unit3(view.vpn)[0]                   # scaled: a subnormal or huge VPN keeps its direction
    u = unit3(cross3(unit3(view.vup)[0], n))[0]
    v = cross3(n, u)
    return u, v, n


def _common_factors(view: View) -> dict[str, np.ndarray]:
    """T(-VRP), R and SH_par, shared by both projections."""
    u, v, n = vrc_basis(view)
    u_min, u_max, v_min, v_max = view.window
    prp = np.asarray(view.prp, dtype=np.float64)
    cw = np.array([(u_min + u_max) / 2, (v_min + v_max) / 2, 0.0])
    dop = cw - prp
    return {
        "T_vrp": translate(*(-np.asarray(view.vrp, dtype=np.float64))),
        "R": rows_as_rotation(u, v, n),
        "SH_par": shear_xy(-dop[0] / dop[2], -dop[1] / dop[2]),
    }


def _validated(view: View, projection: str) -> dict[str, np.ndarray]:
    """Check the view and build its chain once; raise ViewError naming every problem."""
    found = _problems(view, projection)
    factors = None if found else _factors_or_overflow(view, projection, found)
    if found:
        raise ViewError(f"{view.label}: " + "; ".join(found))
    return factors


def n_par_factors(view: View, validate: bool = True) -> dict[str, np.ndarray]:
    """The parallel chain by name: T_vrp, R, SH_par, T_par, S_par and N_par (FvDFH 6.5.1)."""
    return _validated(view, "parallel") if validate else _n_par(view)


def _n_par(view: View) -> dict[str, np.ndarray]:
    u_min, u_max, v_min, v_max = view.window
    f = _common_factors(view)
    f["T_par"] = translate(-(u_max + u_min) / 2, -(v_max + v_min) / 2, -view.front)
    f["S_par"] = scale(2 / (u_max - u_min), 2 / (v_max - v_min), 1 / (view.front - view.back))
    f["N_par"] = f["S_par"] @ f["T_par"] @ f["SH_par"] @ f["R"] @ f["T_vrp"]
    return f


def n_per_factors(view: View, validate: bool = True) -> dict[str, np.ndarray]:
    """The perspective chain by name: T_vrp, R, T_prp, SH_par, S_per, N_per, and z_min.

    ``z_min`` is returned as a 0-d array beside the matrices (FvDFH 6.5.2).
    """
    return _validated(view, "perspective") if validate else _n_per(view)


def _n_per(view: View) -> dict[str, np.ndarray]:
    u_min, u_max, v_min, v_max = view.window
    f = _common_factors(view)
    f["T_prp"] = translate(*(-np.asarray(view.prp, dtype=np.float64)))
    vrp_z = -view.prp[2]                      # z of the VRP after T(-PRP) and the shear
    f["S_per"] = scale(2 * vrp_z / ((u_max - u_min) * (vrp_z + view.back)),
                       2 * vrp_z / ((v_max - v_min) * (vrp_z + view.back)),
                       -1 / (vrp_z + view.back))
    f["N_per"] = f["S_per"] @ f["SH_par"] @ f["T_prp"] @ f["R"] @ f["T_vrp"]
    f["z_min"] = np.array(-(vrp_z + view.front) / (vrp_z + view.back))
    return f


def normalizing_transform(view: View, projection: str) -> tuple[np.ndarray, float]:
    """``(N, z_min)``: N_per or N_par for ``projection``; z_min is 0 for parallel (unused).

    Raises :class:`ViewError` for an invalid view. (A renderer drawing the same view frame
    after frame keeps the answer in its :class:`core.context.RenderContext`.)
    """
    if projection == "perspective":
        f = n_per_factors(view)
        return f["N_per"], float(f["z_min"])
    if projection == "parallel":
        return n_par_factors(view)["N_par"], 0.0
    raise ValueError(f"projection must be one of {PROJECTIONS}, not {projection!r}")


class Eye(NamedTuple):
    """Where the viewer is, in world coordinates: ``point`` (perspective: the PRP) or
    ``direction`` (parallel: the unit vector towards the viewer, −DOP/|DOP|); the other is None."""

    point: np.ndarray | None
    direction: np.ndarray | None


def eye_from_view(view: View, projection: str) -> Eye:
    """The viewer of ``view`` in world coordinates (FvDFH 6.5: PRP and DOP are given in VRC).

    Perspective: the PRP, ``VRP + prp_u u + prp_v v + prp_n n``. Parallel: the direction
    opposite the DOP, ``DOP = CW − PRP`` with ``CW`` the centre of the window, turned into
    world coordinates by the VRC basis and normalised.
    """
    u, v, n = vrc_basis(view)
    prp = np.asarray(view.prp, dtype=np.float64)
    if projection == "perspective":
        return Eye(np.asarray(view.vrp, dtype=np.float64) + prp[0] * u + prp[1] * v + prp[2] * n,
                   None)
    if projection == "parallel":
        u_min, u_max, v_min, v_max = view.window
        dop = np.array([(u_min + u_max) / 2, (v_min + v_max) / 2, 0.0]) - prp
        toward_viewer = -(dop[0] * u + dop[1] * v + dop[2] * n)
        return Eye(None, toward_viewer / np.linalg.norm(toward_viewer))
    raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")


def pick_view(views: list, which):
    """``views[which]`` (counting round), or ``which`` itself when it is a camera (a
    :class:`View`: the window's user's, which replaces an animation's own)."""
    if isinstance(which, View):
        return which
    return views[which % len(views)]
