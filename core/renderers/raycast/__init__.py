"""The exact ray caster (``raycast``): the analytic surfaces of ``scene.primitives``, the
reference the tessellated renderers are measured against.

- :mod:`~core.renderers.raycast.draw`: the compiled intersections, ``render_reference`` and
  ``draw``, the registered renderer;
- :mod:`~core.renderers.raycast.inspect`: one pixel's samples, rays, hits and Phong terms.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
