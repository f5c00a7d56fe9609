"""The GPU side shows exactly what the CPU drew: the blit and the ImGui backend, headless (EGL).

The blit must give back the CPU framebuffer bit for bit (row order and the 1-byte row alignment
of odd widths are the usual ways to get this wrong). Dear ImGui's OpenGL 3 renderer (the
binding's own, on our moderngl context) must put ImGui's rectangles where ImGui says, clipped
by its clip rectangles, at 1x, 2x (HiDPI) and fractional scales, and leave the GL state the
blit needs as it found it.
"""

from __future__ import annotations

import numpy as np
import pytest

from tools import llvmpipe_context, need_module                    # noqa: E402

moderngl = need_module("moderngl", "the blit needs moderngl")
imgui_bundle = need_module("imgui_bundle", "the window's panel needs Dear ImGui (imgui-bundle)")
imgui = imgui_bundle.imgui

from core.settings import RenderSettings
from app.viewer.blit import Blit, clear_around  # noqa: E402
from app.viewer.gui_backend import GuiRenderer, framebuffer_scale, set_display  # noqa: E402


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


# -- the ImGui renderer --------------------------------------------------------------------

@pytest.fixture
def gui(ctx):
    context = imgui.create_context()
    imgui.get_io().set_ini_filename(None)     # no imgui.ini left in the working directory
    renderer = GuiRenderer()
    yield renderer
    renderer.release()
    imgui.destroy_context(context)


def draw_gui(ctx, renderer, build, display=(200, 150), scale=1):
    """Run one ImGui frame with ``build()`` and draw it into a fresh black framebuffer."""
    io = imgui.get_io()
    fb_size = (round(display[0] * scale), round(display[1] * scale))
    set_display(io, display, fb_size)
    io.delta_time = 1.0 / 60.0
    renderer.new_frame()
    imgui.new_frame()
    build()
    imgui.render()
    fbo = ctx.simple_framebuffer(fb_size, components=4)
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 1.0)
    renderer.render(imgui.get_draw_data())
    image = read_image(fbo)
    fbo.release()
    return image


RED = 0xFF0000FF        # IM_COL32(255, 0, 0, 255): ImGui packs colours as A B G R bytes


def red_mask(image):
    return (image[:, :, 0] == 255) & (image[:, :, 1] == 0) & (image[:, :, 2] == 0)


@pytest.mark.parametrize("scale", [1, 2])
def test_imgui_rect_lands_where_imgui_puts_it(ctx, gui, scale):
    def build():
        imgui.get_background_draw_list().add_rect_filled((10, 20), (50, 30), RED)

    image = draw_gui(ctx, gui, build, scale=scale)
    expected = np.zeros(image.shape[:2], bool)
    expected[20 * scale:30 * scale, 10 * scale:50 * scale] = True
    assert np.array_equal(red_mask(image), expected)


@pytest.mark.parametrize("scale", [1, 2])
def test_imgui_clip_rect_becomes_scissor(ctx, gui, scale):
    # The clip rectangle (display points, y down) must cut the rectangle, y flipped correctly.
    def build():
        draw_list = imgui.get_background_draw_list()
        draw_list.push_clip_rect((20, 22), (40, 60))
        draw_list.add_rect_filled((10, 10), (50, 30), RED)
        draw_list.pop_clip_rect()

    image = draw_gui(ctx, gui, build, scale=scale)
    expected = np.zeros(image.shape[:2], bool)
    expected[22 * scale:30 * scale, 20 * scale:40 * scale] = True
    assert np.array_equal(red_mask(image), expected)


def test_imgui_window_draws_text_inside_its_rectangle(ctx, gui):
    def build():
        imgui.set_next_window_pos((30, 40))
        imgui.set_next_window_size((120, 60))
        imgui.begin("Panel")
        imgui.text("view 3 of 7 (100% of 50%d)")   # a '%' is text, not a format
        imgui.end()

    image = draw_gui(ctx, gui, build)
    lit = image.any(axis=2)
    inside = lit[40:100, 30:150]
    # The panel's background and title bar cover its rectangle; nothing is drawn outside it.
    assert inside.mean() > 0.9
    assert not lit[:40].any() and not lit[100:].any()
    assert not lit[:, :30].any() and not lit[:, 150:].any()
    # The text is drawn: the body holds pixels of two colours at least (text on background).
    body = image[70:100, 32:148].reshape(-1, 3)
    assert len(np.unique(body, axis=0)) > 2


