"""In-betweening: a keyed value as a function of time (course notes, 11 and 16 April).

A :class:`Track` holds keys ``(t_i, V_i)`` (``V`` a vector of any length) and a method:

- ``linear``: the notes' ``V_t = V_i (1 - u) + u V_f`` on each interval, ``u`` in [0, 1].
- ``ease``: the same lerp with ``u`` replaced by ``(1 - cos(pi u)) / 2`` (ease-in/ease-out:
  zero speed at every key). The notes name a "trigonometric method" but give no formula;
  this cosine is ours.
- ``catmull-rom``: the cubic Hermite spline through the keys with tangents
  ``(V_{i+1} - V_{i-1}) / (t_{i+1} - t_{i-1})``: C1 in time at every key.
- ``kochanek-bartels``: Hermite with Kochanek and Bartels' (1984) incoming and outgoing
  tangents, shaped by tension T, continuity C and bias B (T = C = B = 0 is Catmull–Rom), and
  scaled for unequal key spacing so that C = 0 keeps the curve C1 in time.
- ``double``: the double-interpolant method (Steketee and Badler 1985): one spline for the
  path's *shape*, through the keys against the key number ``k``, and a second, monotone spline
  for the *timing*, ``k(t)`` through ``(t_i, i)``. Shape and timing are then adjusted
  independently (a key can be moved in time without changing the path).

``constant_speed=True`` re-parametrises a track by arc length: the same curve, travelled at
constant speed from the first key's time to the last (the keys in between are passed at the
times their arc length dictates).

Times outside the keys hold the first or last value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

METHODS = ("linear", "ease", "catmull-rom", "kochanek-bartels", "double")


def lerp(v_i, v_f, u):
    """The notes' ``V_t = V_i (1 - t) + t V_f``."""
    return v_i * (1.0 - u) + u * v_f


