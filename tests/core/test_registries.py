"""Every registry is one shape: a :class:`core.registries.Registry` of entries by name.

For each kind (renderers, shading modes, shaders, lighting models, scene and material keys,
mesh file types) a toy entry is registered through the kind's own public function, found in
its listing and by its lookup, refused by name when unknown (the error names the choices, in
the kind's words), and gone once unregistered.
"""

from __future__ import annotations

import numpy as np
import pytest

import core.renderers  # noqa: F401  (the built-in renderers register on import)
import core.shading.models  # noqa: F401  (the built-in lighting models)
from core.registries import Registry, load
from core.registry import (RENDERERS, SHADINGS, get_renderer, get_shading, names_that,
                           register_renderer, register_shading, renderer_names, renderers,
                           shading_modes, shading_names, unregister_renderer, unregister_shading)
from core.scene.formats import keys
from core.scene.formats.mesh.read import MESH_EXTENSIONS, MESH_FORMATS, MeshFormat, read_mesh
from core.shading.models.registry import (MODELS, lighting_model, lighting_model_names,
                                          lighting_models, model_id, register_lighting_model,
                                          unregister_lighting_model)
from core.shading.registry import (SHADERS, Shader, get_shader, register_shader, shader_names,
                                   unregister_shader)

ALL = {"renderers": RENDERERS, "shading modes": SHADINGS, "shaders": SHADERS,
       "lighting models": MODELS, "scene keys": keys.SCENE_KEYS,
       "material keys": keys.MATERIAL_KEYS, "scene contents": keys.CONTENTS,
       "mesh file types": MESH_FORMATS}


def _refused(lookup, name: str, words: str, choices) -> str:
    with pytest.raises(ValueError) as error:
        lookup(name)
    message = str(error.value)
    assert message == f"{words} must be one of {', '.join(choices)}, not {name!r}"
    return message


# -- the one class ------------------------------------------------------------------------
def test_every_kind_holds_its_entries_in_the_one_registry_class():
    for kind, registry in ALL.items():
        assert type(registry) is Registry, kind


def test_every_entry_has_a_name_a_label_and_a_description():
    for kind, registry in ALL.items():
        entries = registry.entries()
        assert entries, kind
        for entry in entries:
            assert entry.name in registry.names(), (kind, entry)
            assert isinstance(entry.label, str) and entry.label, (kind, entry.name)
            assert isinstance(entry.description, str), (kind, entry.name)


def test_the_registries_module_imports_nothing_of_the_core():
    from tests.test_layers import import_graph
    assert {m for m in import_graph()["core.registries"] if m.startswith("core")} == set()


# -- the generic registry -----------------------------------------------------------------
class Toy:
    def __init__(self, name: str, label: str = "", fast: bool = False):
        self.name, self.label, self.description, self.fast = name, label or name, "", fast


def test_a_registry_keeps_the_order_of_registration_and_replaces_in_place():
    registry = Registry("toy")
    for name in ("a", "b", "c"):
        registry.register(Toy(name))
    replaced = registry.register(Toy("a", label="A again", fast=True))
    assert registry.names() == ("a", "b", "c")
    assert registry.get("a") is replaced and registry.get("a").label == "A again"
    assert registry.names_that("fast") == ("a",)
    registry.unregister("b")
    registry.unregister("never there")               # no error: nothing to remove
    assert registry.names() == ("a", "c") and "b" not in registry
    _refused(registry.get, "b", "toy", ("a", "c"))


def test_a_loader_registers_the_built_ins_on_the_first_lookup_and_for_a_listing():
    calls = []

    def loader(name):
        calls.append(name)
        if name in ("lazy", None):
            registry.register(Toy("lazy"))
        if name is None:
            registry.register(Toy("other"))

    registry = Registry("toy", loader)
    assert calls == []                                 # nothing loaded before a lookup
    assert registry.get("lazy").name == "lazy"
    assert calls == ["lazy"]                           # its own module only
    _refused(registry.get, "missing", "toy", ("lazy", "other"))
    assert calls == ["lazy", "missing", None]          # then every built-in, for the error
    assert registry.names() == ("lazy", "other") and calls[-1] is None


def test_load_imports_a_named_function_and_passes_a_function_through():
    assert load("core.registries:load") is load
    assert load(len) is len
    with pytest.raises(AttributeError):
        load("core.registries:no_such_function")


# -- each kind, through its public functions ------------------------------------------------
def test_renderers():
    entry = register_renderer("toy-renderer", "core.renderers.zbuffer.draw:draw",
                              description="a toy", caustics=True)
    try:
        assert "toy-renderer" in renderer_names() and entry in renderers()
        assert get_renderer("toy-renderer") is entry and entry.label == "toy-renderer"
        assert "toy-renderer" in names_that("caustics")
        assert entry.function() is load("core.renderers.zbuffer.draw:draw")
        _refused(get_renderer, "nope", "renderer", renderer_names())
    finally:
        unregister_renderer("toy-renderer")
    assert "toy-renderer" not in renderer_names()
    with pytest.raises(ValueError, match="renderer must be one of .*zbuffer"):
        get_renderer("toy-renderer")


