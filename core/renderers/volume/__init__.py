"""The volume renderer (``volume``): the opaque geometry by the z-buffer, then the scene's
volumes ray-marched, cut at its depth (the data, marching cubes and the marcher's kernels:
:mod:`core.volume`).

- :mod:`~core.renderers.volume.draw`: ``draw``, the registered renderer;
- :mod:`~core.renderers.volume.inspect`: the ray through each volume, and the marching cube
  an isosurface point lies in.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
