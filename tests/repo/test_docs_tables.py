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
import re
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
KEYS = "a file format's keys and defaults: arguments, typed where the format is defined"
NO_FILE = ("a result of a command that writes no file (it prints its numbers): to become a "
           "generate: line when the command writes one")
RUNS = ("a result of `spindlebench paper` runs that make run does not do (other phases, "
        "training runs, machines or all methods): to become a generate: line when they are "
        "snapshotted under docs/snapshots/")
#: Tables typed by hand: (page, header line) -> why. Every other table must be generated, and
#: every table listed here must still be in the docs.
HAND_TABLES: dict[tuple[str, str], str] = {
    ("contracts.md", "| name | unit | meaning |"): PROSE,
    ("fmu.md", "| symbol | what it does |"): PROSE,
    ("index.md", "| you want to | read |"): PROSE,
    ("iso230-3.md", "| test | scenario | programme | start | air |"): PROSE,
    ("model.md", "| part | nodes (default build) | heat in | heat out |"): PROSE,
    ("model.md", "| term (output) | span | material | sign |"): PROSE,
    ("model.md", "| node (state) | '+' half | what puts heat into it more than into the other "
     "half |"): PROSE,
    ("model.md", "| parameter | default | source |"): "arguments: the .mo's defaults, typed "
        "beside the source each cites, and checked against the FMU's model description by "
        "test_the_typed_parameter_defaults_are_the_fmus",
    ("model.md", "| sensor | part | mounted on | surroundings |"): PROSE,
    ("model.md", "| statistic | real spindles, min–max (issue 20) |"): QUOTED,
    ("sensors.md", "| sensors | location (Xu et al. 2023, Table 1) | sensors | location |"):
        QUOTED,
    ("study-placement.md", "| key | default | meaning |"): KEYS,
    ("study-sweep.md", "| table | keys (default) | meaning |"): KEYS,
    ("study-sweep.md", "| key | default | meaning |"): KEYS,
}
HAND_TABLES.update({
    ("twin.md", "| regressor | reads | fitted as |"): PROSE,
})
HAND_TABLES.update({
    ("benchmark.md", "| task | what trains | what is predicted | folds |"):
        "the suite's tasks in words, with the arguments of benchmarks/default.toml and its "
        "studies",
})


def _hand_tables() -> dict[tuple[str, str], str]:
    """The hand-typed tables, each listed with why it is typed."""
    return dict(HAND_TABLES)


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


def test_every_value_in_prose_reads_again_from_its_file(pages):
    """Each ``<!-- value: ... -->`` of a page became its file's field (``tables.VALUE_OUT``),
    and reading that field again from the file alone gives the same text."""
    checked = 0
    for name, text in pages.items():
        assert not tables.VALUE.search(text), f"{name}: a value line was not expanded"
        assert "(value: `" not in text, f"{name}: a value's file is missing"
        for source, key, spec, shown in tables.VALUE_OUT.findall(text):
            assert tables.value_text(tables.Sources().path(source), key, spec) == shown, \
                f"{name}: {key} of {source} is no longer {shown}"
            checked += 1
    assert checked >= 10


