"""Dynamic control: the BVH reader (core.animation.bvh) and a take played on a figure
(core.animation.mocap). Oracles: joint positions worked by hand for a three-joint chain;
the shipped take's counts and its own writer; and a forward kinematics written here in
plain numpy (a parser of its own, rotation matrices by hand) for the figure's toe."""

from __future__ import annotations

import importlib.util
import math
import re
import time
import tracemalloc

import numpy as np
import pytest

from core.animation.bvh import MAX_FRAMES, format_bvh, load_bvh, read_bvh
from core.animation.keys import animation_of
from core.paths import SCENES_DIR
from core.scene.formats import ReaderError, load_scene
from core.scene.formats.mesh import merge_vertices, signed_volume

WALK = SCENES_DIR / "mocap" / "walk.bvh"

# A root that moves and turns, a joint below it, a joint below that, and an End Site. The
# root lists Z X Y, the middle joint X Y Z, the last Y X: each joint's turn is the product in
# its own listed order.
CHAIN = """HIERARCHY
ROOT a
{
  OFFSET 1 2 3
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT b
  {
    OFFSET 0 2 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    JOINT c
    {
      OFFSET 0 0 1
      CHANNELS 2 Yrotation Xrotation
      End Site
      {
        OFFSET 1 0 0
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.5
0 0 0 90 0 0 0 0 0 0 0
10 0 0 0 90 0 90 90 0 0 0
0 0 0 0 0 0 0 0 0 90 90
"""


def test_a_three_joint_chain_against_positions_worked_by_hand():
    """Rx(90): y → z, z → −y. Ry(90): z → x, x → −z. Rz(90): x → y, y → −x.

    Frame 1: a = (1, 2, 3) (the offset, no translation); R_a = Rz(90); b = a + R_a (0, 2, 0)
    = a + (−2, 0, 0) = (−1, 2, 3); R_b = I, c = b + R_a (0, 0, 1) = (−1, 2, 4); the end
    = c + R_a (1, 0, 0) = (−1, 3, 4).
    Frame 2: a = (1, 2, 3) + (10, 0, 0) = (11, 2, 3); R_a = Rz(0) Rx(90) Ry(0) = Rx(90);
    b = a + Rx(90) (0, 2, 0) = (11, 2, 5); R_b = Rx(90) Ry(90) (X, then Y as listed);
    c = b + R_a R_b (0, 0, 1) = b + Rx(90) Rx(90) Ry(90) (0, 0, 1) = b + Rx(90) Rx(90) (1, 0, 0)
    = b + (1, 0, 0) = (12, 2, 5); the end = c + R_a R_b (1, 0, 0) = c + Rx Rx Ry (1, 0, 0)
    = c + Rx Rx (0, 0, −1) = c + Rx (0, 1, 0) = c + (0, 0, 1) = (12, 2, 6).
    Frame 3: only c turns: R_c = Ry(90) Rx(90) (Y, then X); the end = c + R_c (1, 0, 0)
    = c + Ry(90) (1, 0, 0) = c + (0, 0, −1); c = (1, 2, 3) + (0, 2, 0) + (0, 0, 1)."""
    motion = read_bvh(CHAIN, "chain.bvh")
    assert motion.names == ["a", "b", "c"] and list(motion.parent) == [-1, 0, 1]
    assert motion.channels[2] == ("Yrotation", "Xrotation") and motion.frame_time == 0.5
    joints, _, ends = motion.world(motion.frames)
    expected = {0: ([1, 2, 3], [-1, 2, 3], [-1, 2, 4], [-1, 3, 4]),
                1: ([11, 2, 3], [11, 2, 5], [12, 2, 5], [12, 2, 6]),
                2: ([1, 2, 3], [1, 4, 3], [1, 4, 4], [1, 4, 3])}
    for f, (a, b, c, end) in expected.items():
        assert np.allclose(joints[f], [a, b, c], atol=1e-12), f
        assert np.allclose(ends[f, 0], end, atol=1e-12), f
    # the order is the file's: the same values listed Y X Y for b turn the end elsewhere
    swapped = read_bvh(CHAIN.replace("CHANNELS 3 Xrotation Yrotation Zrotation",
                                     "CHANNELS 3 Yrotation Xrotation Zrotation"), "chain.bvh")
    _, _, other = swapped.world(swapped.frames)
    # R_b = Ry(90) Rx(90) from the same two numbers: c = b + Rx Ry Rx (0, 0, 1) = b + Rx Ry
    # (0, −1, 0) = b + Rx (0, −1, 0) = b + (0, 0, −1) = (11, 2, 4)
    assert np.allclose(swapped.world(swapped.frames)[0][1, 2], [11, 2, 4], atol=1e-12)
    assert not np.allclose(other[1, 0], ends[1, 0])


