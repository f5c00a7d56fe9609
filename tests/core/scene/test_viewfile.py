"""The view-file reader: any number of views, comments, and a message for every bad view."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from core.paths import SCENES_DIR
from core.scene.formats.viewfile import read_views

EXAMPLE = "0 0 54\n0 0 1\n0 1 0\n-1 17 -1 17\n8 6 30\n1 -23\n"


def test_the_notes_example_view():
    views, messages = read_views(EXAMPLE, "grade.data")
    assert messages == []
    (v,) = views
    assert v.vrp == (0, 0, 54) and v.vpn == (0, 0, 1) and v.vup == (0, 1, 0)
    assert v.window == (-1, 17, -1, 17) and v.prp == (8, 6, 30)
    assert (v.front, v.back) == (1, -23)
    assert v.label == "grade.data: view 1 (line 1)"


def test_comments_blank_lines_and_numbers_split_across_lines():
    text = "# a view\n\n0 0\n54 # VRP\n0 0 1\n\n0 1 0 -1 17\n-1 17 8 6 30 1\n-23\n" + EXAMPLE
    views, messages = read_views(text, "v")
    assert messages == [] and len(views) == 2
    assert views[1].label == "v: view 2 (line 10)"


def test_bad_views_are_reported_and_the_rest_still_load():
    bad_token = EXAMPLE.replace("0 1 0", "0 one 0")
    nan = EXAMPLE.replace("8 6 30", "8 nan 30")
    inf = EXAMPLE.replace("1 -23", "1 -inf")
    parallel = EXAMPLE.replace("0 1 0", "0 0 5")
    truncated = "0 0 54\n0 0 1\n"
    text = EXAMPLE + bad_token + nan + inf + parallel + EXAMPLE + truncated
    views, messages = read_views(text, "grade.data")
    assert len(views) == 2
    assert [v.label for v in views] == ["grade.data: view 1 (line 1)", "grade.data: view 6 (line 31)"]
    assert messages == [
        "grade.data: view 2 (line 7): line 9: VUP: 'one' is not a number",
        "grade.data: view 3 (line 13): line 17: PRP: 'nan' is not a finite number",
        "grade.data: view 4 (line 19): line 24: B: '-inf' is not a finite number",
        "grade.data: view 5 (line 25): VUP is parallel to VPN",
        "grade.data: view 7 (line 37): truncated: expected 18 numbers, found 6 before the end "
        "of the input",
    ]


def test_empty_input_has_no_views_and_no_messages():
    assert read_views("", "empty") == ([], [])
    assert read_views("# only a comment\n\n", "c") == ([], [])


def test_shipped_house_views():
    views, messages = read_views((SCENES_DIR / "house.views").read_text(), "house.views")
    assert len(views) == 14
    kinds = ["VPN is zero", "VUP is parallel to VPN", "PRP lies on the view plane",
             "window is degenerate", "is not behind F", "is not a number"]
    assert len(messages) == len(kinds)
    for message, kind in zip(messages, kinds):
        assert kind in message


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=400))
def test_any_text_never_raises(text):
    views, messages = read_views(text, "fuzz")
    assert all(isinstance(m, str) and m.startswith("fuzz: view") for m in messages)
