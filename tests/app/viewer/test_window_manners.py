"""The window's manners, headless: the pivot under the cursor (read from the shown frame's
depth), the turntable, the headlight, depth shading from the eye, the old frame stretched
after a resize, and saved views in the user's state folder.

Every expected number is derived by hand in the test from the scene's few numbers: a square
(or a tilted one) in front of a camera whose view plane is z = 0, eye at z = 2.
"""

from __future__ import annotations

import math
import os
import stat

import numpy as np
import pytest

from app.session.pick import PICK_KEY, point_at
from app.session.state import ViewerState
from app.viewer.hands import CameraHands
from app.viewer.loupe import stretched
from core.camera.view import View, eye_from_view, vrc_basis
from core.scene.model import Light, Material, Mesh, Scene

SIZE = 40                                   # the picture: 40 x 40 pixels
VIEW = View(vrp=(0.0, 0.0, 0.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
            window=(-1.0, 1.0, -1.0, 1.0), prp=(0.0, 0.0, 2.0), front=1.0, back=-1.0)
EYE = np.array([0.0, 0.0, 2.0])
WHITE = Material(ka=0.0, kd=1.0, ks=0.0, od=(1.0, 1.0, 1.0))


def square(side: float = 1.0, slope: float = 0.0) -> Mesh:
    """The square |x|, |y| <= side on the plane z = -slope x, facing +z (open: two-sided)."""
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64) * side
    positions = np.column_stack([corners, -slope * corners[:, 0]])
    normal = np.array([slope, 0.0, 1.0]) / math.hypot(slope, 1.0)
    return Mesh(positions, triangles=[[0, 1, 2], [0, 2, 3]], normals=np.tile(normal, (4, 1)),
                material=WHITE, name="square")


def state_of(mesh: Mesh, shading: str = "flat", projection: str = "perspective",
             view: View = VIEW) -> ViewerState:
    """A window's state of one mesh, lit by a light that grazes it (N . L = 0: black)."""
    scene = Scene(name="square", meshes=[mesh], views=[view], ambient=(0.0, 0.0, 0.0),
                  lights=[Light(direction=(1.0, 0.0, 0.0))], shading=shading,
                  projection=projection, size=(SIZE, SIZE))
    return ViewerState(scene=scene, scene_source="square", size=(SIZE, SIZE))


def pixel_point(column: int, row: int) -> tuple[float, float]:
    """(u, v) on the view plane z = 0 of the centre of pixel (column, row from the top)."""
    return -1.0 + (column + 0.5) * 2 / SIZE, 1.0 - (row + 0.5) * 2 / SIZE


# -- the point under the cursor ---------------------------------------------------------------
@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_the_point_under_a_pixel_is_read_from_the_frames_depth(projection):
    # The plane z = -x/2: the ray through pixel (14, 12), view-plane point (u, v, 0) =
    # (-0.275, 0.375, 0), meets it at t = 2 / (2 - u/2) from the eye (perspective, P = E +
    # t (u, v, -2)), or at z = -u/2 straight behind the view-plane point (parallel).
    state = state_of(square(0.6, slope=0.5), projection=projection)
    assert state.frames.update()
    u, v = pixel_point(14, 12)
    if projection == "perspective":
        t = 2 / (2 - 0.5 * u)
        expected = EYE + t * np.array([u, v, -2.0])
    else:
        expected = np.array([u, v, -0.5 * u])
    found = point_at(state.frame.stats[PICK_KEY], 14, 12)
    # the rasterizer interpolates depth from fixed-point corners: a few millionths of the
    # square's size (the exact answer is 0.2573, 0.3509, 0.1287 in perspective)
    assert np.allclose(found, expected, atol=1e-5), (found, expected)
    # pixel (0, 0) looks past the square's edge (x = 0.6): the background, no point
    assert point_at(state.frame.stats[PICK_KEY], 0, 0) is None
    assert point_at(state.frame.stats[PICK_KEY], SIZE, 3) is None       # outside the frame


