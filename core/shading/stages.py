"""The compiled stages of the triangle path (the pipeline's kernels and the shading step),
imported together the first time a frame fills triangles (a wireframe frame never loads numba)."""

from threadpoolctl import threadpool_limits

from core.pipeline.clip_polygon import clip_triangles  # noqa: F401
from core.pipeline.cull import front_faces  # noqa: F401
from core.pipeline.derivatives import barycentric_planes  # noqa: F401
from core.pipeline.raster import VisibilityBuffer, rasterize  # noqa: F401
from core.pipeline.vertex_kernels import (transform_affine, transform_projective,  # noqa: F401
                                          view_points)
from core.shading import shade  # noqa: F401

# Our compiled kernels run their own threads (screen bands, pixel rows). OpenBLAS's threads,
# started by numpy's small matrix products, would spin-wait on the same two cores between our
# calls: measured here, a 100k-triangle Gouraud frame took 92 ms with them and 17 ms without.
threadpool_limits(limits=1, user_api="blas")
