"""Every table in the docs matches the file that generated it, and a changed machine parameter
reaches every table that depends on it with no hand edit.

A generated table carries a marker (``<!-- table by=... source=... key=... -->``, written by
``docs/hooks/tables.py``); this test makes the table again from the marker's source alone and
compares. A page built from a README a command wrote (``<!-- tables copied from FILE -->``)
must carry each of its tables verbatim from that file. A table with neither is typed by hand
and must be listed in ``HAND_TABLES`` with the reason it is typed (and a listed table that has
gone must leave the list).
"""

from __future__ import annotations

import importlib
import shutil
import sys

import pytest
from conftest import REPO

HOOKS = REPO / "docs" / "hooks"


def _module(name: str):
    """A module of docs/hooks (not a package: the hook imports ``tables`` by its path)."""
    if str(HOOKS) not in sys.path:
        sys.path.insert(0, str(HOOKS))
    return importlib.import_module(name)


tables = _module("tables")

QUOTED = "quoted from a source outside the repository (the paper, issue 20's recordings)"
PROSE = "words, not numbers: names, homes, keys or where to read"
RESULT = ("a result quoted from a command's output before the tables were generated; to be "
          "replaced by a generate: line reading that output")
#: Tables typed by hand: (page, header line) -> why. Every other table must be generated.
HAND_TABLES: dict[tuple[str, str], str] = {}
_HAND = {
    "benchmark.md": RESULT, "compensation.md": RESULT, "contracts.md": PROSE, "fmu.md": RESULT,
    "index.md": PROSE, "iso230-3.md": RESULT, "recordings.md": RESULT, "results.md": RESULT,
    "sensors.md": PROSE, "studies.md": RESULT, "study-placement.md": RESULT,
    "study-sweep.md": RESULT, "twin.md": RESULT, "validation.md": RESULT,
}
_MODEL = {
    "| part | nodes (default build) | heat in | heat out |": PROSE,
    "| term (output) | span | material | sign |": PROSE,
    "| node (state) | '+' half | what puts heat into it more than into the other half |": PROSE,
    "| parameter | default | source |": "cites a source per parameter; the values are the "
    ".mo's defaults (the generated parameters table covers those a machine sets)",
    "| sensor | part | mounted on | surroundings |": PROSE,
    "| statistic | real spindles, min–max (issue 20) |": QUOTED,
    "| segments | 1 h | 2 h | 4 h |": RESULT,
}


def _hand_tables() -> dict[tuple[str, str], str]:
    """The hand-typed tables as they stand: each page's (listed above by page) by header."""
    listed = dict(HAND_TABLES)
    for page in sorted((REPO / "docs").glob("*.md")):
        for marker, header, _ in tables.tables(page.read_text(encoding="utf-8")):
            if page.name in _HAND and marker is None:
                listed[(page.name, header)] = _HAND[page.name]
    listed.update({("model.md", header): why for header, why in _MODEL.items()})
    return listed


def _pages() -> dict[str, str]:
    """Every page as the site renders its Markdown: docs/*.md expanded, and the generated
    pages of the hook (machines, results folders)."""
    generate = _module("generate")
    pages = {p.name: tables.expand(p.read_text(encoding="utf-8"))
             for p in sorted((REPO / "docs").glob("*.md"))}
    pages["generated/machines.md"] = generate.machines_page()

    class Config(dict):
        pass

    class Files(list):
        pass

    import mkdocs.structure.files as files_module

    original = files_module.File.generated
    files_module.File.generated = staticmethod(lambda *a, **k: None)
    try:
        pages.update(generate.result_pages(Files(), Config()))
    finally:
        files_module.File.generated = original
    return pages


@pytest.fixture(scope="module")
def pages() -> dict[str, str]:
    return _pages()


