"""A small Dear ImGui backend: draws pyimgui's draw lists with moderngl and feeds it glfw input.

pyimgui 2.0 wraps Dear ImGui 1.82. Its own glfw integration pulls in PyOpenGL; this one uses
the moderngl context we already have.

- :class:`ImGuiRenderer` takes ``imgui.get_draw_data()`` after ``imgui.render()`` and draws it:
  one program (``shaders/imgui.vert``/``.frag``: a ``ProjMtx`` uniform and a sampler), vertices
  of 2 floats position, 2 floats UV and 4 normalised bytes colour, a vertex and an index buffer
  refilled each frame (grown when a frame needs more), alpha blending, and a scissor rectangle
  per draw command (y flipped, scaled by the framebuffer scale for HiDPI). Each command is drawn
  from its own index offset; its vertex offset is added to its indices.
- :class:`GlfwInput` turns glfw callbacks into ImGui's io (display size, framebuffer scale,
  delta time, mouse position, buttons and wheel, keys and characters). The window owns the glfw
  callbacks and forwards each event here first, then asks ``io.want_capture_*`` whether the
  event was ImGui's.
"""

from __future__ import annotations

import ctypes

import imgui
import moderngl
import numpy as np

from app.viewer.blit import load_program

# ImDrawCmd of Dear ImGui 1.82 as laid out in memory (64-bit): pyimgui exposes only
# clip_rect, texture_id and elem_count, so the offsets are read from the command buffer.
_DRAW_CMD = np.dtype({
    "names": ["clip_rect", "texture_ptr", "vtx_offset", "idx_offset", "elem_count",
              "user_callback", "user_callback_data"],
    "formats": [("<f4", 4), "<u8", "<u4", "<u4", "<u4", "<u8", "<u8"],
    "offsets": [0, 16, 24, 28, 32, 40, 48],
    "itemsize": 56,
})
_INDEX_DTYPE = np.uint32 if imgui.INDEX_SIZE == 4 else np.uint16


def _raw_bytes(address: int, count: int) -> bytes:
    return ctypes.string_at(address, count) if count else b""


def draw_commands(draw_list) -> np.ndarray:
    """The draw list's commands as a structured array of :data:`_DRAW_CMD` records."""
    n = draw_list.cmd_buffer_size
    return np.frombuffer(_raw_bytes(draw_list.cmd_buffer_data, n * _DRAW_CMD.itemsize),
                         dtype=_DRAW_CMD, count=n)