def test_a_value_is_one_field_of_its_file_and_a_wrong_key_is_one_line(tmp_path):
    """The value form's paths (key, index, ``[KEY=VALUE]`` item), its formats, the snapshot
    fallback, and a missing field or item named with the file and key."""
    import json

    path = tmp_path / "snapshots" / "study" / "out.json"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({"goals": {"cpu_s": 120.0}, "the goals": {"a 0.8 m": 3.2}, "rows": [
        {"fit": "a", "hours": 39.0, "cpu_s": 43.094106}, {"fit": "b", "hours": 46.3,
                                                          "cpu_s": 47.2671, "share": 0.0187}]}),
        encoding="utf-8")
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots")
    page = tables.expand("took <!-- value: study/out.json rows.0.cpu_s .1f --> CPU-s, then "
                         "<!-- value: study/out.json rows.[hours=46.3].cpu_s .2f --> "
                         "(<!-- value: study/out.json rows.-1.share .1% -->, goal "
                         "<!-- value: study/out.json goals.cpu_s -->, "
                         '<!-- value: study/out.json "the goals.[a 0.8 m]" .0f -->)\n', sources)
    shown = [m[3] for m in tables.VALUE_OUT.findall(page)]
    assert shown == ["43.1", "47.27", "1.9%", "120", "3"]
    assert "not in this build" not in page
    assert "from=snapshots/study/out.json key=rows.0.cpu_s" in page
    for key, error in (("rows.2.cpu_s", "no item 2"), ("rows.[hours=1].cpu_s", "0 items"),
                       ("goals.wall_s", "no field 'wall_s'"), ("rows", "is not one value")):
        with pytest.raises(ValueError, match=f"out.json: {re.escape(key)}: {error}"):
            tables.expand(f"<!-- value: study/out.json {key} -->", sources)
    assert "not in this build" in tables.expand("<!-- value: other/x.json a -->", sources)
    assert tables.expand("`<!-- value: FILE PATH -->`", sources) == \
        "`<!-- value: FILE PATH -->`"  # the form quoted in code stays as written
    (path.parent / "rows.csv").write_text("label,m,rmse_um\ngreedy,2,1.9193\ngreedy,3,1.33\n"
                                          "fuzzy,2,\n", encoding="utf-8")
    page = tables.expand("<!-- value: study/rows.csv [label=greedy,m=3].rmse_um .2f -->, "
                         "<!-- value: study/rows.csv [m=2.0,label=greedy].rmse_um .1f -->",
                         sources)
    assert [m[3] for m in tables.VALUE_OUT.findall(page)] == ["1.33", "1.9"]
    for key, error in (("[label=fuzzy,m=2].rmse_um", "is not one value"),  # an empty cell
                       ("[m=2].rmse_um", "2 items have m=2")):
        with pytest.raises(ValueError, match=re.escape(f"rows.csv: {key}: {error}")):
            tables.expand(f"<!-- value: study/rows.csv {key} -->", sources)
    path.write_text(path.read_text(encoding="utf-8").replace("43.094106", "44.0"),
                    encoding="utf-8")
    assert tables.value_text(path, "rows.0.cpu_s", ".1f") != shown[0]  # the check would fail


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
    assert "speed probe" not in page  # a file from before the probe: nothing made up


def test_the_provenance_gives_the_speed_probe_at_start_and_end():
    document = {"date_utc": "2026-12-03T00:00:00+00:00", "git_commit": "abc",
                "load_average": [0.1, 0.2, 0.3], "machine": {"nproc": 2, "cpu_model": "x"},
                "speed_probe_ms": {"start": 93.4, "end": 236.6, "additions": 1_000_000}}
    text = tables.bench_provenance(document, "bench/results/bench_x.json")
    assert "speed probe 93 / 237 ms at the start / end" in text
    assert "1,000,000 Python additions" in text


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


def test_the_run_tables_come_from_results_first_then_the_snapshot_and_average_what_they_read(
        tmp_path):
    """``paper-summary``, ``run-table`` and ``sensitivity`` read ``results/`` when a command
    wrote it there, else the snapshot; the sensitivity's last row is computed from the runs."""
    results, snapshots = tmp_path / "results", tmp_path / "snapshots"
    csv = ("clusters,group,a,mean\n2,all_raw,1,1.0\n2,six_raw,1,2.0\n2,six_diff,1,3.0\n")
    for base, scale in ((snapshots, 1.0), (results, 10.0)):
        (base / "paper_study").mkdir(parents=True)
        (base / "paper_study" / "table6_rmse.csv").write_text(
            csv.replace(",1.0", f",{1.0 * scale}").replace(",2.0", f",{2.0 * scale}"),
            encoding="utf-8")
    sources = tables.Sources(root=tmp_path, results=results, snapshots=snapshots)
    page = tables.expand("<!-- generate: paper-summary paper_study -->\n", sources)
    assert "source=results/paper_study/table6_rmse.csv" in page and "| 2 | 10.0 | 20.0 |" in page
    shutil.rmtree(results)
    page = tables.expand("<!-- generate: paper-summary paper_study -->\n", sources)
    assert "source=snapshots/paper_study/table6_rmse.csv" in page and "| 2 | 1.0 | 2.0 |" in page
    with pytest.raises(ValueError, match="paper-comparison folder"):
        tables.run_file("elsewhere/table6_rmse.csv", sources)
    (snapshots / "paper_study" / "README.md").write_text(
        "text\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\nmore\n\n| c |\n|---|\n| 3 |\n",
        encoding="utf-8")
    page = tables.expand("<!-- generate: run-table paper_study/README.md@2 -->\n", sources)
    assert "| c |\n|---|\n| 3 |" in page and "| a | b |" not in page
    for run, mean in (("run1", 1.0), ("run2", 4.0)):
        folder = snapshots / "caiviac_sensitivity" / "heating" / f"train_{run}"
        folder.mkdir(parents=True)
        (folder / "table6_rmse.csv").write_text(f"clusters,group,mean\n2,all_raw,{mean}\n",
                                                encoding="utf-8")
        (folder / "provenance.json").write_text('{"six": ["t1_C", "t2_C"]}', encoding="utf-8")
    page = tables.expand("<!-- generate: sensitivity heating -->\n", sources)
    assert "| run1 | t1, t2 | 1.0 |" in page and "| **mean over training runs** |  | 2.5 |" in page
    for marker, _, table in tables.tables(page):
        assert tables.regenerate(*marker.groups(), sources) == table


