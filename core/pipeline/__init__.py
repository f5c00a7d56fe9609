"""The z-buffer pipeline's stages, one module each, in the order they run:

``cull`` (back faces) → ``vertex_kernels`` (N on every vertex) → ``clip`` (Cohen–Sutherland
lines) / ``clip_polygon`` (Sutherland–Hodgman triangles; ``clip_liang_barsky`` and
``clip_homogeneous`` the other ``--clipper`` kernels) → ``project`` (M_per,
perspective-to-parallel, M_vv3dv, divide by W) → ``raster_lines`` (midpoint lines) /
``raster`` (scan conversion with the fill rule into a z-buffered visibility buffer).

The stages know nothing about light: shading is :mod:`core.shading`.
"""