def test_between_two_frames_a_joint_turns_the_short_way_by_slerp(tmp_path):
    """Yrotation 170 then −170: the short way is through 180 (slerp), 20 degrees; the
    Euler angles in-betweened apart would swing 340 degrees back through 0."""
    text = ("HIERARCHY\nROOT r\n{\n OFFSET 0 0 0\n CHANNELS 1 Yrotation\n End Site\n {\n"
            "  OFFSET 0 0 1\n }\n}\nMOTION\nFrames: 2\nFrame Time: 1\n170\n-170\n")
    (tmp_path / "turn.bvh").write_text(text)
    (tmp_path / "turn.toml").write_text(
        '[[geometry]]\ngenerator = "cube"\n[[mocap]]\nfile = "turn.bvh"\nloop = false\n'
        'joint_radius = 0\n[[view]]\nvrp = [0, 0, 0]\nvpn = [0, 0, 1]\nvup = [0, 1, 0]\n'
        'window = [-2, 2, -2, 2]\nprp = [0, 0, 8]\nfront = 4\nback = -4\n')
    figure = animation_of(load_scene(tmp_path / "turn.toml")).movers[0]
    for t, degrees in ((0.0, 170.0), (0.25, 175.0), (0.5, 180.0), (0.75, 185.0), (1.0, 190.0)):
        end = figure.pose_at(t)[2][0]
        a = math.radians(degrees)
        assert np.allclose(end, [math.sin(a), 0.0, math.cos(a)], atol=1e-12), t
    # start = 1, speed = 2: the first frame until t = 1, the take's 0.5 s at t = 1.25, its
    # end held from t = 1.5 (loop = false); "step" shows the frame recorded before
    figure.start, figure.speed = 1.0, 2.0
    for t, degrees in ((0.5, 170.0), (1.25, 180.0), (1.5, 190.0), (9.0, 190.0)):
        a = math.radians(degrees)
        assert np.allclose(figure.pose_at(t)[2][0], [math.sin(a), 0.0, math.cos(a)], atol=1e-12)
    figure.interpolation = "step"
    a = math.radians(170.0)
    assert np.allclose(figure.pose_at(1.4)[2][0], [math.sin(a), 0.0, math.cos(a)], atol=1e-12)


def test_the_shipped_take_round_trips_its_frames_and_frame_time():
    motion = load_bvh(WALK)
    assert motion.frame_count == 97 and motion.frame_time == 0.05
    assert len(motion.names) == 17 and motion.channel_count == 6 + 16 * 3
    assert len(motion.ends) == 5
    text = WALK.read_text()
    assert format_bvh(motion, digits=3) == text               # written back: the same bytes
    again = read_bvh(format_bvh(motion), "again.bvh")
    assert again.frame_count == 97 and again.frame_time == 0.05
    assert again.names == motion.names and again.channels == motion.channels
    assert np.array_equal(again.frames, motion.frames)
    assert np.array_equal(again.offsets, motion.offsets)
    # and it is what its maker writes
    spec = importlib.util.spec_from_file_location("make_walk", WALK.parent / "make_walk.py")
    maker = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(maker)
    assert maker.text() == text


