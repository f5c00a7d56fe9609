"""Solving B_i = E_i + ρ_i Σ_j B_j F_ij: progressive refinement and Gauss–Seidel.

Form factors come a row at a time from the shooting patch p to every element e,
``F(p → e)`` (:class:`Shooter`: the hemicube at the patch's centre, or ray casting to the
patch from every element's centre). By reciprocity the element gathers
``K_ep = F(p → e) A_p / A_e`` of the patch's radiosity. Point and directional lights of the
scene shoot first (:func:`direct_light`): ρ I f_att (N·L) where a shadow ray reaches the light,
the Phong model's diffuse term, so the same scene looks alike in both renderers.

- :class:`Progressive` (Cohen, Chen, Wallace, Greenberg 1988): repeatedly the patch with the
  most unshot energy ΔB_p A_p shoots it: each element gains ρ_e ΔB_p K_ep, each patch's unshot
  radiosity grows by its elements' gains (area-weighted). It stops when the unshot energy is
  below ``converge`` of what was there to shoot at the start, or after ``max_steps``. For
  display the *ambient term* ρ_e · R · (Σ ΔB_p A_p / Σ A_p), R = 1 / (1 − mean ρ), stands in
  for the light not yet shot.
- :func:`gauss_seidel` solves the same system, all rows at once, sweeping the elements in
  place until no radiosity moves by more than ``tolerance``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from core.jit import njit
from core.radiosity.mesh import Elements

from core.settings import FORM_FACTOR_METHODS, SOLVERS  # noqa: E402,F401  (listed there)
ROW_CACHE_BYTES = 256 << 20         # form-factor rows kept for patches that shoot again
MAX_GAUSS_SEIDEL = 40_000_000       # elements x patches of the full matrix


class Shooter:
    """Form-factor rows ``F(p → e)`` (E,) of the shooting patches, kept while memory allows."""

    def __init__(self, e: Elements, method: str = "hemicube", resolution: int = 128, bvh=None):
        if method not in FORM_FACTOR_METHODS:
            raise ValueError(f"form factors must be one of {', '.join(FORM_FACTOR_METHODS)}, "
                             f"not {method!r}")
        self.e, self.method, self.resolution = e, method, int(resolution)
        self.bvh = bvh
        self.rows: dict[int, np.ndarray] = {}
        self.computed = 0                        # rows computed (not taken from the cache)
        self.seconds = 0.0
        if method == "hemicube":
            self.positions = e.corners.reshape(-1, 3)
            self.triangles = np.arange(3 * len(e), dtype=np.int64).reshape(-1, 3)

    def row(self, p: int) -> np.ndarray:
        if p in self.rows:
            return self.rows[p]
        start = time.perf_counter()
        row = self._hemicube(p) if self.method == "hemicube" else self._raycast(p)
        self.seconds += time.perf_counter() - start
        self.computed += 1
        if (len(self.rows) + 1) * row.nbytes <= ROW_CACHE_BYTES:
            self.rows[p] = row
        return row

    def _hemicube(self, p: int) -> np.ndarray:
        from core.radiosity.hemicube import form_factors
        e = self.e
        point, normal = e.patch_centre[p], e.patch_normal[p]
        # Back faces of two-sided pairs are culled (their twin, coplanar, receives); a
        # one-sided element seen from behind still blocks the view but receives nothing.
        facing = np.einsum("ij,ij->i", e.centre - point, e.normal) < 0.0
        drawn = np.flatnonzero(facing | ~e.two_sided)
        f = np.zeros(len(e))
        f[drawn] = form_factors(self.positions, self.triangles[drawn], point, normal,
                                self.resolution, e.scale)
        f[~facing] = 0.0
        return f

    def _raycast(self, p: int) -> np.ndarray:
        from core.radiosity.raycast import factors_to_patch
        e = self.e
        to_patch = factors_to_patch(self.bvh, e.centre, e.normal, e.patch_corners[p],
                                    e.patch_normal[p], e.scale)
        return to_patch * e.area / e.patch_area[p]


def scene_bvh(scene):
    """The ray tracer's BVH over every triangle of the scene (shadow rays, ray-cast factors)."""
    from core.raytrace.bvh import build
    positions = [m.positions for m in scene.meshes if len(m.triangles)]
    offsets = np.cumsum([0] + [len(p) for p in positions])
    triangles = [m.triangles + offsets[i]
                 for i, m in enumerate([m for m in scene.meshes if len(m.triangles)])]
    return build(np.concatenate(positions), np.concatenate(triangles))[0]


def direct_light(e: Elements, lights, bvh) -> np.ndarray:
    """(E, 3) radiosity each element reflects straight from the point and directional lights:
    ρ I f_att (N·L) where the shadow ray from its centre reaches the light."""
    from core.raytrace.bvh import occluded_rays
    out = np.zeros((len(e), 3))
    offset = 1e-7 * e.scale
    for light in lights:
        if light.position is not None:
            to_light = np.asarray(light.position, float) - e.centre
            distance = np.linalg.norm(to_light, axis=1)
            c1, c2, c3 = light.attenuation
            f_att = np.minimum(1.0, 1.0 / np.maximum(c1 + c2 * distance + c3 * distance ** 2,
                                                     1e-300))
            t_max = 1.0 - 1e-9
        else:
            to_light = np.repeat(np.asarray(light.direction, float)[None], len(e), axis=0)
            distance = np.ones(len(e))
            f_att, t_max = np.ones(len(e)), np.inf
        cos = np.einsum("ij,ij->i", to_light, e.normal) / np.maximum(distance, 1e-300)
        lit = cos > 0.0
        if lit.any():
            origins = e.centre[lit] + offset * e.normal[lit]
            blocked = occluded_rays(bvh, origins, to_light[lit], 1e-9, t_max)
            gain = np.where(blocked, 0.0, f_att[lit] * cos[lit])
            out[lit] += e.rho[lit] * np.asarray(light.intensity, float)[None] * gain[:, None]
    return out


