"""Procedural geometry: the FvDFH house and the analytic test meshes.

Each generator returns a :class:`core.scene.Mesh` in world coordinates.
"""

from __future__ import annotations

import numpy as np

from core.scene import Mesh


def house() -> Mesh:
    """The house of FvDFH Fig. 6.24: 10 vertices, 15 edges (wireframe only).

    Front wall at z = 54 and back wall at z = 30, each the pentagon
    (0,0) (16,0) (16,10) (8,16) (0,10); five edges join the matching corners.
    """
    pentagon = np.array([(0, 0), (16, 0), (16, 10), (8, 16), (0, 10)], dtype=np.float64)
    front = np.column_stack([pentagon, np.full(5, 54.0)])
    back = np.column_stack([pentagon, np.full(5, 30.0)])
    ring = np.array([(i, (i + 1) % 5) for i in range(5)])
    edges = np.concatenate([ring, ring + 5, [(i, i + 5) for i in range(5)]])
    return Mesh(positions=np.concatenate([front, back]), edges=edges, name="house")
