"""The view-file reader: any number of six-line views (Assignment #1's input format).

Takes the text of a view file (or of standard input) and returns the valid views and one
message per rejected view. A view is 18 numbers in the order of pipeline.md (VRP 3, VPN 3,
VUP 3, window 4, PRP 3, F B 2); like the course's ``prog < grade.data`` the numbers are read
as a stream, so blank lines and ``#`` comments may fall anywhere between them.

A bad token (not a number, NaN, inf) spoils only its own view: it takes that number's slot, so
the views after it stay aligned and still load. A truncated last view is reported, as is every
invalid or unreasonable view (:func:`core.camera.view.load_problems`: the renderer's own rules, so
that every view that loads can be drawn). Nothing in the text can raise.
"""

from __future__ import annotations

import math

from core.camera.view import View, load_problems
from core.scene.formats.errors import printable

NUMBERS_PER_VIEW = 18
_FIELDS = ("VRP", "VRP", "VRP", "VPN", "VPN", "VPN", "VUP", "VUP", "VUP",
           "u_min", "u_max", "v_min", "v_max", "PRP", "PRP", "PRP", "F", "B")


def _tokens(text: str):
    """(line number, token) for every whitespace-separated token outside comments."""
    for number, line in enumerate(text.splitlines(), start=1):
        for token in line.split("#", 1)[0].split():
            yield number, token


def _parse(token: str) -> tuple[float | None, str | None]:
    """The token's value, or None and the reason it is not a usable number."""
    try:
        value = float(token)
    except ValueError:
        shown = token if len(token) <= 20 else token[:20] + "..."
        return None, f"{shown!r} is not a number"
    if not math.isfinite(value):
        return None, f"{token!r} is not a finite number"
    return value, None


def read_views(text: str, source: str = "<views>") -> tuple[list[View], list[str]]:
    """Parse every view in ``text``; returns ``(views, messages)``.

    Each message names the file, the view number (counting every view in the file, valid or
    not), the line, and the reason, e.g. ``"house.views: view 9 (line 61): VUP is parallel to
    VPN"``. A view is refused when neither projection can draw it (the renderer's rules,
    matrices included); a view that only one projection refuses (F behind the eye in
    perspective) loads and is reported when it is drawn that way.
    """
    entries = read_view_entries(text, source)
    return ([e for e in entries if isinstance(e, View)],
            [e for e in entries if not isinstance(e, View)])


def read_view_entries(text: str, source: str = "<views>") -> list[View | str]:
    """Every view of ``text`` in file order: the :class:`View` when valid, its message when
    not (so that view K of the file is entry K - 1, as the course numbers them)."""
    source = printable(source, 200)          # it names every message; it may come from a file
    entries: list[View | str] = []
    group: list[tuple[int, str]] = []
    for item in _tokens(text):
        group.append(item)
        if len(group) == NUMBERS_PER_VIEW:
            entries.append(_finish(group, len(entries) + 1, source))
            group = []
    if group:
        entries.append(f"{source}: view {len(entries) + 1} (line {group[0][0]}): truncated: "
                       f"expected {NUMBERS_PER_VIEW} numbers, found {len(group)} before the end "
                       "of the input")
    return entries


def _finish(group, index, source) -> View | str:
    """The view of one group of 18 tokens, or the message saying why it is invalid."""
    label = f"{source}: view {index} (line {group[0][0]})"
    values, errors = [], []
    for slot, (line, token) in enumerate(group):
        value, reason = _parse(token)
        values.append(value)
        if reason:
            errors.append(f"line {line}: {_FIELDS[slot]}: {reason}")
    if errors:
        return f"{label}: " + "; ".join(errors)
    v = values
    view = View(vrp=tuple(v[0:3]), vpn=tuple(v[3:6]), vup=tuple(v[6:9]), window=tuple(v[9:13]),
                prp=tuple(v[13:16]), front=v[16], back=v[17], label=label)
    found = load_problems(view)
    return f"{label}: " + "; ".join(found) if found else view
