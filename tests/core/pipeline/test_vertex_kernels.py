"""The compiled vertex loops compute what the numpy forms compute."""

from __future__ import annotations

import numpy as np

from core.pipeline import project
from core.transforms import apply
from core.pipeline.vertex_kernels import transform_affine, transform_projective
from core.camera.view import View, normalizing_transform

VIEW = View((16, 0, 54), (1, 0, 1), (-0.17, 0.98, 0.17), (-20, 20, -5, 35), (0, 25, 28.3), 1, -35)


def test_affine_equals_apply():
    points = np.random.uniform(-50, 50, (1000, 3))
    n, _ = normalizing_transform(VIEW, "perspective")
    assert np.allclose(transform_affine(n, points), apply(n, points)[:, :3], rtol=1e-14, atol=1e-12)


def test_projective_equals_project_triangles_and_never_divides_by_zero():
    n, z_min = normalizing_transform(VIEW, "perspective")
    points = apply(n, np.random.uniform(-50, 50, (1000, 3)))[:, :3]
    points[0] = 0.0                                   # the eye: W = 0
    vp = project.viewport(VIEW.window, 333, 217)
    xyz, inv_w = transform_projective(project.triangle_matrix("perspective", z_min, vp), points)
    ref_xyz, ref_inv_w = project.project_triangles(points, "perspective", z_min, vp)
    assert inv_w[0] == 0.0 and np.all(np.isfinite(xyz))
    assert np.allclose(inv_w, ref_inv_w, rtol=1e-14, atol=0)
    assert np.allclose(xyz, ref_xyz, rtol=1e-13, atol=1e-9)