def _disagrees(page: str, sources, path, change) -> None:
    """Every table of ``page`` matches its file; after ``change`` edits that file, the check of
    ``test_every_table_is_generated_from_its_file_or_listed_as_typed`` no longer passes."""
    import json

    found = [(marker, table) for marker, _, table in tables.tables(page)]
    assert found and all(marker is not None for marker, _ in found)
    for marker, table in found:
        assert tables.regenerate(*marker.groups(), sources) == table
    document = json.loads(path.read_text(encoding="utf-8"))
    change(document)
    path.write_text(json.dumps(document), encoding="utf-8")
    assert any(tables.regenerate(*marker.groups(), sources) != table for marker, table in found)


def test_the_discretisation_table_comes_from_its_json_and_fails_when_they_disagree(tmp_path):
    """docs/model.md's discretisation table: from ``model.discretisation --out``'s JSON (the
    results copy first, else the snapshot), with the model's hash; an edited number fails."""
    import json

    from spindlebench.core.provenance import provenance, sha256_file
    from spindlebench.model import discretisation

    model = tmp_path / "models" / "SpindleBench.mo"
    model.parent.mkdir()
    model.write_text("package SpindleBench end SpindleBench;\n", encoding="utf-8")
    document = {"hours": [1.0, 2.0], "default_segments": 12,
                "rows": [{"segments": 6, "drift_rise_um": [21.0, 24.0]},
                         {"segments": 12, "drift_rise_um": [20.0, 25.0]}],
                "provenance": provenance(command="python -m x", solver="BDF", ambient_C=8.0,
                                         speed_rpm=4000.0, feed_mm_per_min=1500.0,
                                         model={"path": "models/SpindleBench.mo",
                                                "sha256": sha256_file(model)})}
    path = tmp_path / "snapshots" / tables.DISCRETISATION
    discretisation.write(path, document)
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots")
    page = tables.expand("<!-- generate: discretisation -->\n", sources)
    assert "source=snapshots/discretisation/discretisation.json" in page
    assert "| **12 (default)** | 20.0 | 25.0 | 0.0 % |" in page and "| 6 | 21.0 | 24.0 | 5.0 % |" \
        in page and "has changed since" not in page
    model.write_text("package SpindleBench /* edited */ end SpindleBench;\n", encoding="utf-8")
    assert "`models/SpindleBench.mo` has changed since" in tables.expand(
        "<!-- generate: discretisation -->\n", sources)
    assert json.loads(path.read_text(encoding="utf-8")) == document  # what write() wrote

    def change(d):
        d["rows"][0]["drift_rise_um"][1] = 24.5

    _disagrees(page, sources, path, change)


def test_the_leaderboard_tables_come_from_leaderboard_json_and_fail_when_they_disagree(
        tmp_path):
    """docs/benchmark.md's leaderboard: the overall table and one per task, in the suite's
    order, from a run's leaderboard.json; a changed RMSE there fails the check."""
    row = {"rank": 1.0, "rmse_um": 2.5, "rmse_sd_um": 0.1, "max_abs_error_um": 7.0,
           "within_band": 0.9, "n_sensors": 3.0, "stability": 1.0, "rollout_rmse_um": 2.5,
           "worse_than": "", "folds": 3, "error": ""}
    document = {
        "provenance": {"command": "spindlebench benchmark -o x", "partial": False,
                       "fmu_sha256": "ab" * 32, "package_versions": {"spindlebench": "0.1.0"}},
        "suite": {"name": "tiny", "version": "0.1", "tasks_sha256": "cd" * 32, "k": 3,
                  "band_um": 5.0, "seed": 0},
        "overall": [{"overall_rank": 1, "method": "lasso", "mean_rank": 1.5,
                     "mean_rmse_um": 3.0, "failed": 0, "worse_than_constant": 0,
                     "worse_than_replay": 1, "worse_than_ols_all": 0},
                    {"overall_rank": 2, "method": "baseline:replay", "mean_rank": 1.5,
                     "mean_rmse_um": 3.2, "failed": 0, "worse_than_constant": 0,
                     "worse_than_replay": 0, "worse_than_ols_all": 0}],
        "rows": [{**row, "task": "b/second", "method": "lasso", "rank": 2.0, "rmse_um": 3.5,
                  "worse_than": "baseline:replay"},
                 {**row, "task": "b/second", "method": "baseline:replay"},
                 {**row, "task": "a/first", "method": "lasso"},
                 {**row, "task": "a/first", "method": "baseline:replay", "rank": None,
                  "rmse_um": None, "error": "no data"}]}
    path = tmp_path / "results" / "benchmark" / "mine" / "leaderboard.json"
    path.parent.mkdir(parents=True)
    import json

    path.write_text(json.dumps(document), encoding="utf-8")
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots")
    page = tables.expand("<!-- generate: leaderboard benchmark/mine -->\n", sources)
    assert page.index("### b/second") < page.index("### a/first")  # the suite's order
    assert "| 1 | `lasso` | 1.50 | 3.00 | 0 / 1 / 0 | 0 |" in page
    assert "| 2.0 | `lasso` | 3.50 | 0.10 | 7.00 | 0.90 | 3.0 | 1.00 | 2.50 | R |" in page
    assert "| – | `baseline:replay` | failed: no data |" in page  # a failed entrant last
    assert "written by `spindlebench benchmark -o x`" in page

    def change(d):
        d["rows"][0]["rmse_um"] = 3.6

    _disagrees(page, sources, path, change)


