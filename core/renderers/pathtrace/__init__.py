"""The path tracer (``pathtrace``): Kajiya's rendering equation on the ray tracer's BVH (the
kernel: :mod:`core.pathtrace.kernel`).

- :mod:`~core.renderers.pathtrace.draw`: ``draw``, the registered renderer, the scene packed
  for the kernel (``pack``) and the film's passes (``render_passes``);
- :mod:`~core.renderers.pathtrace.inspect`: one pixel's paths traced again;
- :mod:`~core.renderers.pathtrace.options`: its options (the sampler);
- :mod:`~core.renderers.pathtrace.progressive`: the window's frames, pass by pass.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
