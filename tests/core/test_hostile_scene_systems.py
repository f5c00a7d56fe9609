"""Textures, animation keys, particles and primitives under hostile input.

Every hostile case (a file or setting a user could write) ends in one clean line and a non-zero exit, or in a correct
picture: nothing hangs (a FIFO as a texture), nothing grows without a budget (texels, particle
steps, splatted pixels, arc-length tables), no Python text reaches the user, and no silent
clamp. The memory cases run in a child process and assert its peak (``ru_maxrss``) stays
under 2 GB; their figures are printed (``pytest -s``) for docs/limits.md.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from PIL import Image

from app import cli
from core.paths import ROOT
from core.scene.formats import ReaderError, load_scene, read_scene_file

GB = 1 << 30


def run(capsys, *argv) -> tuple[int, str]:
    """``python -m app ARGV`` in process: (exit status, stderr), never a traceback."""
    try:
        status = cli.main([str(a) for a in argv])
    except SystemExit as exit_:
        status = exit_.code
    err = capsys.readouterr().err
    assert "Traceback" not in err and "Warning" not in err, err
    return status, err


def render(capsys, scene, tmp_path, *more) -> tuple[int, str]:
    return run(capsys, "render", scene, "--size", "24x24", "--out", tmp_path / "out.png", *more)


def one_error(status: int, err: str, *words: str) -> str:
    """The run failed with exactly one line, ``error: …`` holding ``words``."""
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert status != 0 and len(lines) == 1, err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def scene_file(tmp_path, text: str, name: str = "s.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def peak_of(code: str, timeout: float = 600) -> dict:
    """Run ``code`` in a child Python (this checkout first on its path) and return the JSON it
    prints on its last line, with ``peak_mb``: the child's peak resident memory."""
    wrapped = code + textwrap.dedent("""
        import resource as _r, json as _j
        print(_j.dumps({**RESULT, "peak_mb": _r.getrusage(_r.RUSAGE_SELF).ru_maxrss / 1024}))
    """)
    done = subprocess.run([sys.executable, "-c", wrapped], cwd=ROOT, capture_output=True,
                          text=True, timeout=timeout)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    print(f"\npeak memory: {result}")
    return result


# ----------------------------------------------------------------------------- textures

TEXTURED = """
[[geometry]]
generator = "icosphere"
name = "ball"
material = {{ texture = {texture} }}
"""


def test_a_fifo_as_texture_is_refused_not_read(tmp_path, capsys):
    os.mkfifo(tmp_path / "pipe.png")          # opened for reading, it would block forever
    scene = scene_file(tmp_path, TEXTURED.format(texture='"pipe.png"'))
    status, err = render(capsys, scene, tmp_path)
    assert status == 0 and "not a regular file" in err and "drawn untextured" in err
    assert "geometry[1].material.texture" in err


def test_a_symlink_loop_says_so_not_corrupt(tmp_path, capsys):
    (tmp_path / "a.png").symlink_to(tmp_path / "b.png")
    (tmp_path / "b.png").symlink_to(tmp_path / "a.png")
    status, err = render(capsys, scene_file(tmp_path, TEXTURED.format(texture='"a.png"')), tmp_path)
    assert status == 0 and "symbolic links" in err and "corrupt" not in err


@pytest.mark.parametrize("name, shown", [
    ("a\\nerror: forged.png", "a\\nerror: forged.png"),
    ("\\u001b[2Jx.png", "\\x1b[2Jx.png"),
    ("\\u202egnp.png", "\\u202egnp.png"),
    ("nul\\u0000.png", "nul\\x00.png"),
])
def test_texture_names_are_escaped(tmp_path, capsys, name, shown):
    status, err = render(capsys, scene_file(tmp_path, TEXTURED.format(texture=f'"{name}"')), tmp_path)
    assert status == 0 and len(err.splitlines()) == 1 and shown in err
    assert "\x1b" not in err and "\u202e" not in err and "\0" not in err


