"""Writes walk.bvh: a 17-joint figure walking once round a circle, 97 frames at 20 a second.

Not a capture: a gait made of a few sinusoids (hips, knees, ankles, arms, a bob and a
sway), written in the BVH format so that the viewer's motion-capture path reads a real
file. Centimetres, y up, the figure facing +z at rest with its arms hanging. Four gait
cycles of 1.2 s make one lap of radius 80 cm (4.8 s); the last frame is the first pose
again (the yaw one turn on), so the take loops without a seam.

    python scenes/mocap/make_walk.py            # rewrites scenes/mocap/walk.bvh
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent))

from core.animation.bvh import Motion, format_bvh  # noqa: E402

CYCLE = 1.2                 # seconds a gait cycle (two steps)
CYCLES = 4                  # a lap
RADIUS = 80.0               # cm, the circle the hips go round
FRAME_TIME = 0.05
HIP_SWING = 20.0            # degrees each way
ARM_SWING = 16.0
ZXY = ("Zrotation", "Xrotation", "Yrotation")

# name, parent, offset (cm)
JOINTS = [
    ("Hips", None, (0, 0, 0)),
    ("Spine", "Hips", (0, 10, 0)),
    ("Chest", "Spine", (0, 15, 0)),
    ("Neck", "Chest", (0, 20, 0)),
    ("Head", "Neck", (0, 8, 0)),
    ("LeftShoulder", "Chest", (17, 17, 0)),
    ("LeftElbow", "LeftShoulder", (0, -28, 0)),
    ("LeftWrist", "LeftElbow", (0, -25, 0)),
    ("RightShoulder", "Chest", (-17, 17, 0)),
    ("RightElbow", "RightShoulder", (0, -28, 0)),
    ("RightWrist", "RightElbow", (0, -25, 0)),
    ("LeftHip", "Hips", (9, -6, 0)),
    ("LeftKnee", "LeftHip", (0, -42, 0)),
    ("LeftAnkle", "LeftKnee", (0, -41, 0)),
    ("RightHip", "Hips", (-9, -6, 0)),
    ("RightKnee", "RightHip", (0, -42, 0)),
    ("RightAnkle", "RightKnee", (0, -41, 0)),
]
ENDS = {"Head": (0, 18, 0), "LeftWrist": (0, -16, 0), "RightWrist": (0, -16, 0),
        "LeftAnkle": (0, -7, 14), "RightAnkle": (0, -7, 14)}
STANDING = 6 + 42 + 41 + 7          # the hips' height with straight legs


def pose(t: float) -> dict:
    """Every joint's channel values at t (degrees; the root's position in cm)."""
    phase = 2 * math.pi * t / CYCLE
    yaw = 360.0 * t / (CYCLE * CYCLES)              # one lap
    psi = math.radians(yaw)
    out = {}
    bob = 1.6 * math.cos(2 * phase)                 # highest at mid-stance, twice a cycle
    out["Hips"] = (-RADIUS * math.cos(psi), STANDING - 2.4 + bob, RADIUS * math.sin(psi),
                   yaw, 3.0, 3.0 * math.sin(phase))  # Y X Z: yaw, a lean, a sway
    out["Spine"] = (0.0, 0.0, -4.0 * math.sin(phase))       # the chest turns against the hips
    out["Chest"] = (0.0, 1.0, -3.0 * math.sin(phase))
    out["Neck"] = (0.0, -2.0, 2.0 * math.sin(phase))
    out["Head"] = (0.0, -2.0, 2.0 * math.sin(phase))
    for side, shift, sign in (("Left", 0.0, 1.0), ("Right", math.pi, -1.0)):
        p = phase + shift
        forward = HIP_SWING * math.sin(p)                   # the thigh ahead of the hip
        swing = max(0.0, math.cos(p)) ** 2                  # 1 at mid-swing, 0 in stance
        knee = 4.0 + 55.0 * swing + 8.0 * max(0.0, math.sin(p)) ** 4
        out[f"{side}Hip"] = (-2.0 * sign, -forward, 0.0)    # -x: the leg forward
        out[f"{side}Knee"] = (0.0, knee, 0.0)               # +x: the shin back
        out[f"{side}Ankle"] = (0.0, 0.6 * (forward - knee) - 6.0 * swing, 0.0)
        arm = -ARM_SWING * math.sin(p)                       # against the same side's leg
        out[f"{side}Shoulder"] = (8.0 * sign, -arm, 0.0)
        out[f"{side}Elbow"] = (0.0, -12.0 - 10.0 * max(0.0, -math.sin(p)), 0.0)
        out[f"{side}Wrist"] = (0.0, -5.0, 0.0)
    return out


def motion() -> Motion:
    names = [j[0] for j in JOINTS]
    parent = [names.index(p) if p else -1 for _, p, _ in JOINTS]
    channels = [("Xposition", "Yposition", "Zposition", "Yrotation", "Xrotation", "Zrotation")]
    channels += [ZXY] * (len(JOINTS) - 1)
    count = int(round(CYCLE * CYCLES / FRAME_TIME)) + 1
    rows = []
    for k in range(count):
        values = pose(k * FRAME_TIME)
        rows.append([v for name in names for v in values[name]])
    ends = [(names.index(n), np.array(o, np.float64)) for n, o in ENDS.items()]
    return Motion(names, np.array(parent), np.array([j[2] for j in JOINTS], np.float64),
                  channels, ends, np.array(rows), FRAME_TIME, "walk.bvh")


def text() -> str:
    return format_bvh(motion(), digits=3)


if __name__ == "__main__":
    (HERE / "walk.bvh").write_text(text())
    print(f"wrote {HERE / 'walk.bvh'}")