# ---------------------------------------------------------------------- an independent FK


def _parse(text):
    """Offsets, channels and parents of a well-formed BVH, by regular expressions."""
    joints, stack, ends = [], [], {}
    for line in text.split("MOTION")[0].splitlines():
        words = line.split()
        if words[:1] in (["ROOT"], ["JOINT"]):
            joints.append({"name": words[1], "parent": stack[-1] if stack else None})
            pending = joints[-1]["name"]
        elif words[:2] == ["End", "Site"]:
            pending = ("end", stack[-1])
        elif words[:1] == ["{"]:
            stack.append(pending)
        elif words[:1] == ["}"]:
            stack.pop()
        elif words[:1] == ["OFFSET"]:
            if isinstance(stack[-1], tuple):
                ends[stack[-1][1]] = np.array(words[1:], float)
            else:
                joints[-1]["offset"] = np.array(words[1:], float)
        elif words[:1] == ["CHANNELS"]:
            joints[-1]["channels"] = words[2:]
    motion = text.split("MOTION")[1]
    frame_time = float(re.search(r"Frame Time:\s*(\S+)", motion).group(1))
    rows = np.array([line.split() for line in motion.strip().splitlines()[2:]], float)
    return {j["name"]: j for j in joints}, [j["name"] for j in joints], ends, rows, frame_time


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _toe_path(chain):
    joints, order, ends, rows, frame_time = _parse(WALK.read_text())
    first, column = {}, 0
    for name in order:
        first[name] = column
        column += len(joints[name]["channels"])
    path = []
    for row in rows:
        position, frame = np.zeros(3), np.eye(3)
        points = []
        for name in chain:
            local = joints[name]["offset"].copy()
            turn = np.eye(3)
            for k, channel in enumerate(joints[name]["channels"]):
                value = row[first[name] + k]
                if channel.endswith("position"):
                    local["XYZ".index(channel[0])] += value
                else:
                    turn = turn @ {"X": _rx, "Y": _ry, "Z": _rz}[channel[0]](math.radians(value))
            position = position + frame @ local
            frame = frame @ turn
            points.append(position)
        toe = position + frame @ ends[chain[-1]]
        path.append((points[-1], toe))
    return np.array(path), frame_time


def test_the_figures_toe_follows_an_independent_forward_kinematics():
    scene = load_scene(SCENES_DIR / "mocap_walk.toml")
    anim = animation_of(scene)
    figure = anim.movers[0]
    path, frame_time = _toe_path(["Hips", "LeftHip", "LeftKnee", "LeftAnkle"])
    path = path * 0.01                                  # the scene's scale = 0.01, no turn
    toe = figure.motion.names.index("LeftAnkle")
    end = [e for e, (j, _) in enumerate(figure.motion.ends) if j == toe][0]
    # the limb from the ankle to the toe (the ankle's first mesh; its second is the ball):
    # a prism symmetric end for end, so its vertices' mean is the bone's middle
    limb = figure.carried[toe][0]
    for k in range(0, 97, 4):
        t = k * frame_time
        points, _, ends = figure.pose_at(t)
        assert np.allclose(points[toe], path[k, 0], atol=1e-9), k
        assert np.allclose(ends[end], path[k, 1], atol=1e-9), k
        if t < anim.duration:
            drawn = anim.scene_at(t).meshes[limb].positions
            lo, hi = drawn.min(axis=0), drawn.max(axis=0)
            middle = 0.5 * (path[k, 0] + path[k, 1])
            assert np.allclose(drawn.mean(axis=0), middle, atol=1e-9), k
            assert np.all(lo <= path[k, 1] + 1e-9) and np.all(path[k, 1] <= hi + 1e-9)
    # the loop: 4.8 s on, the take is at its start again (its last frame is its first pose)
    assert np.allclose(figure.pose_at(4.8 + 0.35)[0], figure.pose_at(0.35)[0], atol=1e-9)


