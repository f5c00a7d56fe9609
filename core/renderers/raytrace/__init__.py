"""The Whitted ray tracer (``raytrace``): shadows, mirrors and glass, on the BVH of
:mod:`core.raytrace` (the kernels: ``whitted``, ``bvh``, ``intersect``, ``optics``,
``geometry``, ``adaptive``).

- :mod:`~core.renderers.raytrace.draw`: ``draw``, the registered renderer, and the frame's
  pieces others reuse (``prepare``, ``primary``, ``trace_tile``, ``render_image``);
- :mod:`~core.renderers.raytrace.inspect`: the pixel's ray tree and the buffer views;
- :mod:`~core.renderers.raytrace.options`: its options (depth limit, ε, shadows, Fresnel, ...);
- :mod:`~core.renderers.raytrace.progressive`: the window's frames, coarse, then tile by tile.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