def test_the_frame_keeps_its_own_depth_when_the_next_frame_overwrites_the_buffer():
    state = state_of(square(0.6, slope=0.5))
    assert state.frames.update()
    pick = state.frame.stats[PICK_KEY]
    before = point_at(pick, 14, 12)
    state.views.set_hand_view(View(vrp=(0.3, 0.0, 0.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
                             window=VIEW.window, prp=(0.0, 0.0, 2.0), front=1.0, back=-1.0))
    assert state.frames.update()                      # drawn into the same context's z-buffer
    assert np.array_equal(point_at(pick, 14, 12), before)


def _drag(hands, x0, y0, x1, y1, under=None):
    hands.press(x0, y0, pan=False, under=under)
    for k in range(1, 7):
        hands.move(x0 + (x1 - x0) * k / 6, y0 + (y1 - y0) * k / 6, threshold=3)
    assert hands.release(x1, y1, threshold=3)


def test_a_drag_pressed_on_the_model_orbits_about_the_point_under_the_cursor():
    state = state_of(square(0.6, slope=0.5))
    assert state.frames.update()
    under = point_at(state.frame.stats[PICK_KEY], 14, 12)
    hands = CameraHands(state)
    _drag(hands, 14.5, 12.5, 30, 20, under=under)
    after = state.views.current
    eye = eye_from_view(after, "perspective").point
    # turned about the point: the eye and the VRP keep their distances to it ...
    assert math.isclose(np.linalg.norm(eye - under), np.linalg.norm(EYE - under), rel_tol=1e-12)
    assert math.isclose(np.linalg.norm(np.asarray(after.vrp) - under), np.linalg.norm(under),
                        rel_tol=1e-12)
    # ... and not to the scene's centre (the origin), which a miss would have kept
    assert abs(np.linalg.norm(eye) - 2.0) > 1e-3
    # a press that misses the model (no point) orbits about the scene's centre
    state.views.reset()
    _drag(hands, 0.5, 0.5, 16, 8)
    eye = eye_from_view(state.views.current, "perspective").point
    assert math.isclose(np.linalg.norm(eye), 2.0, rel_tol=1e-12)
    # the VRP pivot stays a choice: the VRP (the origin here) does not move
    state.views.reset()
    hands.set_pivot("vrp")
    _drag(hands, 14.5, 12.5, 30, 20, under=under)
    assert np.array_equal(state.views.current.vrp, (0.0, 0.0, 0.0))


# -- the turntable ----------------------------------------------------------------------------
def test_the_turntable_yaws_about_up_and_pitches_about_right_without_roll():
    state = state_of(square())
    hands = CameraHands(state)
    hands.set_rotation("turntable")
    # pi radians over the shorter side (40 px): 20 px right is a quarter turn of the scene
    # about +y (its front moves right), so the eye goes round to -x: VPN (-1, 0, 0)
    _drag(hands, 10, 20, 30, 20)
    assert np.allclose(state.views.current.vpn, (-1.0, 0.0, 0.0), atol=1e-12)
    assert np.allclose(state.views.current.vup, (0.0, 1.0, 0.0), atol=0)
    # 10 px down: the eye rises by pi/4 over the horizon
    _drag(hands, 20, 10, 20, 20)
    assert np.allclose(state.views.current.vpn,
                       (-math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0), atol=1e-12)
    # far down: the elevation stops at 89 degrees, the picture never rolls
    _drag(hands, 20, 0, 20, 400)
    assert math.isclose(state.views.current.vpn[1], math.sin(math.radians(89)), rel_tol=1e-12)
    u, _, _ = vrc_basis(state.views.current)
    assert abs(u[1]) < 1e-12                         # the right axis stays horizontal


# -- the headlight ----------------------------------------------------------------------------
def _square_pixels(state) -> np.ndarray:
    assert state.frames.update()
    return state.frame.color[..., 0].astype(int)


@pytest.mark.parametrize("shading, centre, corner", [
    # flat: lit once at the centroid (0, 0, 0), L = +z: N . L = 1
    ("flat", 255, 255),
    # Gouraud: every corner (+-1, +-1, 0) has N . L = 2 / sqrt(6) = 0.8165, so every pixel
    ("gouraud", 208.2, 208.2),
    # Phong: the centre pixel's point (0.025, -0.025, 0): 2 / sqrt(4.00125) = 0.99984;
    # corner pixel (0, 0) at (-0.975, 0.975, 0): 2 / sqrt(5.90125) = 0.82330
    ("phong", 254.96, 209.94),
])
def test_the_headlight_lights_what_the_eye_sees_in_every_local_shading(shading, centre, corner):
    state = state_of(square(), shading=shading)
    assert (_square_pixels(state) == 0).all()     # the scene's light grazes the square
    state.lighting.set_headlight(True)
    lit = _square_pixels(state)
    assert abs(lit[20, 20] - centre) <= 1 and abs(lit[0, 0] - corner) <= 1
    assert "headlight on" in state.lighting.note


def test_the_headlight_follows_the_camera_and_the_inspector_sees_it():
    # The eye turned 60 degrees about y: flat lights the centroid with N . L = cos 60 = 0.5
    state = state_of(square())
    state.lighting.set_headlight(True)
    turned = (math.sin(math.radians(60)), 0.0, math.cos(math.radians(60)))
    state.views.set_hand_view(View(vrp=(0.0, 0.0, 0.0), vpn=turned, vup=(0.0, 1.0, 0.0),
                             window=VIEW.window, prp=(0.0, 0.0, 2.0), front=1.5, back=-1.5))
    pixels = _square_pixels(state)
    assert abs(pixels[20, 20] - 127.5) <= 1
    assert np.allclose(state.lighting.drawn_scene().lights[0].position, 2 * np.array(turned))
    state.lighting.set_headlight(False)
    assert _square_pixels(state)[20, 20] == 0 and state.lighting.drawn_scene() is state.scene


def test_the_global_illumination_renderers_keep_the_scenes_lights_and_say_so():
    state = state_of(square())
    state.lighting.set_headlight(True)
    state.choices.set_renderer("radiosity")
    assert "off for radiosity" in state.lighting.note
    assert state.lighting.drawn_scene() is state.scene
    assert state.lighting.note and not ViewerState(
        scene=state.scene, scene_source="square", size=(SIZE, SIZE)).lighting.note


# -- depth shading -----------------------------------------------------------------------------
def test_depth_shading_colours_by_the_distance_from_the_eye_and_by_height_on_request():
    # A floor (y = 0) seen from 45 degrees above: every point has the same height, so the
    # height map gives one colour; from the eye, the near (lower) rows are brighter.
    floor = Mesh(np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], dtype=np.float64),
                 triangles=[[0, 2, 1], [0, 3, 2]], material=WHITE, name="floor")
    above = View(vrp=(0.0, 0.0, 0.0), vpn=(0.0, 1.0, 1.0), vup=(0.0, 1.0, 0.0),
                 window=(-1.2, 1.2, -1.2, 1.2), prp=(0.0, 0.0, 3.0), front=2.0, back=-2.0)
    state = state_of(floor, shading="depth", view=above)
    assert state.choices.settings().depth_shading == "view"
    assert state.frames.update()
    column = state.frame.color[:, 20, 0].astype(int)
    covered = np.flatnonzero(np.isfinite(state.frame.depth[:, 20]))
    levels = column[covered]
    assert len(covered) > 10 and levels[-1] > levels[0] + 100
    assert (np.diff(levels) >= 0).all()               # brighter row by row towards the eye
    state.choices.set_depth_shading("height")
    assert state.frames.update()
    colours = state.frame.color[covered, 20]
    assert (colours == colours[0]).all()


