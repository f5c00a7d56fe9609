"""The GPU side shows exactly what the CPU drew: the blit and the ImGui backend, headless (EGL).

The blit must give back the CPU framebuffer bit for bit (row order and the 1-byte row alignment
of odd widths are the usual ways to get this wrong). The ImGui backend must put ImGui's
rectangles where ImGui says, clipped by its clip rectangles, at 1x and at 2x (HiDPI) scale.
"""

from __future__ import annotations

import numpy as np
import pytest

from tools import llvmpipe_context, need_module                    # noqa: E402

moderngl = need_module("moderngl", "the blit needs moderngl")
imgui = need_module("imgui", "the window's panel needs Dear ImGui's bindings")

from core.settings import RenderSettings
from app.viewer.blit import Blit  # noqa: E402
from app.viewer.imgui_backend import ImGuiRenderer, draw_commands  # noqa: E402


@pytest.fixture(scope="module")
def ctx():
    context = llvmpipe_context()
    yield context
    context.release()


def read_image(fbo: moderngl.Framebuffer) -> np.ndarray:
    """The framebuffer as an (H, W, 3) image, row 0 at the top (GL reads bottom row first)."""
    width, height = fbo.size
    data = fbo.read(components=3, alignment=1)
    return np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1]


def blit_through(ctx, blit: Blit, image: np.ndarray) -> np.ndarray:
    height, width = image.shape[:2]
    fbo = ctx.simple_framebuffer((width, height), components=4)
    fbo.use()
    fbo.clear(0.5, 0.5, 0.5, 1.0)
    blit.upload(image)
    blit.draw()
    out = read_image(fbo)
    fbo.release()
    return out


@pytest.mark.parametrize("size", [(500, 500), (333, 217), (1, 1), (7, 3)])
def test_blit_is_bit_exact(ctx, size):
    width, height = size
    rng = np.random.default_rng(width * 1000 + height)
    image = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    blit = Blit(ctx)
    out = blit_through(ctx, blit, image)
    blit.release()
    assert out.shape == image.shape
    differ = np.count_nonzero((out != image).any(axis=2))
    assert differ == 0, f"{differ} pixels differ"


def test_blit_keeps_row_order(ctx):
    # Row 0 of the image is the top of the screen: a top half red, bottom half blue image.
    image = np.zeros((10, 4, 3), np.uint8)
    image[:5] = (255, 0, 0)
    image[5:] = (0, 0, 255)
    blit = Blit(ctx)
    out = blit_through(ctx, blit, image)
    blit.release()
    assert (out[0, 0] == (255, 0, 0)).all() and (out[-1, 0] == (0, 0, 255)).all()


def test_blit_recreates_texture_on_resize(ctx):
    blit = Blit(ctx)
    rng = np.random.default_rng(7)
    for width, height in [(64, 48), (64, 48), (333, 217), (17, 5)]:
        image = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
        assert np.array_equal(blit_through(ctx, blit, image), image)
        assert blit.size == (width, height)
    blit.release()


def test_blit_rejects_wrong_image(ctx):
    blit = Blit(ctx)
    with pytest.raises(ValueError, match="uint8"):
        blit.upload(np.zeros((4, 4, 3), np.float64))
    with pytest.raises(ValueError, match="uint8"):
        blit.upload(np.zeros((4, 4), np.uint8))
    blit.release()


# -- the ImGui backend --------------------------------------------------------------------

@pytest.fixture
def gui(ctx):
    context = imgui.create_context()
    imgui.get_io().ini_file_name = None       # no imgui.ini left in the working directory
    renderer = ImGuiRenderer(ctx)
    yield renderer
    renderer.release()
    imgui.destroy_context(context)


def draw_gui(ctx, renderer, build, display=(200, 150), scale=1):
    """Run one ImGui frame with ``build()`` and draw it into a fresh black framebuffer."""
    io = imgui.get_io()
    io.display_size = display
    io.display_fb_scale = (scale, scale)
    io.delta_time = 1.0 / 60.0
    imgui.new_frame()
    build()
    imgui.render()
    fbo = ctx.simple_framebuffer((display[0] * scale, display[1] * scale), components=4)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 1.0)
    draw_data = imgui.get_draw_data()
    renderer.render(draw_data)
    image = read_image(fbo)
    fbo.release()
    return image, draw_data


RED = 0xFF0000FF        # IM_COL32(255, 0, 0, 255): ImGui packs colours as A B G R bytes


def red_mask(image):
    return (image[:, :, 0] == 255) & (image[:, :, 1] == 0) & (image[:, :, 2] == 0)


