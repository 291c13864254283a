"""A number with a unit in the docs' prose is an argument or comes from a file (issue 27).

Issue 27's rule: "a number in prose is typed by hand only where it is an argument". A result
in a sentence is written as ``<!-- value: FILE PATH [FORMAT] -->`` (``docs/hooks/tables.py``:
read from the file a command wrote, checked by ``test_docs_tables.py``) or left to the
generated table beside it. This test is the ratchet that keeps it so: every number with a unit
in the prose of ``README.md`` and ``docs/*.md`` (outside code, tables, HTML comments and the
``value`` / ``generate`` lines) must be in ``prose_numbers.toml`` beside this file, under a
reason. A new one fails here, naming page and line; one that left the page must leave the
list, so it only shrinks. (The ``unreviewed`` and ``parallel`` entries, typed before this
check, have each been moved under a reason or out of the prose, and those two reasons are
gone: a number can be listed only as an argument, a goal, a quotation or history.)

The scan reads the pages as committed (a few hundred kB of text): well under a second. It
sees a number with its unit: in "12.2 / 12.5 µm" or "1.79 → 1.27 CPU-s" only the last one
counts, and a bare number ("mean 9.6", "2 of 20") is not seen at all; the list is keyed by
page and text, not line, so moving a sentence within its page does not fail it.
"""

from __future__ import annotations

import re
import tomllib
from collections import Counter

from conftest import REPO

ALLOWED = REPO / "tests" / "repo" / "prose_numbers.toml"

#: The units a result is given in on these pages (longest first where one is another's start).
UNITS = ("CPU-s", "CPU-ms", "CPU-h", "CPU s", "CPU seconds", "µm/K", "um/K", "µm/s", "K/h",
         "W/K", "W/(m²·K)", "J/(kg·K)", "kJ/K", "µm", "um", "µrad", "urad", "°C", "kW", "W",
         "K", "rpm", "mm/min", "m/min", "mm", "m²", "kg", "MB", "GB", "kB", "ms", "min", "h",
         "s", "%", "×", "x", "Hz", "N", "days", "day", "hours", "hour", "minutes", "seconds")
#: A number (digits grouped by spaces, a decimal part, a range) followed by a unit.
NUMBER = re.compile(
    r"(?<![\w.\-/+−±])[-+−±]?\d{1,3}(?: \d{3})+(?:\.\d+)?(?:\s?[–-]\s?\d+(?:\.\d+)?)?"
    r"\s?(?:" + "|".join(re.escape(u) for u in UNITS) + r")(?![\w/²])"
    r"|(?<![\w.\-/+−±])[-+−±]?\d+(?:\.\d+)?(?:\s?[–-]\s?[-+−]?\d+(?:\.\d+)?)?"
    r"\s?(?:" + "|".join(re.escape(u) for u in UNITS) + r")(?![\w/²])")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.MULTILINE | re.DOTALL)
COMMENT = re.compile(r"<!--.*?-->", re.DOTALL)
CODE = re.compile(r"`[^`\n]*`")
LINK_TARGET = re.compile(r"\]\([^)]*\)")


def pages() -> list[str]:
    """The pages the rule covers, as paths relative to the repository."""
    return ["README.md", *sorted(f"docs/{p.name}" for p in (REPO / "docs").glob("*.md"))]


def _blank(match: re.Match) -> str:
    """A stripped part keeps its line breaks, so a hit's line number stays the page's."""
    return "\n" * match.group().count("\n")


def prose_numbers(text: str) -> list[tuple[int, str]]:
    """(line, number with its unit) of every number with a unit in a page's prose: not in
    fenced or inline code, a table row, an HTML comment (``value`` and ``generate`` lines are
    comments) or a link's target."""
    text = COMMENT.sub(_blank, FENCE.sub(_blank, text))
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("|"):
            continue
        line = LINK_TARGET.sub("]", CODE.sub("", line))
        found += [(number, " ".join(m.group().split())) for m in NUMBER.finditer(line)]
    return found


def allowed() -> tuple[dict[str, str], dict[str, Counter]]:
    """The reasons, and per page the numbers allowed (how often each may appear)."""
    document = tomllib.loads(ALLOWED.read_text(encoding="utf-8"))
    reasons = document["reasons"]
    per_page: dict[str, Counter] = {}
    for page, groups in document["pages"].items():
        for reason, numbers in groups.items():
            assert reason in reasons, f"{ALLOWED.name}: [{page}] {reason}: no such reason"
            per_page.setdefault(page, Counter()).update(numbers)
    return reasons, per_page


def test_the_scan_finds_numbers_with_units_in_prose_only():
    page = ("Z rises to 19.4 µm at 1.9 h, 45 080 rows, a 5–20 K rise, −3.1 µm and 30×; 2 000 mm.\n"
            "| 20.9 µm | in a table |\n`exp1 at 4000 rpm` in code, [a](x_2h.md), "
            "<!-- value: a.json b .1f --> CPU-s, <!-- 3 h --> exp2, k = 3\n"
            "```\n6 h\n```\nafter the fence 2 min\n")
    assert prose_numbers(page) == [(1, "19.4 µm"), (1, "1.9 h"), (1, "5–20 K"),
                                   (1, "−3.1 µm"), (1, "30×"), (1, "2 000 mm"), (7, "2 min")]


def compare(page: str, text: str, allowed_here: Counter) -> tuple[list[str], list[str]]:
    """The page's numbers the list does not allow (``page:line: number``), and the list's
    numbers the page no longer has."""
    hits = prose_numbers(text)
    extra = Counter(n for _, n in hits) - allowed_here
    new = []
    for line, number in hits:
        if extra[number] > 0:
            new.append(f"{page}:{line}: {number!r}")
            extra[number] -= 1
    gone = [f"{page}: {number!r} ({count}×)" for number, count in
            (allowed_here - Counter(n for _, n in hits)).items()]
    return new, gone


def test_a_new_number_or_a_removed_one_is_named():
    text = "It ran 6 h.\nThen 6 h more, and 12.5 µm.\n"
    assert compare("p.md", text, Counter({"6 h": 2, "12.5 µm": 1})) == ([], [])
    assert compare("p.md", text, Counter({"6 h": 1, "3 K": 1})) == (
        ["p.md:1: '6 h'", "p.md:2: '12.5 µm'"], ["p.md: '3 K' (1×)"])  # the first is named


def test_every_number_with_a_unit_in_prose_is_allowed_with_a_reason():
    reasons, per_page = allowed()
    new, gone = [], []
    for page in pages():
        found = compare(page, (REPO / page).read_text(encoding="utf-8"),
                        per_page.get(page, Counter()))
        new += found[0]
        gone += found[1]
    assert not new, (
        "a number with a unit was typed into prose: write it as <!-- value: FILE PATH FORMAT "
        "--> from the file the command writes, point to the generated table, or (an argument, "
        f"a quotation) add it to {ALLOWED.name} under its reason ({', '.join(reasons)}):\n"
        + "\n".join(new))
    assert not gone, (f"no longer in the page: remove from {ALLOWED.name} (the list only "
                      "shrinks):\n" + "\n".join(gone))


def test_every_allowed_page_is_a_page():
    _, per_page = allowed()
    assert set(per_page) <= set(pages())
