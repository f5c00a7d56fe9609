"""The scene: what is drawn. Data only; the pipeline reads it and never changes it.

- :mod:`core.scene.model` — :class:`Scene`, :class:`Mesh` (named per-vertex attributes),
  :class:`Material`, :class:`Light`;
- :mod:`core.scene.generators` — the house, sphere, torus, cube, Bézier patch, torus knot;
- :mod:`core.scene.normals` — face and vertex normals of a mesh;
- :mod:`core.scene.formats` — every reader (``.tri``, OBJ/PLY/OFF/STL, TOML, view files).
"""

from core.scene.model import MAX_IMAGE_SIDE, SHADINGS, Light, Material, Mesh, Scene

__all__ = ["MAX_IMAGE_SIDE", "SHADINGS", "Light", "Material", "Mesh", "Scene"]