def hermite(p0, p1, m0, m1, u, h):
    """The cubic Hermite segment from p0 to p1 over a time span h, tangents m (per unit time)."""
    u2, u3 = u * u, u * u * u
    return ((2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * h * m0
            + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * h * m1)


def kb_tangents(times: np.ndarray, values: np.ndarray, tension=0.0, continuity=0.0, bias=0.0):
    """Kochanek–Bartels incoming and outgoing tangents per key, in value per unit time.

    Per key, with ``a = V_i - V_{i-1}`` and ``b = V_{i+1} - V_i``:
    outgoing ``(1-T)(1+C)(1+B)/2 a + (1-T)(1-C)(1-B)/2 b``,
    incoming ``(1-T)(1-C)(1+B)/2 a + (1-T)(1+C)(1-B)/2 b``,
    each per key interval, turned into per unit time by ``2 / (t_{i+1} - t_{i-1})``. An end key
    repeats its one interval (the curve leaves it along the chord).
    """
    n = len(times)
    t, v = np.asarray(times, np.float64), np.asarray(values, np.float64)
    incoming, outgoing = np.empty_like(v), np.empty_like(v)
    for i in range(n):
        lo, hi = max(i - 1, 0), min(i + 1, n - 1)
        if lo == hi:                                   # a single key: no motion
            incoming[i] = outgoing[i] = 0.0
            continue
        a = v[i] - v[lo] if i > 0 else v[hi] - v[i]
        b = v[hi] - v[i] if i < n - 1 else v[i] - v[lo]
        span = (t[hi] - t[lo]) * (2.0 if (i == 0 or i == n - 1) else 1.0)
        T, C, B = tension, continuity, bias
        out_ = (1 - T) * (1 + C) * (1 + B) / 2 * a + (1 - T) * (1 - C) * (1 - B) / 2 * b
        in_ = (1 - T) * (1 - C) * (1 + B) / 2 * a + (1 - T) * (1 + C) * (1 - B) / 2 * b
        outgoing[i], incoming[i] = out_ * (2.0 / span), in_ * (2.0 / span)
    return incoming, outgoing


def monotone_slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Fritsch–Carlson slopes: a cubic Hermite through increasing data that never turns back
    (the double interpolant's timing curve must be monotone or the path would run backwards)."""
    d = np.diff(y) / np.diff(x)
    m = np.empty(len(x))
    m[0], m[-1] = d[0], d[-1]
    for i in range(1, len(x) - 1):
        m[i] = 0.0 if d[i - 1] * d[i] <= 0 else 2.0 / (1.0 / d[i - 1] + 1.0 / d[i])
    return m


@dataclass
class Track:
    """A keyed value: ``times`` (K,) strictly increasing, ``values`` (K, D)."""

    times: np.ndarray
    values: np.ndarray
    method: str = "catmull-rom"
    tension: float = 0.0
    continuity: float = 0.0
    bias: float = 0.0
    constant_speed: bool = False

    def __post_init__(self) -> None:
        self.times = np.asarray(self.times, dtype=np.float64).reshape(-1)
        self.values = np.asarray(self.values, dtype=np.float64).reshape(len(self.times), -1)
        if self.method not in METHODS:
            raise ValueError(f"interpolation {self.method!r} is not one of {', '.join(METHODS)}")
        if len(self.times) == 0:
            raise ValueError("a track needs at least one key")
        if np.any(np.diff(self.times) <= 0):
            raise ValueError("key times must increase strictly")
        self._incoming, self._outgoing = kb_tangents(
            self.times, self.values, *((self.tension, self.continuity, self.bias)
                                       if self.method == "kochanek-bartels" else (0, 0, 0)))
        if self.method == "double":
            k = np.arange(len(self.times), dtype=np.float64)
            self._shape = Track(k, self.values, "catmull-rom")
            self._timing_slopes = monotone_slopes(self.times, k) if len(k) > 1 else np.zeros(1)
        self._arc = self._arc_table() if self.constant_speed and len(self.times) > 1 else None

    def __call__(self, t: float) -> np.ndarray:
        """The value at time ``t``."""
        if self._arc is not None:
            t = self._arc_time(t)
        return self._curve(t)

    def _interval(self, t: float) -> tuple[int, float, float]:
        """(i, u, h): the key interval [t_i, t_{i+1}] holding t, u in [0, 1], h its length."""
        i = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2))
        h = self.times[i + 1] - self.times[i]
        return i, (t - self.times[i]) / h, h

    def _curve(self, t: float) -> np.ndarray:
        if len(self.times) == 1 or t <= self.times[0]:
            return self.values[0].copy()
        if t >= self.times[-1]:
            return self.values[-1].copy()
        i, u, h = self._interval(t)
        v0, v1 = self.values[i], self.values[i + 1]
        if self.method == "linear":
            return lerp(v0, v1, u)
        if self.method == "ease":
            return lerp(v0, v1, (1.0 - np.cos(np.pi * u)) / 2.0)
        if self.method == "double":
            k = hermite(float(i), float(i + 1), self._timing_slopes[i], self._timing_slopes[i + 1],
                        u, h)
            return self._shape._curve(k)
        return hermite(v0, v1, self._outgoing[i], self._incoming[i + 1], u, h)

    # ------------------------------------------------------------------ ranges

    def interval_ranges(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)``, each ``(K - 1, D)``: the exact least and greatest value of each
        component over each key interval (from the cubic's ends and turning points), so that
        a check at load time sees what the in-betweens will be (a scale keyed 1 → −1 passes
        through 0). ``linear`` and ``ease`` stay between their keys; ``double`` runs along its
        shape spline (its timing is monotone), as does a constant-speed track."""
        if len(self.times) == 1:
            return self.values[:1].copy(), self.values[:1].copy()
        if self.method in ("linear", "ease"):
            v0, v1 = self.values[:-1], self.values[1:]
            return np.minimum(v0, v1), np.maximum(v0, v1)
        if self.method == "double":
            return self._shape.interval_ranges()
        h = np.diff(self.times)[:, None]
        p0, p1 = self.values[:-1], self.values[1:]
        m0, m1 = self._outgoing[:-1] * h, self._incoming[1:] * h
        a = 2 * p0 + m0 - 2 * p1 + m1                     # p(u) = a u³ + b u² + c u + d
        b = -3 * p0 - 2 * m0 + 3 * p1 - m1
        low, high = np.minimum(p0, p1), np.maximum(p0, p1)
        with np.errstate(divide="ignore", invalid="ignore"):
            disc = np.sqrt(np.maximum(b * b - 3 * a * m0, 0.0))   # p'(u) = 3a u² + 2b u + c
            roots = [(-b + disc) / (3 * a), (-b - disc) / (3 * a), -m0 / (2 * b)]
        for u in roots:
            inside = np.isfinite(u) & (u > 0.0) & (u < 1.0)
            u = np.where(inside, u, 0.0)
            value = np.where(inside, ((a * u + b) * u + m0) * u + p0, p0)
            low, high = np.minimum(low, value), np.maximum(high, value)
        return low, high

    # ------------------------------------------------------------------ arc length

    SAMPLES_PER_INTERVAL = 256
    MAX_ARC_SAMPLES = 1 << 20         # the whole table's; many keys get fewer per interval

    def _arc_table(self) -> tuple[np.ndarray, np.ndarray]:
        """Cumulative chord length of the curve sampled finely: (times, lengths). The samples
        are evaluated together (:meth:`_curve_many`) and bounded in number, so that a track
        of 20,000 keys costs time and memory linear in its keys."""
        intervals = len(self.times) - 1
        per = max(8, min(self.SAMPLES_PER_INTERVAL, self.MAX_ARC_SAMPLES // intervals))
        ts = np.linspace(self.times[0], self.times[-1], per * intervals + 1)
        points = self._curve_many(ts)
        lengths = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
        return ts, lengths

    def _curve_many(self, ts: np.ndarray) -> np.ndarray:
        """:meth:`_curve` at every time of ``ts`` (inside the keys), ``(len(ts), D)``."""
        ts = np.clip(ts, self.times[0], self.times[-1])
        i = np.clip(np.searchsorted(self.times, ts, side="right") - 1, 0, len(self.times) - 2)
        h = self.times[i + 1] - self.times[i]
        u = ((ts - self.times[i]) / h)[:, None]
        v0, v1 = self.values[i], self.values[i + 1]
        if self.method == "linear":
            return lerp(v0, v1, u)
        if self.method == "ease":
            return lerp(v0, v1, (1.0 - np.cos(np.pi * u)) / 2.0)
        if self.method == "double":
            k = hermite(i.astype(np.float64), i + 1.0, self._timing_slopes[i],
                        self._timing_slopes[i + 1], u[:, 0], h)
            return self._shape._curve_many(k)
        return hermite(v0, v1, self._outgoing[i], self._incoming[i + 1], u, h[:, None])

    def _arc_time(self, t: float) -> float:
        """The curve time at which the arc length is the fraction of the whole that t is of
        the keyed span (inverted by linear interpolation in the table)."""
        ts, lengths = self._arc
        if lengths[-1] == 0.0:
            return t
        f = np.clip((t - self.times[0]) / (self.times[-1] - self.times[0]), 0.0, 1.0)
        return float(np.interp(f * lengths[-1], lengths, ts))


ORIENTATION_METHODS = ("slerp", "squad")


@dataclass
class OrientationTrack:
    """Keyed orientations as unit quaternions: ``slerp`` on each interval (constant angular
    speed, the short way round) or ``squad`` through all keys (C1 at the keys).

    Never Euler angles: interpolating the three angles separately twists the object through
    orientations that neither key has (see the gimbal-lock test).
    """

    times: np.ndarray
    keys: np.ndarray                  # (K, 4) unit quaternions
    method: str = "squad"

    def __post_init__(self) -> None:
        from core.animation import quaternion as qt
        self.times = np.asarray(self.times, dtype=np.float64).reshape(-1)
        if self.method not in ORIENTATION_METHODS:
            raise ValueError(f"orientation {self.method!r} is not one of "
                             f"{', '.join(ORIENTATION_METHODS)}")
        if len(self.times) == 0:
            raise ValueError("a track needs at least one key")
        if np.any(np.diff(self.times) <= 0):
            raise ValueError("key times must increase strictly")
        keys = np.array([qt.normalize(q) for q in np.asarray(self.keys, np.float64).reshape(-1, 4)])
        self.keys = qt.hemisphere(keys)
        self._controls = qt.squad_controls(self.keys) if self.method == "squad" else None

    def __call__(self, t: float) -> np.ndarray:
        from core.animation import quaternion as qt
        if len(self.times) == 1 or t <= self.times[0]:
            return self.keys[0].copy()
        if t >= self.times[-1]:
            return self.keys[-1].copy()
        i = int(np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2))
        u = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        if self._controls is None:
            return qt.slerp(self.keys[i], self.keys[i + 1], u)
        return qt.normalize(qt.squad(self.keys[i], self.keys[i + 1], self._controls[i],
                                     self._controls[i + 1], u))
