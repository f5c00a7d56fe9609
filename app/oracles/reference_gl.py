"""The OpenGL oracle: the same scene drawn by real OpenGL (Mesa llvmpipe through EGL).

Used by the tests (coverage and shading oracles), by the bench, and as the picture our frame is
held against by the window's ``h`` (compare with OpenGL) and ``python -m app compare``; the
viewer never shows a frame drawn with it as its own. Takes a :class:`core.scene.Scene`, a view index, a projection and a shading
mode; returns an ``(H, W, 3)`` uint8 image in image order (row 0 is the top),
exactly like ``core.render.render(...).color``.

The geometry goes through the SAME matrices as the CPU core, composed into one clip matrix:

    clip = L · M · N        (world -> GL clip coordinates)

- ``N`` is ``core.camera.view.normalizing_transform(view, projection)`` (N_per or N_par, FvDFH 6.5);
- ``M`` is FvDFH's perspective-to-parallel matrix (identity for parallel), so that after GL's
  divide by ``W = -z`` the point lies in the canonical parallel volume (x, y in [-1, 1],
  z in [-1, 0], larger z nearer);
- ``L`` is affine: x and y go to the framebuffer's normalised coordinates through the same
  viewport the CPU uses (the canonical square onto the letterboxed rectangle of the window's
  aspect), and canonical z in [-1, 0] becomes GL depth ``-2z - 1`` in [1, -1], so that nearer
  passes ``GL_LESS``. GL's own clipping at ``-W <= z_clip <= W`` is then exactly the front and
  back planes; pixels whose centre falls outside the letterboxed rectangle are discarded, which
  is the x/y clipping of the canonical volume evaluated at pixel centres.

The fragment shaders implement the Phong illumination model in WORLD coordinates
(FvDFH 16.1, 16.2): ``I = I_a k_a O_d + sum f_att I_p [k_d O_d max(N.L, 0) + k_s O_s max(R.V, 0)^n]``
per RGB channel, ``f_att = min(1, 1 / (c1 + c2 d + c3 d^2))`` (1 for directional lights), the halfway form ``(N.H)^n`` when
the scene says ``specular = "halfway"``; meshes that are not closed are lit from both sides
(the normal is flipped to face the viewer); closed meshes have their back faces culled.

- flat:    one evaluation per polygon at its centroid with its normal (a planar polygon's
           triangles share them, as in :mod:`core.shading.flat`); every triangle gets its own
           three vertices carrying that normal and point (``flat`` varyings);
- gouraud: the model evaluated per vertex (vertex shader) with the same vertex normals as the
           CPU (:func:`core.scene.normals.vertex_normals`), clamped, then interpolated
           perspective-correctly;
- phong:   world position and normal interpolated, renormalised, evaluated per fragment;
- gouraud_linear: Gouraud with ``noperspective`` varyings: the vertex intensities interpolated
           linearly in screen space, as the course notes do and as the scan-line rasterizer
           (``core/pipeline/raster_scanline.py``) does;
- coverage: one flat colour (white on black), for the coverage oracle.

Buffers are uploaded once per scene (:meth:`GLRenderer.load`), so that a timed frame is only
uniforms, draw calls and ``ctx.finish()``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import moderngl
import numpy as np

from core.shading.illumination import eye_from_view
from core.scene.normals import vertex_normals
from core.pipeline.project import perspective_to_parallel, viewport
from core.scene.model import Scene
from core.camera.view import View, normalizing_transform

MODES = ("coverage", "flat", "gouraud", "phong", "gouraud_linear")
MAX_LIGHTS = 8

_LIGHTING_GLSL = """
#define MAX_LIGHTS %(max_lights)d
uniform int n_lights;
uniform vec4 light_where[MAX_LIGHTS];   // xyz: position (w = 1) or direction towards it (w = 0)
uniform vec3 light_intensity[MAX_LIGHTS];
uniform vec3 light_attenuation[MAX_LIGHTS];   // c1, c2, c3
uniform vec3 ambient;                    // I_a
uniform float ka;
uniform float kd;
uniform float ks;
uniform float shininess;                 // the exponent n
uniform vec3 od;
uniform vec3 os;
uniform int halfway;                     // 1: (N.H)^n, 0: (R.V)^n
uniform int two_sided;                   // 1: flip N to face the viewer (open meshes)
uniform int perspective;                 // 1: V points to the PRP, 0: V = -DOP
uniform vec3 eye;                        // PRP in world coordinates
uniform vec3 toward_viewer;              // -DOP / |DOP| in world coordinates

