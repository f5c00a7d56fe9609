"""The radiosity renderer (``radiosity``): the scene's solution (:mod:`core.radiosity`: the
mesh, form factors, the solvers) drawn Gouraud by the z-buffer.

- :mod:`~core.renderers.radiosity.draw`: ``draw``, the registered renderer, and the solution
  kept with the scene (``solution_for``, ``use_solution``), which the two-pass renderer shares;
- :mod:`~core.renderers.radiosity.inspect`: the element a pixel shows;
- :mod:`~core.renderers.radiosity.options`: its options (form factors, hemicube, solver, ...);
- :mod:`~core.renderers.radiosity.progressive`: the window's frames, shot by shot.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
