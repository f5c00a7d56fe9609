"""A toy renderer and a toy shading mode, both registered by this one module.

``register()`` is all a newcomer's renderer and mode would need (their entries); the
registry consumers' tests call it and then find the two in every place that offers a
renderer or a shading mode. The toy renderer draws with the z-buffer; the toy mode lights
every pixel with Phong's shader under its own name.
"""

from __future__ import annotations

from core.registry import register_shading, unregister_shading
from core.renderers import register_renderer, unregister_renderer
from core.shading.registry import get_shader, register_shader

RENDERER, MODE = "toy", "toy-mode"


def register() -> None:
    register_shader(get_shader("phong")._replace(name=MODE))
    register_shading(MODE, __name__, label="Toy mode", key="9", normals="vertex",
                     lights="pixels", description="Phong's shader under another name")
    register_renderer(RENDERER, "core.renderers.zbuffer.draw:draw",
                      inspector="core.renderers.zbuffer.inspect:inspect_pixel",
                      description="the z-buffer under another name", label="Toy", key="X",
                      title="toy drawn", shaders=True, bench="painters",
                      warm_up=(("toy frame", "closed", {"shading": "flat"}),),
                      quick={"samples": 1})


def unregister() -> None:
    unregister_shading(MODE)
    unregister_renderer(RENDERER)
