"""Cohen–Sutherland line clipping in the canonical volumes, against an independent reference."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.pipeline.clip import clip_lines, outcodes, planes

Z_MIN = -0.25


def _halfspaces(projection, z_min):
    """The canonical view volumes written here from their inequalities (pipeline.md), each as
    f(x, y, z) <= 0 inside: not the product's ``planes()``, so the reference shares nothing
    with the clipper under test (a row of ``planes`` gone wrong is caught below)."""
    def f(a, b, c, d):
        return [a, b, c, d]
    if projection == "parallel":       # -1 <= x, y <= 1, -1 <= z <= 0
        rows = [f(1, 0, 0, -1), f(-1, 0, 0, -1), f(0, 1, 0, -1), f(0, -1, 0, -1),
                f(0, 0, -1, -1), f(0, 0, 1, 0)]
    else:                              # z <= x, y <= -z, -1 <= z <= z_min
        rows = [f(1, 0, 1, 0), f(-1, 0, 1, 0), f(0, 1, 1, 0), f(0, -1, 1, 0),
                f(0, 0, -1, -1), f(0, 0, 1, -z_min)]
    return np.array(rows, float)


def test_the_products_planes_are_the_canonical_volumes():
    for projection in ("parallel", "perspective"):
        ours = {tuple(row) for row in planes(projection, Z_MIN)}
        assert ours == {tuple(row) for row in _halfspaces(projection, Z_MIN)}


def _inside(points, projection, z_min, tol=1e-9):
    pl = _halfspaces(projection, z_min)
    return np.all(points @ pl[:, :3].T + pl[:, 3] <= tol, axis=1)


def _reference(p0, p1, projection, z_min, tol=0.0):
    """Independent clipper: the parametric interval of the segment inside every half-space
    (Liang–Barsky style, no outcodes). Values within ``tol`` of a plane count as on it.
    Returns (t0, t1) or None."""
    pl = _halfspaces(projection, z_min)
    f0 = pl[:, :3] @ p0 + pl[:, 3]
    f1 = pl[:, :3] @ p1 + pl[:, 3]
    f0[np.abs(f0) <= tol] = 0.0
    f1[np.abs(f1) <= tol] = 0.0
    t0, t1 = 0.0, 1.0
    for a, b in zip(f0, f1):
        if a > 0 and b > 0:
            return None
        if a > 0:
            t0 = max(t0, a / (a - b))
        elif b > 0:
            t1 = min(t1, a / (a - b))
    return (t0, t1) if t0 <= t1 else None


def test_outcode_bits_follow_pipeline_md():
    par = outcodes(np.array([[0, 2, -0.5], [0, -2, -0.5], [2, 0, -0.5], [-2, 0, -0.5],
                             [0, 0, -2], [0, 0, 1], [1, 1, 0]]), "parallel")
    assert par.tolist() == [1, 2, 4, 8, 16, 32, 0]           # on the planes counts as inside
    per = outcodes(np.array([[0, 0.6, -0.5], [0, -0.6, -0.5], [0.6, 0, -0.5], [-0.6, 0, -0.5],
                             [0, 0, -2], [0, 0, -0.1], [0.5, -0.5, -0.5]]), "perspective", Z_MIN)
    assert per.tolist() == [1, 2, 4, 8, 16, 32, 0]


def test_hand_clipped_segments():
    # Parallel: a horizontal line through the volume loses its ends at x = ±1.
    q0, q1 = clip_lines([[-3, 0.5, -0.5]], [[3, 0.5, -0.5]], "parallel")
    assert np.allclose(q0, [[-1, 0.5, -0.5]]) and np.allclose(q1, [[1, 0.5, -0.5]])
    # Perspective: along the axis from behind the eye to beyond the back plane.
    q0, q1 = clip_lines([[0, 0, 1]], [[0, 0, -3]], "perspective", Z_MIN)
    assert np.allclose(q0, [[0, 0, Z_MIN]]) and np.allclose(q1, [[0, 0, -1]])
    # A segment wholly beside the volume is rejected; one inside is returned bit for bit.
    q0, _ = clip_lines([[2, 0, -0.5]], [[3, 0, -0.5]], "parallel")
    assert len(q0) == 0
    p0, p1 = np.array([[0.1, 0.2, -0.3]]), np.array([[-0.4, 0.5, -0.9]])
    q0, q1 = clip_lines(p0, p1, "parallel")
    assert np.array_equal(q0, p0) and np.array_equal(q1, p1)


def test_segment_behind_the_eye_never_reaches_a_divide():
    q0, q1 = clip_lines([[0.1, 0.1, 0.5], [-1, 0, 2]], [[5, 5, 0.2], [1, 0, 0.1]], "perspective", Z_MIN)
    assert len(q0) == 0


coord = st.floats(-3, 3, allow_nan=False)
point = st.tuples(coord, coord, coord)


@settings(max_examples=300, deadline=None)
@given(point, point, st.sampled_from(["parallel", "perspective"]), st.floats(-0.9, -0.01))
def test_clip_agrees_with_reference(a, b, projection, z_min):
    p0, p1 = np.array(a), np.array(b)
    q0, q1 = clip_lines(p0[None], p1[None], projection, z_min)
    ref = _reference(p0, p1, projection, z_min)
    length = np.linalg.norm(p1 - p0)
    if not _well_posed(ref, _reference(p0, p1, projection, z_min, tol=1e-12), length):
        # The segment runs within 1e-12 of a plane: either answer is right; ours must be inside.
        assert _inside(np.vstack([q0, q1]), projection, z_min).all()
        return
    if ref is None or (ref[1] - ref[0]) * length < 1e-9:
        # Rejected by the reference (or it keeps a single point): ours keeps at most a speck.
        assert len(q0) == 0 or np.linalg.norm(q1[0] - q0[0]) < 1e-7
        return
    assert len(q0) == 1
    assert _inside(np.vstack([q0, q1]), projection, z_min).all()
    expected0, expected1 = p0 + ref[0] * (p1 - p0), p0 + ref[1] * (p1 - p0)
    assert np.allclose(q0[0], expected0, atol=1e-9) and np.allclose(q1[0], expected1, atol=1e-9)
    if _inside(np.vstack([p0, p1]), projection, z_min, tol=0).all():
        assert np.array_equal(q0[0], p0) and np.array_equal(q1[0], p1)


def _well_posed(ref, ref_tol, length):
    """Whether nudging values within 1e-12 of a plane onto it changes the reference's answer."""
    if (ref is None) != (ref_tol is None):
        return False
    return ref is None or max(abs(ref[0] - ref_tol[0]), abs(ref[1] - ref_tol[1])) * length < 1e-9


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(point, point), min_size=1, max_size=40), st.sampled_from(["parallel", "perspective"]))
def test_batch_equals_one_by_one(segments, projection):
    p0 = np.array([s[0] for s in segments])
    p1 = np.array([s[1] for s in segments])
    b0, b1 = clip_lines(p0, p1, projection, Z_MIN)
    one = [clip_lines(p0[i:i + 1], p1[i:i + 1], projection, Z_MIN) for i in range(len(p0))]
    s0 = np.vstack([o[0] for o in one]) if one else np.zeros((0, 3))
    s1 = np.vstack([o[1] for o in one]) if one else np.zeros((0, 3))
    assert np.array_equal(b0, s0) and np.array_equal(b1, s1)
    assert _inside(np.vstack([b0, b1]), projection, Z_MIN).all()


@pytest.mark.parametrize("projection", ["parallel", "perspective"])
def test_line_and_triangle_clippers_share_their_outcodes(projection):
    # core.pipeline.clip (numpy, so wireframes need no compiler) and core.pipeline.clip_polygon (compiled, for
    # half a million vertices a frame) must classify every point alike, planes included.
    from core.pipeline.clip_polygon import outcodes as triangle_outcodes
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.5, 1.5, (5000, 3))
    points[:1000, 0] = -points[:1000, 2]                  # exactly on x = -z
    points[1000:2000, 2] = Z_MIN                          # exactly on the front plane
    points[2000:2500] = np.round(points[2000:2500])       # on the parallel planes
    assert np.array_equal(outcodes(points, projection, Z_MIN),
                          triangle_outcodes(points, projection, Z_MIN).astype(np.int64))
