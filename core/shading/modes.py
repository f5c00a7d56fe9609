"""The built-in shading modes a user may choose, each one registration (core.registry).

A new mode is one module that registers its :class:`core.shading.registry.Shader` (a vertex
step and a pixel step) and one :func:`register_shading` line here naming that module, what
the plan computes for it and where it lights: the scene reader, ``RenderSettings``, the plan,
the command line's ``--shading`` and the window's Shading menu then offer it. This module
imports nothing heavy: the shaders' kernels load when a mode is first drawn.
"""

from core.registry import register_shading

register_shading("wireframe", None, label="Wireframe", key="W",
                 description="the edges, midpoint lines (no shader: the pipeline's lines)")
register_shading("flat", "core.shading.flat", label="Flat", key="1", normals="face",
                 lights="faces", description="one evaluation per planar polygon")
register_shading("gouraud", "core.shading.gouraud", label="Gouraud", key="2",
                 normals="vertex", lights="vertices",
                 description="the model at the vertices, intensities interpolated")
register_shading("phong", "core.shading.phong", label="Phong", key="3", normals="vertex",
                 lights="pixels", description="normals interpolated, the model at every pixel")
register_shading("depth", "core.shading.depth", label="Depth (colour map)",
                 description="unlit: colour from height or view depth alone")
