"""The names of the wrap modes and filters (no numba here: the scene reader and the command
line import these without loading the compiled samplers of :mod:`core.texture.sample`)."""

REPEAT, CLAMP, MIRROR = 0, 1, 2
WRAPS = {"repeat": REPEAT, "clamp": CLAMP, "mirror": MIRROR}
NEAREST, BILINEAR, TRILINEAR, ANISOTROPIC = 0, 1, 2, 3
FILTERS = {"nearest": NEAREST, "bilinear": BILINEAR, "trilinear": TRILINEAR,
           "anisotropic": ANISOTROPIC}