def test_imgui_draws_many_vertices(ctx, gui):
    # Far more vertices than a first buffer holds: everything must still be drawn.
    def build():
        draw_list = imgui.get_background_draw_list()
        for i in range(4000):
            x, y = i % 200, (i // 200) % 150
            draw_list.add_rect_filled((x, y), (x + 1, y + 1), RED)

    image = draw_gui(ctx, gui, build)
    assert red_mask(image)[:20].all()


def test_the_blit_still_draws_after_the_gui(ctx, gui):
    # The GUI renderer restores the GL state it changed: the blit that follows it in the next
    # frame must still give back its picture bit for bit.
    draw_gui(ctx, gui, lambda: imgui.get_background_draw_list().add_rect_filled(
        (0, 0), (100, 100), RED))
    rng = np.random.default_rng(3)
    image = rng.integers(0, 256, size=(31, 45, 3), dtype=np.uint8)
    blit = Blit(ctx)
    assert np.array_equal(blit_through(ctx, blit, image), image)
    blit.release()


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
    # 401 points at 501/401 pixels a point: float32 makes the product 500.99997, and the
    # renderer truncates it to size its viewport: one pixel short would leave the last row and
    # column empty and shift the picture. framebuffer_scale rounds the scale up to 501.
    assert np.float32(401) * np.float32(framebuffer_scale(401, 501)) >= 501
    assert framebuffer_scale(401, 501) - 501 / 401 < 1e-6

    def build():
        draw_list = imgui.get_background_draw_list()
        draw_list.add_rect_filled((0, 0), (401, 401), RED)          # the whole display
        draw_list.push_clip_rect((0, 0), (401, 200.4))              # the top 250.4 pixels
        draw_list.add_rect_filled((0, 0), (401, 401), 0xFF00FF00)   # green
        draw_list.pop_clip_rect()

    image = draw_gui(ctx, gui, build, display=(401, 401), scale=501 / 401)
    assert image.shape[:2] == (501, 501)
    red, green = red_mask(image), (image == (0, 255, 0)).all(axis=2)
    assert (red | green).all()                  # every pixel, to the last row and column
    rows = np.flatnonzero(green.any(axis=1))
    # Dear ImGui's OpenGL 3 renderer truncates the scissor's bottom edge counted from the
    # framebuffer's bottom, so a clip edge at 250.4 pixels moves the band by up to a row.
    assert rows[0] <= 1 and rows[-1] - rows[0] == 249 and green[rows].all()


@pytest.mark.parametrize("points, pixels", [(1, 1), (400, 800), (401, 501), (333, 417),
                                            (1000, 1250), (7, 11)])
def test_framebuffer_scale_reaches_the_framebuffer(points, pixels):
    scale = np.float32(framebuffer_scale(points, pixels))
    assert np.float32(points) * scale >= pixels
    assert int(np.float32(points) * scale) == pixels           # and not a pixel more


def test_the_loupe_shows_each_pixel_as_a_block_of_one_colour(ctx):
    # Oracle: numpy indexing of the image by the loupe's mapping, worked out for the anchor
    # (the framebuffer pixel (13, 9) stays under the cursor at picture pixel (21, 17)).
    from app.viewer.loupe import Loupe
    rng = np.random.default_rng(8)
    image = rng.integers(0, 256, size=(40, 48, 3), dtype=np.uint8)
    blit = Blit(ctx)
    loupe = Loupe()
    loupe.texel = (13, 9)                      # as if zoomed round there before
    loupe.screen = (21, 17)
    loupe.magnification = 8
    blit.loupe(**loupe.uniforms())
    out = blit_through(ctx, blit, image)
    blit.release()
    rows, cols = np.mgrid[0:40, 0:48]
    src_c, src_r = 13 + (cols - 21) // 8, 9 + (rows - 17) // 8
    inside = (src_c >= 0) & (src_c < 48) & (src_r >= 0) & (src_r < 40)
    expected = np.zeros_like(image)
    expected[inside] = image[src_r[inside], src_c[inside]]
    assert np.array_equal(out, expected)
    assert np.array_equal(out[17, 21], image[9, 13])
    block = out[17:25, 21:29]             # the 8 x 8 block that starts at the anchor
    assert (block == image[9, 13]).all()
    assert loupe.texel_at(21, 17) == (13, 9) and loupe.texel_at(20, 16) == (12, 8)


def test_the_clear_leaves_the_picture_and_fills_the_rest(ctx):
    # A 40 x 30 window with a 25 x 20 picture at its top left: the strip beside the picture
    # and the strip below it take the colour; the picture's pixels keep what was there.
    fbo = ctx.simple_framebuffer((40, 30), components=4)
    fbo.use()
    fbo.clear(1.0, 0.0, 0.0, 1.0)
    clear_around(ctx, (40, 30), (25, 20), (0.0, 0.0, 1.0, 1.0))
    out = read_image(fbo)
    fbo.release()
    assert (out[:20, :25] == (255, 0, 0)).all()               # the picture: untouched
    assert (out[:, 25:] == (0, 0, 255)).all() and (out[20:, :] == (0, 0, 255)).all()
    assert ctx.scissor is None or tuple(ctx.scissor) == (0, 0, 40, 30)


def test_the_plain_copy_and_the_loupe_agree_at_magnification_one(ctx):
    # Two fragment shaders draw the picture: the plain copy (every frame) and the loupe's
    # (magnified or stretched). Forced through the loupe's shader, the plain frame must come
    # out the same, bit for bit.
    rng = np.random.default_rng(11)
    image = rng.integers(0, 256, size=(37, 53, 3), dtype=np.uint8)
    blit = Blit(ctx)
    plain = blit_through(ctx, blit, image)
    blit.magnify = 0                # not 1: draw() takes the loupe's program, uniforms at 1
    through_loupe = blit_through(ctx, blit, image)
    blit.release()
    assert np.array_equal(plain, image) and np.array_equal(through_loupe, image)


@pytest.mark.parametrize("window", [(60, 50), (1580, 1080)])
def test_the_plain_copy_fills_its_viewport_at_the_window_top_left_and_nothing_else(ctx, window):
    # The window draws the picture at its top left, with the viewport set to the picture's
    # rectangle (app.viewer.loop): the copy's rectangle covers that viewport exactly, each
    # pixel its own texel, and leaves the rest of the window as it was.
    fb_w, fb_h = window
    width, height = fb_w * 2 // 3 + 1, fb_h // 2 + 3
    image = np.random.default_rng(fb_w).integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    fbo = ctx.simple_framebuffer(window, components=4)
    fbo.use()
    fbo.clear(0.0, 1.0, 0.0, 1.0)
    blit = Blit(ctx)
    blit.upload(image)
    ctx.viewport = (0, fb_h - height, width, height)
    blit.draw((0, fb_h - height))
    out = read_image(fbo)
    blit.release()
    fbo.release()
    assert np.array_equal(out[:height, :width], image)
    assert (out[height:] == (0, 255, 0)).all() and (out[:, width:] == (0, 255, 0)).all()
