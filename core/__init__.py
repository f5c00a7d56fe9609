"""The CPU core of the viewer: every transform, clip, z-buffer test and shading step.

``render(scene, view, settings) -> Frame`` is the one call (``render_file(path, shading=…)``
for a scene file; a ``Frame`` shows itself in Jupyter); read the packages in pipeline order:

- ``transforms`` — T, S, R, shear, unit vectors (FvDFH 5);
- ``scene/`` — what is drawn: meshes with named attributes, materials, lights, analytic
  primitives, generators, every file reader;
- ``camera/`` — the view (VRC, N_per, N_par; FvDFH 6) and the film (samples per pixel);
- ``pipeline/`` — the z-buffer's stages in order: cull → clip → project → raster;
- ``shading/`` — the Phong model once; flat, Gouraud, Phong as registered shaders;
- ``renderers/`` — the z-buffer and the exact ray caster, by name;
- ``settings``, ``context``, ``plan``, ``render`` — how to draw, what outlives a frame, which
  stages run and why, and the front door;
- ``jit`` — numba for every kernel: ``from core.jit import njit, prange`` (cached kernels load
  without numba's full registry refresh, and go stale when any kernel file changes);
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

from core.camera.view import View, ViewError  # noqa: E402
from core.context import RenderContext  # noqa: E402
from core.render import Frame, render, render_file  # noqa: E402
from core.scene.model import Light, Material, Mesh, Scene  # noqa: E402
from core.settings import Projection, RenderSettings  # noqa: E402
import core.systems  # noqa: E402,F401  (the systems' scene keys, registered before any file is read)

__all__ = ["render", "render_file", "Frame", "RenderContext", "RenderSettings", "Projection", "View",
           "ViewError", "Scene", "Mesh", "Material", "Light"]
