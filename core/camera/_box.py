"""The film's compiled box filter (kept apart so that importing the film loads no numba)."""

from core.jit import njit, prange


@njit(cache=True, parallel=True, nogil=True)
def _box_filter(image, k, out):
    height, width = out.shape[0], out.shape[1]
    scale = 1.0 / (k * k)
    for row in prange(height):
        for col in range(width):
            for c in range(3):
                total = 0
                for a in range(k):
                    for b in range(k):
                        total += image[row * k + a, col * k + b, c]
                out[row, col, c] = total * scale
