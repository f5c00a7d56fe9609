"""The Mach bands scene and report: flat's staircase and Gouraud's continuous profile with a
slope that jumps at each facet edge, against the illumination model worked by hand for the
12-sided cylinder (closed form: I = O_d (k_a I_a + k_d N·L), N radial at a vertex, the facet's
own normal for flat)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.reports.mach_report import facet_slopes, profiles, write, SIZE

L = np.array([-0.6, 0.2, 1.0]) / np.linalg.norm([-0.6, 0.2, 1.0])


def _intensity(angle: float) -> float:
    """0-255 for the normal (sin θ, 0, cos θ): the scene's k_a 0.3, I_a 0.1, k_d 0.9, O_d 0.85."""
    n_dot_l = max(math.sin(angle) * L[0] + math.cos(angle) * L[2], 0.0)
    return 255 * 0.85 * (0.3 * 0.1 + 0.9 * n_dot_l)


def _column(angle: float) -> float:
    return (math.sin(angle) + 1.2) / 2.4 * SIZE[0]          # window -1.2..1.2 on 480 pixels


@pytest.fixture(scope="module")
def p():
    return profiles()


def test_flat_is_a_staircase_with_the_facets_own_intensity(p):
    for k in range(9, 15):                 # the facets from θ = -90° to +90°, left to right
        a, b = 2 * math.pi * k / 12, 2 * math.pi * (k + 1) / 12
        middle = int(round((_column(a) + _column(b)) / 2))
        assert p["flat"][middle] == pytest.approx(_intensity((a + b) / 2), abs=1.0)
        if k > 9:                          # the step at the facet edge, as the model has it
            edge = int(round(_column(a)))
            before = _intensity((a + a - 2 * math.pi / 12) / 2)
            assert p["flat"][edge + 2] - p["flat"][edge - 2] == pytest.approx(
                _intensity((a + b) / 2) - before, abs=1.5)


def test_gouraud_is_continuous_and_its_slope_jumps_at_the_facet_edges(p):
    g = p["gouraud"]
    inside = np.flatnonzero(g > 0)
    assert np.abs(np.diff(g[inside[0] + 2:inside[-1] - 2])).max() <= 8   # no step
    slopes = facet_slopes(g, p["edges"])
    expected = []
    for k in range(9, 15):
        a, b = 2 * math.pi * k / 12, 2 * math.pi * (k + 1) / 12
        expected.append((_intensity(b) - _intensity(a)) / (_column(b) - _column(a)))
    assert [s for _, s in slopes] == pytest.approx(expected, abs=0.05)
    jumps = np.abs(np.diff([s for _, s in slopes]))
    assert jumps.min() > 0.3                # the slope changes at every edge: the bands


def test_the_report_writes_its_three_files(tmp_path):
    paths = write(tmp_path)
    assert [q.name for q in paths] == ["mach_bands.csv", "mach_bands.png", "mach_bands.md"]
    assert "Gouraud's slope on each facet" in paths[2].read_text()
    rows = np.loadtxt(paths[0], delimiter=",", skiprows=1)
    assert rows.shape == (SIZE[0], 3)
