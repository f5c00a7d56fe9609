"""The perception chart (core.colour.perception, ``python -m app colour --perception``):
CIE L* against its closed form at hand-worked values, the chart's bytes, and the two ramps'
rises of lightness worked out here from the sRGB curve and the L* formula."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from core.colour import perception, srgb
from tests.conftest import ROOT


def test_lightness_is_the_cie_1976_formula():
    # L*(Y) = 116 Y^(1/3) - 16 above (6/29)^3, where both pieces give 116 (6/29) - 16 = 8
    assert perception.lightness(0.0) == pytest.approx(0.0, abs=1e-12)
    assert perception.lightness(1.0) == pytest.approx(100.0, abs=1e-12)
    assert perception.lightness(0.18) == pytest.approx(116 * 0.18 ** (1 / 3) - 16, abs=1e-12)
    assert perception.lightness(0.18) == pytest.approx(49.496, abs=1e-3)   # 18 % grey
    knee = (6 / 29) ** 3
    assert perception.lightness(knee) == pytest.approx(8.0, abs=1e-9)
    assert perception.lightness(knee * (1 + 1e-9)) == pytest.approx(8.0, abs=1e-6)
    assert perception.lightness(0.001) == pytest.approx(0.001 * 903.2963, rel=1e-4)  # (29/3)^3


def test_the_same_grey_on_both_grounds_is_the_same_bytes():
    chart = perception.perception_chart(640, 720)
    top, bottom = perception.layout(640, 720)["contrast"]
    middle = (top + bottom) // 2
    left, right = chart[middle, 160], chart[middle, 480]
    assert tuple(left) == tuple(right) == (128, 128, 128)             # floor(255 · 0.5 + 0.5)
    assert tuple(chart[top + 2, 2]) == (31, 31, 31)                    # the dark ground, 0.12
    assert tuple(chart[bottom - 2, 637]) == (224, 224, 224)            # the light one, 0.88


def test_even_code_steps_look_even_and_even_light_steps_do_not():
    codes, light = perception.ramps(11)
    assert np.allclose(codes, np.arange(11) / 10)
    assert np.allclose(srgb.decode(light), np.arange(11) / 10)
    even_code = perception.lightness_steps(codes)
    even_light = perception.lightness_steps(light)
    # worked here: the first patch of even light is Y = 0.1, L* = 116 · 0.1^(1/3) - 16 = 37.84;
    # the last rise, L*(1) - L*(0.9) = 100 - (116 · 0.9^(1/3) - 16) = 4.00
    assert even_light[0] == pytest.approx(116 * 0.1 ** (1 / 3) - 16, abs=1e-9)
    assert even_light[-1] == pytest.approx(116 - 116 * 0.9 ** (1 / 3), abs=1e-9)
    assert even_light.max() / even_light.min() > 9          # 37.8 against 4.0
    assert even_code.max() / even_code.min() < 1.4          # 12.2 against 8.9
    chart = perception.perception_chart(660, 720)
    rows = perception.layout(660, 720)
    for name, ramp in (("even codes", codes), ("even light", light)):
        row = (rows[name][0] + rows[name][1]) // 2
        patches = chart[row, 30::60, 0]                       # each patch's middle column
        assert list(patches) == [int(np.floor(255 * c + 0.5)) for c in ramp], name


def test_the_command_draws_the_chart_and_prints_the_rises(tmp_path):
    from PIL import Image
    out = tmp_path / "p.png"
    done = subprocess.run([sys.executable, "-m", "app", "colour", "--perception", "--out",
                           str(out)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert Image.open(out).size == (640, 720)
    assert "even light L* rises 37.8 14.0" in done.stdout
    bad = subprocess.run([sys.executable, "-m", "app", "colour", "--perception", "--scene",
                          "scenes/sphere.toml", "--out", str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "takes none" in bad.stderr
