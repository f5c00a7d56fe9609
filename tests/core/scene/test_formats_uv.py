"""Texture coordinates from mesh files: OBJ ``vt`` and PLY ``s t`` / ``u v`` become Mesh.uv;
a texture seam keeps its vertex copies apart, and the surface is still judged closed."""

from __future__ import annotations

import numpy as np

from core.scene.formats.mesh import read_mesh

QUAD_OBJ = b"""v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 0.5 0
vt 0.5 0.25
vt 0 0.25
f 1/1 2/2 3/3 4/4
"""


def test_obj_vt_become_the_vertices_uv():
    mesh = read_mesh(QUAD_OBJ, "quad.obj", ".obj")
    by_position = {tuple(p): tuple(t) for p, t in zip(mesh.positions, mesh.uv)}
    assert by_position == {(0, 0, 0): (0, 0), (1, 0, 0): (0.5, 0), (1, 1, 0): (0.5, 0.25),
                           (0, 1, 0): (0, 0.25)}
    assert "uv" in mesh.attributes


def test_ply_s_t_and_u_v_are_read():
    for names in (("s", "t"), ("u", "v")):
        header = (f"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  f"property float z\nproperty float {names[0]}\nproperty float {names[1]}\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n")
        body = "0 0 0 0.1 0.2\n1 0 0 0.3 0.4\n0 1 0 0.5 0.6\n3 0 1 2\n"
        mesh = read_mesh((header + body).encode(), "tri.ply", ".ply")
        assert np.allclose(mesh.uv, [[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]]), names


def test_a_seam_keeps_its_copies_and_the_solid_stays_closed():
    # A tetrahedron whose apex has a different (u, v) on each face: 4 positions, 6 vertices.
    obj = b"""v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
vt 0 0
vt 1 0
vt 0 1
vt 0.2 0.2
vt 0.4 0.4
vt 0.6 0.6
f 1/1 3/3 2/2
f 1/1 2/2 4/4
f 2/2 3/3 4/5
f 3/3 1/1 4/6
"""
    mesh = read_mesh(obj, "tet.obj", ".obj")
    assert len(mesh.positions) == 6 and len(np.unique(mesh.positions, axis=0)) == 4
    apex = np.all(mesh.positions == (0, 0, 1), axis=1)
    assert sorted(map(tuple, mesh.uv[apex])) == [(0.2, 0.2), (0.4, 0.4), (0.6, 0.6)]
    assert mesh.closed


def test_meshes_without_coordinates_have_none(bunny_path):
    assert read_mesh(QUAD_OBJ.replace(b"/1", b"").replace(b"/2", b"").replace(b"/3", b"")
                     .replace(b"/4", b""), "q.obj", ".obj").uv is None
    assert read_mesh(bunny_path.read_bytes(), "bun_zipper.ply", ".ply").uv is None
