"""Procedural textures: checker, bricks, the bump demo's height functions, value and Perlin noise.

Each is a function of (u, v) in [0, 1]² evaluated at the texel centres of a ``resolution`` x
``resolution`` image (numpy, vectorised), so that it is sampled, filtered and MIP-mapped like
an image file. All of them tile: the pattern repeats exactly across u = 1 and v = 1 (checker
and bricks by whole counts, noise by a lattice that wraps), so ``wrap = "repeat"`` shows no
seam. Colours are display values (what one would paint), so :func:`make` builds the texture
with ``srgb = True``; height fields are data in [0, 1] (``srgb = False``).

``texture = { procedural = "checker", scale = 8 }`` in a scene file calls :func:`make` with the
table's other keys as parameters; :data:`PROCEDURALS` lists every name with its parameters.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

import numpy as np

from core.texture.image import Texture, srgb_to_linear

# Texels a side. Computing a pattern takes a dozen float64 arrays of the whole image at once
# (perlin at 4096²: 2.3 GB measured), so procedurals stop at 2048² (a quarter of that); a larger
# texture is an image file, read a band at a time.
MAX_RESOLUTION = 2048
DEFAULT_RESOLUTION = 256


def _grid(resolution: int) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) at the texel centres, arrays (resolution, resolution), row 0 at v = 0."""
    c = (np.arange(resolution) + 0.5) / resolution
    return np.meshgrid(c, c)


def _mix(a, b, t):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a + (b - a) * np.asarray(t, float)[..., None]


@dataclass(frozen=True)
class Palette:
    """An image of few colours: ``colours[pick]``. :func:`make` decodes the colours from sRGB
    before it gathers them, the same numbers as decoding every texel (a 1024² checker: its
    sRGB decoding 85 ms → nothing)."""
    colours: np.ndarray                 # (K, 3)
    pick: np.ndarray                    # (h, w) indices into colours


def _two_colours(a, b, pick):
    """``_mix(a, b, pick)`` for a ``pick`` of 0s and 1s, as a :class:`Palette` of the two
    colours mixed once (the same numbers; the 1024² checker's image: 30 ms instead of 90)."""
    return Palette(_mix(a, b, np.array([0.0, 1.0])), pick)


def checker(resolution: int = 256, scale: int = 8, a=(0.9, 0.9, 0.9), b=(0.1, 0.1, 0.1)):
    """``scale`` x ``scale`` squares, colour ``a`` where (⌊u scale⌋ + ⌊v scale⌋) is even."""
    c = (np.arange(resolution) + 0.5) / resolution          # u (columns) and v (rows)
    cell = np.floor(c * scale).astype(np.int64)
    return _two_colours(a, b, (cell[:, None] + cell[None, :]) % 2), True


def _bricks_mask(resolution, rows, columns, mortar):
    """1 on a brick, 0 in the mortar; every other row shifted by half a brick."""
    u, v = _grid(resolution)
    y = v * rows
    row = np.floor(y)
    x = u * columns + 0.5 * (row % 2)
    fx, fy = x - np.floor(x), y - row
    half = mortar / 2
    return ((fx > half) & (fx < 1 - half) & (fy > half) & (fy < 1 - half)).astype(float)


def bricks(resolution: int = 256, rows: int = 8, columns: int = 4, mortar: float = 0.08,
           brick=(0.62, 0.22, 0.14), joint=(0.78, 0.76, 0.72)):
    """Running-bond bricks: ``rows`` courses of ``columns`` bricks, ``mortar`` joints
    (a fraction of a brick's height)."""
    mask = _bricks_mask(resolution, rows, columns, mortar).astype(np.int64)
    return _two_colours(joint, brick, mask), True


def bricks_height(resolution: int = 256, rows: int = 8, columns: int = 4, mortar: float = 0.08):
    """The bricks as a height field: 1 on the bricks, 0 in the joints."""
    return _bricks_mask(resolution, rows, columns, mortar), False


