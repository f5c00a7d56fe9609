"""The texture oracle: a textured mesh drawn by real OpenGL (Mesa llvmpipe through EGL).

Used only by the tests (issue 11): the same triangles, the same (u, v) per vertex, the same
world-to-clip matrix as the CPU core (:func:`app.tools.reference_gl.clip_from_world`) and the
same texels — every MIP level of :class:`core.texture.Texture` uploaded as it is (RGBA32F, so
neither side rounds texels to 8 bits) — with ``GL_NEAREST``, ``GL_LINEAR`` or
``GL_LINEAR_MIPMAP_LINEAR`` and the texture's wrap mode. The fragment shader writes the
filtered texel unlit into a float framebuffer, so the comparison is of the filtering alone.
"""

from __future__ import annotations

import moderngl
import numpy as np

from app.tools.reference_gl import clip_from_world
from core.texture import Texture

_VERTEX = """
#version 330
uniform mat4 clip_from_world;
in vec3 in_position;
in vec2 in_uv;
out vec2 uv;
void main() {
    uv = in_uv;
    gl_Position = clip_from_world * vec4(in_position, 1.0);
}
"""

_FRAGMENT = """
#version 330
uniform sampler2D tex;
in vec2 uv;
out vec4 frag_color;
void main() {
    frag_color = texture(tex, uv);
}
"""

FILTERS = {"nearest": (moderngl.NEAREST, moderngl.NEAREST),
           "bilinear": (moderngl.LINEAR, moderngl.LINEAR),
           "trilinear": (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)}


class TextureGL:
    """A standalone llvmpipe context with a float framebuffer of ``size``."""

    def __init__(self, size: tuple[int, int]) -> None:
        self.ctx = moderngl.create_standalone_context(backend="egl")
        self.size = (int(size[0]), int(size[1]))
        self.program = self.ctx.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
        self.fbo = self.ctx.framebuffer(
            color_attachments=[self.ctx.renderbuffer(self.size, components=4, dtype="f4")],
            depth_attachment=self.ctx.depth_renderbuffer(self.size))

    @property
    def renderer_name(self) -> str:
        return self.ctx.info["GL_RENDERER"]

    def _texture(self, texture: Texture, filter_name: str):
        base = texture.levels[0]
        tex = self.ctx.texture((base.shape[1], base.shape[0]), 4, dtype="f4")
        tex.build_mipmaps()                        # allocates the levels; then ours replace them
        for k, level in enumerate(texture.levels):
            tex.write(np.ascontiguousarray(level, dtype=np.float32).tobytes(), level=k)
        tex.filter = FILTERS[filter_name]
        tex.anisotropy = 1.0
        tex.repeat_x = tex.repeat_y = texture.wrap == "repeat"     # else GL_CLAMP_TO_EDGE
        return tex

    def render(self, positions: np.ndarray, triangles: np.ndarray, uv: np.ndarray,
               view, projection: str, texture: Texture, filter_name: str) -> np.ndarray:
        """``(H, W, 4)`` float32, row 0 the top; empty pixels are −1."""
        tex = self._texture(texture, filter_name)
        if texture.wrap not in ("repeat", "clamp"):
            raise ValueError("the oracle draws repeat and clamp only (moderngl has no mirror)")
        vertices = np.column_stack([positions, uv]).astype(np.float32)
        vbo = self.ctx.buffer(vertices.tobytes())
        ibo = self.ctx.buffer(np.ascontiguousarray(triangles, dtype=np.int32).tobytes())
        vao = self.ctx.vertex_array(self.program, [(vbo, "3f 2f", "in_position", "in_uv")],
                                    index_buffer=ibo)
        self.program["clip_from_world"].write(
            clip_from_world(view, projection, self.size).T.astype(np.float32).tobytes())
        try:
            self.fbo.use()
            self.fbo.clear(-1.0, -1.0, -1.0, -1.0, depth=1.0)
            self.ctx.enable(moderngl.DEPTH_TEST)
            tex.use(0)
            vao.render(moderngl.TRIANGLES)
            self.ctx.finish()
            data = self.fbo.read(components=4, dtype="f4", alignment=1)
        finally:
            for obj in (vao, vbo, ibo, tex):
                obj.release()
        width, height = self.size
        return np.frombuffer(data, dtype=np.float32).reshape(height, width, 4)[::-1].copy()

    def release(self) -> None:
        self.ctx.release()

