"""The README is one page a newcomer reads in one sitting, and no link in the docs is dead."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote

import pytest

from tests.conftest import ROOT

README = ROOT / "README.md"
DOCS = sorted((ROOT / "docs").glob("*.md"))

LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^```.*?^```", re.S | re.M)


def links(path: Path) -> list[tuple[int, str]]:
    """Every Markdown link or image target of ``path`` outside code fences, with its line."""
    text = path.read_text(encoding="utf-8")
    text = FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)   # keep line numbers
    return [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in LINK.finditer(text)]


def anchors(path: Path) -> set[str]:
    """GitHub's anchors for the headings of a Markdown file."""
    text = FENCE.sub("", path.read_text(encoding="utf-8"))
    found = set()
    for heading in re.findall(r"^#{1,6}\s+(.*?)\s*#*\s*$", text, re.M):
        slug = re.sub(r"[^\w\- ]", "", heading.lower().replace("`", "")).replace(" ", "-")
        found.add(slug)
    return found


def dead(path: Path, root: Path = ROOT) -> list[str]:
    problems = []
    for line, target in links(path):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):      # http:, https:, mailto:
            continue
        file_part, _, anchor = target.partition("#")
        where = (path.parent / unquote(file_part)).resolve() if file_part else path
        if not where.is_file():
            problems.append(f"{path.relative_to(root)}:{line}: {target} (no such file)")
        elif anchor and where.suffix == ".md" and anchor not in anchors(where):
            problems.append(f"{path.relative_to(root)}:{line}: {target} (no such heading)")
    return problems


def test_the_link_checker_finds_a_dead_link_and_a_wrong_anchor(tmp_path):
    (tmp_path / "b.md").write_text("# The startup code's screen\n")
    page = tmp_path / "a.md"
    page.write_text("[ok](b.md) [ok](b.md#the-startup-codes-screen) ![pic](b.md)\n"
                    "[web](https://example.org/x) [self](#top)\n# Top\n"
                    "```\n[not a link](nowhere.md)\n```\n"
                    "[gone](missing.md) [bad anchor](b.md#nowhere)\n")
    assert dead(page, tmp_path) == ["a.md:7: missing.md (no such file)",
                                    "a.md:7: b.md#nowhere (no such heading)"]


@pytest.mark.parametrize("page", [README] + DOCS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(page):
    assert links(page) or page != README, "the README links to the docs"
    assert dead(page) == []


def test_the_readme_is_one_page_with_a_picture_and_both_commands_on_its_first_screen():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) < 250, f"README.md has {len(lines)} lines; the rest belongs in docs/"
    first_screen = "\n".join(lines[:40])
    assert re.search(r"!\[[^\]]*\]\([^)]+\.png\)", first_screen), "no picture on the first screen"
    assert "make run" in first_screen and "make test" in first_screen


def test_every_doc_is_reachable_from_the_readme():
    text = README.read_text(encoding="utf-8")
    for page in DOCS:
        assert f"docs/{page.name}" in text, f"README.md does not link docs/{page.name}"


def test_user_facing_text_names_no_issue_numbers():
    pages = [README] + DOCS + sorted((ROOT / "scenes").glob("*.toml"))
    found = [f"{p.relative_to(ROOT)}:{n}" for p in pages
             for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(r"\bissues? \d", line, re.I)]
    assert found == []
