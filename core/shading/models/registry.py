"""Lighting models (BRDFs) by name: what a material's ``model`` key chooses.

A lighting model is one module (a *model module*) and one :func:`register_lighting_model`
call (in :mod:`core.shading.models`). The module defines, by these names:

- ``point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway) -> (r, g, b)``
  (numba): the local model at a world point for surface row ``s``, clamped to [0, 1], the
  signature of :func:`core.shading.illumination.phong_point`: the z-buffer's flat, Gouraud
  and Phong steps, the textured shader, the ray tracer and the ray caster call it;
- ``glossy(m, at, nx, ny, nz, wox, woy, woz, wix, wiy, wiz, ps) -> (fr, fg, fb, pdf)`` and
  ``sample_glossy(m, at, nx, ny, nz, wox, woy, woz, u1, u2) -> (wx, wy, wz)`` (numba): the
  path tracer's glossy lobe, its BRDF and ``ps`` times the solid-angle pdf of sampling
  ``ω_i`` from it, read from a surface row stored in ``m`` at column ``at``;
- ``terms(p, n, s, surfaces, lights, ambient, eye, halfway, shadow=None) -> dict``
  (Python): the same model term by term, for the pixel inspector.

The kernels reach the models through one seam, :mod:`core.shading.models.dispatch`: numba
compiles calls statically, so the dispatch functions are generated from this registry when
that module is imported (one branch per model, on the row's ``MODEL`` column).

A model's *parameters* (its material keys beyond the Phong terms, e.g. a roughness) are
declared in its registration, so that the scene reader checks them without importing numba;
:func:`pack_model` writes them into the surface row's ``PARAMETERS`` columns in order.
Models are numbered in the order they register; ``phong`` (FvDFH 16.2) is model 0, the
default, and every material without a ``model`` key is lit by it. The models are a
:class:`core.registries.Registry` (the one shape of every registry), in that order.
"""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass

from core.registries import Registry

PARAMETER_COLUMNS = 4            # the surface row's room for a model's parameters
DEFAULT_MODEL = "phong"


@dataclass(frozen=True)
class Parameter:
    """A material key of a model: a number (``size`` 1) or an RGB triple (``size`` 3) in
    ``[low, high]``, ``default`` when the material does not give it."""

    name: str
    default: float | tuple[float, ...]
    low: float
    high: float
    size: int = 1
    help: str = ""


@dataclass(frozen=True)
class LightingModel:
    name: str
    module: str                  # "package.module": point, glossy, sample_glossy, terms
    label: str = ""
    parameters: tuple[Parameter, ...] = ()
    description: str = ""

    def kernels(self):
        """The model module (imported now: numba with it)."""
        return importlib.import_module(self.module)


MODELS = Registry("lighting model")


def register_lighting_model(name: str, module: str, label: str = "",
                            parameters: tuple[Parameter, ...] = (),
                            description: str = "") -> LightingModel:
    """Make ``name`` a value of a material's ``model`` key (registered again under the same
    name, it replaces the entry and keeps its number)."""
    width = sum(p.size for p in parameters)
    if width > PARAMETER_COLUMNS:
        raise ValueError(f"lighting model {name!r}: its parameters need {width} columns, "
                         f"a surface row has {PARAMETER_COLUMNS}")
    return MODELS.register(LightingModel(name, module, label or name, tuple(parameters),
                                         description))


def unregister_lighting_model(name: str) -> None:
    MODELS.unregister(name)


def lighting_model_names() -> tuple[str, ...]:
    return MODELS.names()


def lighting_models() -> tuple[LightingModel, ...]:
    return MODELS.entries()


def lighting_model(name: str) -> LightingModel:
    return MODELS.get(name)


def model_id(name: str) -> int:
    """The model's number: its row's ``MODEL`` column, the dispatch's branch."""
    lighting_model(name)
    return MODELS.names().index(name)


def model_of(material) -> tuple[str, dict]:
    """``(model name, parameters)`` of a :class:`core.scene.Material`: what its ``model`` key
    chose (``Material.extra["lighting"]``), else Phong with no parameters."""
    chosen = getattr(material, "extra", {}).get("lighting")
    return (chosen["model"], chosen["parameters"]) if chosen else (DEFAULT_MODEL, {})


def pack_model(material) -> tuple[int, list[float]]:
    """The row's ``MODEL`` number and its ``PARAMETER_COLUMNS`` parameter values."""
    name, given = model_of(material)
    values: list[float] = []
    for p in lighting_model(name).parameters:
        value = given.get(p.name, p.default)
        values += list(value) if p.size > 1 else [float(value)]
    return model_id(name), values + [0.0] * (PARAMETER_COLUMNS - len(values))


def with_model(material, name: str, parameters: dict | None = None):
    """A copy of ``material`` lit by model ``name`` (its parameters: ``parameters``, else
    those the material gave for that model, else the defaults)."""
    lighting_model(name)
    current, given = model_of(material)
    if name == DEFAULT_MODEL and not parameters:
        extra = {k: v for k, v in material.extra.items() if k != "lighting"}
    else:
        kept = given if current == name else {}
        extra = {**material.extra, "lighting": {"model": name,
                                                "parameters": dict(parameters or kept)}}
    return dataclasses.replace(material, extra=extra)


def scene_lit_by(scene, name: str):
    """A copy of ``scene`` whose every material (meshes and analytic primitives) is lit by
    model ``name``: the command line's and the window's override of what the materials
    chose. Arrays are shared; a primitive's meshes still name their (copied) primitive."""
    lighting_model(name)
    primitives = {id(p): dataclasses.replace(p, material=with_model(p.material, name))
                  for p in scene.primitives}
    for mesh in scene.meshes:            # a tessellated primitive that is not in the list
        prim = mesh.tessellates
        if prim is not None and id(prim) not in primitives:
            primitives[id(prim)] = dataclasses.replace(prim, material=with_model(prim.material,
                                                                                 name))
    meshes = [dataclasses.replace(m, material=with_model(m.material, name),
                                  tessellates=primitives.get(id(m.tessellates)))
              for m in scene.meshes]
    return dataclasses.replace(scene, meshes=meshes,
                               primitives=[primitives[id(p)] for p in scene.primitives])
