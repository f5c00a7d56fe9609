"""The CPU core of the viewer: every transform, clip, z-buffer test and shading step.

Read the modules in pipeline order:

``transforms`` (T, S, R, shear) → ``view`` (VRC, N_per, N_par) → ``clip`` (Cohen–Sutherland
lines, Sutherland–Hodgman triangles) → ``project`` (M_per, perspective-to-parallel, M_vv3dv,
divide by W) → ``raster`` (scan conversion, z-buffer) → ``shade`` (Phong illumination; flat,
Gouraud, Phong shading) → ``render`` (assembles only the stages a scene needs).

``core`` imports no GL and no window library.
"""
