"""The Whitted ray tracer's systems: the BVH and the ray tree, on the same scenes, views and
Phong model as the z-buffer. The renderer that draws with them (its frame, pixel inspector,
options and progressive drawer) is :mod:`core.renderers.raytrace`; the path tracer, the
two-pass method and radiosity's ray-cast form factors use the BVH too.

Modules, in the order a ray meets them: ``intersect`` (Möller–Trumbore, the notes' sphere
quadratic and plane formula), ``bvh`` (binned-SAH hierarchy, numba traversal), ``optics``
(reflection, Snell refraction, Schlick), ``geometry`` (a scene packed for the kernels),
``whitted`` (the recursive ray tree, iterative in numba), ``adaptive`` (adaptive
supersampling over a lattice of pixel corners).
"""