def test_a_5000_character_texture_name_is_cut(tmp_path, capsys):
    status, err = render(capsys, scene_file(tmp_path, TEXTURED.format(texture=f'"{"x" * 5000}.png"')),
                         tmp_path)
    assert status == 0 and len(err.splitlines()) == 1 and len(err) < 500
    assert "more characters" in err


def test_an_image_over_the_texel_budget_is_drawn_untextured(tmp_path, capsys):
    """9400² (88M texels, a 258 KB PNG): refused from its header, before any pixel is decoded;
    the sphere is drawn in its material colour."""
    Image.new("L", (9400, 9400)).save(tmp_path / "huge.png")
    status, err = render(capsys, scene_file(tmp_path, TEXTURED.format(texture='"huge.png"')), tmp_path)
    assert status == 0 and "9400 x 9400" in err and "texels" in err and "drawn untextured" in err
    untextured = scene_file(tmp_path, TEXTURED.replace("material = {{ texture = {texture} }}", ""),
                            "plain.toml")
    plain = tmp_path / "plain.png"
    assert cli.main(["render", str(untextured), "--size", "24x24", "--out", str(plain)]) == 0
    assert np.array_equal(np.asarray(Image.open(tmp_path / "out.png")), np.asarray(Image.open(plain)))


@pytest.mark.slow
def test_a_4096_texture_stays_under_2_gb(tmp_path):
    """A 49 KB 4096² PNG took 2.4 GB: its levels are now held once, built a band at a time."""
    image = np.zeros((4096, 4096, 3), np.uint8)
    image[::64, :, 0] = 255
    Image.fromarray(image).save(tmp_path / "big.png")
    scene = scene_file(tmp_path, TEXTURED.format(texture='"big.png"'))
    result = peak_of(f"""
from core.scene.formats import load_scene
from core.texture.material import maps_of
scene = load_scene({str(scene)!r})
texture = maps_of(scene.meshes[0].material).color
texels, levels = texture.packed()
RESULT = {{"size": texture.size, "levels": len(levels), "top": float(texels[0, 0])}}
""")
    assert result["size"] == [4096, 4096] and result["levels"] == 13
    assert result["peak_mb"] < 2 * 1024


def test_procedurals_past_the_texel_budget_are_refused_by_key(tmp_path, capsys, monkeypatch):
    """Textures draw on one texel budget per scene: the procedural that would pass it is
    refused naming its key, before it is computed (here with the budget cut to 3 · 64²)."""
    from core.texture import image
    monkeypatch.setattr(image, "MAX_SCENE_TEXELS", 3 * 64 * 64)
    geometry = "".join(f"""
[[geometry]]
generator = "cube"
name = "c{i}"
material = {{ texture = {{ procedural = "checker", resolution = 64 }} }}
""" for i in range(5))
    one_error(*render(capsys, scene_file(tmp_path, geometry), tmp_path),
              "geometry[4].material.texture.resolution", "needs 4,096 texels",
              "may hold 12,288 together (12,288 already used)")


def test_a_procedural_at_4096_is_refused(tmp_path, capsys):
    """Five ``resolution = 4096`` procedurals exhausted memory (one perlin: 2.3 GB)."""
    table = '{ procedural = "perlin", resolution = 4096 }'
    one_error(*render(capsys, scene_file(tmp_path, TEXTURED.format(texture=table)), tmp_path),
              "texture.resolution", "from 1 to 2048")


@pytest.mark.slow
def test_the_costliest_procedural_stays_under_2_gb():
    """Perlin at the largest resolution and the finest lattice allowed."""
    result = peak_of("""
from core.texture import procedural
texture = procedural.make("perlin", resolution=2048, scale=8, octaves=9)
RESULT = {"size": texture.size}
""")
    assert result["size"] == [2048, 2048] and result["peak_mb"] < 2 * 1024