class ImGuiRenderer:
    """Renders Dear ImGui draw data into the currently bound framebuffer."""

    def __init__(self, ctx: moderngl.Context):
        if not imgui.get_current_context():
            raise RuntimeError("create the ImGui context (imgui.create_context()) first")
        self.ctx = ctx
        self.io = imgui.get_io()
        self.program = load_program(ctx, "imgui")
        self.program["Texture"].value = 0
        self._textures: dict[int, moderngl.Texture] = {}
        self._vbo = ctx.buffer(reserve=64 * 1024, dynamic=True)
        self._ibo = ctx.buffer(reserve=32 * 1024, dynamic=True)
        self._make_vao()
        self.refresh_font_texture()

    def _make_vao(self) -> None:
        self._vao = self.ctx.vertex_array(
            self.program,
            [(self._vbo, "2f 2f 4f1", "Position", "UV", "Color")],   # f1: normalised ubyte
            index_buffer=self._ibo,
            index_element_size=imgui.INDEX_SIZE,
        )

    def refresh_font_texture(self) -> None:
        """Build the font atlas texture and hand its id to ImGui."""
        width, height, pixels = self.io.fonts.get_tex_data_as_rgba32()
        old = self._textures.pop(getattr(self, "_font_id", -1), None)
        if old is not None:
            old.release()
        font = self.ctx.texture((width, height), 4, data=pixels)
        font.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._font_id = self.register_texture(font)
        self.io.fonts.texture_id = self._font_id
        self.io.fonts.clear_tex_data()

    def register_texture(self, texture: moderngl.Texture) -> int:
        """Make a texture drawable by ImGui (``imgui.image``); returns its texture id."""
        self._textures[texture.glo] = texture
        return texture.glo

    def _fill(self, buffer: moderngl.Buffer, data: bytes) -> moderngl.Buffer:
        """Write ``data`` into ``buffer``, growing it (doubling) when it is too small."""
        if len(data) > buffer.size:
            buffer.orphan(max(len(data), 2 * buffer.size))
            # orphan() reallocates the same buffer object, so the vertex array stays valid.
        buffer.write(data)
        return buffer

    def render(self, draw_data) -> None:
        """Draw ``draw_data`` with the viewport set to the whole framebuffer."""
        display_x, display_y = draw_data.display_pos
        display_w, display_h = draw_data.display_size
        scale_x, scale_y = draw_data.frame_buffer_scale
        # rounded, not truncated: ImGui keeps these in float32, so 401 points at 501/401 is
        # 499.99997 and int() would draw the GUI one pixel short
        fb_width, fb_height = round(display_w * scale_x), round(display_h * scale_y)
        if fb_width <= 0 or fb_height <= 0:
            return

        ctx = self.ctx
        ctx.viewport = (0, 0, fb_width, fb_height)
        ctx.enable_only(moderngl.BLEND)        # no depth test, no culling
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA,
                          moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA)

        # Orthographic projection of display points onto clip space, y down (column-major).
        left, right = display_x, display_x + display_w
        top, bottom = display_y, display_y + display_h
        projection = np.array([
            [2.0 / (right - left), 0.0, 0.0, 0.0],
            [0.0, 2.0 / (top - bottom), 0.0, 0.0],
            [0.0, 0.0, -1.0, 0.0],
            [(right + left) / (left - right), (top + bottom) / (bottom - top), 0.0, 1.0],
        ], dtype="f4")
        self.program["ProjMtx"].write(projection.tobytes())

        try:
            for draw_list in draw_data.commands_lists:
                self._fill(self._vbo, _raw_bytes(draw_list.vtx_buffer_data,
                                                 draw_list.vtx_buffer_size * imgui.VERTEX_SIZE))
                indices = np.frombuffer(
                    _raw_bytes(draw_list.idx_buffer_data,
                               draw_list.idx_buffer_size * imgui.INDEX_SIZE),
                    dtype=_INDEX_DTYPE).copy()
                commands = draw_commands(draw_list)
                # A command may start at a vertex offset; fold it into its indices so that one
                # vertex buffer serves every command (moderngl has no base-vertex draw).
                for cmd in commands[commands["vtx_offset"] != 0]:
                    start, count = int(cmd["idx_offset"]), int(cmd["elem_count"])
                    indices[start:start + count] += _INDEX_DTYPE(cmd["vtx_offset"])
                self._fill(self._ibo, indices.tobytes())

                # texture_id comes from pyimgui's own command objects: it stores the Python
                # object we gave it (our int id), the raw record holds only its address.
                for cmd, texture_id in zip(commands, (c.texture_id for c in draw_list.commands)):
                    if cmd["user_callback"]:
                        continue          # no callbacks are registered by this program
                    count = int(cmd["elem_count"])
                    if count == 0:
                        continue
                    x1, y1, x2, y2 = cmd["clip_rect"]
                    # Clip rectangle in framebuffer pixels, with GL's y axis pointing up.
                    cx1 = max(int((x1 - display_x) * scale_x), 0)
                    cy1 = max(int((y1 - display_y) * scale_y), 0)
                    cx2 = min(int((x2 - display_x) * scale_x), fb_width)
                    cy2 = min(int((y2 - display_y) * scale_y), fb_height)
                    if cx2 <= cx1 or cy2 <= cy1:
                        continue
                    ctx.scissor = (cx1, fb_height - cy2, cx2 - cx1, cy2 - cy1)
                    texture = self._textures.get(texture_id)
                    if texture is None:
                        continue          # an id nobody registered: draw nothing, not garbage
                    texture.use(location=0)
                    self._vao.render(moderngl.TRIANGLES, vertices=count,
                                     first=int(cmd["idx_offset"]))
        finally:
            ctx.scissor = None
            ctx.disable(moderngl.BLEND)

    def release(self) -> None:
        for texture in self._textures.values():
            texture.release()
        self._textures.clear()
        self._vao.release()
        self._vbo.release()
        self._ibo.release()
        self.program.release()