// v / |v|, and the zero vector for a zero v (GLSL's normalize would give NaN).
vec3 unit(vec3 v) {
    float len = length(v);
    return len > 0.0 ? v / len : vec3(0.0);
}

// Phong illumination model (FvDFH eq. 16.14-16.15) at world point p with unit (or zero)
// normal n, clamped to [0, 1]. The degenerate cases follow core/shading/illumination.py: V = N at the
// eye, no term from a light at p, none (diffuse or specular) where N.L <= 0, no specular
// where L + V = 0, the specular base clamped to [0, 1], f_att = 1 when c1 + c2 d + c3 d^2 <= 1.
vec3 illuminate(vec3 p, vec3 n) {
    vec3 v;
    if (perspective == 1) {
        v = unit(eye - p);
        if (v == vec3(0.0)) {
            v = n;
        }
    } else {
        v = toward_viewer;
    }
    if (two_sided == 1 && dot(n, v) < 0.0) {
        n = -n;
    }
    vec3 color = ambient * ka * od;
    for (int i = 0; i < n_lights; ++i) {
        vec3 l;
        float f_att = 1.0;
        if (light_where[i].w > 0.5) {
            vec3 to_light = light_where[i].xyz - p;
            float d = length(to_light);
            if (d == 0.0) {
                continue;
            }
            l = to_light / d;
            vec3 c = light_attenuation[i];
            float den = c.x + c.y * d + c.z * d * d;
            f_att = den <= 1.0 ? 1.0 : 1.0 / den;
        } else {
            l = unit(light_where[i].xyz);
        }
        float n_dot_l = dot(n, l);
        if (!(n_dot_l > 0.0)) {
            continue;
        }
        float base;
        if (halfway == 1) {
            base = dot(n, unit(l + v));
        } else {
            base = dot(2.0 * n_dot_l * n - l, v);
        }
        // pow(0, 0) is undefined in GLSL; x^0 = 1 as in Python.
        float specular = shininess == 0.0 ? 1.0 : pow(clamp(base, 0.0, 1.0), shininess);
        color += f_att * light_intensity[i] * (kd * od * n_dot_l + ks * os * specular);
    }
    return clamp(color, 0.0, 1.0);
}
""" % {"max_lights": MAX_LIGHTS}

# Pixels whose centre lies outside the viewport rectangle (x0, y0, x1, y1) are discarded:
# the x/y planes of the canonical volume, evaluated where the CPU evaluates coverage.
_DISCARD_GLSL = """
uniform vec4 viewport_rect;
void clip_to_viewport() {
    if (gl_FragCoord.x < viewport_rect.x || gl_FragCoord.x > viewport_rect.z ||
        gl_FragCoord.y < viewport_rect.y || gl_FragCoord.y > viewport_rect.w) {
        discard;
    }
}
"""

_SHADERS = {
    "coverage": ("""
#version 330
uniform mat4 clip_from_world;
in vec3 in_position;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
}
""", """
#version 330
%s
out vec4 frag_color;
void main() {
    clip_to_viewport();
    frag_color = vec4(1.0);
}
""" % _DISCARD_GLSL),
    "flat": ("""
#version 330
uniform mat4 clip_from_world;
%s
in vec3 in_position;
in vec3 in_face_normal;
in vec3 in_centroid;
flat out vec3 face_color;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
    face_color = illuminate(in_centroid, in_face_normal);
}
""" % _LIGHTING_GLSL, """
#version 330
%s
flat in vec3 face_color;
out vec4 frag_color;
void main() {
    clip_to_viewport();
    frag_color = vec4(face_color, 1.0);
}
""" % _DISCARD_GLSL),
    "gouraud": ("""
#version 330
uniform mat4 clip_from_world;
%s
in vec3 in_position;
in vec3 in_normal;
out vec3 vertex_color;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
    vertex_color = illuminate(in_position, unit(in_normal));
}
""" % _LIGHTING_GLSL, """
#version 330
%s
in vec3 vertex_color;
out vec4 frag_color;
void main() {
    clip_to_viewport();
    frag_color = vec4(vertex_color, 1.0);
}
""" % _DISCARD_GLSL),
    "gouraud_linear": ("""
