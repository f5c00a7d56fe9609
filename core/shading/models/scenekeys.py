"""A material's lighting-model keys in a scene file (registered with the scene reader).

::

    material = { kd = 0.5, ks = 0.5, model = "cook-torrance", roughness = 0.25, f0 = [0.95, 0.64, 0.54] }

``model`` names a registered lighting model (:mod:`core.shading.models`; ``"phong"`` when
absent); the other keys are the parameters that model declares (a number, or for an RGB
parameter a number or a list of three), each checked against its range. A parameter without
``model``, or of another model than the one named, is an error that says which model has it.
"""

from __future__ import annotations

import dataclasses
from core.scene.formats.keys import register_material_keys
from core.shading.models import lighting_model, lighting_model_names, lighting_models


def parameter_keys() -> tuple[str, ...]:
    return tuple(dict.fromkeys(p.name for m in lighting_models() for p in m.parameters))


def _owners(key: str) -> str:
    return ", ".join(m.name for m in lighting_models() if any(p.name == key for p in m.parameters))


def _value(reader, parameter, value, path):
    if parameter.size == 1 or not isinstance(value, list):
        number = reader.number(value, path, parameter.low, parameter.high)
        return number if parameter.size == 1 else (number,) * parameter.size
    return reader.vector(value, path, parameter.size, parameter.low, parameter.high)


def read_lighting(reader, table: dict, path: tuple, material):
    """The material with ``Material.extra["lighting"]`` set from its ``model`` keys."""
    given = [k for k in parameter_keys() if k in table]
    if "model" not in table:
        if given:
            raise reader.fail(path + (given[0],), f"is a parameter of the {_owners(given[0])} "
                                                  "lighting model: name it with model = \"…\"")
        return material
    name = reader.choice(table["model"], path + ("model",), lighting_model_names())
    own = {p.name: p for p in lighting_model(name).parameters}
    parameters = {}
    for key in given:
        if key not in own:
            raise reader.fail(path + (key,), f"is not a parameter of the {name} lighting model "
                                             f"(it is of {_owners(key)})")
        parameters[key] = _value(reader, own[key], table[key], path + (key,))
    return dataclasses.replace(material, extra={**material.extra, "lighting": {
        "model": name, "parameters": parameters}})


register_material_keys("lighting models", ("model",) + parameter_keys(), read_lighting)