def bricks_normal(resolution: int = 256, rows: int = 8, columns: int = 4, mortar: float = 0.08,
                  strength: float = 4.0):
    """A tangent-space normal map of the bricks (rgb = (n + 1) / 2, z out of the surface):
    the height's gradient by central differences that wrap, ``strength`` times steeper."""
    height = _bricks_mask(resolution, rows, columns, mortar)
    dhdu = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) / 2 * strength
    dhdv = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) / 2 * strength
    n = np.stack([-dhdu, -dhdv, np.ones_like(height)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return (n + 1) / 2, False


def demo_height(resolution: int = 256, map: int = 0):
    """The bump demo's B(x, y) (``J3DPanel.bump``, maps 0 … 3) over its window: u → x = 100 u,
    v → y = −100 (1 − v), so the texture's top-left is the demo's (0, 0); B in [−2, 2] is
    mapped to [0, 1] by (B + 2) / 4."""
    from core.texture.demo_scene import demo_bump_numpy
    u, v = _grid(resolution)
    return (demo_bump_numpy(map, 100.0 * u, -100.0 * (1.0 - v)) + 2.0) / 4.0, False


def _lattice(seed: int, period: int, dims=(1,)):
    rng = np.random.default_rng(seed)
    return rng.random((period, period) + dims)


def _fade(t):
    return t * t * t * (t * (t * 6 - 15) + 10)       # Perlin's quintic: C2 across cells


def _value_octave(resolution, period, seed):
    u, v = _grid(resolution)
    x, y = u * period, v * period
    i, j = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = _fade(x - i), _fade(y - j)
    table = _lattice(seed, period)[..., 0]
    c = lambda di, dj: table[(j + dj) % period, (i + di) % period]   # noqa: E731
    return (c(0, 0) * (1 - fx) * (1 - fy) + c(1, 0) * fx * (1 - fy)
            + c(0, 1) * (1 - fx) * fy + c(1, 1) * fx * fy)


def _perlin_octave(resolution, period, seed):
    u, v = _grid(resolution)
    x, y = u * period, v * period
    i, j = np.floor(x).astype(int), np.floor(y).astype(int)
    dx, dy = x - i, y - j
    angle = 2 * np.pi * _lattice(seed, period)[..., 0]
    gx, gy = np.cos(angle), np.sin(angle)

    def corner(di, dj):
        a, b = (j + dj) % period, (i + di) % period
        return gx[a, b] * (dx - di) + gy[a, b] * (dy - dj)
    fx, fy = _fade(dx), _fade(dy)
    bottom = corner(0, 0) * (1 - fx) + corner(1, 0) * fx
    top = corner(0, 1) * (1 - fx) + corner(1, 1) * fx
    return 0.5 + (bottom * (1 - fy) + top * fy) / np.sqrt(2)   # |noise| <= sqrt(1/2)


def _octaves(octave, resolution, scale, octaves, seed):
    total, amplitude, weight = 0.0, 1.0, 0.0
    for k in range(octaves):
        total = total + amplitude * octave(resolution, scale * 2 ** k, seed + k)
        weight += amplitude
        amplitude /= 2
    return total / weight


def value_noise(resolution: int = 256, scale: int = 8, octaves: int = 4, seed: int = 1,
                a=(0.0, 0.0, 0.0), b=(1.0, 1.0, 1.0)):
    """Value noise: random values on a ``scale`` x ``scale`` lattice, smoothly interpolated,
    ``octaves`` octaves of halving amplitude; coloured from ``a`` (0) to ``b`` (1)."""
    return _mix(a, b, _octaves(_value_octave, resolution, scale, octaves, seed)), True


def perlin(resolution: int = 256, scale: int = 8, octaves: int = 4, seed: int = 1,
           a=(0.0, 0.0, 0.0), b=(1.0, 1.0, 1.0)):
    """Perlin's gradient noise (1985, with his 2002 quintic fade), ``octaves`` octaves."""
    return _mix(a, b, _octaves(_perlin_octave, resolution, scale, octaves, seed)), True


def perlin_height(resolution: int = 256, scale: int = 8, octaves: int = 4, seed: int = 1):
    """Perlin noise as a height field in [0, 1]."""
    return _octaves(_perlin_octave, resolution, scale, octaves, seed), False


def sky(resolution: int = 256, zenith=(0.15, 0.35, 0.8), horizon=(0.85, 0.9, 0.95),
        ground=(0.35, 0.3, 0.25), squares: int = 16, sun=(0.3, 0.75)):
    """An equirectangular environment (u: longitude, v: latitude, up): a sky from ``horizon``
    to ``zenith``, a sun at (u, v) = ``sun``, and a checkered ground below the horizon, so a
    mirror shows where it reflects."""
    u, v = _grid(resolution)
    up = np.clip((v - 0.5) * 2, 0, 1) ** 0.6
    image = _mix(horizon, zenith, up)
    sun_distance = np.hypot((u - sun[0]) * 2, v - sun[1])
    image = _mix(image, (1.0, 0.97, 0.85), np.exp(-(sun_distance / 0.03) ** 2))
    checks = (np.floor(u * squares) + np.floor(v * squares)) % 2
    floor = _mix(ground, np.asarray(ground) * 0.5, checks)
    return np.where((v < 0.5)[..., None], floor, image), True


PROCEDURALS = {
    "checker": checker, "bricks": bricks, "bricks_height": bricks_height,
    "bricks_normal": bricks_normal,
    "demo_height": demo_height, "value_noise": value_noise, "perlin": perlin,
    "perlin_height": perlin_height, "sky": sky,
}


def parameters(name: str) -> tuple[str, ...]:
    """The parameters procedural texture ``name`` takes (for the scene reader's checks)."""
    return tuple(inspect.signature(PROCEDURALS[name]).parameters)


# What each parameter may be: a whole number in a range, a number in a range, a colour (three
# numbers in [0, 1]) or a point of the (u, v) square. The scene file passes TOML values
# straight through, so every one is checked here: a string, a NaN, a list of a thousand numbers
# (which numpy would broadcast over the whole image) or a colour of 1e308 is refused by name.
_WHOLE = {"resolution": (1, MAX_RESOLUTION), "scale": (1, 1024), "rows": (1, 1024),
          "columns": (1, 1024), "octaves": (1, 16), "squares": (1, 1024),
          "seed": (0, 2**63 - 1), "map": (0, 3)}
_REAL = {"mortar": (0.0, 1.0), "strength": (0.0, 1e3)}
_COLOURS = ("a", "b", "brick", "joint", "zenith", "horizon", "ground")
# The finest noise lattice has scale · 2^(octaves − 1) cells a side (tables of that many
# squared numbers); finer than the texels it is aliasing only, and its tables the largest
# arrays (32768²: 8.6 GB each). It may have as many cells a side as the texture has texels,
# or MIN_LATTICE for a small texture.
MIN_LATTICE = 256


class ParameterError(ValueError):
    """A procedural texture's parameter that cannot be used; ``key`` names it."""

    def __init__(self, key: str, reason: str) -> None:
        self.key = key
        super().__init__(reason)


def check_parameters(name: str, params: dict) -> dict:
    """``params`` of procedural ``name`` checked one by one (ValueError naming the first bad
    one); whole numbers come back as int, colours and points as tuples of floats."""
    allowed = parameters(name)
    out = {}
    for key, value in params.items():
        if key not in allowed:
            raise ParameterError(key, f"{name} has no parameter {key!r} (it takes "
                                      f"{', '.join(allowed)})")
        if key in _WHOLE:
            low, high = _WHOLE[key]
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise ParameterError(key, f"{key} must be a whole number from {low} to {high}, "
                                          f"not {_shown(value)}")
            out[key] = int(value)
        elif key in _REAL:
            out[key] = _real(key, value, *_REAL[key])
        else:
            length = 3 if key in _COLOURS else 2
            what = "a colour: 3 numbers from 0 to 1" if length == 3 else "a point: 2 numbers (u, v) from 0 to 1"
            if not isinstance(value, (list, tuple)) or len(value) != length:
                raise ParameterError(key, f"{key} must be {what}, not {_shown(value)}")
            out[key] = tuple(_real(key, v, 0.0, 1.0, f"{key}[{i + 1}]") for i, v in enumerate(value))
    if name in ("value_noise", "perlin", "perlin_height"):
        scale, octaves = out.get("scale", 8), out.get("octaves", 4)
        finest = scale * 2 ** (octaves - 1)
        limit = max(out.get("resolution", DEFAULT_RESOLUTION), MIN_LATTICE)
        if finest > limit:
            raise ParameterError("octaves" if "octaves" in params else "scale",
                                 f"scale · 2^(octaves − 1) = {finest} lattice cells a side; at "
                                 f"most {limit}, the texels a side (a finer lattice only "
                                 f"aliases, and its tables would take "
                                 f"{3 * finest * finest * 8 / 2**30:.1f} GiB)")
    if name == "checker" and out.get("scale", 8) % 2:
        raise ParameterError("scale", "checker: scale must be even (an odd count puts two "
                                      "squares of one colour side by side where it repeats)")
    return out


def _real(key: str, value, low: float, high: float, shown: str | None = None) -> float:
    shown = shown or key
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(key, f"{shown} must be a number, not {_shown(value)}")
    if not low <= value <= high:                      # also refuses NaN
        raise ParameterError(key, f"{shown} must lie in [{low:g}, {high:g}], not {_shown(value)}")
    return float(value)


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:40] + "..."


def make(name: str, wrap: str = "repeat", **params) -> Texture:
    """The procedural texture ``name`` with ``params``, as a MIP-mapped :class:`Texture`.

    Raises ValueError for an unknown name, an unknown parameter or one out of its range.
    """
    if name not in PROCEDURALS:
        raise ValueError(f"unknown procedural texture {name!r} (known: {', '.join(PROCEDURALS)})")
    image, srgb = PROCEDURALS[name](**check_parameters(name, params))
    if isinstance(image, Palette):
        colours = srgb_to_linear(image.colours) if srgb else image.colours
        return Texture.from_array(colours[image.pick], wrap=wrap, srgb=srgb, decoded=srgb,
                                  source=f"procedural {name}")
    return Texture.from_array(image, wrap=wrap, srgb=srgb, source=f"procedural {name}")