#version 330
uniform mat4 clip_from_world;
%s
in vec3 in_position;
in vec3 in_normal;
noperspective out vec3 vertex_color;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
    vertex_color = illuminate(in_position, unit(in_normal));
}
""" % _LIGHTING_GLSL, """
#version 330
%s
noperspective in vec3 vertex_color;
out vec4 frag_color;
void main() {
    clip_to_viewport();
    frag_color = vec4(vertex_color, 1.0);
}
""" % _DISCARD_GLSL),
    "phong": ("""
#version 330
uniform mat4 clip_from_world;
in vec3 in_position;
in vec3 in_normal;
out vec3 world_position;
out vec3 world_normal;
void main() {
    gl_Position = clip_from_world * vec4(in_position, 1.0);
    world_position = in_position;
    world_normal = in_normal;
}
""", """
#version 330
%s
%s
in vec3 world_position;
in vec3 world_normal;
out vec4 frag_color;
void main() {
    clip_to_viewport();
    frag_color = vec4(illuminate(world_position, unit(world_normal)), 1.0);
}
""" % (_DISCARD_GLSL, _LIGHTING_GLSL)),
}


def viewport_rect(view: View, size: tuple[int, int],
                  keep_aspect: bool = False) -> tuple[float, float, float, float]:
    """``(x0, y0, w, h)`` in device pixels: the canonical square's image on the framebuffer.

    The CPU's own rule (:func:`core.pipeline.project.viewport`): the whole framebuffer (the
    window stretched, the course's mapping), or with ``keep_aspect`` the largest whole-pixel
    rectangle of the window's aspect, centred (letterboxing).
    """
    x_min, x_max, y_min, y_max = viewport(view.window, *size, keep_aspect=keep_aspect)
    return x_min, y_min, x_max - x_min, y_max - y_min


def clip_from_world(view: View, projection: str, size: tuple[int, int],
                    keep_aspect: bool = False) -> np.ndarray:
    """``L · M · N``: world coordinates to GL clip coordinates (float64, column vectors)."""
    n, z_min = normalizing_transform(view, projection)
    m = perspective_to_parallel(z_min) if projection == "perspective" else np.eye(4)
    x0, y0, w, h = viewport_rect(view, size, keep_aspect)
    width, height = size
    # x_ndc = 2 (x0 + (x + 1) w / 2) / width - 1, likewise y; z_ndc = -2 z - 1. Each row acts
    # on (X, Y, Z, W) before the divide, so the constant terms multiply W.
    sx, sy = w / width, h / height
    tx, ty = 2.0 * x0 / width + sx - 1.0, 2.0 * y0 / height + sy - 1.0
    l = np.array([[sx, 0.0, 0.0, tx],
                  [0.0, sy, 0.0, ty],
                  [0.0, 0.0, -2.0, -1.0],
                  [0.0, 0.0, 0.0, 1.0]])
    return l @ m @ n


def eye_of(view: View) -> tuple[np.ndarray, np.ndarray]:
    """The PRP in world coordinates, and the unit vector towards the viewer for parallel
    (-DOP): the viewing parameters the CPU's shading uses (``core.shading.illumination``)."""
    return (eye_from_view(view, "perspective").point, eye_from_view(view, "parallel").direction)


@dataclass
class _MeshBuffers:
    """One mesh's vertex arrays on the GPU, one vertex array object per mode."""

    closed: bool
    material: object
    vaos: dict
    buffers: list


