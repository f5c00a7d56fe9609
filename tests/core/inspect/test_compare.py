"""``compare``: made-up student pictures held against our render, and the buffer
views (``render --buffer``) against the inspector's per-pixel records."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from app.cli import main
from core import RenderContext, RenderSettings, render
from core.inspect import inspect_pixel
from core.inspect.buffers import buffer
from core.paths import SCENES_DIR
from core.scene.formats import load_scene

SCENE = str(SCENES_DIR / "cube.toml")
SIZE = (160, 120)


@pytest.fixture(scope="module")
def ours():
    scene = load_scene(SCENE)
    settings = RenderSettings.for_scene(scene, shading="gouraud", size=SIZE)
    return render(scene, scene.views[0], settings, RenderContext()).color.copy()


def _compare(tmp_path, picture, *extra):
    path = tmp_path / "student.png"
    Image.fromarray(picture).save(path)
    heat = tmp_path / "heat.png"
    code = main(["compare", SCENE, "--shading", "gouraud", "--image", str(path),
                 "--out", str(heat), *extra])
    return code, np.asarray(Image.open(heat).convert("RGB"))


def test_our_own_render_has_no_difference(tmp_path, ours, capsys):
    code, heat = _compare(tmp_path, ours)
    out = capsys.readouterr().out
    assert code == 0
    assert "same within 1/255: 0 of 19200 pixels beyond the tolerance, 0 beyond 1/255" in out
    assert np.array_equal(heat, ours // 4)           # nothing beyond: the dimmed picture


def test_a_picture_shifted_by_one_pixel_is_found(tmp_path, ours, capsys):
    shifted = np.roll(ours, 1, axis=1)
    code, heat = _compare(tmp_path, shifted)
    out = capsys.readouterr().out
    assert code == 1 and "DIFFERENT within 1/255" in out
    beyond = int(out.split(" of 19200")[0].split()[-1])
    # the cube's silhouette moved: every row it covers differs at its left and right edges
    rows = (ours != ours[0, 0]).any(axis=2).any(axis=1).sum()
    assert beyond >= 2 * rows
    assert "the inspector at that pixel: pixel (" in out
    assert (heat != ours // 4).any(axis=2).sum() == beyond


def test_a_tint_of_2_levels_is_found_and_a_tolerance_of_2_accepts_it(tmp_path, ours, capsys):
    tinted = np.clip(ours.astype(int) + [2, 0, 0], 0, 255).astype(np.uint8)
    code, _ = _compare(tmp_path, tinted)
    out = capsys.readouterr().out
    changed = int((tinted != ours).any(axis=2).sum())
    assert code == 1
    assert f"{changed} of 19200 pixels beyond the tolerance, {changed} beyond 1/255" in out
    assert "0 beyond 8/255" in out and "by 2/255" in out
    code, _ = _compare(tmp_path, tinted, "--tolerance", str(2 / 255))
    assert code == 0


def test_a_picture_of_the_wrong_view_is_found(tmp_path, ours, capsys):
    scene = load_scene(SCENE)
    settings = RenderSettings.for_scene(scene, shading="gouraud", size=SIZE)
    other = render(scene, scene.views[1], settings, RenderContext()).color
    code, _ = _compare(tmp_path, other)
    out = capsys.readouterr().out
    assert code == 1
    beyond_8 = int(out.split(" beyond 8/255")[0].split()[-1])
    assert beyond_8 > 0.05 * SIZE[0] * SIZE[1]
    code, _ = _compare(tmp_path, other, "--view", "2")     # and it is view 2, exactly
    assert code == 0


def test_bad_input_is_refused_in_one_line(tmp_path, ours, capsys):
    path = tmp_path / "student.png"
    Image.fromarray(ours).save(path)
    assert main(["compare", SCENE, "--image", str(tmp_path / "none.png")]) == 2
    assert main(["compare", SCENE, "--image", str(path), "--size", "10x10"]) == 2
    assert main(["compare", SCENE, "--image", str(path), "--tolerance", "3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: --image {tmp_path / 'none.png'}: no such file",
                   f"error: --image {path} is 160x120, --size says 10x10",
                   "error: --tolerance must be on 0..1 (1/255 = 0.00392), not 3.0"]


@pytest.mark.parametrize("scene_name, shading", [("torus.toml", "phong"),
                                                 ("cube.toml", "gouraud"),
                                                 ("texture_floor.toml", "phong")])
def test_buffers_agree_with_the_inspector_pixel_by_pixel(scene_name, shading):
    scene = load_scene(SCENES_DIR / scene_name)
    settings = RenderSettings.for_scene(scene, shading=shading, size=(80, 60))
    view, context = scene.views[0], RenderContext()
    names = ["depth", "triangle", "barycentrics", "normal", "overdraw"]
    if scene_name.startswith("texture"):
        names += ["uv", "mip"]
    values = {name: buffer(scene, view, settings, name, context)[0] for name in names}
    rng = np.random.default_rng(7)
    covered = 0
    for _ in range(300):
        x, y = int(rng.integers(80)), int(rng.integers(60))
        record = inspect_pixel(scene, view, settings, x, y, context)
        if record["layer"] != "triangle":
            assert values["triangle"][y, x] == -1 and np.isnan(values["depth"][y, x])
            continue
        covered += 1
        assert values["triangle"][y, x] == record["scene triangle"]
        assert values["depth"][y, x] == record["depth"]["npc"]
        assert values["barycentrics"][y, x] == pytest.approx(record["weights"]["used"])
        assert values["overdraw"][y, x] >= 1
        normal = record.get("normal") or record.get("perturbed normal") \
            or record.get("interpolated normal")
        if shading != "gouraud":
            assert values["normal"][y, x] == pytest.approx(
                record.get("interpolated normal", normal) if "uv" in record else normal,
                abs=1e-9)
        if "uv" in record:
            assert values["uv"][y, x] == pytest.approx(record["uv"], rel=1e-6)
            assert values["mip"][y, x] == pytest.approx(record["texture"]["mip level"],
                                                        abs=1e-6)
    assert covered > 50


def test_render_buffer_writes_the_png_and_the_raw_values(tmp_path, capsys):
    out = tmp_path / "depth.png"
    assert main(["render", SCENE, "--shading", "flat", "--size", "40x30", "--buffer", "depth",
                 "--out", str(out)]) == 0
    raw = np.load(tmp_path / "depth.npy")
    picture = np.asarray(Image.open(out).convert("RGB"))
    assert raw.shape == (30, 40) and picture.shape == (30, 40, 3)
    assert (np.isnan(raw) == (picture == 0).all(axis=2)).all()     # empty pixels are black
    nearest = np.unravel_index(np.nanargmax(raw), raw.shape)
    assert tuple(picture[nearest]) == (255, 255, 255)                # the nearest is white
    assert main(["render", SCENE, "--renderer", "raycast", "--buffer", "depth", "--out",
                 str(out)]) == 1
    assert "the raycast renderer keeps no depth buffer" in capsys.readouterr().err


def test_hostile_pictures_are_refused_in_one_line_before_they_are_decoded(tmp_path, capsys):
    import os
    fifo = tmp_path / "pipe.png"
    os.mkfifo(fifo)
    assert main(["compare", SCENE, "--image", str(fifo)]) == 2
    assert "not a regular file" in capsys.readouterr().err
    big = tmp_path / "big.png"                      # 140 KB that declares 12,000 x 12,000
    Image.new("L", (12000, 12000)).save(big, optimize=True)
    assert main(["compare", SCENE, "--image", str(big)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "12000 x 12000 pixels is larger" in err   # no PIL warning


def test_a_16_bit_grey_picture_is_scaled_not_clipped(tmp_path, ours, capsys):
    grey = np.asarray(Image.fromarray(ours).convert("L"))
    eight, sixteen = tmp_path / "eight.png", tmp_path / "sixteen.png"
    Image.fromarray(grey).save(eight)
    Image.fromarray(grey.astype(np.uint16) * 257).save(sixteen)
    assert Image.open(sixteen).mode == "I;16"
    outs = []
    for path in (eight, sixteen):
        main(["compare", SCENE, "--shading", "gouraud", "--image", str(path), "--out",
              str(tmp_path / "heat.png")])
        outs.append(capsys.readouterr().out.split(": ", 1)[1].splitlines()[0])
    assert outs[0] == outs[1]                       # the same verdict for the same picture


def test_inspect_json_of_a_volume_is_strict_json(capsys):
    import json
    assert main(["inspect", str(SCENES_DIR / "volume_phantom.toml"), "--pixel", "5,5",
                 "--json", "--size", "40x40"]) == 0
    text = capsys.readouterr().out
    assert "Infinity" not in text and "NaN" not in text
    record = json.loads(text, parse_constant=lambda name: pytest.fail(f"{name} in the JSON"))
    assert record["renderer"] == "volume" and '"inf"' in text      # said as a string


def test_a_picture_wider_than_any_framebuffer_is_refused_naming_the_file(tmp_path, capsys):
    wide = tmp_path / "wide.png"
    Image.new("L", (8_000_000, 1)).save(wide)
    assert main(["compare", SCENE, "--image", str(wide)]) == 2
    assert f"--image {wide}: 8000000 x 1 pixels is larger" in capsys.readouterr().err


def test_a_reference_bomb_is_one_line_without_pils_warning(tmp_path):
    import warnings
    from app.viewer.reference import load_reference
    bomb = tmp_path / "bomb.png"
    Image.new("L", (12000, 12000)).save(bomb, optimize=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="12000 x 12000 pixels is larger than any picture"):
            load_reference(bomb)
