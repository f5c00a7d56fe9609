"""Reactive control: actors that sense their surroundings and respond (Reynolds' steering).

The course's animation lecture ends its procedural control with "reactive control /* AI */":
beyond a flock's three rules, each actor perceives what is near it — within its ``senses``'
radius and field of view (:class:`~core.animation.actors.Senses`) — and chooses a steering
acceleration from what it perceives (Reynolds, *Steering Behaviors for Autonomous
Characters*, GDC 1999). The behaviours here are registered with ``senses=True``, so they are
handed the group's :class:`~core.animation.actors.Surroundings` (every group's actors at the
step's start); a scene whose actors sense others steps all its groups together
(:class:`~core.animation.actors.Stage`).

- ``avoid_obstacles``: spheres (and named geometry, by its bounding sphere) in the way. An
  obstacle is a threat when the actor perceives it, it lies ahead (``d · h > 0``, d from the
  actor to its centre, h the heading) and the actor's line of travel passes nearer its centre
  than ``R + clearance``. Against the nearest threat the actor turns as hard as
  ``acceleration`` allows, across its heading and away from the centre (no braking: its
  speed is kept). Alone, at speed s, that is a circle of radius ``ρ = s² / acceleration``
  begun when the obstacle comes within the sensing radius r of its surface, and an actor
  heading straight at the centre passes it at ``√(ρ² + D²) − ρ`` from the centre,
  ``D = r + R`` (while that is under ``R + clearance``; past it, the turn stops at that
  distance): clear of the obstacle whenever ``r² + 2 r R > 2 ρ R``.
- ``pursue``: the nearest perceived actor of the group ``target``, at where it will be
  (its position plus its velocity times ``T = min(distance / max_speed, prediction)``):
  the desired velocity is ``max_speed`` toward that point, and the steering
  ``(desired − v) / reaction``.
- ``flee``: the same, away from the nearest perceived actor of the group ``threat``
  (``prediction = 0``: away from where it is).
- ``wander``: no perception; a heading that turns by a smooth deterministic rate (two
  sines of different periods, phases spread over the group) at ``speed``, in the
  horizontal plane.

Each returns zero for an actor that perceives nothing to react to, so under
``steering = "priority"`` the next behaviour in the list decides for it.
"""

from __future__ import annotations

import math

import numpy as np

from core.animation.actors import register_behaviour

UP = np.array([0.0, 1.0, 0.0])
GOLDEN = 0.6180339887498949


def _flat(a: np.ndarray, horizontal: bool) -> np.ndarray:
    if not horizontal:
        return a
    out = np.array(a, np.float64, copy=True)
    out[..., 1] = 0.0
    return out


def avoid_obstacles(t, x, v, p, world) -> np.ndarray:
    spheres = p["spheres"]
    out = np.zeros_like(x)
    if not len(spheres):
        return out
    horizontal = bool(p["horizontal"])
    centres = np.array([c for c, _ in spheres], np.float64)
    radii = np.array([r for _, r in spheres], np.float64)
    xs, vs = _flat(x, horizontal), _flat(v, horizontal)
    cs = _flat(centres, horizontal)
    seen = world.see(xs, vs, cs, radii)                          # (N, M)
    speed = np.linalg.norm(vs, axis=1)
    moving = speed > 0.0
    h = vs / np.maximum(speed, 1e-300)[:, None]
    d = cs[None, :, :] - xs[:, None, :]                          # actor → centre
    ahead = np.einsum("nmk,nk->nm", d, h)
    lateral = d - ahead[..., None] * h[:, None, :]
    off = np.linalg.norm(lateral, axis=2)
    threat = seen & moving[:, None] & (ahead > 0.0) & (off < radii[None, :] + p["clearance"])
    if not threat.any():
        return out
    nearest = np.argmin(np.where(threat, ahead, np.inf), axis=1)
    for i in np.flatnonzero(threat.any(axis=1)):
        k = nearest[i]
        if off[i, k] > 1e-12 * (1.0 + np.abs(d[i, k]).max()):
            away = -lateral[i, k] / off[i, k]
        else:                                   # dead ahead: to the actor's right (h × up)
            side = np.cross(h[i], UP)
            if np.linalg.norm(side) < 1e-12:    # heading straight up or down
                side = np.cross(h[i], [1.0, 0.0, 0.0])
            away = side / np.linalg.norm(side)
        out[i] = p["acceleration"] * away
    return out


def _nearest_seen(x, v, world, name, exclude_self=True):
    """For each actor: the index of the nearest perceived actor of group ``name`` (-1: none),
    and that group's x, v."""
    ox, ov, same = world.others(name)
    if not len(ox):
        return np.full(len(x), -1), ox, ov
    seen = world.see(x, v, ox)
    dist = np.linalg.norm(ox[None, :, :] - x[:, None, :], axis=2)
    if same and exclude_self:
        np.fill_diagonal(seen, False)
    dist = np.where(seen, dist, np.inf)
    k = np.argmin(dist, axis=1)
    k[~np.isfinite(dist[np.arange(len(x)), k])] = -1
    return k, ox, ov


def _steer_from(x, v, p, world, name, sign) -> np.ndarray:
    k, ox, ov = _nearest_seen(x, v, world, name)
    out = np.zeros_like(x)
    has = k >= 0
    if not has.any():
        return out
    q, qv = ox[k[has]], ov[k[has]]
    distance = np.linalg.norm(q - x[has], axis=1)
    ahead = np.minimum(distance / world.max_speed, p["prediction"])
    aim = sign * (q + qv * ahead[:, None] - x[has])
    if p.get("horizontal"):
        aim = _flat(aim, True)
    size = np.linalg.norm(aim, axis=1, keepdims=True)
    direction = np.where(size > 0.0, aim / np.maximum(size, 1e-300), 0.0)
    desired = world.max_speed * direction
    out[has] = (desired - v[has]) / p["reaction"]
    return out


def pursue(t, x, v, p, world) -> np.ndarray:
    return _steer_from(x, v, p, world, p["target"], 1.0)


def flee(t, x, v, p, world) -> np.ndarray:
    return _steer_from(x, v, p, world, p["threat"], -1.0)


def wander(t, x, v, p) -> np.ndarray:
    n = len(x)
    phase = 2.0 * math.pi * ((np.arange(n) * GOLDEN) % 1.0)
    rate = math.radians(p["turn"]) * 0.5 * (np.sin(1.3 * t + phase)
                                             + np.sin(0.53 * t + 2.0 * phase))
    flat = _flat(v, True)
    speed = np.linalg.norm(flat, axis=1)
    h = np.where(speed[:, None] > 0.0, flat / np.maximum(speed, 1e-300)[:, None], [1.0, 0.0, 0.0])
    side = np.cross(UP, h)                                   # to the left of the heading
    cruise = (p["speed"] * h - flat) / p["reaction"]
    return cruise + (rate * p["speed"])[:, None] * side


register_behaviour("avoid_obstacles", avoid_obstacles,
                   {"spheres": [], "obstacles": [], "clearance": 0.2, "acceleration": 8.0,
                    "horizontal": False}, senses=True)
register_behaviour("pursue", pursue, {"target": "", "prediction": 1.0, "reaction": 0.5,
                                      "horizontal": False}, senses=True)
register_behaviour("flee", flee, {"threat": "", "prediction": 1.0, "reaction": 0.5,
                                  "horizontal": False}, senses=True)
register_behaviour("wander", wander, {"speed": 1.0, "turn": 60.0, "reaction": 0.5})