@pytest.mark.parametrize("scale", [1, 2])
def test_imgui_rect_lands_where_imgui_puts_it(ctx, gui, scale):
    def build():
        imgui.get_background_draw_list().add_rect_filled(10, 20, 50, 30, RED)

    image, _ = draw_gui(ctx, gui, build, scale=scale)
    expected = np.zeros(image.shape[:2], bool)
    expected[20 * scale:30 * scale, 10 * scale:50 * scale] = True
    assert np.array_equal(red_mask(image), expected)


@pytest.mark.parametrize("scale", [1, 2])
def test_imgui_clip_rect_becomes_scissor(ctx, gui, scale):
    # The clip rectangle (display points, y down) must cut the rectangle, y flipped correctly.
    def build():
        draw_list = imgui.get_background_draw_list()
        draw_list.push_clip_rect(20, 22, 40, 60)
        draw_list.add_rect_filled(10, 10, 50, 30, RED)
        draw_list.pop_clip_rect()

    image, _ = draw_gui(ctx, gui, build, scale=scale)
    expected = np.zeros(image.shape[:2], bool)
    expected[22 * scale:30 * scale, 20 * scale:40 * scale] = True
    assert np.array_equal(red_mask(image), expected)


def test_imgui_window_draws_text_inside_its_rectangle(ctx, gui):
    def build():
        imgui.set_next_window_position(30, 40)
        imgui.set_next_window_size(120, 60)
        imgui.begin("Panel")
        imgui.text("view 3 of 7")
        imgui.end()

    image, draw_data = draw_gui(ctx, gui, build)
    lit = image.any(axis=2)
    inside = lit[40:100, 30:150]
    # The panel's background and title bar cover its rectangle; nothing is drawn outside it.
    assert inside.mean() > 0.9
    assert not lit[:40].any() and not lit[100:].any()
    assert not lit[:, :30].any() and not lit[:, 150:].any()
    # Several draw commands (window, title, text), each starting at its own index offset.
    commands = np.concatenate([draw_commands(dl) for dl in draw_data.commands_lists])
    assert len(commands) >= 2
    for draw_list in draw_data.commands_lists:
        records = draw_commands(draw_list)
        assert list(records["elem_count"]) == [c.elem_count for c in draw_list.commands]
        assert list(records["idx_offset"]) == list(np.cumsum([0, *records["elem_count"][:-1]]))
        assert records["elem_count"].sum() == draw_list.idx_buffer_size


def test_imgui_buffers_grow(ctx, gui):
    # Far more vertices than the initial buffers hold: everything must still be drawn.
    def build():
        draw_list = imgui.get_background_draw_list()
        for i in range(4000):
            x, y = i % 200, (i // 200) % 150
            draw_list.add_rect_filled(x, y, x + 1, y + 1, RED)

    image, _ = draw_gui(ctx, gui, build)
    assert red_mask(image)[:20].all()


def test_a_rendered_frame_round_trips_through_its_padded_upload(ctx):
    # The viewer uploads Frame.rgbx (a padding byte per pixel); what comes back from the screen
    # must still be Frame.color, bit for bit, at an odd size.
    from core.scene.formats import load_scene
    from core.paths import SCENES_DIR
    from core.render import render

    torus = load_scene(SCENES_DIR / "torus.toml")
    frame = render(torus, torus.views[0], RenderSettings(shading="gouraud", size=(333, 217)))
    assert frame.rgbx.shape == (217, 333, 4)
    blit = Blit(ctx)
    assert np.array_equal(blit_through(ctx, blit, frame.rgbx), frame.color)
    blit.release()


def test_imgui_at_a_fractional_scale_fills_the_framebuffer_to_its_last_row(ctx, gui):
    # 401 points at 501/401 pixels a point: float32 makes the product 500.99997. The scissor's
    # y flip counts from the framebuffer's top, so a height one pixel short shifts it by one.
    io = imgui.get_io()
    io.display_size = (401, 401)
    io.display_fb_scale = (501 / 401, 501 / 401)
    io.delta_time = 1.0 / 60.0
    imgui.new_frame()
    draw_list = imgui.get_background_draw_list()
    draw_list.push_clip_rect(0, 0, 401, 200.4)              # the top 250 framebuffer rows
    draw_list.add_rect_filled(0, 0, 401, 401, RED)
    draw_list.pop_clip_rect()
    imgui.render()
    fbo = ctx.simple_framebuffer((501, 501), components=4)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 1.0)
    gui.render(imgui.get_draw_data())
    rows = np.flatnonzero(red_mask(read_image(fbo)).any(axis=1))
    fbo.release()
    assert rows[0] == 0 and rows[-1] == 249