def test_the_cold_start_table_comes_from_its_json_and_says_when_the_fmu_changed(tmp_path):
    """docs/model.md's magnitudes table: from ``model.cold_start --json``'s file, with the
    FMU's hash (another FMU is said beside the table); an edited rise fails the check."""
    from spindlebench.core.provenance import file_entry, provenance
    from spindlebench.model import cold_start

    fmu = tmp_path / "SpindleBench.fmu"
    fmu.write_bytes(b"not an fmu")
    run = {"sensor_rise_K": {"T10_C": [0.0, 0.1], "T2_C": [11.0, 15.2]},
           "drift_rise_um": [20.6, 20.6], "drift_peak_um": 24.7, "drift_peak_h": 2.1}
    document = {"read_at_min": [50.0, 300.0], "runs": {"4000": run},
                "provenance": provenance(command="python -m x --json y", fmu=file_entry(fmu),
                                         ambient_C=8.0, hours=5.0, feed_mm_per_min=1500.0,
                                         solver="CVode")}
    path = cold_start.write_json(tmp_path / "results" / tables.COLD_START, document)
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots", fmu=fmu)
    page = tables.expand("<!-- generate: cold-start -->\n", sources)
    assert "| rise since the start | 4000 rpm, 50 min | 4000 rpm, 5 h |" in page
    assert page.index("| T2 (K) | +11.0 | +15.2 |") < page.index("| T10 (K) | +0.0 | +0.1 |")
    assert "| drift's peak (µm; when) | 24.7 | at 2.1 h |" in page
    assert "has changed since" not in page
    fmu.write_bytes(b"another fmu")
    assert "`SpindleBench.fmu` has changed since" in tables.expand(
        "<!-- generate: cold-start -->\n", sources)

    def change(d):
        d["runs"]["4000"]["sensor_rise_K"]["T2_C"][0] = 11.2

    _disagrees(page, sources, path, change)


def test_the_typed_parameter_defaults_are_the_fmus():
    """docs/model.md's typed parameter table (arguments, each with its source) states the
    committed FMU's start values: a changed default in the model fails here, not silently."""
    import re

    from spindlebench.testbench.runner import inspect_fmu

    known = inspect_fmu(REPO / "fmus" / "SpindleBench.fmu").parameters
    header = "| parameter | default | source |"
    page = (REPO / "docs" / "model.md").read_text(encoding="utf-8")
    (table,) = [t for _, h, t in tables.tables(page) if h == header]
    checked = 0
    for line in table.splitlines()[2:]:
        names_cell, values_cell = [c.strip() for c in line.strip("|").split("|")][:2]
        names = re.findall(r"`([^`]+)`", names_cell)
        values = [float(v) for v in re.findall(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?",
                                                values_cell)]
        values = values * len(names) if len(values) == 1 else values
        assert len(values) == len(names), line
        for name, value in zip(names, values, strict=True):
            assert name in known, f"model.md: {name} is not a parameter of the FMU"
            assert float(known[name].start) == pytest.approx(value), \
                f"model.md: {name} = {value}, the FMU's default is {known[name].start}"
            checked += 1
    assert checked >= 10