@pytest.mark.parametrize("table, key, words", [
    ('{ procedural = "perlin", scale = 1024, octaves = 6 }', "octaves", "32768 lattice cells"),
    ('{ procedural = "perlin", scale = 1024, octaves = 16 }', "octaves", "33554432 lattice cells"),
    ('{ procedural = "checker", a = [' + ", ".join(["0.5"] * 3000) + "] }", "a",
     "a colour: 3 numbers"),
    ('{ procedural = "checker", a = [nan, 0, 0] }', "a", "a[1] must lie in"),
    ('{ procedural = "checker", b = [inf, 0, 0] }', "b", "b[1] must lie in"),
    ('{ procedural = "checker", a = [1e308, 0, 0] }', "a", "a[1] must lie in"),
    ('{ procedural = "checker", a = ["x", "y", "z"] }', "a", "a[1] must be a number"),
    ('{ procedural = "sky", sun = [] }', "sun", "2 numbers"),
    ('{ procedural = "sky", sun = {} }', "sun", "2 numbers"),
    ('{ procedural = "sky", sun = [1] }', "sun", "2 numbers"),
    ('{ procedural = "demo_height", map = 99 }', "map", "from 0 to 3"),
    ('{ procedural = "demo_height", map = "x" }', "map", "whole number"),
    ('{ procedural = "bricks", mortar = nan }', "mortar", "must lie in"),
])
def test_procedural_parameters_are_checked(tmp_path, capsys, table, key, words):
    status, err = render(capsys, scene_file(tmp_path, TEXTURED.format(texture=table)), tmp_path)
    line = one_error(status, err, f"geometry[1].material.texture.{key}:", words)
    assert "ufunc" not in line and len(line) < 400


def test_a_bump_demo_map_out_of_range_is_refused(tmp_path, capsys):
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "plane"
        material = { bump_demo = { map = 99 } }
        """)
    one_error(*render(capsys, scene, tmp_path), "bump_demo.map", "out of range [0, 3]")
    demo = ROOT / "scenes" / "bump_demo.toml"
    one_error(*render(capsys, demo, tmp_path, "--bump-map", "99"), "--bump-map", "0 to 3")


def test_a_signed_32_bit_tiff_with_negative_values_gives_finite_texels(tmp_path):
    """Negative texels were NaN after the sRGB decoding (a black sphere): they are clamped to 0."""
    from core.texture.image import load_image
    values = np.array([[-2**31, -5], [0, 2**31 - 1]], dtype=np.int32)
    Image.fromarray(values, mode="I").save(tmp_path / "signed.tif")
    texture = load_image(tmp_path / "signed.tif", "texture")
    top = texture.levels[0]
    assert np.all(np.isfinite(top))
    assert top[1, 0, 0] == 0.0 and top[1, 1, 0] == 0.0 and top[0, 1, 0] == pytest.approx(1.0)


# ----------------------------------------------------------------------------- primitives

def test_a_tiny_plane_normal_draws_as_its_direction(tmp_path, capsys):
    """``normal = [0, 1e-320, 0]`` is the direction +y: drawn exactly as ``[0, 1, 0]``."""
    pictures = []
    for normal in ("[0, 1e-320, 0]", "[0, 1, 0]"):
        scene = scene_file(tmp_path, f"""
            [[geometry]]
            primitive = "plane"
            normal = {normal}
            """)
        status, err = render(capsys, scene, tmp_path, "--view", "3")
        assert status == 0 and err == ""
        pictures.append(np.asarray(Image.open(tmp_path / "out.png")))
    assert np.array_equal(*pictures) and pictures[0].any()


def test_no_runtime_warning_reaches_the_terminal(tmp_path):
    scene = scene_file(tmp_path, """
        [[geometry]]
        primitive = "plane"
        normal = [0, 1e-320, 0]
        """)
    done = subprocess.run([sys.executable, "-m", "app", "render", str(scene), "--size", "16x16",
                           "--out", str(tmp_path / "o.png")], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0 and "Warning" not in done.stderr, done.stderr


@pytest.mark.parametrize("geometry, key, words", [
    ('primitive = "sphere"\nmaterial = { ior = ' + "9" * 400 + " }", "material.ior",
     "not an integer of 400 digits"),                      # found by the long fuzz run
    ('primitive = "sphere"\nradius = 1e20', "radius", "out of range [1e-06, 1e+06]"),
    ('primitive = "sphere"\nradius = 1e7', "radius", "out of range"),
    ('primitive = "plane"\nchecker = 1e-300', "checker", "over a million checker squares"),
    ('primitive = "sphere"\nsegments = 8.5', "segments", "expected a whole number"),
])
def test_primitive_keys_are_refused_cleanly(tmp_path, capsys, geometry, key, words):
    scene = scene_file(tmp_path, "[[geometry]]\n" + geometry + "\n")
    one_error(*render(capsys, scene, tmp_path), f"geometry[1].{key}:", words)


# ----------------------------------------------------------------------------- options

SPHERE = "[[geometry]]\nprimitive = \"sphere\"\n"


def test_a_non_square_sample_count_is_refused_for_the_regular_grid(tmp_path, capsys):
    scene = scene_file(tmp_path, SPHERE)
    for count in ("2", "3", "8"):
        one_error(*render(capsys, scene, tmp_path, "--samples", count), "not a square")
    status, _ = render(capsys, scene, tmp_path, "--samples", "4")
    assert status == 0


@pytest.mark.parametrize("time", ["nan", "inf", "-inf"])
def test_a_time_that_is_not_finite_is_refused(tmp_path, capsys, time):
    scene = scene_file(tmp_path, SPHERE)
    one_error(*render(capsys, scene, tmp_path, f"--time={time}"), "--time", "finite")


# ----------------------------------------------------------------------------- animation keys

def test_a_keyed_scale_through_zero_is_refused_at_load(tmp_path, capsys):
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "icosphere"
        name = "c"
        [[key]]
        time = 0
        object.c = { scale = 1.0 }
        [[key]]
        time = 1
        object.c = { scale = -1.0 }
        """)
    one_error(*render(capsys, scene, tmp_path, "--time", "0.5"), "key[2].object.c.scale",
              "passes through zero between the keys at t = 0 and t = 1")


