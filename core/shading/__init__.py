"""Shading: the Phong illumination model, written once, and the shading modes that evaluate it.

- :mod:`core.shading.illumination` — the model (numba, one point; numpy, many points);
- :mod:`core.shading.registry` — shading modes by name: a vertex step and a pixel step each;
- :mod:`core.shading.shade` — what every mode shares: the scene's arrays, normals, caches,
  and :func:`~core.shading.shade.prepare` / :func:`~core.shading.shade.resolve`;
- :mod:`core.shading.flat`, :mod:`~core.shading.gouraud`, :mod:`~core.shading.phong` — FvDFH
  16.2.3–16.2.5, registered when first needed.

Importing this package loads no numba: the built-in modes are imported (and register
themselves) the first time a mode is looked up.
"""
