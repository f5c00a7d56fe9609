"""The projection taxonomy (FvDFH 6.1, the notes' tree): each view's class from its numbers,
against classes derived by hand from the view files' numbers (the derivation beside each)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from core.camera.taxonomy import NoClass, classify, describe
from core.camera.view import View
from core.paths import ROOT
from core.scene.formats import load_scene

# scenes/house_projections.views, view by view, with the reason worked by hand:
PROJECTIONS = [
    ("parallel", "orthographic (front elevation)"),   # DOP = (0,0,0) - (0,0,40) ∥ VPN = z
    ("parallel", "orthographic (top view, plan)"),    # DOP ∥ VPN = y
    ("parallel", "orthographic (side elevation)"),    # DOP ∥ VPN = x
    ("parallel", "isometric"),          # n = (1,1,1)/√3: each axis shortened to √(2/3)
    ("parallel", "dimetric"),           # n = (2,1,2)/3: x, z to √5/3, y to √8/3
    ("parallel", "trimetric"),          # n = (3,2,4)/√29: 1 - 9/29, 1 - 4/29, 1 - 16/29 differ
    ("parallel", "cavalier"),           # DOP (-24,-18,-30): |(24,18)| = 30 = |DOP_n|
    ("parallel", "cabinet"),            # DOP (-12,-9,-30): |(12,9)| = 15 = 30 / 2
    ("perspective", "one-point perspective"),      # VPN (0,0,1): only z cut
    ("perspective", "two-point perspective"),      # VPN (1,0,1): x and z cut
    ("perspective", "three-point perspective"),    # VPN (1,0.6,1): all three cut
]


def test_every_named_house_view_is_the_class_its_entry_says():
    scene = load_scene(ROOT / "scenes" / "house_projections.toml")
    assert len(scene.views) == len(PROJECTIONS)
    text = (ROOT / "scenes" / "house_projections.views").read_text()
    for k, (view, (projection, expected)) in enumerate(zip(scene.views, PROJECTIONS), start=1):
        assert classify(view, projection).name == expected, k
        header = next(line for line in text.splitlines() if line.startswith(f"# {k}. "))
        assert f"({projection})" in header and expected.split(" (")[0].lower() in header.lower()


# scenes/house.views (the loaded ones): perspective by VPN's non-zero components; parallel by
# DOP = CW - PRP against VPN (None: oblique at a ratio that is neither 1 nor 1/2)
HOUSE = {1: ("one-point perspective", None),       # DOP (-8,-6,-84): ratio 10/84
         2: ("one-point perspective", None),       # CW (8,8), PRP (8,6,30): ratio 2/30
         5: ("one-point perspective", None),       # CW (0,15), PRP (20,25,20): √500/20
         6: ("two-point perspective", None),       # VPN (1,0,1)
         7: ("two-point perspective", None),
         8: ("one-point perspective", "orthographic (front elevation)"),   # CW = PRP_uv
         12: ("one-point perspective", "orthographic (front elevation)"),  # VPN (0,0,-1)
         13: ("three-point perspective", "isometric")}                    # VPN (-1,1,1)


@pytest.mark.parametrize("number", sorted(HOUSE))
def test_each_house_view_in_both_projections(number):
    scene = load_scene(ROOT / "scenes" / "house.toml")
    view = next(v for v in scene.views if f"view {number} (" in v.label)
    perspective, parallel = HOUSE[number]
    assert classify(view, "perspective").name == perspective
    if parallel is None:
        with pytest.raises(NoClass, match=r"an oblique parallel projection of none of the named "
                                          r"classes: .* cavalier draws them at 1"):
            classify(view, "parallel")
    else:
        assert classify(view, "parallel").name == parallel


def test_a_view_of_no_class_and_a_view_of_no_plane_get_one_message_each():
    oblique = View((0, 0, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (3, 0, 10), 1, -1,
                   label="x.views: view 1 (line 1)")
    assert describe(oblique, "parallel") == {
        "class": None, "family": None,
        "why": "x.views: view 1 (line 1): an oblique parallel projection of none of the named "
               "classes: DOP (-3, 0, -10) is oblique to VPN: lines perpendicular to the view "
               "plane are drawn at 0.3 of their length (projectors at 73.3 degrees to the "
               "plane); cavalier draws them at 1 (45 degrees), cabinet at 1/2 (63.43 degrees)"}
    flat = View((0, 0, 0), (0, 0, 0), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 10), 1, -1, label="v")
    assert describe(flat, "perspective")["why"] == "v: VPN is zero: no projection plane to classify"
    # an orthographic view of a plane parallel to z: x and y shortened alike, z not at all
    assert classify(View((0, 0, 0), (1, 1, 0), (0, 0, 1), (-1, 1, -1, 1), (0, 0, 10), 1, -1),
                    "parallel").name == "dimetric"


def test_matrices_names_the_class():
    out = subprocess.run([sys.executable, "-m", "app", "matrices",
                          str(ROOT / "scenes" / "house_projections.toml"), "--view", "8",
                          "--projection", "parallel"], cwd=ROOT, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    found = json.loads(out.stdout)["class"]
    assert found["class"] == "cabinet" and found["family"] == "parallel: oblique"