class GlfwInput:
    """Feeds one glfw window's input to ImGui's io; call :meth:`new_frame` before ImGui's.

    A mouse press and release that arrive between two frames would be invisible to a renderer
    that polls button state, so presses are latched until the next frame has seen them.
    """

    def __init__(self, window):
        import glfw                      # only the window needs glfw; the renderer does not

        self._glfw = glfw
        self.window = window
        self.io = imgui.get_io()
        self._time = None
        self._just_pressed = [False] * 5
        self._press_pos = (0.0, 0.0)
        self._map_keys()

    def _map_keys(self) -> None:
        glfw = self._glfw
        key_map = self.io.key_map
        for imgui_key, glfw_key in (
            (imgui.KEY_TAB, glfw.KEY_TAB), (imgui.KEY_LEFT_ARROW, glfw.KEY_LEFT),
            (imgui.KEY_RIGHT_ARROW, glfw.KEY_RIGHT), (imgui.KEY_UP_ARROW, glfw.KEY_UP),
            (imgui.KEY_DOWN_ARROW, glfw.KEY_DOWN), (imgui.KEY_PAGE_UP, glfw.KEY_PAGE_UP),
            (imgui.KEY_PAGE_DOWN, glfw.KEY_PAGE_DOWN), (imgui.KEY_HOME, glfw.KEY_HOME),
            (imgui.KEY_END, glfw.KEY_END), (imgui.KEY_INSERT, glfw.KEY_INSERT),
            (imgui.KEY_DELETE, glfw.KEY_DELETE), (imgui.KEY_BACKSPACE, glfw.KEY_BACKSPACE),
            (imgui.KEY_SPACE, glfw.KEY_SPACE), (imgui.KEY_ENTER, glfw.KEY_ENTER),
            (imgui.KEY_ESCAPE, glfw.KEY_ESCAPE), (imgui.KEY_PAD_ENTER, glfw.KEY_KP_ENTER),
            (imgui.KEY_A, glfw.KEY_A), (imgui.KEY_C, glfw.KEY_C), (imgui.KEY_V, glfw.KEY_V),
            (imgui.KEY_X, glfw.KEY_X), (imgui.KEY_Y, glfw.KEY_Y), (imgui.KEY_Z, glfw.KEY_Z),
        ):
            key_map[imgui_key] = glfw_key

    # -- events, forwarded by the window's glfw callbacks ------------------------------------
    def on_key(self, key: int, action: int, mods: int) -> None:
        glfw, io = self._glfw, self.io
        if 0 <= key < 512:
            if action == glfw.PRESS:
                io.keys_down[key] = True
            elif action == glfw.RELEASE:
                io.keys_down[key] = False
        io.key_ctrl = bool(mods & glfw.MOD_CONTROL)
        io.key_shift = bool(mods & glfw.MOD_SHIFT)
        io.key_alt = bool(mods & glfw.MOD_ALT)
        io.key_super = bool(mods & glfw.MOD_SUPER)

    def on_char(self, codepoint: int) -> None:
        if 0 < codepoint < 0x10000:
            self.io.add_input_character(codepoint)

    def on_scroll(self, x_offset: float, y_offset: float) -> None:
        self.io.mouse_wheel_horizontal += x_offset
        self.io.mouse_wheel += y_offset

    def on_mouse_button(self, button: int, action: int) -> None:
        if action == self._glfw.PRESS and 0 <= button < len(self._just_pressed):
            self._just_pressed[button] = True
            # Where the press happened: the pointer may have moved on before the next frame
            # (a slow frame), and ImGui must judge the click where it was made.
            self._press_pos = self._glfw.get_cursor_pos(self.window)

    # -- once per frame ----------------------------------------------------------------------
    def new_frame(self) -> None:
        """Display size, framebuffer scale, time step, mouse position and buttons."""
        glfw, io = self._glfw, self.io
        window_w, window_h = glfw.get_window_size(self.window)
        fb_w, fb_h = glfw.get_framebuffer_size(self.window)
        io.display_size = window_w, window_h
        if window_w > 0 and window_h > 0:
            io.display_fb_scale = fb_w / window_w, fb_h / window_h

        now = glfw.get_time()
        io.delta_time = max(now - self._time, 1e-4) if self._time is not None else 1.0 / 60.0
        self._time = now

        # The cursor position is used whether or not the window has the keyboard focus: a
        # window without a window manager (Xvfb) never gets it.
        if any(self._just_pressed):
            io.mouse_pos = self._press_pos
        elif glfw.get_window_attrib(self.window, glfw.HOVERED):
            io.mouse_pos = glfw.get_cursor_pos(self.window)
        else:
            io.mouse_pos = -float("inf"), -float("inf")   # ImGui's "no mouse"
        for button in range(3):
            io.mouse_down[button] = (self._just_pressed[button]
                                     or glfw.get_mouse_button(self.window, button) == glfw.PRESS)
        self._just_pressed = [False] * 5