class GLRenderer:
    """A standalone EGL context (llvmpipe) with an offscreen framebuffer of ``size``.

    ``load(scene)`` uploads the geometry once; ``draw`` issues the frame without waiting;
    ``finish`` waits for llvmpipe; ``read`` returns the image. ``render`` does all three.
    """

    def __init__(self, size: tuple[int, int] = (500, 500), ctx=None) -> None:
        self.ctx = ctx or moderngl.create_standalone_context(backend="egl")
        self.programs = {mode: self.ctx.program(vertex_shader=vs, fragment_shader=fs)
                         for mode, (vs, fs) in _SHADERS.items()}
        self.size = (0, 0)
        self.fbo = None
        self.scene = None
        self.loaded: tuple[str, ...] = ()
        self.keep_aspect = False          # letterbox like RenderSettings.keep_aspect
        self._meshes: list[_MeshBuffers] = []
        self.resize(size)

    @property
    def renderer_name(self) -> str:
        return self.ctx.info["GL_RENDERER"]

    def resize(self, size: tuple[int, int]) -> None:
        size = (int(size[0]), int(size[1]))
        if size == self.size:
            return
        if self.fbo is not None:
            self.fbo.release()
        self.size = size
        self.fbo = self.ctx.framebuffer(
            color_attachments=[self.ctx.renderbuffer(size, components=4)],
            depth_attachment=self.ctx.depth_renderbuffer(size))

    def release(self) -> None:
        self._release_meshes()
        self.ctx.release()

    def _release_meshes(self) -> None:
        for mb in self._meshes:
            for vao in mb.vaos.values():
                vao.release()
            for buf in mb.buffers:
                buf.release()
        self._meshes = []

    def load(self, scene: Scene, modes: tuple[str, ...] = MODES) -> None:
        """Upload every mesh's triangles for ``modes`` (once per scene)."""
        self._release_meshes()
        self.scene = scene
        self.loaded = tuple(modes)
        ctx = self.ctx
        for mesh in scene.meshes:
            if len(mesh.triangles) == 0:
                continue
            positions = mesh.positions.astype("f4")
            triangles = mesh.triangles.astype("i4")
            vaos, buffers = {}, []
            pos_buf = ctx.buffer(positions.tobytes())
            idx_buf = ctx.buffer(triangles.tobytes())
            buffers += [pos_buf, idx_buf]
            if "coverage" in modes:
                vaos["coverage"] = ctx.vertex_array(
                    self.programs["coverage"], [(pos_buf, "3f", "in_position")], idx_buf)
            if {"gouraud", "phong", "gouraud_linear"} & set(modes):
                nrm_buf = ctx.buffer(vertex_normals(mesh).astype("f4").tobytes())
                buffers.append(nrm_buf)
                for mode in ("gouraud", "phong", "gouraud_linear"):
                    if mode in modes:
                        vaos[mode] = ctx.vertex_array(
                            self.programs[mode],
                            [(pos_buf, "3f", "in_position"), (nrm_buf, "3f", "in_normal")],
                            idx_buf)
            if "flat" in modes:
                # Each triangle gets its own three corners carrying the point and normal its
                # polygon is lit with (core.shading.flat: a planar quad's two triangles share
                # them), so the flat varying is the same whichever vertex provokes.
                from core.shading.flat import lighting_points
                corners = mesh.positions[mesh.triangles]                    # (T, 3, 3)
                centroid, normal = lighting_points(mesh)
                flat = np.empty((len(corners), 3, 9), dtype="f4")
                flat[:, :, 0:3] = corners
                flat[:, :, 3:6] = normal[:, None, :]
                flat[:, :, 6:9] = centroid[:, None, :]
                flat_buf = ctx.buffer(flat.tobytes())
                buffers.append(flat_buf)
                vaos["flat"] = ctx.vertex_array(
                    self.programs["flat"],
                    [(flat_buf, "3f 3f 3f", "in_position", "in_face_normal", "in_centroid")])
            self._meshes.append(_MeshBuffers(mesh.closed, mesh.material, vaos, buffers))

    def _set_lighting(self, program, view: View, projection: str) -> None:
        scene = self.scene
        eye, toward = eye_of(view)
        lights = scene.lights[:MAX_LIGHTS]
        if len(scene.lights) > MAX_LIGHTS:
            raise ValueError(f"the GL oracle takes at most {MAX_LIGHTS} lights")
        where = np.zeros((MAX_LIGHTS, 4), "f4")
        intensity = np.zeros((MAX_LIGHTS, 3), "f4")
        attenuation = np.zeros((MAX_LIGHTS, 3), "f4")
        attenuation[:, 0] = 1.0
        for i, light in enumerate(lights):
            if light.position is not None:
                where[i] = (*light.position, 1.0)
            else:
                where[i] = (*light.direction, 0.0)
            intensity[i] = light.intensity
            attenuation[i] = light.attenuation
        values = {
            "n_lights": len(lights), "light_where": where, "light_intensity": intensity,
            "light_attenuation": attenuation, "ambient": np.asarray(scene.ambient, "f4"),
            "halfway": int(scene.specular == "halfway"),
            "perspective": int(projection == "perspective"),
            "eye": eye.astype("f4"), "toward_viewer": toward.astype("f4"),
        }
        for name, value in values.items():
            if program.get(name, None) is not None:
                if isinstance(value, np.ndarray):
                    program[name].write(value.tobytes())
                else:
                    program[name].value = value

    @staticmethod
    def _set_material(program, material, two_sided: bool) -> None:
        values = {"ka": material.ka, "kd": material.kd, "ks": material.ks,
                  "shininess": material.n, "od": tuple(material.od), "os": tuple(material.os),
                  "two_sided": int(two_sided)}
        for name, value in values.items():
            if program.get(name, None) is not None:
                program[name].value = value

    def draw(self, view: View, projection: str, shading: str) -> None:
        """Issue one frame of ``view`` (any view; clear and draw every mesh); does not wait
        for llvmpipe."""
        if shading not in MODES:
            raise ValueError(f"shading must be one of {MODES}, not {shading!r}")
        scene = self.scene
        if shading not in self.loaded:
            raise ValueError(f"{shading!r} was not loaded (loaded: {', '.join(self.loaded)})")
        program = self.programs[shading]
        ctx = self.ctx
        self.fbo.use()
        ctx.viewport = (0, 0, *self.size)
        if shading == "coverage":
            self.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        else:
            self.fbo.clear(*scene.background, 1.0, depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = "<"
        ctx.front_face = "ccw"
        ctx.cull_face = "back"
        m = clip_from_world(view, projection, self.size, self.keep_aspect)
        program["clip_from_world"].write(m.T.astype("f4").tobytes())   # GL is column-major
        x0, y0, w, h = viewport_rect(view, self.size, self.keep_aspect)
        program["viewport_rect"].value = (x0, y0, x0 + w, y0 + h)
        if shading != "coverage":
            self._set_lighting(program, view, projection)
        for mb in self._meshes:
            if mb.closed:
                ctx.enable(moderngl.CULL_FACE)
            else:
                ctx.disable(moderngl.CULL_FACE)
            if shading != "coverage":
                self._set_material(program, mb.material, two_sided=not mb.closed)
            mb.vaos[shading].render(moderngl.TRIANGLES)

    def finish(self) -> None:
        """Wait until llvmpipe has drawn everything issued."""
        self.ctx.finish()

    def read(self) -> np.ndarray:
        """The framebuffer as ``(H, W, 3)`` uint8 in image order (row 0 is the top)."""
        width, height = self.size
        data = self.fbo.read(components=3, alignment=1)
        return np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)[::-1].copy()

    def render(self, view: View, projection: str, shading: str) -> np.ndarray:
        self.draw(view, projection, shading)
        self.finish()
        return self.read()

    def timed_frame(self, view: View, projection: str, shading: str) -> tuple[float, float]:
        """Seconds for draw + finish, and for the readback, of one frame."""
        t0 = time.perf_counter()
        self.draw(view, projection, shading)
        self.finish()
        t1 = time.perf_counter()
        self.read()
        return t1 - t0, time.perf_counter() - t1


GL_SHADINGS = ("flat", "gouraud", "phong")


def opengl_reference(scene, view, settings):
    """The same view drawn by real OpenGL (app/oracles/reference_gl.py), or (None, why)."""
    if settings.shading not in GL_SHADINGS:
        return None, (f"the OpenGL oracle draws {', '.join(GL_SHADINGS)} shading, not "
                      f"{settings.shading}")
    from core.texture.shaders import shading_for
    if shading_for(scene, settings.shading) != settings.shading:
        return None, ("the OpenGL oracle (app/oracles/reference_gl.py) draws no textures, and "
                      f"{scene.name} has textured materials")
    if settings.renderer != "zbuffer":
        return None, (f"the OpenGL oracle draws what the z-buffer draws; this frame is "
                      f"{settings.renderer}")
    mode = settings.shading
    if mode == "gouraud" and settings.rasterizer == "scanline":
        mode = "gouraud_linear"
    try:
        gl = GLRenderer(settings.size)
    except Exception as error:                      # no EGL, no llvmpipe: say so
        return None, f"OpenGL is not available here ({type(error).__name__}: {error})"
    try:
        gl.load(scene)
        return gl.render(view, settings.projection, mode), None
    finally:
        gl.release()
