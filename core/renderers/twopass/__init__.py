"""The two-pass renderer (``twopass``): radiosity's solution for the diffuse part, Whitted's
rays for the specular part (the rays: :mod:`core.twopass.second_pass`).

- :mod:`~core.renderers.twopass.draw`: ``draw``, the registered renderer;
- :mod:`~core.renderers.twopass.inspect`: the pixel's ray tree, each ray's diffuse term;
- :mod:`~core.renderers.twopass.plan`: the two passes in place of the z-buffer's stages.

Its options and its progressive drawer are radiosity's (:mod:`core.renderers.radiosity`).
Nothing is imported here, so that naming a module of the package loads only that module.
"""