def test_shading_modes():
    mode = register_shading("toy-shading", None, description="unlit lines")
    try:
        assert "flat" in shading_names()                # the built-ins, loaded on lookup
        assert "toy-shading" in shading_names() and mode in shading_modes()
        assert get_shading("toy-shading") is mode and mode.label == "toy-shading"
        _refused(get_shading, "nope", "shading", shading_names())
    finally:
        unregister_shading("toy-shading")
    assert "toy-shading" not in shading_names()
    with pytest.raises(ValueError, match="shading must be one of wireframe, flat"):
        get_shading("toy-shading")


def test_shaders():
    def vertex(*args):
        return None

    register_shader(Shader("toy-shader", vertex, vertex, description="draws nothing"))
    try:
        shader = get_shader("toy-shader")
        assert shader.vertex is vertex and shader.label == "toy-shader"
        assert "toy-shader" in shader_names() and "phong" in shader_names()
        _refused(get_shader, "nope", "shading", shader_names())
    finally:
        unregister_shader("toy-shader")
    assert "toy-shader" not in shader_names()
    with pytest.raises(ValueError, match="shading must be one of"):
        get_shader("toy-shader")


def test_lighting_models():
    before = lighting_model_names()
    model = register_lighting_model("toy-model", "core.shading.models.phong",
                                    description="Phong again")
    try:
        assert lighting_model_names() == before + ("toy-model",)
        assert lighting_model("toy-model") is model and model in lighting_models()
        assert model.label == "toy-model" and model_id("toy-model") == len(before)
        _refused(lighting_model, "nope", "lighting model", lighting_model_names())
    finally:
        unregister_lighting_model("toy-model")
    assert lighting_model_names() == before
    with pytest.raises(ValueError, match="lighting model must be one of phong"):
        lighting_model("toy-model")


def test_scene_keys():
    def read(reader, doc, scene):
        scene.seen = doc.get("toy_key")

    class Scene:
        seen = None

    keys.register_scene_keys("toy keys", ("toy_key",), read, arrays=("toy_key",))
    try:
        entry = keys.SCENE_KEYS.get("toy keys")
        assert entry in keys.scene_readers() and entry.label == "toy keys"
        assert "toy_key" in keys.top_keys() and "toy_key" in keys.table_arrays()
        scene = Scene()
        entry.read(None, {"toy_key": 3}, scene)
        assert scene.seen == 3
        with pytest.raises(ValueError, match="read elsewhere already"):
            keys.register_scene_keys("another", ("toy_key",), read)
        _refused(keys.SCENE_KEYS.get, "nope", "scene keys", keys.SCENE_KEYS.names())
    finally:
        keys.SCENE_KEYS.unregister("toy keys")
    assert "toy keys" not in keys.SCENE_KEYS.names() and "toy_key" not in keys.top_keys()


def test_material_keys_named_lazily():
    keys.register_material_keys("toy material", ("toy_gloss",),
                                "tests.core.test_registries:_read_material")
    try:
        entry = keys.MATERIAL_KEYS.get("toy material")
        assert entry in keys.material_readers() and "toy_gloss" in keys.material_keys()
        assert entry.read(None, {"toy_gloss": 2}, (), "m") == ("m", 2)
        _refused(keys.MATERIAL_KEYS.get, "nope", "material keys", keys.MATERIAL_KEYS.names())
    finally:
        keys.MATERIAL_KEYS.unregister("toy material")
    assert "toy_gloss" not in keys.material_keys()


def _read_material(reader, table, path, material):
    return material, table["toy_gloss"]


def test_scene_contents():
    def bounds(scene):
        return np.zeros((1, 3))

    keys.register_scene_contents("toy_volume", bounds)
    try:
        assert keys.scene_contents()["toy_volume"] is bounds
        assert keys.CONTENTS.get("toy_volume").label == "toy_volume"
    finally:
        keys.CONTENTS.unregister("toy_volume")
    assert "toy_volume" not in keys.scene_contents()


def _toy_check(data, file, budget):
    """A file of three numbers a line, every three lines a triangle, read without trimesh."""
    rows = np.array([line.split() for line in data.decode().splitlines()], dtype=np.float64)
    return data, {"vertices": rows, "faces": np.arange(len(rows)).reshape(-1, 3)}


def test_mesh_file_types():
    assert MESH_EXTENSIONS == MESH_FORMATS.names() == (".obj", ".ply", ".off", ".stl")
    MESH_FORMATS.register(MeshFormat(".toy", "tests.core.test_registries:_toy_check", "Toy"))
    try:
        assert ".toy" in MESH_FORMATS.names() and MESH_FORMATS.get(".toy").label == "Toy"
        mesh = read_mesh(b"0 0 0\n1 0 0\n0 1 0\n", "tri.toy", ".toy")
        assert mesh.triangles.tolist() == [[0, 1, 2]] and mesh.positions[1].tolist() == [1, 0, 0]
        _refused(MESH_FORMATS.get, ".nope", "mesh file type", MESH_FORMATS.names())
    finally:
        MESH_FORMATS.unregister(".toy")
    assert ".toy" not in MESH_FORMATS.names()
    with pytest.raises(Exception, match=r"not a mesh file type we read \(.obj, .ply, .off, .stl\)"):
        read_mesh(b"0 0 0\n", "tri.toy", ".toy")
