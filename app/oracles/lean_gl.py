"""The bench's lean llvmpipe row: the cheapest honest OpenGL path to the same picture.

The GLSL oracle (:mod:`app.oracles.reference_gl`) is written to match our model exactly: every
light of the scene in a loop, attenuation, two-sided lighting, the letterbox discard, flat
shading through un-indexed corners. That costs llvmpipe time our pipeline does not spend,
so a ratio against it flatters us. This row is what a GL programmer would write for speed:

- both meshes in one indexed vertex buffer (positions and normals, float32), one draw call;
- back faces culled (the bench scene is closed), depth test ``GL_LESS``;
- ONE light (the scene's first), the model without attenuation or two-sided lighting:
  Gouraud evaluates it in the vertex shader, Phong in the fragment shader, flat takes the
  provoking vertex's Gouraud colour (``flat`` varying);
- the same clip matrix ``L · M · N`` as the oracle, so the picture lands on the same pixels.

Timed like the oracle: draw + ``ctx.finish()`` (no readback). Used only by the bench.
"""

from __future__ import annotations

import time

import moderngl
import numpy as np

_MODEL = """
uniform vec3 light;          // position (light_is_point = 1) or unit direction towards it
uniform int light_is_point;
uniform vec3 intensity;
uniform vec3 ambient;
uniform vec4 k;              // ka, kd, ks, n
uniform vec3 od;
uniform vec3 os;
uniform vec3 eye;
vec3 shade(vec3 p, vec3 n) {
    vec3 l = normalize(light_is_point == 1 ? light - p : light);
    vec3 v = normalize(eye - p);
    float nl = dot(n, l);
    float spec = nl > 0.0 ? pow(max(dot(2.0 * nl * n - l, v), 0.0), k.w) : 0.0;
    return clamp(ambient * k.x * od + intensity * (k.y * od * max(nl, 0.0) + k.z * os * spec),
                 0.0, 1.0);
}
"""

_SHADERS = {
    "gouraud": ("""#version 330
uniform mat4 clip_from_world;
in vec3 in_position; in vec3 in_normal;
out vec3 color;
""" + _MODEL + """
void main() { color = shade(in_position, in_normal);
              gl_Position = clip_from_world * vec4(in_position, 1.0); }
""", """#version 330
in vec3 color; out vec4 frag;
void main() { frag = vec4(color, 1.0); }
"""),
    "flat": ("""#version 330
uniform mat4 clip_from_world;
in vec3 in_position; in vec3 in_normal;
flat out vec3 color;
""" + _MODEL + """
void main() { color = shade(in_position, in_normal);
              gl_Position = clip_from_world * vec4(in_position, 1.0); }
""", """#version 330
flat in vec3 color; out vec4 frag;
void main() { frag = vec4(color, 1.0); }
"""),
    "phong": ("""#version 330
uniform mat4 clip_from_world;
in vec3 in_position; in vec3 in_normal;
out vec3 p; out vec3 n;
void main() { p = in_position; n = in_normal;
              gl_Position = clip_from_world * vec4(in_position, 1.0); }
""", """#version 330
in vec3 p; in vec3 n; out vec4 frag;
""" + _MODEL + """
void main() { frag = vec4(shade(p, normalize(n)), 1.0); }
"""),
}
MODES = tuple(_SHADERS)


class LeanGL:
    """A standalone EGL context with the lean programs; :meth:`load` uploads a scene once."""

    def __init__(self, size=(500, 500), ctx=None) -> None:
        self.ctx = ctx or moderngl.create_standalone_context(backend="egl")
        self.size = (int(size[0]), int(size[1]))
        self.programs = {mode: self.ctx.program(vertex_shader=vs, fragment_shader=fs)
                         for mode, (vs, fs) in _SHADERS.items()}
        self.fbo = self.ctx.framebuffer(
            color_attachments=[self.ctx.renderbuffer(self.size, components=4)],
            depth_attachment=self.ctx.depth_renderbuffer(self.size))
        self._objects: list = []
        self.vaos: dict = {}
        self.scene = None

    def load(self, scene) -> None:
        """Both meshes in one indexed buffer; the first light and the first material."""
        from core.scene.normals import vertex_normals
        self._release_scene()
        self.scene = scene
        meshes = [m for m in scene.meshes if len(m.triangles)]
        offsets = np.cumsum([0] + [len(m.positions) for m in meshes])
        vertices = np.concatenate([np.concatenate([m.positions, vertex_normals(m)], axis=1)
                                   for m in meshes]).astype("f4")
        indices = np.concatenate([m.triangles + o for m, o in zip(meshes, offsets)]).astype("i4")
        vbo = self.ctx.buffer(vertices.tobytes())
        ibo = self.ctx.buffer(indices.tobytes())
        self._objects = [vbo, ibo]
        for mode, program in self.programs.items():
            self.vaos[mode] = self.ctx.vertex_array(
                program, [(vbo, "3f 3f", "in_position", "in_normal")], ibo)
        light = scene.lights[0]
        material = meshes[0].material
        point = light.position is not None
        where = np.asarray(light.position if point else light.direction, np.float64)
        if not point:
            where = where / np.linalg.norm(where)
        for program in self.programs.values():
            values = {"light": tuple(where), "light_is_point": int(point),
                      "intensity": tuple(light.intensity), "ambient": tuple(scene.ambient),
                      "k": (material.ka, material.kd, material.ks, material.n),
                      "od": tuple(material.od), "os": tuple(material.os)}
            for name, value in values.items():
                if program.get(name, None) is not None:
                    program[name].value = value

    def draw(self, view, projection: str, shading: str) -> None:
        from app.oracles.reference_gl import clip_from_world, eye_of
        program = self.programs[shading]
        ctx = self.ctx
        self.fbo.use()
        ctx.viewport = (0, 0, *self.size)
        self.fbo.clear(*self.scene.background, 1.0, depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        ctx.depth_func = "<"
        ctx.front_face = "ccw"
        ctx.cull_face = "back"
        m = clip_from_world(view, projection, self.size)
        program["clip_from_world"].write(m.T.astype("f4").tobytes())
        eye, toward = eye_of(view)
        if program.get("eye", None) is not None:
            # parallel: a far point along the direction towards the viewer
            program["eye"].value = tuple(eye if projection == "perspective" else 1e6 * toward)
        self.vaos[shading].render(moderngl.TRIANGLES)

    def timed_frame(self, view, projection: str, shading: str) -> tuple[float, float]:
        """Seconds for draw + finish, and for the readback (timed apart), of one frame."""
        t0 = time.perf_counter()
        self.draw(view, projection, shading)
        self.ctx.finish()
        t1 = time.perf_counter()
        self.fbo.read(components=3, alignment=1)
        return t1 - t0, time.perf_counter() - t1

    def read(self) -> np.ndarray:
        width, height = self.size
        data = self.fbo.read(components=3, alignment=1)
        return np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1].copy()

    def _release_scene(self) -> None:
        for vao in self.vaos.values():
            vao.release()
        self.vaos = {}
        for obj in self._objects:
            obj.release()
        self._objects = []

    def release(self) -> None:
        self._release_scene()
        self.ctx.release()