def test_every_table_is_generated_from_its_file_or_listed_as_typed(pages):
    hand = _hand_tables()
    seen_hand = set()
    checked = 0
    for name, text in pages.items():
        copied = tables.COPIED.search(text)
        for marker, header, table in tables.tables(text):
            if marker is not None:
                by, source, key = marker.groups()
                assert tables.regenerate(by, source, key) == table, \
                    f"{name}: the {by} table no longer matches {source}"
                checked += 1
            elif copied is not None:
                source = tables.Sources().path(copied.group(1))
                assert table in source.read_text(encoding="utf-8"), \
                    f"{name}: a table is not in {source}, the file the page copies"
                checked += 1
            else:
                assert (name, header) in hand, \
                    f"{name}: table {header!r} has no source marker and is not listed as typed"
                seen_hand.add((name, header))
    gone = set(hand) - seen_hand
    assert not gone, f"listed as typed but no longer in the docs: {sorted(gone)}"
    assert checked >= 1


def test_the_generated_pages_name_their_tables_and_the_speed_page_reads_every_bench_file():
    page = tables.expand((REPO / "docs" / "speed.md").read_text(encoding="utf-8"))
    found = tables.tables(page)
    assert found and all(marker is not None for marker, _, _ in found)
    sources = {marker.group(2) for marker, _, _ in found}
    for path in sorted((REPO / "bench" / "results").glob("*.json")):
        assert f"bench/results/{path.name}" in sources
    assert "load average" in page and "measured 20" in page  # machine, load, date once


def test_an_unknown_bench_file_is_rendered_key_by_key(tmp_path):
    bench = tmp_path / "bench"
    bench.mkdir()
    (bench / "bench_new.json").write_text(
        '{"script": "bench_new", "date_utc": "2026-12-02T00:00:00+00:00", "git_commit": "abc",'
        ' "load_average": [1.0, 2.0, 3.0], "machine": {"nproc": 2, "cpu_model": "x"},'
        ' "goals": {"wall_s": 5}, "rows": [{"size": 10, "wall_s": 0.25}, '
        '{"size": 20, "wall_s": 1.5, "peak_MB": 40}]}', encoding="utf-8")
    page = tables.speed_section(tables.Sources(root=tmp_path, bench=bench))
    assert "| size | wall_s | peak_MB |" in page and "| 20 | 1.5 | 40 |" in page
    assert "| wall_s | 5 |" in page and "load average 1.0 / 2.0 / 3.0" in page


@pytest.mark.slow
def test_a_changed_machine_parameter_updates_every_table_that_depends_on_it(tmp_path):
    """The issue's demonstration: change a parameter in (a copy of) a machine file, rebuild,
    and the parameters and fingerprint tables change, with no hand edit."""
    machines = tmp_path / "machines"
    machines.mkdir()
    shutil.copy(REPO / "scenarios" / "machines" / "default.toml", machines)
    sources = tables.Sources(root=tmp_path, machines=machines,
                             machines_json=tmp_path / "machines.json", run=True)
    page = ("<!-- generate: parameters -->\n\n<!-- generate: fingerprints default -->\n\n"
            "<!-- generate: targets -->\n")
    from spindlebench.studies.fingerprint.machine_check import write_json

    def build() -> str:
        if not (tmp_path / "machines.json").is_file() or \
                tables.stale(tables._read_json(tmp_path / "machines.json"), sources):
            # what make docs does when the file is stale, without the slow sections
            write_json(sources.machines_json, [str(machines / "default.toml")], sources.fmu,
                       fingerprints_only=True)
        return tables.expand(page, sources)

    before = build()
    assert "headstock_column_G" not in before  # the default sets no parameter
    path = machines / "default.toml"
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace("[parameters]", "[parameters]\nheadstock_column_G = 5.0", 1),
                    encoding="utf-8")
    assert tables.stale(tables._read_json(tmp_path / "machines.json"), sources)
    after = build()
    assert "| `headstock_column_G` | W/K | 40 | 5 |" in after
    old, new = (dict((h, t) for m, h, t in tables.tables(x) if m and m.group(1) ==
                     "fingerprints") for x in (before, after))
    assert old.keys() == new.keys() and old != new  # the fingerprints follow the parameter
    for marker, _, table in tables.tables(after):  # and each still matches its source
        by, source, key = marker.groups()
        assert tables.regenerate(by, source, key, sources) == table
