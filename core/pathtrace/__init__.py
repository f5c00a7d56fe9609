"""The path tracer's systems: the compiled paths (``kernel``: light sampling, bounces, multiple
importance sampling, on the ray tracer's BVH) and renderings compared away from edges
(``compare``). The renderer that draws with them (its frame, pixel inspector, options and
progressive drawer) is :mod:`core.renderers.pathtrace`.
"""