@dataclass
class Progressive:
    """Progressive refinement, a shot at a time (:meth:`step`); ``radiosity`` (E, 3) so far."""

    e: Elements
    shooter: Shooter
    source: np.ndarray                      # (E, 3) emission + direct light
    radiosity: np.ndarray = field(init=False)
    unshot: np.ndarray = field(init=False)  # (P, 3)
    steps: int = 0
    start_energy: float = field(init=False)

    def __post_init__(self) -> None:
        e = self.e
        self.radiosity = self.source.copy()
        self.unshot = np.zeros((e.patches, 3))
        np.add.at(self.unshot, e.patch, self.source * e.area[:, None])
        self.unshot /= e.patch_area[:, None]
        self.start_energy = float(self._energy().sum())

    def _energy(self) -> np.ndarray:
        return self.unshot.sum(axis=1) * self.e.patch_area

    def unshot_fraction(self) -> float:
        if self.start_energy <= 0.0:
            return 0.0
        return float(self._energy().sum()) / self.start_energy

    def step(self) -> bool:
        """Shoot once from the patch with the most unshot energy; False when none is left."""
        energy = self._energy()
        p = int(np.argmax(energy))
        if energy[p] <= 0.0:
            return False
        e = self.e
        shot = self.unshot[p].copy()
        self.unshot[p] = 0.0
        k = self.shooter.row(p) * (e.patch_area[p] / e.area)      # K_ep, reciprocity
        gained = e.rho * shot[None] * k[:, None]                   # (E, 3)
        self.radiosity += gained
        share = e.area / e.patch_area[e.patch]                     # element's part of its patch
        for c in range(3):
            self.unshot[:, c] += np.bincount(e.patch, gained[:, c] * share, e.patches)
        self.steps += 1
        return True

    def run(self, converge: float = 0.01, max_steps: int = 100_000, callback=None) -> None:
        while self.steps < max_steps and self.unshot_fraction() > converge:
            if not self.step():
                break
            if callback is not None and callback(self) is False:
                break

    def ambient(self) -> np.ndarray:
        """(E, 3): ρ_e R ΔB̄, the light not yet shot, spread evenly (for display only)."""
        e = self.e
        total = e.patch_area.sum()
        mean_unshot = (self.unshot * e.patch_area[:, None]).sum(axis=0) / total
        mean_rho = (e.rho * e.area[:, None]).sum(axis=0) / e.area.sum()
        return e.rho * (mean_unshot / (1.0 - mean_rho))[None]


def gather_matrix(e: Elements, shooter: Shooter) -> np.ndarray:
    """K (E, P): ``K_ep = F(p → e) A_p / A_e``, every row of every patch."""
    if len(e) * e.patches > MAX_GAUSS_SEIDEL:
        raise ValueError(f"Gauss-Seidel holds the whole matrix: {len(e)} elements x "
                         f"{e.patches} patches is over {MAX_GAUSS_SEIDEL:,}; use the progressive "
                         "solver or fewer elements")
    k = np.empty((len(e), e.patches))
    for p in range(e.patches):
        k[:, p] = shooter.row(p) * (e.patch_area[p] / e.area)
    return k


@njit(cache=True)
def _gauss_seidel(k, rho, source, area, patch, patch_area, b, tolerance, max_sweeps):
    """Sweep B_e = S_e + ρ_e Σ_p K_ep B_p in place; B_p the area mean of the patch's elements."""
    n_e, n_p = k.shape
    bp = np.zeros((n_p, 3))
    for i in range(n_e):
        for c in range(3):
            bp[patch[i], c] += b[i, c] * area[i] / patch_area[patch[i]]
    for sweep in range(max_sweeps):
        change = 0.0
        for i in range(n_e):
            for c in range(3):
                gathered = 0.0
                for p in range(n_p):
                    gathered += k[i, p] * bp[p, c]
                new = source[i, c] + rho[i, c] * gathered
                delta = new - b[i, c]
                bp[patch[i], c] += delta * area[i] / patch_area[patch[i]]
                b[i, c] = new
                change = max(change, abs(delta))
        if change <= tolerance:
            return sweep + 1
    return max_sweeps


def gauss_seidel(e: Elements, shooter: Shooter, source: np.ndarray, tolerance: float = 1e-10,
                 max_sweeps: int = 10_000) -> tuple[np.ndarray, int]:
    """``(radiosity (E, 3), sweeps)`` of the full system, from B = S."""
    k = gather_matrix(e, shooter)
    b = source.copy()
    sweeps = _gauss_seidel(k, e.rho, source, e.area, e.patch, e.patch_area, b, tolerance,
                           max_sweeps)
    return b, sweeps
