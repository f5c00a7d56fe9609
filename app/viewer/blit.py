"""The blit: shows the CPU framebuffer on the GPU, texel for pixel, and nothing more.

Takes the renderer's ``Frame.color`` — an ``(H, W, 3)`` uint8 numpy image, row 0 at the top —
uploads it into a texture of the same size (NEAREST filtering, recreated when the size
changes) and draws it: the plain copy is a rectangle over the picture's area whose fragment
shader reads the texel under each pixel's centre (``shaders/copy.vert`` with
``shaders/copy.frag``); when the loupe magnifies or a resized window stretches the last frame,
one oversized triangle whose fragment shader works out the texel from ``gl_FragCoord``
(``shaders/blit.vert`` with ``shaders/blit.frag``). Depth test and blending are
off: every pixel on screen is exactly the pixel our CPU pipeline wrote. No geometry, no
transform, no lighting happens here (FvDFH's frame buffer, shown by a video controller).
"""

from __future__ import annotations

import moderngl
import numpy as np

from core.paths import SHADERS_DIR


def load_program(ctx: moderngl.Context, name: str) -> moderngl.Program:
    """The program ``shaders/<name>.vert`` + ``shaders/<name>.frag``."""
    return ctx.program(
        vertex_shader=(SHADERS_DIR / f"{name}.vert").read_text(),
        fragment_shader=(SHADERS_DIR / f"{name}.frag").read_text(),
    )


def clear_around(ctx: moderngl.Context, window: tuple[int, int], picture: tuple[int, int],
                 colour: tuple[float, float, float, float]) -> None:
    """Clear what a picture at the window's top left leaves of it: the strip beside it and
    the one below. The picture's own pixels are all drawn by the blit; clearing them as well
    cost llvmpipe 2 ms a frame at 1920 x 1050."""
    (fb_w, fb_h), (width, height) = window, (min(picture[0], window[0]),
                                             min(picture[1], window[1]))
    for rect in ((width, 0, fb_w - width, fb_h), (0, 0, width, fb_h - height)):
        if rect[2] > 0 and rect[3] > 0:
            ctx.scissor = rect
            ctx.clear(*colour)
    ctx.scissor = None


# The plain copy's two triangles over the viewport, in clip space (counter-clockwise).
COPY_RECTANGLE = np.array([-1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1], np.float32)


class Blit:
    """Uploads a CPU image and draws it into the bound framebuffer, pixel (0, 0) bottom-left."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self.program = load_program(ctx, "blit")
        self.program["frame"].value = 0
        self.magnify = 1
        self.loupe(1, (0, 0), (0, 0))
        # No buffers: the vertex shader places the triangle from gl_VertexID.
        self.vao = ctx.vertex_array(self.program, [])
        # the plain copy's program, made at the first draw: only a window draws (a bench that
        # times the uploads on the OpenGL oracle's context made llvmpipe draw the oracle's
        # Phong frames 100 times slower with a second program there; not understood)
        self.copy = self.copy_vao = self.copy_corners = None
        self.texture: moderngl.Texture | None = None

    @property
    def size(self) -> tuple[int, int] | None:
        """(width, height) of the image last uploaded, or None before the first."""
        return None if self.texture is None else self.texture.size

    def upload(self, color: np.ndarray) -> None:
        """Write a new frame; the texture is recreated only when the size or layout changes.

        ``color`` is ``(H, W, 3)`` RGB or ``(H, W, 4)`` with a padding byte per pixel
        (``Frame.rgbx``): the second is one aligned copy, ten times quicker on llvmpipe.
        """
        if color.ndim != 3 or color.shape[2] not in (3, 4) or color.dtype != np.uint8:
            raise ValueError(f"expected an (H, W, 3) or (H, W, 4) uint8 image, got "
                             f"{color.shape} {color.dtype}")
        height, width, components = color.shape
        if (self.texture is None or self.texture.size != (width, height)
                or self.texture.components != components):
            if self.texture is not None:
                self.texture.release()
            # alignment=1: rows of 3*W bytes need not be a multiple of 4 (odd widths).
            self.texture = self.ctx.texture((width, height), components, dtype="f1",
                                            alignment=1)
            self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self.texture.repeat_x = self.texture.repeat_y = False
        # Image row 0 goes to texture row 0; the fragment shader flips rows when it fetches.
        self.texture.write(np.ascontiguousarray(color))

    def loupe(self, magnify: int, screen_anchor: tuple[int, int],
              texel_anchor: tuple[int, int]) -> None:
        """Magnify the picture by a whole number, nearest neighbour: picture pixel q shows
        framebuffer pixel ``texel_anchor + floor((q - screen_anchor) / magnify)`` (rows from
        the top; app.viewer.loupe). 1 is the plain copy."""
        self.magnify = max(int(magnify), 1)
        self.program["magnify"].value = self.magnify
        self.program["screen_anchor"].value = tuple(int(c) for c in screen_anchor)
        self.program["texel_anchor"].value = tuple(int(c) for c in texel_anchor)

    def draw(self, origin: tuple[int, int] = (0, 0),
             shown: tuple[int, int] | None = None) -> None:
        """Draw the last uploaded frame over the current viewport (does nothing before one),
        its bottom-left pixel at window pixel ``origin`` (set the viewport to the same rect).
        ``shown``: the size of the area it fills, when it is not the frame's own (a resized
        window whose new frame is not there yet): the frame is stretched over it, nearest
        neighbour (:func:`app.viewer.loupe.stretched`)."""
        if self.texture is None:
            return
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND | moderngl.CULL_FACE)
        width, height = shown if shown is not None else self.texture.size
        self.texture.use(location=0)
        origin = (int(origin[0]), int(origin[1]))
        if self.magnify == 1 and (width, height) == self.texture.size:
            if self.copy is None:
                self.copy = load_program(self.ctx, "copy")
                self.copy["frame"].value = 0
                self.copy_corners = self.ctx.buffer(COPY_RECTANGLE.tobytes())
                self.copy_vao = self.ctx.vertex_array(
                    self.copy, [(self.copy_corners, "2f", "corner")])
            self.copy_vao.render(moderngl.TRIANGLES)      # the plain copy: every other frame
            return
        self.program["origin"].value = origin
        self.program["shown"].value = (max(int(width), 1), max(int(height), 1))
        self.vao.render(moderngl.TRIANGLES, vertices=3)

    def release(self) -> None:
        if self.texture is not None:
            self.texture.release()
            self.texture = None
        self.vao.release()
        self.program.release()
        if self.copy is not None:
            self.copy_vao.release()
            self.copy_corners.release()
            self.copy.release()
