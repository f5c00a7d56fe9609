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


def test_one_pass_gives_the_three_passes_numbers():
    """view_points (N, the outcodes and the projection in one pass) against the passes it
    replaced, to the bit, on one core and on all: points inside, outside every plane, behind
    the eye and not numbers."""
    from core.pipeline.clip_polygon import outcodes
    from core.pipeline.vertex_kernels import PARALLEL_POINTS, view_points
    rng = np.random.default_rng(7)
    for projection in ("perspective", "parallel"):
        n, z_min = normalizing_transform(VIEW, projection)
        m = project.triangle_matrix(projection, z_min, project.viewport(VIEW.window, 333, 217))
        for count in (50, PARALLEL_POINTS + 11):
            points = rng.uniform(-80, 80, (count, 3))
            points[1] = np.nan
            points[2] = (10, 20, 30)
            canonical, codes = np.empty((count, 3)), np.empty(count, np.uint8)
            device, inv_w = np.empty((count, 3)), np.empty(count)
            found = view_points(n, m, points, projection == "perspective", z_min, canonical,
                                codes, device, inv_w)
            ref = transform_affine(n, points)
            ref_codes = outcodes(ref, projection, z_min)
            ref_device, ref_inv_w = transform_projective(m, ref)
            assert np.array_equal(canonical, ref, equal_nan=True)
            assert np.array_equal(codes, ref_codes) and found == np.bitwise_or.reduce(ref_codes)
            assert np.array_equal(device, ref_device, equal_nan=True)
            assert np.array_equal(inv_w, ref_inv_w, equal_nan=True)
            assert codes[1] == 0b111111 and 0 < found < 64
            assert projection == "parallel" or np.any(inv_w == 0.0)      # W <= 0: behind
