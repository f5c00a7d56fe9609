"""Small compiled loops the painter's renderers share."""

from numba import njit


@njit(cache=True, nogil=True)
def interpolate_rows(out, start, recipe):
    """Row ``start + i`` of ``out`` = ``(1 - t) out[a] + t out[b]``, ``(a, b, t) = recipe[i]``,
    in order (a row may use one made before it)."""
    for i in range(recipe.shape[0]):
        a, b, t = int(recipe[i, 0]), int(recipe[i, 1]), recipe[i, 2]
        for k in range(out.shape[1]):
            out[start + i, k] = (1.0 - t) * out[a, k] + t * out[b, k]
