"""The z-buffer renderer (``zbuffer``): FvDFH's viewing pipeline, lines and triangles.

- :mod:`~core.renderers.zbuffer.draw`: ``draw``, the registered renderer, and its stages
  (``draw_lines``, ``draw_triangles``), which the other rasterizing renderers reuse;
- :mod:`~core.renderers.zbuffer.inspect`: the pixel inspector's record and the buffer views;
- :mod:`~core.renderers.zbuffer.texture`: the record of a textured pixel.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
