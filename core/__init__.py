"""The CPU core of the viewer: every transform, clip, z-buffer test and shading step.

Read the modules in pipeline order:

``transforms`` (T, S, R, shear) → ``view`` (VRC, N_per, N_par) → ``clip`` (Cohen–Sutherland
lines, Sutherland–Hodgman triangles) → ``project`` (M_per, perspective-to-parallel, M_vv3dv,
divide by W) → ``raster`` (scan conversion, z-buffer) → ``shade`` (Phong illumination; flat,
Gouraud, Phong shading) → ``render`` (assembles only the stages a scene needs).

``core`` imports no GL and no window library.
"""

import os

# numba's OpenMP threads spin-wait between parallel regions by default; on a two-core machine
# they steal the core the main thread needs for the next stage (measured under load: a
# 1k-triangle Gouraud frame took 43 ms with spinning threads, 6 ms with passive ones). Only
# takes effect if set before the OpenMP runtime loads, i.e. before the first parallel kernel.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