def test_the_evaluate_runs_table_has_a_row_per_k_and_fails_when_a_file_disagrees(tmp_path):
    """docs/results.md's notebook-6 comparison: one row per ``kN.json`` that ``evaluate --json``
    wrote (k from each file's provenance), per-test RMSE and the mean; an edit fails."""
    import json

    folder = tmp_path / "snapshots" / "caiviac-six-correlated"
    folder.mkdir(parents=True)
    for k, rmse in ((3, {"a/run1.csv": 2.0, "a/run2.csv": 4.0}),
                    (2, {"a/run1.csv": 6.0, "a/run2.csv": 8.0})):
        (folder / f"k{k}.json").write_text(json.dumps({
            "selected": ["t1_C", "t1_C-t2_C"][:k], "rmse_um": rmse,
            "mean_rmse_um": sum(rmse.values()) / 2,
            "provenance": {"clusters": k, "target": "ch3_um", "train": {"sha256": "ab" * 32},
                           "package_versions": {"spindlebench": "0.1.0"}}}), encoding="utf-8")
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots")
    page = tables.expand("<!-- generate: evaluate-runs caiviac-six-correlated -->\n", sources)
    assert "| k | selected | run1 | run2 | mean |" in page
    assert page.index("| 2 | `t1_C`, `t1_C-t2_C` | 6.00 | 8.00 | **7.00** |") < \
        page.index("| 3 |")

    def change(d):
        d["rmse_um"]["a/run1.csv"] = 2.5

    _disagrees(page, sources, folder / "k3.json", change)


def test_the_iso_report_tables_come_from_the_report_json_and_fail_when_they_disagree(tmp_path):
    """docs/iso230-3.md's tables of the default machine's reports: every direction and tilt
    of ``TEST.json`` (whole test, spindle-on phase where the test has one, the spectrum's
    steps); an edited value fails the check."""
    import json

    def channel(range_, at_h):
        return {"range": range_, "max": range_, "min": 0.0, "final": 1.0, "at_max_h": at_h}

    report = {"range_um": {"Z": channel(20.85, 4.3667)}, "range_urad": {"A": channel(23.5, 4.2)},
              "heating_range_um": {"Z": channel(19.4, 1.9)},
              "heating_range_urad": {"A": channel(23.0, 3.9)}, "spindle_on_end_h": 4.0,
              "steps": [{"speed_rpm": 2000.0, "from_h": 0.0, "to_h": 0.9833,
                         "end_um": {"Z": 9.55}, "end_urad": {"A": 1.5}}],
              "provenance": {"fmu": {"sha256": "ab" * 32}}}
    path = tmp_path / "snapshots" / "iso230-3" / "spectrum" / "spectrum.json"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps(report), encoding="utf-8")
    sources = tables.Sources(root=tmp_path, results=tmp_path / "results",
                             snapshots=tmp_path / "snapshots")
    page = tables.expand("<!-- generate: iso230-3-report spectrum -->\n\n"
                         "<!-- generate: iso230-3-report spectrum@steps -->\n", sources)
    assert "| Z (µm) | 20.9 | 20.9 at 4.4 h | 0.0 | 1.0 | 19.4 |" in page
    assert "| A (µrad) | 23.5 | 23.5 at 4.2 h | 0.0 | 1.0 | 23.0 |" in page
    assert "| 2000 | 0.00–0.98 | 9.6 | 1.5 |" in page
    with pytest.raises(ValueError, match="no such test"):
        tables.expand("<!-- generate: iso230-3-report nothing -->\n", sources)

    def change(d):
        d["steps"][0]["end_um"]["Z"] = 9.75

    _disagrees(page, sources, path, change)


def test_the_heating_outputs_table_reads_machine_checks_heating_outputs():
    """docs/model.md's heating outputs table: every machine's heating runs from
    ``machine_check``'s ``heating_outputs`` (peak and when, the value at 8 h, the jacket's
    outlet minus inlet); a machine record without them gives no row."""
    document = {"machines": {
        "m": {"heating_outputs": {"heating/room20_4000": {
            "drift_um": {"start": 0.0, "peak": 20.14, "peak_h": 2.1, "end": 14.3},
            "front_preload_thermal_N": {"start": 0.0, "peak": 244.8, "peak_h": 0.15,
                                        "end": 0.0},
            "jacket_inlet_C": {"start": 20.0, "peak": 20.0, "peak_h": 0.0, "end": 20.0},
            "jacket_outlet_C": {"start": 20.0, "peak": 23.2, "peak_h": 8.0, "end": 23.2}}}},
        "old": {}}}
    table = tables.heating_outputs_table(document)
    assert table.count("\n") == 2  # header, rule, one row
    assert "| `m` | heating/room20_4000 | 20.1 at 2.10 h | 14.3 |  | 244.8 at 0.15 h | 0.0 |" \
        "  |  | 3.2 |" in table
