"""Radiosity's systems: the scene meshed into patches and elements (``mesh``), form factors by
the hemicube (``hemicube``) or by rays through the BVH (``raycast``), the solvers
(``solve``: progressive refinement, Gauss-Seidel), a scene's solution with adaptive
subdivision, saved and loaded (``solution``), closed forms for the tests (``closed_forms``) and
the display's tone curve (``tone``). The renderer that draws a solution (its frame, pixel
inspector, options and progressive drawer) is :mod:`core.renderers.radiosity`.
"""
