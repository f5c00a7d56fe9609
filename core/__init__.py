"""The CPU core of the viewer: every transform, clip, z-buffer test and shading step.

``render(scene, view, settings) -> Frame`` is the one call (``render_file(path, shading=…)``
for a scene file; a ``Frame`` shows itself in Jupyter); read the packages in pipeline order:

- ``transforms``, ``vectors`` — T, S, R, shear (FvDFH 5); unit vectors inside kernels;
- ``scene/`` — what is drawn: meshes with named attributes, materials, lights, analytic
  primitives, generators, every file reader; ``systems`` registers the systems' scene keys;
- ``camera/`` — the view (VRC, N_per, N_par; FvDFH 6) and the film (samples per pixel);
- ``pipeline/`` — the z-buffer's stages in order: cull → clip → project → raster;
  ``stages`` and ``plan`` say which of them run for a scene, and why;
- ``shading/`` — the illumination model once, its lighting models (Phong, Cook–Torrance…)
  and the shading modes (flat, Gouraud, Phong…) as registered shaders;
- ``texture/`` — textures, samplers, texture and bump mapping;
- ``visibility/`` — object-precision visible surfaces: BSP tree, depth sort, Watkins;
- ``effects/`` — what is laid over a picture: depth cueing, transparency;
- ``raytrace/``, ``pathtrace/``, ``radiosity/``, ``twopass/``, ``volume/`` — the other
  renderers' systems (the BVH and ray tree, paths, form factors and solvers, the two-pass
  method, sampled volumes and their isosurfaces);
- ``renderers/`` — every renderer by name, one package each (draw, inspect, options, plan),
  registered in ``registry``; ``progressive`` hands pictures over on the way;
- ``animation/`` — keyframes, particles, linkages, rigid bodies, actors;
- ``colour/`` — the CIE observer, chromaticity, sRGB;
- ``inspect/`` — the pixel inspector's front door;
- ``settings``, ``context``, ``render``, ``work`` — how to draw, what outlives a frame, the
  front door, long work that reports and stops;
- ``jit``, ``arrays``, ``prefetch`` — numba for every kernel: ``from core.jit import njit,
  prange`` (a cached kernel goes stale only when a kernel it calls or inlines changes);
- ``analysis/`` — accuracy, stability, exact arithmetic: they import the core, never the
  other way round.

``core`` imports no GL and no window library.
"""

import os

# numba's OpenMP threads spin-wait between parallel regions by default; on a two-core machine
# they steal the core the main thread needs for the next stage (measured under load: a
# 1k-triangle Gouraud frame took 43 ms with spinning threads, 6 ms with passive ones). Only
# takes effect if set before the OpenMP runtime loads, i.e. before the first parallel kernel.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

# the built-in shading modes, registered before any module can ask for one (data only: no numba)
import core.shading.modes  # noqa: E402,F401
from core.camera.view import View, ViewError  # noqa: E402
from core.context import RenderContext  # noqa: E402
from core.render import Frame, render, render_file  # noqa: E402
from core.scene.model import Light, Material, Mesh, Scene  # noqa: E402
from core.settings import Projection, RenderSettings  # noqa: E402
import core.systems  # noqa: E402,F401  (the systems' scene keys, registered before any file is read)

__all__ = ["render", "render_file", "Frame", "RenderContext", "RenderSettings", "Projection", "View",
           "ViewError", "Scene", "Mesh", "Material", "Light"]
