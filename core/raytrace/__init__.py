"""The Whitted ray tracer: a second renderer on the same scenes, views and Phong model.

Modules, in the order a ray meets them: ``intersect`` (Möller–Trumbore, the notes' sphere
quadratic and plane formula), ``bvh`` (binned-SAH hierarchy, numba traversal), ``optics``
(reflection, Snell refraction, Schlick), ``geometry`` (a scene packed for the kernels),
``whitted`` (the recursive ray tree, iterative in numba), ``renderer`` (the front door),
``inspect`` (the pixel inspector's ray tree and the buffer views).
"""
