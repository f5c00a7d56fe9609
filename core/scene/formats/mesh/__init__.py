"""Mesh files: Wavefront OBJ, PLY, OFF and STL, each format checked by its own module before
trimesh reads it, so that a bad file gives a line-numbered message.

- :mod:`~core.scene.formats.mesh.read`: :func:`read_mesh` (the bytes of a file to a
  :class:`~core.scene.model.Mesh`), :data:`MESH_EXTENSIONS`, the table from extension to the
  format's check, the trimesh glue and the checks of what trimesh returns;
- :mod:`~core.scene.formats.mesh.obj`, :mod:`~core.scene.formats.mesh.ply`,
  :mod:`~core.scene.formats.mesh.off`, :mod:`~core.scene.formats.mesh.stl`: one format each,
  its structure checked line by line (and the common ASCII PLY read with numpy alone);
- :mod:`~core.scene.formats.mesh.topology`: equal vertices merged, repeated triangles
  dropped, polygons fanned, closed surfaces found (also used by the ``.tri`` reader and the
  scene file).
"""

from core.scene.formats.mesh.read import MESH_EXTENSIONS, read_mesh
from core.scene.formats.mesh.topology import (drop_repeated_triangles, edge_problem, fan,
                                              inverse_of, is_closed, merge_vertices,
                                              signed_volume)

__all__ = ["MESH_EXTENSIONS", "drop_repeated_triangles", "edge_problem", "fan", "inverse_of",
           "is_closed", "merge_vertices", "read_mesh", "signed_volume"]
