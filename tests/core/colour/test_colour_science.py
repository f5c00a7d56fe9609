"""Colour science (core.colour): the CIE 1931 table against its published chromaticities,
the sRGB matrix against IEC 61966-2-1's primaries, white and printed matrix, one sRGB curve
everywhere, and the chromaticity diagram's pixels."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core.colour import cie, diagram, srgb

ROOT = Path(__file__).resolve().parents[3]


# CIE 015:2004 Table T.4 (and Wyszecki and Stiles, Table I(3.3.1)): the spectrum locus's
# chromaticity coordinates, five decimals as printed
PUBLISHED_LOCUS = {450: (0.15664, 0.01771), 520: (0.07430, 0.83380), 600: (0.62704, 0.37249)}


@pytest.mark.parametrize("nm", sorted(PUBLISHED_LOCUS))
def test_the_locus_is_the_published_chromaticity(nm):
    wavelengths, xy = cie.spectral_locus()
    k = int(np.flatnonzero(wavelengths == nm)[0])
    # one unit in the printed fifth decimal: the table was printed from the CMFs' own
    # rounding (y(450) here is 0.0177048, printed 0.01771)
    np.testing.assert_allclose(xy[k], PUBLISHED_LOCUS[nm], rtol=0, atol=1e-5)


def test_the_table_is_the_1931_observer():
    nm, cmf = cie.matching_functions()
    assert nm[0] == 380 and nm[-1] == 780 and np.all(np.diff(nm) == 5)
    assert nm[np.argmax(cmf[:, 1])] == 555 and cmf[:, 1].max() == 1.0   # V(λ) peaks at 555 nm
    # equal-energy white E sits at x = y = 1/3: the three CMFs have equal integrals (to the
    # table's rounding, about 1e-4 of each)
    sums = cmf.sum(axis=0)
    np.testing.assert_allclose(sums / sums.mean(), 1.0, atol=2e-4)


def test_the_srgb_matrix_has_the_standards_primaries_and_white():
    m = srgb.RGB_TO_XYZ
    for column, primary in zip(m.T, [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)]):
        np.testing.assert_allclose(cie.chromaticity(column), primary, atol=1e-12)
    white = m @ np.ones(3)
    np.testing.assert_allclose(cie.chromaticity(white), (0.3127, 0.3290), atol=1e-12)
    assert white[1] == pytest.approx(1.0, abs=1e-12)
    printed = [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
    np.testing.assert_allclose(m, printed, rtol=0, atol=5e-5)        # IEC 61966-2-1, 4 decimals


def test_one_srgb_curve_in_every_package():
    from core.radiosity.tone import tone_map
    from core.texture.image import linear_to_srgb, srgb_to_linear
    v = np.linspace(0, 1, 1001)
    assert srgb.encode(0.0031308) == pytest.approx(0.04045, abs=1e-6)   # the two pieces meet
    np.testing.assert_allclose(srgb.decode(srgb.encode(v)), v, atol=1e-12)
    np.testing.assert_array_equal(srgb.encode(v), linear_to_srgb(v))
    np.testing.assert_array_equal(srgb.encode(v), tone_map(v, "srgb"))
    np.testing.assert_array_equal(srgb.decode(v), srgb_to_linear(v))
    from core.texture.surface import encode_srgb                      # the kernels' scalar one
    np.testing.assert_allclose([encode_srgb(x) for x in v], srgb.encode(v), rtol=0, atol=1e-15)
    assert srgb.encode(0.5) * 255 == pytest.approx(187.5, abs=0.1)     # mid grey's code, 188


def test_the_primaries_and_white_fill_with_their_own_colours():
    np.testing.assert_array_equal(diagram.fill_colours(srgb.PRIMARIES), 255 * np.eye(3))
    np.testing.assert_array_equal(diagram.fill_colours(srgb.D65), [255, 255, 255])


W, H, M = 400, 450, 30


def at(image, xy):
    c, r = diagram.pixel_of(xy, W, H, M)
    return tuple(int(v) for v in image[int(r), int(c)])


def test_the_diagrams_fill_is_white_at_d65_and_empty_outside_the_locus():
    bare = diagram.chromaticity_diagram(W, H, M, marks=False)
    assert max(abs(v - 255) for v in at(bare, srgb.D65)) <= 2         # white, a pixel's xy off
    assert at(bare, (0.05, 0.05)) == diagram.BACKGROUND               # left of the blue corner
    assert at(bare, (0.07, 0.87)) == diagram.BACKGROUND               # above 520 nm
    green = at(bare, 0.97 * np.array(PUBLISHED_LOCUS[520]) + 0.03 * srgb.D65)
    assert green[1] == 255 and green[0] < 100 and green[2] < 160      # the spectral green


def test_d65_is_marked_inside_the_srgb_triangle():
    image = diagram.chromaticity_diagram(W, H, M)
    assert at(image, srgb.D65) == diagram.WHITE_MARK
    c, r = (int(v) for v in diagram.pixel_of(srgb.D65, W, H, M))
    for dc, dr in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)]:
        k, met = 1, None
        while met is None:                     # walk out until a line of the drawing
            pixel = tuple(int(v) for v in image[r + k * dr, c + k * dc])
            if pixel in (diagram.TRIANGLE, diagram.LOCUS, diagram.BACKGROUND):
                met = pixel
            k += 1
        assert met == diagram.TRIANGLE, (dc, dr, met)


def test_the_colour_command_plots_a_scenes_material(tmp_path):
    from PIL import Image
    out = tmp_path / "c.png"
    done = subprocess.run([sys.executable, "-m", "app", "colour", "--out", str(out), "--size",
                           f"{W}x{H}", "--scene", "scenes/arm_torques.toml"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    image = np.asarray(Image.open(out).convert("RGB"))
    from app.commands.colour import MARGIN
    od = np.array([0.2, 0.5, 0.9])                  # the load's O_d: a display value (code)
    xy = cie.chromaticity(srgb.RGB_TO_XYZ @ srgb.decode(od))
    c, r = (int(v) for v in diagram.pixel_of(xy, W, H, MARGIN))
    assert tuple(image[r, c]) == (51, 128, 230)     # its dot, in the bytes the z-buffer shows
    assert 0.15 < xy[0] < 0.2 and 0.1 < xy[1] < 0.2     # a blue, between D65 and the blue primary
    bad = subprocess.run([sys.executable, "-m", "app", "colour", "--out", str(out), "--scene",
                          str(tmp_path / "none.toml")], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    scene_out = subprocess.run([sys.executable, "-m", "app", "colour", "--out",
                                str(tmp_path / "c.toml")], cwd=ROOT, capture_output=True,
                               text=True, timeout=120)
    assert scene_out.returncode == 2 and "must end in .png" in scene_out.stderr
