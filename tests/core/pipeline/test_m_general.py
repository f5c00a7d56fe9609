"""M_general (FvDFH eq. 6.18) against its special cases worked by hand: M_per, M'_per, M_ort
and an oblique cavalier projection; and a point projected by it lands on the plane z = z_p on
the line from the centre of projection."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.pipeline.project import m_general, m_per


def test_its_special_cases():
    # M_per, d = -1 (the course's): the centre at the origin, the plane z = -1
    assert np.array_equal(m_general(-1.0, 1.0, (0, 0, 1)), m_per(-1.0))
    # M_per, d = 2: z_p = d, Q = d, direction (0, 0, -1), as FvDFH writes it
    assert np.allclose(m_general(2.0, 2.0, (0, 0, -1)), m_per(2.0), atol=0, rtol=1e-15)
    # M'_per: the plane z = 0, the centre at (0, 0, -d): last row (0, 0, 1/d, 1)
    d = 4.0
    expected = np.eye(4)
    expected[2, 2] = 0.0
    expected[3, 2] = 1.0 / d
    assert np.allclose(m_general(0.0, d, (0, 0, -1)), expected, atol=0, rtol=1e-15)
    # M_ort: the plane z = 0, the centre at infinity along -z
    ort = np.diag([1.0, 1.0, 0.0, 1.0])
    assert np.array_equal(m_general(0.0, math.inf, (0, 0, -1)), ort)
    # cavalier: parallel along (cos 45, sin 45, -1)/√2 onto z = 0: x' = x + z cos 45, ...
    c = math.sqrt(0.5)
    direction = np.array([c, c, -1.0]) / math.sqrt(2.0)
    m = m_general(0.0, math.inf, direction)
    assert m[0, 2] == pytest.approx(c, rel=1e-15) and m[1, 2] == pytest.approx(c, rel=1e-15)


def test_a_point_lands_on_the_plane_on_the_line_from_the_centre():
    z_p, q = 1.5, 3.0
    direction = np.array([0.3, -0.2, 0.9])
    direction /= np.linalg.norm(direction)
    cop = np.array([0.0, 0.0, z_p]) + q * direction
    point = np.array([0.7, 0.4, -2.0, 1.0])
    h = m_general(z_p, q, direction) @ point
    image = h[:3] / h[3]
    assert image[2] == pytest.approx(z_p, abs=1e-12)
    # the image, the point and the centre of projection are collinear
    assert np.linalg.norm(np.cross(image - cop, point[:3] - cop)) <= 1e-12


@pytest.mark.parametrize("z_p, q, direction", [(0.0, 1.0, (1, 0, 0)), (0.0, 0.0, (0, 0, 1)),
                                               (math.nan, 1.0, (0, 0, 1))])
def test_an_impossible_one_is_refused(z_p, q, direction):
    with pytest.raises(ValueError, match="M_general needs dz != 0"):
        m_general(z_p, q, direction)