def test_a_catmull_rom_overshoot_through_zero_is_found():
    """Keys 1, 0.05, 1 never reach 0, but the spline between them dips below it."""
    from core.animation.tracks import Track
    track = Track([0, 1, 2, 3], [[1.0], [0.05], [0.05], [1.0]], "catmull-rom")
    low, high = track.interval_ranges()
    dense = np.array([track(t) for t in np.linspace(0, 3, 3001)])
    assert low.min() <= dense.min() + 1e-12 and high.max() >= dense.max() - 1e-12
    assert dense.min() < 0.05          # the dip the check must see


VIEW = """
[[geometry]]
generator = "cube"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 10]
front = 5
back = -5
"""


@pytest.mark.parametrize("keys, words", [
    ("""
[[key]]
time = 0
view = { prp = [0, 0, 10] }
[[key]]
time = 1
view = { prp = [0, 0, -10] }
""", "PRP crosses the view plane"),
    ("""
[[key]]
time = 0
view = { front = 5, back = -5 }
[[key]]
time = 1
view = { back = 2 }
[[key]]
time = 2
view = { front = -5, back = -15 }
""", "is not behind F"),
    ("""
[[key]]
time = 0
view = { window = [0.99, 1.18, -2, 2] }
[[key]]
time = 1
view = { window = [-1.6, -1.5, -2, 2] }
[[key]]
time = 2
view = { window = [-0.17, 1.69, -2, 2] }
""", "the window is degenerate"),
])
def test_invalid_in_between_views_are_found_at_load(tmp_path, capsys, keys, words):
    scene = scene_file(tmp_path, VIEW + keys)
    one_error(*render(capsys, scene, tmp_path), "the keyed view is invalid", words)


def test_a_key_moves_the_whole_checker_plane(tmp_path):
    scene = load_scene(scene_file(tmp_path, """
        [[geometry]]
        primitive = "plane"
        name = "floor"
        checker = 2.0
        extent = 4.0
        [[key]]
        time = 0
        object.floor = { translate = [0, 0, 0] }
        material.floor = { od = [1, 0, 0] }
        [[key]]
        time = 1
        object.floor = { translate = [0, 5, 0] }
        material.floor = { od = [0, 1, 0] }
        """))
    from core.animation.keys import animation_of
    moved = animation_of(scene).scene_at(1.0)
    assert len(moved.meshes) == 2
    assert all(np.all(m.positions[:, 1] == 5.0) for m in moved.meshes)
    assert [m.material.od for m in moved.meshes] == [(0.0, 1.0, 0.0), (0.1, 0.1, 0.1)]