def test_the_figure_is_closed_limbs_modelled_in_the_first_frames_pose():
    scene = load_scene(SCENES_DIR / "mocap_walk.toml")
    anim = animation_of(scene)
    figure = anim.movers[0]
    limbs = [i for meshes in figure.carried for i in meshes]
    # 16 bones between joints + 5 to End Sites, and a sphere at each of 17 joints
    assert len(limbs) == 16 + 5 + 17
    for i in limbs:
        mesh = scene.meshes[i]
        merged, inverse = merge_vertices(mesh.positions)
        assert mesh.closed and signed_volume(merged, inverse[mesh.triangles]) > 0.0
    assert all(np.allclose(m, np.eye(4), atol=1e-12) for m in figure.matrices_at(0.0).values())
    assert anim.duration == 4.8 and anim.loop


# ---------------------------------------------------------------------- bad input


def _fails(text: str) -> str:
    with pytest.raises(ReaderError) as error:
        read_bvh(text, "bad.bvh")
    message = str(error.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("change, message", [
    (("  }\n}\nMOTION", "  }\nMOTION"),
     "bad.bvh:20: MOTION begins inside joint 'a' (its '{' on line 3): a '}' is missing"),
    (("}\nMOTION", "}\n}\nMOTION"),
     "bad.bvh:21: '}' closes no joint (one '}' too many)"),
    (("    OFFSET 0 2 0\n", ""),
     "bad.bvh:8: joint 'b' has no OFFSET: the first line inside its braces must be OFFSET x y z "
     "(got 'CHANNELS')"),
    (("OFFSET 0 2 0", "OFFSET 0 2"),
     "bad.bvh:9: the OFFSET of joint 'b': 'CHANNELS' is not a number"),
    (("CHANNELS 2 Yrotation Xrotation", "CHANNELS 3 Yrotation Xrotation"),
     "bad.bvh:13: CHANNELS of joint 'c' says 3 but names 2"),
    (("CHANNELS 2 Yrotation Xrotation", "CHANNELS 2 Yrotation Wrotation"),
     "bad.bvh:13: CHANNELS of joint 'c': 'Wrotation' is not a channel (Xposition, Yposition, "
     "Zposition, Xrotation, Yrotation, Zrotation)"),
    (("0 0 0 0 0 0 0 0 0 90 90", "0 0 0 0 0 0 0 0 0 90"),
     "bad.bvh:26: frame 3 has 10 numbers; the hierarchy's CHANNELS give 11"),
    (("10 0 0 0 90 0 90 90 0 0 0", "10 0 0 0 90 0 90 90 0 0 0 0"),
     "bad.bvh:25: frame 2 has 12 numbers; the hierarchy's CHANNELS give 11"),
    (("Frames: 3", "Frames: 4"), "bad.bvh:22: 'Frames: 4' but the file holds 3 rows"),
    (("Frames: 3", "Frames: 2"), "bad.bvh:26: more rows than 'Frames: 2' says (row 3 here)"),
    (("10 0 0 0 90", "10 0 zero 0 90"),
     "bad.bvh:25: frame 2, channel a Zposition: 'zero' is not a number"),
    (("10 0 0 0 90", "10 0 nan 0 90"),
     "bad.bvh:25: frame 2, channel a Zposition: 'nan' is not a finite number"),
    (("10 0 0 0 90", "10 0 inf 0 90"),
     "bad.bvh:25: frame 2, channel a Zposition: 'inf' is not a finite number"),
    (("OFFSET 1 2 3", "OFFSET 1 NaN 3"),
     "bad.bvh:4: the OFFSET of joint 'a': 'NaN' is not a finite number"),
    (("Frame Time: 0.5", "Frame Time: 0"),
     "bad.bvh:23: Frame Time: 0 s is outside [1e-05, 60] s"),
    (("Frame Time: 0.5", "Frame Time: nan"),
     "bad.bvh:23: Frame Time: 'nan' is not a finite number"),
    (("Frames: 3", "Frames: -3"), "bad.bvh:22: Frames: expected a whole number, got '-3'"),
    (("JOINT c", "JOINT b"), "bad.bvh:10: a second joint named 'b'"),
    (("MOTION\n", ""), "bad.bvh:21: expected MOTION after the ROOT's closing '}', got 'Frames:'"),
    (("End Site\n      {\n        OFFSET 1 0 0\n", "End Site\n      {\n"),
     "bad.bvh:16: the End Site of 'c' has no OFFSET (got '}')"),
])
def test_a_broken_file_gets_one_line_naming_its_line(change, message):
    old, new = change
    assert old in CHAIN
    assert _fails(CHAIN.replace(old, new, 1)) == message


def test_a_million_frames_are_refused_before_any_row_is_stored():
    text = CHAIN.replace("Frames: 3", "Frames: 1000000")
    tracemalloc.start()
    start = time.perf_counter()
    try:
        message = _fails(text)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert message == ("bad.bvh:22: Frames: 1,000,000 frames; at most 100,000 are read (the "
                       "reader's limit; cut the take into parts)")
    assert MAX_FRAMES == 100_000
    assert peak < 1_000_000 and time.perf_counter() - start < 1.0
    # a count within the limit that the rows do not hold allocates only its frames
    assert _fails(CHAIN.replace("Frames: 3", "Frames: 100000")) == \
        "bad.bvh:22: 'Frames: 100000' but the file holds 3 rows"
    # 14 joints of 6 channels: 99,999 frames are 8.4 million numbers, refused by their product
    six = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
    deep = "".join(f"JOINT j{k}\n{{\nOFFSET 0 1 0\n{six}\n" for k in range(13))
    text = (f"HIERARCHY\nROOT r\n{{\nOFFSET 0 0 0\n{six}\n{deep}" + "}\n" * 14
            + "MOTION\nFrames: 99999\nFrame Time: 0.01\n")
    assert _fails(text) == ("bad.bvh:73: Frames: 99,999 frames of 84 channels are 8,399,916 "
                            "numbers; at most 8,000,000")


def test_a_broken_take_named_in_a_scene_says_which_file_and_table(tmp_path):
    (tmp_path / "broken.bvh").write_text(CHAIN.replace("    OFFSET 0 2 0\n", ""))
    (tmp_path / "scene.toml").write_text('[[geometry]]\ngenerator = "cube"\n[[mocap]]\n'
                                         'file = "broken.bvh"\n')
    with pytest.raises(ReaderError) as error:
        load_scene(tmp_path / "scene.toml")
    text = str(error.value)
    assert text.endswith("broken.bvh:8: joint 'b' has no OFFSET: the first line inside its "
                         "braces must be OFFSET x y z (got 'CHANNELS') (the motion of mocap[1] "
                         f"in {tmp_path / 'scene.toml'})")
    (tmp_path / "walk.bvh").write_text(CHAIN)
    for key, message in (('radii = { knee = 0.1 }', "mocap[1].radii.knee: no joint is named "
                                                     "'knee' in "),
                         ('radius = 0', "mocap[1].radius: must be greater than 0, got 0"),
                         ('file = "walk.txt"', "mocap[1].file: 'walk.txt': not a BVH file")):
        text = (f'[[geometry]]\ngenerator = "cube"\n[[mocap]]\nfile = "walk.bvh"\n{key}\n'
                if not key.startswith("file") else
                f'[[geometry]]\ngenerator = "cube"\n[[mocap]]\n{key}\n')
        (tmp_path / "scene.toml").write_text(text)
        with pytest.raises(ReaderError, match=re.escape(message)):
            load_scene(tmp_path / "scene.toml")


def test_a_file_past_the_motion_limit_is_refused_unread(tmp_path):
    huge = tmp_path / "huge.bvh"
    with open(huge, "wb") as f:
        f.truncate(64 * (1 << 20) + 1)                 # sparse: no disk, no time
    with pytest.raises(ReaderError, match="a motion input may have at most 67108864 bytes"):
        load_bvh(huge)
