"""The scene: geometry, views, lights and materials — the one place the viewer's data lives.

Data only; the stages in ``core`` read it and never change it. A :class:`Mesh` is a bag of
numpy arrays: triangles ``(T, 3)`` and edges ``(E, 2)`` over named per-vertex attributes
(``position`` ``(V, 3)``; optional ``normal``, ``uv`` ``(V, 2)`` and any others in ``extra``).
Readers (``core.scene.formats``) and generators (``core.scene.generators``) make these objects.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.camera.view import View
from core.settings import SHADINGS  # noqa: F401  (re-exported for the readers)

MAX_IMAGE_SIDE = 8192       # pixels, either side of a framebuffer any input may ask for
# Default crease angle, degrees: edges whose faces meet at more than this are sharp. 45° is
# below the FvDFH house's wall-to-roof edge (53.1°) and a box's 90°, and at or above the step
# of every smooth generator's tessellation (a sphere or torus of 8 segments turns 45° an edge),
# so boxes and houses get flat faces while spheres, tori and the bunny stay smooth.
CREASE_ANGLE = 45.0


@dataclass
class Material:
    """Phong material per mesh: ``k_a, k_d, k_s``, exponent ``n`` and diffuse colour ``O_d``."""

    ka: float = 0.2
    kd: float = 0.7
    ks: float = 0.3
    n: float = 20.0
    od: tuple[float, float, float] = (0.8, 0.8, 0.8)
    # Specular colour O_s; FvDFH 16.1.5 uses the light's colour (O_s = 1) for plastics.
    os: tuple[float, float, float] = (1.0, 1.0, 1.0)
    # Whitted's global terms (the ray tracer's): the mirror coefficient k_r, the
    # transmission coefficient k_t and the index of refraction. The z-buffer family uses k_t
    # too when settings.transparency is on (core.effects.transparency).
    kr: float = 0.0
    kt: float = 0.0
    ior: float = 1.52                      # glass (the notes); only used where kt > 0
    # What a system keeps on a material beyond the Phong terms ("maps", the
    # colour/bump/normal/environment maps of core.texture.material).
    extra: dict = field(default_factory=dict)
    # Global illumination (radiosity and the path tracer read them): the radiosity
    # an area light emits, and on which sides it glows and reflects. ``two_sided`` None: both
    # sides for an open mesh that emits nothing (as the Phong model lights an open soup), else
    # the side its normal (counter-clockwise winding) faces.
    emission: tuple[float, float, float] = (0.0, 0.0, 0.0)
    two_sided: bool | None = None


@dataclass
class Light:
    """A point light (``position``) or a directional one (``direction`` towards the light)."""

    intensity: tuple[float, float, float] = (1.0, 1.0, 1.0)
    position: tuple[float, float, float] | None = None
    direction: tuple[float, float, float] | None = None
    attenuation: tuple[float, float, float] = (1.0, 0.0, 0.0)   # c1, c2, c3
    # f_att = min(1, 1/(c1 + c2 d + c3 d²)) as FvDFH caps it; False: the notes' 1/(...) as is
    attenuation_cap: bool = True


@dataclass(eq=False)          # identity: meshes hold arrays and key the render caches
class Mesh:
    """Triangles and/or line edges over one vertex array.

    ``closed`` says the mesh is closed and consistently wound (counter-clockwise seen from
    outside), so back faces may be culled and lighting is one-sided; an open soup is lit from
    both sides.
    """

    positions: np.ndarray                                   # (V, 3) float64, world
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    normals: np.ndarray | None = None                       # (V, 3) from the file, if any
    closed: bool = False
    material: Material = field(default_factory=Material)
    name: str = "mesh"
    uv: np.ndarray | None = None                            # (V, 2) texture coordinates
    extra: dict = field(default_factory=dict)               # more named (V, k) arrays
    # The analytic primitive (core.scene.primitives) this mesh tessellates for the z-buffer;
    # the ray tracer intersects that primitive instead of these triangles.
    tessellates: object | None = None

    def __post_init__(self) -> None:
        self.positions = np.ascontiguousarray(self.positions, dtype=np.float64).reshape(-1, 3)
        self.triangles = np.ascontiguousarray(self.triangles, dtype=np.int64).reshape(-1, 3)
        self.edges = np.ascontiguousarray(self.edges, dtype=np.int64).reshape(-1, 2)
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=np.float64).reshape(-1, 3)
        if self.uv is not None:
            self.uv = np.ascontiguousarray(self.uv, dtype=np.float64).reshape(-1, 2)
        for name, values in self.extra.items():
            values = np.ascontiguousarray(values, dtype=np.float64)
            self.extra[name] = values.reshape(len(self.positions), -1)

    @property
    def attributes(self) -> dict[str, np.ndarray]:
        """Every named per-vertex array: ``position``, and ``normal``, ``uv`` and the extra
        ones (``tangent``, ``color``, …) where the mesh has them. Rows match ``positions``."""
        named = {"position": self.positions, "normal": self.normals, "uv": self.uv, **self.extra}
        return {name: values for name, values in named.items() if values is not None}

    def all_edges(self) -> np.ndarray:
        """The line edges plus every triangle edge once (for wireframe drawing).

        Vertices at exactly the same position (a texture seam's copies) count as one, so a
        seam is drawn once, like any other edge."""
        t = self.triangles
        tri_edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        both = np.concatenate([self.edges, tri_edges])
        if len(both) == 0:
            return both
        _, first, inverse = np.unique(self.positions, axis=0, return_index=True,
                                      return_inverse=True)
        welded = first[inverse.reshape(-1)][both]            # each vertex → its first copy
        return np.unique(np.sort(welded, axis=1), axis=0)


@dataclass(eq=False)          # identity: a scene keys the render caches
class Scene:
    """Everything one scene file describes.

    ``view_messages`` holds the reader's message for every view it rejected; the valid views
    are in ``views``. ``shading`` and ``projection`` are the scene's defaults.
    """

    name: str
    meshes: list[Mesh]
    views: list[View]
    view_messages: list[str] = field(default_factory=list)
    # The reader's other notes: what it could not use but drew without (a texture file).
    messages: list[str] = field(default_factory=list)
    # Every view in file order, the View when valid and its message when not, so that "view K"
    # means the K-th view of the file (the course's numbering). Empty: valid views, then invalid.
    view_order: list = field(default_factory=list)
    lights: list[Light] = field(default_factory=lambda: [Light(position=(0.0, 0.0, 100.0))])
    ambient: tuple[float, float, float] = (0.2, 0.2, 0.2)         # I_a
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    line_color: tuple[float, float, float] = (1.0, 1.0, 1.0)      # wireframe colour
    shading: str = "flat"
    projection: str = "perspective"
    specular: str = "reflect"             # "reflect": (R.V)^n; "halfway": (N.H)^n
    size: tuple[int, int] = (500, 500)    # preferred framebuffer size, width x height
    source: str = ""                      # file the scene came from
    keep_aspect: bool = False             # letterbox the window instead of stretching it
    rasterizer: str = "edge"              # "edge" | "scanline" (the course's ET/AET algorithm)
    renderer: str = "zbuffer"             # the scene file's renderer (core.registry)
    # Analytic surfaces (core.scene.primitives): ray casters intersect them exactly.
    primitives: list = field(default_factory=list)
    # Those of them that no mesh draws: spheres past the triangle budget, which the reader did
    # not tessellate (the renderers that trace primitives draw them; the others say so).
    untessellated: list = field(default_factory=list)
    # The crease angle (degrees) the reader split vertices at (core.scene.normals.with_creases):
    # faces meeting at more than this keep their own normals along the edge.
    crease_angle: float = CREASE_ANGLE
    # How the global-illumination renderers (radiosity, pathtrace) turn radiosity
    # into pixels: "linear" (clamped, as the Phong model's intensities) or "srgb" (the sRGB
    # transfer curve, for scenes in physical units such as the Cornell box).
    tone: str = "linear"
    # The [depth_cue] table (core.effects.depth_cue.DepthCue), None when the file has none.
    depth_cue: object | None = None
    # How the z-buffer family draws materials with k_t > 0 (settings.TRANSPARENCIES); None:
    # the file does not say, and the settings choose what the scene needs
    # (core.settings.needed_transparency: interpolated where a material has k_t > 0).
    transparency: str | None = None
    # Each system's own data on the scene, by the system's name (core.volume: "volumes",
    # core.animation: "animation"): a copy of the scene (dataclasses.replace) carries them.
    # A system sets its entry by replacing the dict (attach), never by editing it, so a copy
    # made earlier keeps what it had.
    systems: dict = field(default_factory=dict)

    @property
    def triangle_count(self) -> int:
        return sum(len(m.triangles) for m in self.meshes)


def meshes_named(scene, name: str, own_material: bool = False) -> list[int]:
    """The indices of every mesh drawn for the geometry ``name``: a checker plane is two
    meshes (one per colour) with one name, and a key moves the whole of it. With
    ``own_material``, only those in the geometry's own material (not a checker's second
    colour, which a keyed ``od`` leaves alone)."""
    found, seen = [], set()
    for i, mesh in enumerate(scene.meshes):
        if mesh.name != name:
            continue
        shape = id(mesh.tessellates) if mesh.tessellates is not None else None
        if own_material and shape is not None and shape in seen:
            continue
        seen.add(shape)
        found.append(i)
    return found