@pytest.mark.slow
def test_20000_constant_speed_keys_load_in_bounded_memory(tmp_path):
    rng = np.random.default_rng(1)
    keys = "".join(f"[[key]]\ntime = {i * 0.01:.2f}\nobject.c = {{ translate = "
                   f"[{x:.3f}, {y:.3f}, {z:.3f}] }}\n" for i, (x, y, z)
                   in enumerate(rng.uniform(-5, 5, (20_000, 3))))
    scene = scene_file(tmp_path, "[[geometry]]\ngenerator = \"cube\"\nname = \"c\"\n"
                                 "[animation]\nconstant_speed = true\n" + keys)
    result = peak_of(f"""
import time
start = time.process_time()
from core.scene.formats import load_scene
from core.animation.keys import animation_of
track = animation_of(load_scene({str(scene)!r})).objects[0].translate
RESULT = {{"table": len(track._arc[0]), "cpu_s": round(time.process_time() - start, 1),
          "end": track(199.99).tolist()}}
""")
    assert result["table"] <= (1 << 20) + 1
    assert result["peak_mb"] < 2 * 1024


# ----------------------------------------------------------------------------- particles

def test_a_day_of_particles_at_1000_fps_is_refused_at_load(tmp_path, capsys):
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "cube"
        [animation]
        duration = 86400
        fps = 1000
        [[emitter]]
        rate = 10
        """)
    one_error(*render(capsys, scene, tmp_path, "--time", "1"), "animation.duration",
              "345,600,000 simulation steps", "at most 400,000")


def test_the_particle_work_budget_ends_in_a_message(tmp_path, capsys, monkeypatch):
    from core.animation import particles
    monkeypatch.setattr(particles, "MAX_PARTICLE_WORK", 10_000)
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "cube"
        [animation]
        duration = 10
        [[emitter]]
        rate = 1000
        lifetime = 100
        """)
    one_error(*render(capsys, scene, tmp_path, "--time", "5"), "particle-steps",
              "emit fewer")


def test_particles_past_the_cap_are_counted_and_warned_of(tmp_path, capsys, monkeypatch):
    from core.animation import particles
    monkeypatch.setattr(particles, "MAX_PARTICLES", 50)
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "cube"
        [animation]
        duration = 2
        [[emitter]]
        rate = 20
        lifetime = 0.05
        children = 10
        child = { lifetime = 10 }
        """)
    status, err = render(capsys, scene, tmp_path, "--time", "1")
    assert status == 0 and "particles were not born: at most 50 live at once" in err


@pytest.mark.slow
def test_two_million_full_frame_sprites_are_refused_within_budget(tmp_path):
    """2M sprites each covering a 500 x 500 frame were ~36 min of blending: the frame is
    refused by the covered-pixel budget, with a message, in bounded memory."""
    scene = scene_file(tmp_path, """
        [[geometry]]
        generator = "cube"
        params = { size = 0.1 }
        [[view]]
        vrp = [0, 0, 0]
        vpn = [0, 0, 1]
        vup = [0, 1, 0]
        window = [-1, 1, -1, 1]
        prp = [0, 0, 5]
        front = 4
        back = -4
        [animation]
        duration = 1
        fps = 10
        [[emitter]]
        rate = 200000
        lifetime = 100
        size = 50
        """)
    result = peak_of(f"""
from app import cli
import io, contextlib
err = io.StringIO()
with contextlib.redirect_stderr(err):
    status = cli.main(["render", {str(scene)!r}, "--time", "1", "--size", "500x500",
                       "--out", {str(tmp_path / "p.png")!r}])
RESULT = {{"status": status, "err": err.getvalue()}}
""")
    assert result["status"] == 1 and "the particles would cover" in result["err"]
    assert "2,000,000 in view" in result["err"] and "Traceback" not in result["err"]
    assert result["peak_mb"] < 2 * 1024
