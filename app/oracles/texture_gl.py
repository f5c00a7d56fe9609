"""The texture oracle: a textured mesh drawn by real OpenGL (Mesa llvmpipe through EGL).

Used only by the tests: the same triangles, the same (u, v) per vertex, the same
world-to-clip matrix as the CPU core (:func:`app.oracles.reference_gl.clip_from_world`) and the
same texels — every MIP level of :class:`core.texture.Texture` uploaded as it is (RGBA32F, so
neither side rounds texels to 8 bits) — with ``GL_NEAREST``, ``GL_LINEAR`` or
``GL_LINEAR_MIPMAP_LINEAR`` and the texture's wrap mode. The fragment shader writes the
filtered texel unlit into a float framebuffer, so the comparison is of the filtering alone.
"""

from __future__ import annotations

import moderngl
import numpy as np

from app.oracles.reference_gl import clip_from_world
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
uniform bool encode_srgb;
in vec2 uv;
out vec4 frag_color;
vec3 srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
void main() {
    vec4 t = texture(tex, uv);
    frag_color = encode_srgb ? vec4(srgb(t.rgb), t.a) : t;
}
"""

FILTERS = {"nearest": (moderngl.NEAREST, moderngl.NEAREST),
           "bilinear": (moderngl.LINEAR, moderngl.LINEAR),
           "trilinear": (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)}


class TextureGL:
    """A standalone llvmpipe context with a float framebuffer of ``size``."""

    def __init__(self, size: tuple[int, int], ctx=None) -> None:
        self.ctx = ctx or moderngl.create_standalone_context(backend="egl")
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
               view, projection: str, texture: Texture, filter_name: str,
               encode_srgb: bool = False) -> np.ndarray:
        """``(H, W, 4)`` float32, row 0 the top; empty pixels are −1. ``encode_srgb``: the
        filtered colour is sRGB-encoded, as the CPU's shader does for an sRGB texture."""
        tex = self._texture(texture, filter_name)
        if texture.wrap not in ("repeat", "clamp"):
            raise ValueError("the oracle draws repeat and clamp only (moderngl has no mirror)")
        vertices = np.column_stack([positions, uv]).astype(np.float32)
        vbo = self.ctx.buffer(vertices.tobytes())
        ibo = self.ctx.buffer(np.ascontiguousarray(triangles, dtype=np.int32).tobytes())
        vao = self.ctx.vertex_array(self.program, [(vbo, "3f 2f", "in_position", "in_uv")],
                                    index_buffer=ibo)
        self.program["encode_srgb"].value = bool(encode_srgb)
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



# --------------------------------------------------------------------------------------------
# Textured Phong in GLSL, for the bench: the project's lighting GLSL (app/oracles/reference_gl.py)
# with O_d from the texture (trilinear, our MIP chain, sRGB encoded back as our shader does).

def _textured_phong_program(ctx):
    from app.oracles.reference_gl import _DISCARD_GLSL, _LIGHTING_GLSL
    lighting = _LIGHTING_GLSL.replace("uniform vec3 od;", "vec3 od;     // from the texture")
    vertex = """
#version 330
uniform mat4 clip_from_world;
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 world_position;
out vec3 world_normal;
out vec2 uv;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
    world_position = in_position;
    world_normal = in_normal;
    uv = in_uv;
}
"""
    fragment = """
#version 330
%s
%s
uniform sampler2D tex;
in vec3 world_position;
in vec3 world_normal;
in vec2 uv;
out vec4 frag_color;
vec3 srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
void main() {
    clip_to_viewport();
    od = srgb(texture(tex, uv).rgb);
    frag_color = vec4(illuminate(world_position, unit(world_normal)), 1.0);
}
""" % (_DISCARD_GLSL, lighting)
    return ctx.program(vertex_shader=vertex, fragment_shader=fragment)


class TexturedPhongGL:
    """llvmpipe drawing a scene whose meshes have (u, v) and a colour texture, textured Phong
    with GL_LINEAR_MIPMAP_LINEAR; geometry and textures uploaded once (:meth:`load`)."""

    def __init__(self, size: tuple[int, int]) -> None:
        from app.oracles.reference_gl import GLRenderer
        self.gl = GLRenderer(size)            # its context, framebuffer and uniform setters
        self.program = _textured_phong_program(self.gl.ctx)
        self._objects: list = []
        self._draws: list = []

    def load(self, scene) -> None:
        from core.scene.normals import vertex_normals
        from core.texture.material import maps_of
        self.gl.scene = scene
        ctx = self.gl.ctx
        for mesh in scene.meshes:
            maps = maps_of(mesh.material)
            if not len(mesh.triangles) or maps is None or maps.color is None or mesh.uv is None:
                raise ValueError(f"{mesh.name}: the textured GL bench needs (u, v) and a texture")
            normals = mesh.normals if mesh.normals is not None else vertex_normals(mesh)
            data = np.column_stack([mesh.positions, normals,
                                    mesh.uv * np.asarray(maps.uv_scale)]).astype("f4")
            vbo = ctx.buffer(data.tobytes())
            ibo = ctx.buffer(mesh.triangles.astype("i4").tobytes())
            vao = ctx.vertex_array(self.program, [(vbo, "3f 3f 2f", "in_position", "in_normal",
                                                   "in_uv")], ibo)
            tex = ctx.texture(maps.color.size, 4, dtype="f4")
            tex.build_mipmaps()
            for k, level in enumerate(maps.color.levels):
                tex.write(np.ascontiguousarray(level, dtype=np.float32).tobytes(), level=k)
            tex.filter = FILTERS["trilinear"]
            tex.repeat_x = tex.repeat_y = maps.color.wrap == "repeat"
            self._objects += [vao, vbo, ibo, tex]
            self._draws.append((mesh, vao, tex))

    def draw(self, view, projection: str) -> None:
        from app.oracles.reference_gl import clip_from_world, viewport_rect
        gl, ctx, program = self.gl, self.gl.ctx, self.program
        gl.fbo.use()
        ctx.viewport = (0, 0, *gl.size)
        gl.fbo.clear(*gl.scene.background, 1.0, depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        ctx.front_face = "ccw"
        ctx.cull_face = "back"
        program["clip_from_world"].write(
            clip_from_world(view, projection, gl.size).T.astype("f4").tobytes())
        x0, y0, w, h = viewport_rect(view, gl.size)
        program["viewport_rect"].value = (x0, y0, x0 + w, y0 + h)
        gl._set_lighting(program, view, projection)
        for mesh, vao, tex in self._draws:
            if mesh.closed:
                ctx.enable(moderngl.CULL_FACE)
            else:
                ctx.disable(moderngl.CULL_FACE)
            gl._set_material(program, mesh.material, two_sided=not mesh.closed)
            tex.use(0)
            vao.render(moderngl.TRIANGLES)

    def render(self, view, projection: str) -> np.ndarray:
        self.draw(view, projection)
        self.gl.finish()
        return self.gl.read()

    def release(self) -> None:
        for obj in self._objects:
            obj.release()
        self.program.release()
        self.gl.release()