# -- a frame of the old size after a resize ---------------------------------------------------
def test_a_frame_of_the_old_size_is_read_where_the_blit_stretches_it():
    # twice the size: picture texel t shows frame texel floor(t / 2)
    assert stretched((799, 599), (800, 600), (400, 300)) == (399, 299)
    assert stretched((3, 5), (800, 600), (400, 300)) == (1, 2)
    # 7 -> 5 columns: floor(t * 5 / 7) for t = 0..6 is 0 0 1 2 2 3 4
    assert [stretched((t, 0), (7, 1), (5, 1))[0] for t in range(7)] == [0, 0, 1, 2, 2, 3, 4]
    assert stretched((3, 5), (40, 40), (40, 40)) == (3, 5)       # the same size: itself
    assert stretched((-2, 5), (80, 80), (40, 40)) == (-2, 5)     # outside stays outside


def test_the_blit_stretches_an_old_frame_over_the_picture_as_the_readout_maps_it():
    from tools import llvmpipe_context, need_module
    moderngl = need_module("moderngl", "the blit needs moderngl")
    from app.viewer.blit import Blit
    ctx = llvmpipe_context()
    try:
        rng = np.random.default_rng(7)
        image = rng.integers(0, 256, size=(3, 5, 3), dtype=np.uint8)
        shown = (7, 4)
        fbo = ctx.simple_framebuffer(shown, components=4)
        fbo.use()
        blit = Blit(ctx)
        blit.upload(image)
        blit.draw(shown=shown)
        data = fbo.read(components=3, alignment=1)
        out = np.frombuffer(data, np.uint8).reshape(shown[1], shown[0], 3)[::-1]
        expected = np.array([[image[stretched((c, r), shown, (5, 3))[::-1]]
                              for c in range(shown[0])] for r in range(shown[1])])
        assert np.array_equal(out, expected)
        blit.release()
        fbo.release()
        del moderngl
    finally:
        ctx.release()


# -- saved views in the user's state folder -----------------------------------------------------
def test_saved_views_go_to_the_users_state_folder_made_for_its_owner(tmp_path, monkeypatch):
    from app.viewer.files import saved_views_file
    from app.viewer.hands import save_view
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    path = saved_views_file()
    assert path == tmp_path / "state" / "fvd-viewer" / "saved.views"
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700
    assert save_view(VIEW, path, "a test") == 1 and save_view(VIEW, path, "again") == 2
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the folder would go")
    monkeypatch.setenv("XDG_STATE_HOME", str(blocked))
    with pytest.raises(OSError):
        saved_views_file()
