"""The one seam between the kernels and the lighting models: generated from the registry.

Every kernel that lights a point calls :func:`light_point` (the signature of
:func:`core.shading.illumination.phong_point`); the path tracer calls :func:`glossy` and
:func:`sample_glossy`; the inspectors call :func:`lighting_terms`. Each reads the surface
row's ``MODEL`` column and calls that model's function of the same role.

numba compiles a call to a known function, not to a function chosen at run time, so the
dispatch is written out when this module is imported, one branch per registered model
(:func:`dispatch_source` prints it). With Phong and Cook–Torrance registered it reads::

    def light_point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway):
        model = surfaces[s, MODEL]
        if model == 1:
            return cook_torrance_point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway)
        return phong_point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway)

Model 0 (Phong) is the last, unconditional branch: a row whose number names no model is lit
by the course's model. The branches are inlined (``inline="always"``), as ``phong_point``
always was, so a kernel's Phong pixels run the same instructions as before plus one compare
per point. The compiled kernels carry this code; ``core.jit`` stamps them with the code they
reach (this generated source, then each model's kernels), so a model added or removed
recompiles them.
"""

from __future__ import annotations

import linecache
import re

import numba
import numpy as np

from core.jit import njit, reuse_plain_overloads
from core.shading.illumination import LIGHT_COLUMNS, MODEL
from core.shading.models import lighting_models

# role: (the seam's name, its arguments, where a call finds the model's number)
ROLES = {
    "point": ("light_point", "px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway",
              "surfaces[s, MODEL]"),
    "glossy": ("glossy", "m, at, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, ps",
               "m[at + MODEL]"),
    "sample_glossy": ("sample_glossy", "m, at, nx, ny, nz, wox, woy, woz, u1, u2",
                      "m[at + MODEL]"),
}
GENERATED = "<core.shading.models.dispatch: generated>"


def _identifier(name: str) -> str:
    return re.sub(r"\W", "_", name)


def dispatch_source(names: tuple[str, ...]) -> str:
    """The Python source of the seams for the models ``names`` (model i is ``names[i]``)."""
    out = []
    for role, (seam, args, number) in ROLES.items():
        out += _seam_source(names, role, seam, args, number, "")
        if role == "point":
            out += _seam_source(names, role, CALLING, args, number, "_call")
    return "\n".join(out)


def _seam_source(names, role, seam, args, number, suffix) -> list[str]:
    out = [f"def {seam}({args}):", f"    model = {number}"]
    for i, name in enumerate(names[1:], 1):
        out += [f"    if model == {i}:",
                f"        return {_identifier(name)}_{role}{suffix}({args})"]
    return out + [f"    return {_identifier(names[0])}_{role}({args})", ""]


def _build() -> dict:
    models = lighting_models()
    source = dispatch_source(tuple(m.name for m in models))
    scope = {"MODEL": MODEL}
    for k, m in enumerate(models):
        module = m.kernels()
        for role in ROLES:
            scope[f"{_identifier(m.name)}_{role}"] = getattr(module, role)
        if k:       # the calling seam's: the kernel not inlined, compiled once and linked
            # into each kernel that calls it (no cache of its own: only a kernel being
            # compiled needs it)
            scope[f"{_identifier(m.name)}_point_call"] = reuse_plain_overloads(
                numba.njit(module.point.py_func))
    linecache.cache[GENERATED] = (len(source), None, source.splitlines(True), GENERATED)
    exec(compile(source, GENERATED, "exec"), scope)
    # Not cached on their own (no file behind them): they are inlined into cached kernels.
    seams = [seam for seam, _, _ in ROLES.values()] + [CALLING]
    return {seam: numba.njit(inline="always")(scope[seam]) for seam in seams}


# light_point with the models after the first (Phong) called, not inlined. The z-buffer's
# pixel and vertex kernels light every pixel of an interactive frame through light_point,
# every model inlined (a call costs Cook-Torrance's pixels 15 % at 800 x 800). The ray
# tracer, the ray caster and the ray marcher light a point after far more work each (shadow
# rays, six fetches for a gradient) and call the others: each such kernel then carries one
# call instead of a copy of each model, 19 s of the warm-up's 166 s of compiling.
CALLING = "light_point_calling"
_SEAMS = _build()
light_point = _SEAMS["light_point"]
light_point_calling = _SEAMS[CALLING]
glossy = _SEAMS["glossy"]
sample_glossy = _SEAMS["sample_glossy"]


def lighting_terms(p, n, s, surfaces, lights, ambient, eye, halfway, shadow=None) -> dict:
    """The model of surface row ``s`` term by term (the model module's ``terms``), with its
    name under ``"model"``."""
    models = lighting_models()
    number = int(surfaces[s, MODEL])
    entry = models[number] if 0 <= number < len(models) else models[0]
    terms = entry.kernels().terms(p, n, s, surfaces, lights, ambient, eye, halfway, shadow)
    return {"model": entry.name, "model label": entry.label, **terms}


def illuminate(points: np.ndarray, normals: np.ndarray, surface: np.ndarray,
               surfaces: np.ndarray, lights: np.ndarray, ambient: np.ndarray,
               eye: np.ndarray, halfway: bool) -> np.ndarray:
    """:func:`core.shading.illumination.illuminate` with each point lit by its row's lighting
    model: ``(N, 3)`` RGB in [0, 1]."""
    p = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    out = np.empty((len(p), 3))
    _illuminate_points(p, np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 3),
                       np.ascontiguousarray(surface, dtype=np.int64).reshape(-1),
                       np.ascontiguousarray(surfaces, dtype=np.float64),
                       np.ascontiguousarray(lights, dtype=np.float64).reshape(-1, LIGHT_COLUMNS),
                       np.ascontiguousarray(ambient, dtype=np.float64),
                       np.ascontiguousarray(eye, dtype=np.float64), bool(halfway), out)
    return out


@njit(cache=True)
def _illuminate_points(points, normals, surface, surfaces, lights, ambient, eye, halfway, out):
    for i in range(points.shape[0]):
        r, g, b = light_point(points[i, 0], points[i, 1], points[i, 2], normals[i, 0],
                              normals[i, 1], normals[i, 2], surface[i], surfaces, lights,
                              ambient, eye, halfway)
        out[i, 0], out[i, 1], out[i, 2] = r, g, b
